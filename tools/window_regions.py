"""Does an error window err like the frame? One node's error run in each window (the window's own
run) beside that window's region of one whole-frame run (docs/levels.md, "The window check").

    python tools/window_regions.py shaders/trashcan.glsl sessions/trashcan.json n2085 2 \\
        --algorithm two-pass --window 8,0,320,240 --window 160,120,320,240

Prints, per window and for the whole frame, the mean error over covered pixels of the steady
frames: run in the window, and inside the whole-frame run.
"""
from __future__ import annotations

import argparse

import numpy as np


def main(argv=None) -> int:
    from rrcache.gl.formats import ERROR_FORMAT
    from rrcache.harness.execute import execute
    from rrcache.harness.metrics import mean_l2
    from rrcache.harness.segments import restart
    from rrcache.pipeline import WorkSource, load_bench
    from rrcache.runs import RunSpec
    from rrcache.runtime.spec import VariantSpec

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("shader"), ap.add_argument("session"), ap.add_argument("node"), ap.add_argument("period", type=int)
    ap.add_argument("--algorithm", default="two-pass"), ap.add_argument("--filter", default="bilinear")
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--window", action="append", default=[], help="x,y,w,h in pixels, origin bottom left")
    args = ap.parse_args(argv)
    bench = load_bench(WorkSource(args.shader, args.session))
    size = tuple(int(v) for v in bench.session.resolution)
    frames = tuple(range(min(args.frames, int(bench.session.frames))))
    spec = VariantSpec("cache", (args.node,), args.algorithm, args.filter, periods=(args.period,))
    windows = [tuple(int(v) for v in w.split(",")) for w in args.window] + [(0, 0) + size]
    own = {}
    for win in windows[:-1]:
        r = execute(RunSpec("error", spec, frames, size, win, ERROR_FORMAT), bench)
        own[win] = float(np.mean([f.error for f in r.steady]))
    whole = RunSpec("error", spec, frames, size, None, ERROR_FORMAT)
    refs = bench.references(whole)
    cached, _ = bench.cached(whole)
    restart(cached, frames[0])
    inside = {w: [] for w in windows}
    height = size[1]
    for index, ref in zip(frames, refs):
        got = cached.render_frame(index)
        if index == frames[0]:
            continue  # the first frame has no cache (the steady frames follow it)
        for (x, y, w, h) in windows:
            rows, cols = slice(height - y - h, height - y), slice(x, x + w)
            err, _ = mean_l2(got.image[rows, cols], ref.image[rows, cols], ref.mask[rows, cols])
            if np.isfinite(err):
                inside[(x, y, w, h)].append(float(err))
    bench.close()
    print(f"{args.node} at Δn={args.period}, {len(frames)} frames at {size[0]}×{size[1]}")
    print("| region | error run in the window | that region of a whole-frame run |\n|---|---|---|")
    for win in windows:
        mine = own.get(win, float(np.mean(inside[win])))
        print(f"| {win} | {mine:.5f} | {float(np.mean(inside[win])):.5f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
