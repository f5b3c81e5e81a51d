"""How fast any refresh rule could be at a PSNR level: an oracle over the misses of one run.

One run of a node at refresh period Δn (:func:`rrcache.harness.cached.compare` with exact hit
maps, ``rgba32f``) gives every hit pixel's squared error against the original. An **oracle**
that knew those errors would refresh the hits that err most and keep the rest: refreshing whole
``B×B`` blocks (the runtime refreshes aligned blocks, a GPU shades 2×2 quads, llvmpipe 4×4 at a
time), ranked by squared error per hit pixel, it keeps the largest share of hits whose squared
error, pooled over every pixel of every steady frame, stays within the level (35 dB: a mean
squared error of 10^−3.5; pooled, which is never above the mean of per-frame PSNRs that
validation reports, so the bound is for the stricter measure). A refreshed pixel costs the
original's time and a hit the node's all-hit cost ``c`` (:func:`rrcache.harness.limit.all_hit_limit`,
as a share of the original's time), so no rule refreshing within this run's hits can beat

    speed-up ≤ 1 / ((1 − h) + h · c),       h = the hit rate the oracle keeps

(the misses' own extra cost, the cache's passes on refreshed pixels, only lowers it: at Δn = 2
on the Trashcan the formula says 1.53× where 1.48× was measured). An entry that is kept longer
than Δn errs more than any hit of this run, so the bound holds for rules whose entries are at
most Δn frames old.

Beside the oracle, a cheap **contrast** rule, the one a hit test could compute from what it
reads anyway: each hit ranked by the spread (max − min over the channels' 2×2 neighbourhood) of
the reconstructed value, blocks by their largest spread. It says how much of the oracle's
headroom a real predictor of the resampling error reaches.

    PYTHONPATH=. python -m rrcache.bench.refresh_bound shaders/trashcan.glsl sessions/trashcan.json \\
        --node n1931 --period 16 --frames 40 --level 35

docs/refresh_bound.md has the Trashcan's figures and what they decide.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import asdict, dataclass, field
from typing import Optional, Sequence

import numpy as np

from rrcache.gl.formats import DEFAULT_TIMING_FORMAT, ERROR_FORMAT

#: the block sizes compared by default: pixels, GPU quads, llvmpipe's 4×4, the runtime's 8×8
BLOCKS = (1, 2, 4, 8)
RULES = ("oracle", "contrast")


@dataclass
class FrameErrors:
    """One steady frame: ``se`` the squared error of each hit pixel (0 elsewhere), ``hits`` the
    hit pixels, ``spread`` the reconstructed value's 2×2 spread, ``covered`` the covered pixels."""

    se: np.ndarray
    hits: np.ndarray
    spread: np.ndarray
    covered: int


def frame_errors(image: np.ndarray, original: np.ndarray, hit_map: np.ndarray, mask: np.ndarray) -> FrameErrors:
    """The :class:`FrameErrors` of one cached frame against the original (RGB clamped to [0, 1],
    squared error averaged over the channels, as :func:`rrcache.harness.metrics.psnr`).

    >>> img = np.zeros((2, 2, 4), np.float32); ref = img.copy(); img[0, 0, :3] = 0.5
    >>> f = frame_errors(img, ref, np.ones((2, 2), bool), np.ones((2, 2), bool))
    >>> float(f.se[0, 0]), float(f.se[1, 1]), float(f.spread[0, 0]), float(f.spread[1, 1]), f.covered
    (0.25, 0.0, 0.5, 0.0, 4)
    """
    a = np.clip(np.nan_to_num(image[..., :3], nan=0.0), 0.0, 1.0)
    b = np.clip(np.nan_to_num(original[..., :3], nan=0.0), 0.0, 1.0)
    hits = np.asarray(hit_map, bool) & np.asarray(mask, bool)
    se = np.where(hits, ((a - b) ** 2).mean(axis=2), 0.0)
    p = np.pad(a, ((0, 1), (0, 1), (0, 0)), mode="edge")
    quad = np.stack([p[:-1, :-1], p[1:, :-1], p[:-1, 1:], p[1:, 1:]])
    spread = np.where(hits, (quad.max(0) - quad.min(0)).max(-1), 0.0)
    return FrameErrors(se, hits, spread, int(np.asarray(mask, bool).sum()))


def _blocks(x: np.ndarray, block: int, reduce) -> np.ndarray:
    h, w = x.shape[0] // block * block, x.shape[1] // block * block
    return reduce(x[:h, :w].reshape(h // block, block, w // block, block), axis=(1, 3)).ravel()


def kept_hit_rate(frames: Sequence[FrameErrors], level_db: float, block: int = 1, rule: str = "oracle") -> float:
    """The share of covered pixels that can hit with the pooled squared error within ``level_db``,
    refreshing whole ``block``×``block`` blocks in the order of ``rule`` (module docstring).
    Edge rows and columns that do not fill a block are left out of the hits (never refreshed
    into them: a bound that errs low by at most a block's width).

    >>> z = np.zeros((2, 2))
    >>> f = FrameErrors(np.array([[0.0, 0.0], [0.0, 0.4]]), np.ones((2, 2), bool), z, 4)
    >>> kept_hit_rate([f], 10.0)   # 10 dB: a pooled squared error of 0.1 over 4 pixels: 0.4 fits
    1.0
    >>> kept_hit_rate([f], 11.0)   # it no longer does: the erring pixel is refreshed
    0.75
    >>> kept_hit_rate([f], 11.0, block=2)
    0.0
    """
    if rule not in RULES:
        raise ValueError(f"rule must be one of {RULES}, not {rule!r}")
    pixels = sum(f.se.size for f in frames)
    covered = sum(f.covered for f in frames)
    if not covered:
        return 0.0
    se = np.concatenate([_blocks(f.se, block, np.sum) for f in frames])
    n = np.concatenate([_blocks(f.hits.astype(np.float64), block, np.sum) for f in frames])
    spread = np.concatenate([_blocks(f.spread, block, np.max) for f in frames])
    some = n > 0
    se, n, spread = se[some], n[some], spread[some]
    key = se / n if rule == "oracle" else spread
    order = np.argsort(key, kind="stable")
    pooled = np.cumsum(se[order])
    kept = int(np.searchsorted(pooled, pixels * 10.0 ** (-level_db / 10.0), side="right"))
    return float(n[order][:kept].sum() / covered)


def speedup_bound(hit_rate: float, hit_cost: float) -> float:
    """1 / ((1 − h) + h · c): every refreshed pixel at the original's cost, every hit at ``c``.

    >>> round(speedup_bound(0.5, 0.3), 3)
    1.538
    """
    return 1.0 / ((1.0 - hit_rate) + hit_rate * hit_cost)


@dataclass
class Bound:
    """The oracle's and the contrast rule's kept hit rate and speed-up bound for each block size."""

    shader: str
    session: str
    node: str
    resolution: list
    frames: int
    period: int
    level_db: float
    measured_psnr: float
    pooled_psnr: float
    measured_hit_rate: float
    hit_cost: float
    hit_cost_source: str
    rows: list = field(default_factory=list)

    def markdown(self) -> str:
        out = [f"`{self.shader}` × `{self.session}`, `{self.node}` at Δn={self.period}, "
               f"{self.resolution[0]}×{self.resolution[1]}, {self.frames} frames: measured "
               f"{self.measured_psnr:.2f} dB (pooled {self.pooled_psnr:.2f}), hit rate {self.measured_hit_rate:.3f}; "
               f"hit cost {self.hit_cost:.3f} of the original ({self.hit_cost_source})", "",
               f"| refreshed in | rule | hit rate kept at {self.level_db:g} dB | speed-up at most |",
               "|---|---|---|---|"]
        for r in self.rows:
            out.append(f"| {r['block']}×{r['block']} | {r['rule']} | {r['hit_rate']:.3f} | {r['speedup_bound']:.2f}× |")
        return "\n".join(out)


def measure(shader: str, session_path: str, node: str, period: int, frames: int, level_db: float = 35.0,
            resolution=None, blocks: Sequence[int] = BLOCKS, filter: str = "bilinear",
            algorithm: str = "three-pass", hit_cost: Optional[float] = None) -> Bound:
    """One exact run of ``node`` at ``period`` over the first ``frames`` frames, then the bound
    for each block size and rule (module docstring). ``hit_cost`` (a share of the original's time)
    is measured with :func:`~rrcache.harness.limit.all_hit_limit` in the timing format when not
    given."""
    from rrcache.harness.cached import compare
    from rrcache.harness.limit import all_hit_limit, probe_frames
    from rrcache.pipeline import load_for_session, variant_for
    from rrcache.session import load_session

    session = load_session(session_path)
    work = load_for_session(shader, session)
    variant = variant_for(work, node, algorithm, filter=filter)
    indices = list(range(min(frames, session.frames)))
    kept: list[FrameErrors] = []

    def on_frame(row, cached, original):
        if row.index != indices[0]:  # the first frame has no cache (Comparison.skip_first)
            kept.append(frame_errors(cached.image, original.image, cached.hit_map, cached.mask))

    run = compare(variant, session, work.prepared, indices, period=period, resolution=resolution, hit_maps=True,
                  on_frame=on_frame, color_format=ERROR_FORMAT)
    if hit_cost is None:
        limit = all_hit_limit(variant, session, work.prepared, probe_frames(indices), resolution, period=period,
                              color_format=DEFAULT_TIMING_FORMAT)
        hit_cost, source = limit.limit_ms / limit.original_median_ms, f"all-hit limit, {DEFAULT_TIMING_FORMAT}"
    else:
        source = "given"
    pixels = sum(f.se.size for f in kept)
    pooled = sum(float(f.se.sum()) for f in kept) / pixels if pixels else 0.0
    bound = Bound(shader, session_path, node, list(run.resolution), len(indices), int(period), float(level_db),
                  float(run.psnr), 10.0 * math.log10(1.0 / pooled) if pooled > 0 else math.inf,
                  float(run.hit_rate), float(hit_cost), source)
    for block in blocks:
        for rule in RULES:
            h = kept_hit_rate(kept, level_db, block, rule)
            bound.rows.append({"block": int(block), "rule": rule, "hit_rate": h,
                               "speedup_bound": speedup_bound(h, hit_cost)})
    return bound


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("shader")
    ap.add_argument("session")
    ap.add_argument("--node", required=True)
    ap.add_argument("--period", type=int, required=True)
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--level", type=float, default=35.0, help="the PSNR level in dB (default 35)")
    ap.add_argument("--resolution", default=None, help="WxH (default: the session's)")
    ap.add_argument("--blocks", default=",".join(map(str, BLOCKS)))
    ap.add_argument("--hit-cost", type=float, default=None,
                    help="the node's all-hit cost as a share of the original's time (default: measured)")
    ap.add_argument("--json", action="store_true", help="print JSON instead of Markdown")
    args = ap.parse_args(argv)
    resolution = tuple(int(v) for v in args.resolution.lower().split("x")) if args.resolution else None
    bound = measure(args.shader, args.session, args.node, args.period, args.frames, args.level, resolution,
                    [int(b) for b in args.blocks.split(",") if b.strip()], hit_cost=args.hit_cost)
    print(json.dumps(asdict(bound), indent=1) if args.json else bound.markdown())
    return 0


if __name__ == "__main__":
    sys.exit(main())
