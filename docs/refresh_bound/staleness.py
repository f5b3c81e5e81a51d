"""Staleness alone: the Trashcan's frame t shaded with the 24 outer samples seen from the camera of
k frames earlier (variants.py's stale.glsl, STALE_DEG = k: the session orbits 1 degree a frame), against the exact
frame t; no cache, so no reprojection and no resampling. A cache refreshed every Δn frames holds
entries 0 .. Δn-1 frames old, equally many of each: its staleness-only error is the mean over k.

    PYTHONPATH=. python docs/refresh_bound/staleness.py 640x480 40
"""
import json
import math
import sys
from pathlib import Path

import tempfile

import numpy as np

from rrcache.harness.metrics import squared_error_map
from rrcache.harness.renderer import render
from rrcache.session import load_session

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE))
import variants  # noqa: E402


def main(size: str = "640x480", frames: int = 40) -> dict:
    session = load_session(str(ROOT / "sessions" / "trashcan.json"))
    resolution = tuple(int(v) for v in size.split("x"))
    indices = list(range(frames))
    exact = render(str(ROOT / "shaders" / "trashcan.glsl"), session, frames=indices, resolution=resolution)
    mse = {}
    with tempfile.TemporaryDirectory() as folder:
        stale_path, _ = variants.write(folder)
        for k in range(9):
            stale = render(str(stale_path), session, frames=indices, resolution=resolution,
                           defines={"STALE_DEG": f"{float(k):.1f}"})
            per_frame = [float(squared_error_map(a.image, b.image).mean()) for a, b in zip(stale.frames, exact.frames)]
            mse[k] = float(np.mean(per_frame))
            print(f"k={k}: {10 * math.log10(1 / mse[k]) if mse[k] else math.inf:.1f} dB", flush=True)
    for period in (2, 3, 4, 6, 8):
        pooled = float(np.mean([mse[k] for k in range(period)]))
        print(f"Δn={period}: entries 0..{period - 1} frames old: {10 * math.log10(1 / pooled):.1f} dB")
    return mse


if __name__ == "__main__":
    args = sys.argv[1:]
    print(json.dumps(main(args[0] if args else "640x480", int(args[1]) if len(args) > 1 else 40)))
