"""Render a contact sheet of each example scene into ``docs/contact_sheet_<scene>.png``.

Each sheet shows frames spread evenly over the session (6 by default, first and last included)
in a grid, rendered by the original shader through the rrcache harness, so it shows what the
profiler sees. Uses only the public library (``rrcache.session.load_session`` and
``rrcache.harness.render``)::

    python docs/make_contact_sheets.py                 # all three scenes, 320x240 frames
    python docs/make_contact_sheets.py chess --frames 4 --resolution 160x120
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from rrcache.harness import render
from rrcache.session import load_session

ROOT = Path(__file__).resolve().parent.parent
# scene name -> (shader, session)
SCENES = {
    "marble": ("shaders/marble.glsl", "sessions/marble.json"),
    "trashcan": ("shaders/trashcan.glsl", "sessions/trashcan.json"),
    "chess": ("shaders/ambient_occlusion.glsl", "sessions/chess.json"),
}
COLUMNS = 3
GAP = 4                      # pixels between frames
GAP_COLOR = (0.85, 0.85, 0.85)


def spread_frames(total: int, count: int) -> list[int]:
    """`count` frame indices spread evenly over ``0..total-1``, first and last included.

    >>> spread_frames(150, 6)
    [0, 30, 60, 89, 119, 149]
    """
    if count <= 1 or total <= 1:
        return [0]
    return sorted({round(k * (total - 1) / (count - 1)) for k in range(count)})


def tile(images: list[np.ndarray], columns: int, gap: int) -> np.ndarray:
    """Lay out equally sized H x W x 3 images row by row, `gap` pixels apart."""
    h, w = images[0].shape[:2]
    rows = (len(images) + columns - 1) // columns
    sheet = np.empty((rows * h + (rows + 1) * gap, columns * w + (columns + 1) * gap, 3), np.float32)
    sheet[:] = GAP_COLOR
    for k, image in enumerate(images):
        r, c = divmod(k, columns)
        y, x = gap + r * (h + gap), gap + c * (w + gap)
        sheet[y:y + h, x:x + w] = image[..., :3]
    return sheet


def write_png(path: Path, image: np.ndarray) -> None:
    """Write a float image in [0, 1] (clamped) as an 8-bit PNG."""
    pixels = np.round(np.clip(np.nan_to_num(image), 0.0, 1.0) * 255.0).astype(np.uint8)
    out = oiio.ImageOutput.create(str(path))
    if out is None or not out.open(str(path), oiio.ImageSpec(pixels.shape[1], pixels.shape[0], 3, "uint8")):
        raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
    out.write_image(pixels)
    out.close()


def contact_sheet(scene: str, frame_count: int, resolution: tuple[int, int]) -> Path:
    """Render `scene` and write its contact sheet; returns the PNG's path."""
    shader, session_file = SCENES[scene]
    session = load_session(ROOT / session_file)
    frames = spread_frames(session.frames, frame_count)
    result = render(ROOT / shader, session, frames=frames, resolution=resolution)
    sheet = tile([f.image for f in result.frames], COLUMNS, GAP)
    path = ROOT / "docs" / f"contact_sheet_{scene}.png"
    write_png(path, sheet)
    print(f"{path.relative_to(ROOT)}: frames {frames}, {result.ms_per_frame:.0f} ms/frame "
          f"at {resolution[0]}x{resolution[1]}")
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", metavar="SCENE",
                        help=f"scenes to render: {', '.join(SCENES)} (default: all)")
    parser.add_argument("--frames", type=int, default=6, help="frames per sheet (default 6)")
    parser.add_argument("--resolution", default="320x240", help="frame size WxH (default 320x240)")
    args = parser.parse_args(argv)
    unknown = [s for s in args.scenes if s not in SCENES]
    if unknown:
        parser.error(f"unknown scene(s) {', '.join(unknown)}; choose from {', '.join(SCENES)}")
    w, h = (int(v) for v in args.resolution.lower().split("x"))
    os.environ.setdefault("LP_NUM_THREADS", "1")
    for scene in args.scenes or list(SCENES):
        contact_sheet(scene, args.frames, (w, h))
    return 0


if __name__ == "__main__":
    sys.exit(main())
