"""Adaptive against fixed refresh at equal time, side by side with the original.

For one node of a scene, :func:`measure` renders each configuration beside the original
(:func:`rrcache.harness.cached.compare`, alternating frame by frame): fixed periods Δn, and
adaptive configurations (max age Δn, threshold, fast period; :mod:`rrcache.runtime.adaptive`).
Per configuration: the error and PSNR over ``frames`` drawn exactly (``rgba32f``), and the time
ratio (the variant's median frame time over the original's, in ``rgba8`` as applications draw)
over ``timed`` frames, ``repeats`` times (the median ratio stands, the range is kept).

:func:`equal_time` puts an adaptive point against the fixed ones at the same time: the fixed
points' error is interpolated (linearly in log error against the time ratio, between the two
fixed points whose times bracket it); outside their range there is no equal-time figure.

    PYTHONPATH=. LP_NUM_THREADS=1 python -m rrcache.bench.adaptive shaders/marble.glsl sessions/marble.json \\
        --node n2392 --periods 8,16,32,50 --adaptive 100:0.01:8,100:0.02:8 --frames 40 --timed 24 --repeats 3
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
from dataclasses import asdict, dataclass, field
from typing import Optional, Sequence

from rrcache import atomic
from rrcache.gl.formats import ERROR_FORMAT


@dataclass
class Point:
    """One configuration measured beside the original."""

    label: str
    period: int
    threshold: Optional[float]
    fast_period: Optional[int]
    error: float
    psnr: float
    time_ratio: float
    hit_rate: float
    ratios: list = field(default_factory=list)

    @property
    def speedup(self) -> float:
        return 1.0 / self.time_ratio


def _measure_one(variant, session, work, frames, timed, repeats, resolution, period, kw, label, threshold=None,
                 fast=None):
    from rrcache.harness.cached import compare

    exact = compare(variant, session, work.prepared, frames, period=period, resolution=resolution,
                    color_format=ERROR_FORMAT, **kw)
    ratios = []
    for _ in range(repeats):
        run = compare(variant, session, work.prepared, timed, period=period, resolution=resolution,
                      color_format="rgba8", **kw)
        ratios.append(run.ms_per_frame / run.original_ms_per_frame)
    return Point(label, int(period), threshold, fast, float(exact.mean_error), float(min(exact.psnr, 100.0)),
                 float(statistics.median(ratios)), float(exact.hit_rate), ratios)


def measure(shader: str, session_path: str, node: str, periods: Sequence[int], adaptive: Sequence[tuple],
            frames: int, timed: int, repeats: int = 1, resolution=None, algorithm: str = "three-pass",
            filter: str = "bilinear", progress=None) -> dict:
    """Fixed ``periods`` and ``adaptive`` configurations ``(max age, threshold, fast period)`` of
    ``node``, each measured beside the original (see the module docstring)."""
    from rrcache.pipeline import load_for_session, variant_for
    from rrcache.session import load_session

    session = load_session(session_path)
    work = load_for_session(shader, session)
    frame_range = list(range(min(frames, session.frames)))
    timed_range = frame_range[:max(2, min(timed, len(frame_range)))]
    fixed_variant = variant_for(work, node, algorithm, filter=filter)
    fixed = []
    for p in periods:
        fixed.append(_measure_one(fixed_variant, session, work, frame_range, timed_range, repeats, resolution, p,
                                  {}, f"Δn={p}"))
        if progress:
            progress(fixed[-1])
    adaptive_variant = variant_for(work, node, algorithm, filter=filter, adaptive=True) if adaptive else None
    points = []
    for period, threshold, fast in adaptive:
        kw = {"threshold": float(threshold), "fast_period": int(fast)}
        points.append(_measure_one(adaptive_variant, session, work, frame_range, timed_range, repeats, resolution,
                                   int(period), kw, f"adaptive ≥{threshold:g} Δf={fast} Δn={period}",
                                   float(threshold), int(fast)))
        if progress:
            progress(points[-1])
    return {"shader": shader, "session": session_path, "node": node, "algorithm": algorithm, "filter": filter,
            "frames": len(frame_range), "timed_frames": len(timed_range), "repeats": repeats,
            "resolution": list(resolution) if resolution else list(session.resolution),
            "fixed": [dict(asdict(p), speedup=p.speedup) for p in fixed],
            "adaptive": [dict(asdict(p), speedup=p.speedup, equal_time=equal_time(fixed, p)) for p in points]}


def equal_time(fixed: Sequence[Point], point: Point) -> Optional[dict]:
    """The fixed refresh's error and PSNR interpolated at ``point``'s time ratio (None outside the
    fixed points' range of times).

    >>> f = [Point("a", 8, None, None, 0.004, 44.0, 0.5, 0.8), Point("b", 32, None, None, 0.016, 38.0, 0.3, 0.9)]
    >>> r = equal_time(f, Point("x", 50, 0.01, 8, 0.005, 43.0, 0.4, 0.9))
    >>> round(r["error"], 4), round(r["psnr"], 1)
    (0.008, 41.0)
    """
    pts = sorted(fixed, key=lambda p: p.time_ratio)
    for lo, hi in zip(pts, pts[1:]):
        if lo.time_ratio <= point.time_ratio <= hi.time_ratio:
            span = hi.time_ratio - lo.time_ratio
            t = 0.0 if span == 0 else (point.time_ratio - lo.time_ratio) / span
            if lo.error > 0 and hi.error > 0:
                error = math.exp(math.log(lo.error) + t * (math.log(hi.error) - math.log(lo.error)))
            else:
                error = lo.error + t * (hi.error - lo.error)
            return {"error": error, "psnr": lo.psnr + t * (hi.psnr - lo.psnr), "between": [lo.label, hi.label]}
    return None


def _adaptive_items(text: str) -> list[tuple]:
    out = []
    for item in text.split(","):
        if item.strip():
            period, threshold, fast = item.split(":")
            out.append((int(period), float(threshold), int(fast)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("shader")
    ap.add_argument("session")
    ap.add_argument("--node", required=True)
    ap.add_argument("--periods", default="8,16,32,50")
    ap.add_argument("--adaptive", default="", help="MAXAGE:THRESHOLD:FAST,...")
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--timed", type=int, default=24)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--resolution", default=None)
    ap.add_argument("--algorithm", default="three-pass")
    ap.add_argument("--filter", default="bilinear")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    resolution = tuple(int(v) for v in args.resolution.split("x")) if args.resolution else None
    result = measure(args.shader, args.session, args.node, [int(p) for p in args.periods.split(",") if p],
                     _adaptive_items(args.adaptive), args.frames, args.timed, args.repeats, resolution,
                     args.algorithm, args.filter,
                     progress=lambda p: print(f"{p.label}: error {p.error:.5f}, {p.psnr:.1f} dB, "
                                              f"{p.speedup:.2f}x, hit rate {p.hit_rate:.3f}", file=sys.stderr,
                                              flush=True))
    text = json.dumps(result, indent=1)
    if args.out:
        atomic.write_text(args.out, text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
