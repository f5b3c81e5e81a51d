"""How fast could a refresh rule be at a PSNR level? Oracles over measured runs.

Runs of a node at refresh periods Δn (:func:`rrcache.harness.cached.compare` with exact hit maps,
``rgba32f``) give every hit pixel's squared error against the original. Two oracles use them
with hindsight, refreshing whole ``B×B`` blocks (the runtime refreshes aligned blocks, a GPU
shades 2×2 quads, llvmpipe 4×4 at a time):

- **within one run** (:func:`kept_hit_rate`): refresh the blocks of that run whose hits err most
  per hit pixel and keep the rest, as many as the level affords. Its errors are those of this
  schedule's entries (0 … Δn − 1 frames old); a rule that refreshed other pixels would give them
  other ages, so this is an estimate of what picking the refreshed pixels better could gain at
  that period, not a proof about every rule.
- **a period per block** (:func:`per_block_periods`): each block of the screen keeps, over the
  whole run, one of the measured periods (or Δn = 1: always refreshed, exact), chosen to keep the
  most hits within the level: the best any rule could do that gives calm regions long periods
  and volatile ones short periods, judged by the errors and hit rates each block measured at each
  period (the entries' ages then come with the schedule, unlike the first oracle; a block's
  neighbours run at the same period in each measurement, which a mixed schedule changes only
  through the bilinear taps at its border).

The level is on the squared error pooled over every pixel of the steady frames (35 dB: a mean
squared error of 10^−3.5; pooled PSNR is never above the mean of per-frame PSNRs that validation
reports). A refreshed pixel costs the original's time and a hit the node's all-hit cost ``c``
(:func:`rrcache.harness.limit.all_hit_limit`, a share of the original's time), so a kept hit
rate ``h`` allows at most

    speed-up ≤ 1 / ((1 − h) + h · c)

(the misses' own extra cost, the cache's passes on refreshed pixels, only lowers it: at Δn = 2
on the Trashcan the formula says 1.53× where 1.48× was measured).

Beside the oracles, a cheap **contrast** rule in the first oracle's place: blocks refreshed in
order of the largest spread (max − min over the channels and a 3×3 neighbourhood) of the cached
frame's colour at their hits. A hit test would read the spread from the payload's taps instead
(for a node under the final colour, a value before the rest of the shader): this is a stand-in
that says how much of the oracle's headroom a contrast predictor reaches.

    PYTHONPATH=. python -m rrcache.bench.refresh_bound shaders/trashcan.glsl sessions/trashcan.json \\
        --node n1931 --periods 2,4,8,16,32,50 --frames 40 --level 35

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
from rrcache.harness.metrics import clamped_rgb, squared_error_map

#: the block sizes compared by default: pixels, GPU quads, llvmpipe's 4×4, the runtime's 8×8
BLOCKS = (1, 2, 4, 8)
RULES = ("oracle", "contrast")


@dataclass
class FrameErrors:
    """One steady frame: ``se`` the squared error of each hit pixel (0 elsewhere), ``hits`` the
    hit pixels, ``spread`` the cached colour's 3×3 spread at each hit, ``covered`` the covered
    pixels, ``total_se`` the squared error summed over every pixel (misses too)."""

    se: np.ndarray
    hits: np.ndarray
    spread: np.ndarray
    covered: int
    total_se: float = 0.0


def frame_errors(image: np.ndarray, original: np.ndarray, hit_map: np.ndarray, mask: np.ndarray) -> FrameErrors:
    """The :class:`FrameErrors` of one cached frame against the original (RGB clamped to [0, 1],
    squared error averaged over the channels, as :func:`rrcache.harness.metrics.psnr`).

    >>> img = np.zeros((3, 3, 4), np.float32); ref = img.copy(); img[0, 0, :3] = 0.5
    >>> f = frame_errors(img, ref, np.ones((3, 3), bool), np.ones((3, 3), bool))
    >>> float(f.se[0, 0]), float(f.se[2, 2]), float(f.spread[1, 1]), float(f.spread[2, 2]), f.covered
    (0.25, 0.0, 0.5, 0.0, 9)
    """
    se, a = squared_error_map(image, original), clamped_rgb(image)
    hits = np.asarray(hit_map, bool) & np.asarray(mask, bool)
    p = np.pad(a, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = a.shape[:2]
    around = np.stack([p[y:y + h, x:x + w] for y in range(3) for x in range(3)])
    spread = (around.max(0) - around.min(0)).max(-1)
    return FrameErrors(np.where(hits, se, 0.0), hits, np.where(hits, spread, 0.0),
                       int(np.asarray(mask, bool).sum()), float(se.sum()))


def _blocks(x: np.ndarray, block: int, reduce) -> np.ndarray:
    h, w = x.shape[0] // block * block, x.shape[1] // block * block
    return reduce(x[:h, :w].reshape(h // block, block, w // block, block), axis=(1, 3)).ravel()


def _budget(frames: Sequence[FrameErrors], level_db: float) -> float:
    return sum(f.se.size for f in frames) * 10.0 ** (-level_db / 10.0)


def kept_hit_rate(frames: Sequence[FrameErrors], level_db: float, block: int = 1, rule: str = "oracle") -> float:
    """The share of covered pixels that can hit with the pooled squared error within ``level_db``,
    refreshing whole ``block``×``block`` blocks in the order of ``rule`` (module docstring).
    Rows and columns at the edges that do not fill a block count as refreshed (the kept share
    errs low by at most a block's width).

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
    kept = int(np.searchsorted(np.cumsum(se[order]), _budget(frames, level_db), side="right"))
    return float(n[order][:kept].sum() / covered)


def per_block_periods(runs: dict, level_db: float, block: int = 4) -> tuple[float, dict]:
    """The second oracle (module docstring): ``runs`` maps each measured period to its steady
    frames (the same frames of the same session in every run); each ``block``×``block`` block of
    the screen takes one period for the whole run, or Δn = 1 (refreshed every frame: no hits, no
    error), keeping the most hits with the pooled squared error within ``level_db``. Returns the
    kept share of covered pixels and how many blocks took each period (of those that hit in some
    run). Solved by its Lagrangian
    (each block maximises hits − μ · error; μ the smallest that fits, found by bisection), which
    is optimal among the blocks' choices up to one block's change.

    >>> still = [FrameErrors(np.zeros((2, 2)), np.ones((2, 2), bool), np.zeros((2, 2)), 4)]
    >>> busy = [FrameErrors(np.array([[0.0, 0.0], [0.0, 0.9]]), np.ones((2, 2), bool), np.zeros((2, 2)), 4)]
    >>> per_block_periods({8: still, 50: busy}, 20.0, block=1)   # Δn = 8 errs nowhere: all keep it
    (1.0, {1: 0, 8: 4, 50: 0})
    >>> rate, counts = per_block_periods({8: busy}, 20.0, block=1)
    >>> rate, counts   # the erring pixel is refreshed every frame
    (0.75, {1: 1, 8: 3})
    """
    periods = sorted(runs)
    first = runs[periods[0]]
    covered = sum(f.covered for f in first)
    if not covered:
        return 0.0, {}
    budget = _budget(first, level_db)
    # per block and period: the squared error and the hits over the whole run
    se = np.stack([np.sum([_blocks(f.se, block, np.sum) for f in runs[p]], axis=0) for p in periods])
    n = np.stack([np.sum([_blocks(f.hits.astype(np.float64), block, np.sum) for f in runs[p]], axis=0)
                  for p in periods])
    se = np.vstack([np.zeros((1, se.shape[1])), se])  # Δn = 1: exact, no hits
    n = np.vstack([np.zeros((1, n.shape[1])), n])

    def choose(mu: float) -> np.ndarray:
        # the most hits for the price; ties to the cheaper error, then the shorter period
        score = n - mu * se
        best = score.max(axis=0)
        cheapest = np.where(score >= best - 1e-12 * np.maximum(1.0, np.abs(best)), se, np.inf)
        return cheapest.argmin(axis=0)

    def error(pick: np.ndarray) -> float:
        return float(se[pick, np.arange(se.shape[1])].sum())

    lo, hi = 0.0, 1.0
    if error(choose(lo)) > budget:
        while error(choose(hi)) > budget and hi < 1e30:
            hi *= 4.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if error(choose(mid)) > budget else (lo, mid)
        pick = choose(hi)
    else:
        pick = choose(lo)
    kept = float(n[pick, np.arange(n.shape[1])].sum() / covered)
    some = n.sum(axis=0) > 0  # blocks that never hit (the background) are not counted
    counts = {p: int((pick[some] == i).sum()) for i, p in enumerate([1, *periods])}
    return kept, counts


def speedup_bound(hit_rate: float, hit_cost: float) -> float:
    """1 / ((1 − h) + h · c): every refreshed pixel at the original's cost, every hit at ``c``.

    >>> round(speedup_bound(0.5, 0.3), 3)
    1.538
    """
    return 1.0 / ((1.0 - hit_rate) + hit_rate * hit_cost)


def _psnr(se_sum: float, pixels: int) -> float:
    return 10.0 * math.log10(pixels / se_sum) if se_sum > 0 else math.inf


@dataclass
class Bound:
    """For each period run: its measured figures and each rule's kept hit rate per block size;
    then the per-block-period oracle per block size. Speed-ups use ``hit_cost``."""

    shader: str
    session: str
    node: str
    resolution: list
    frames: int
    level_db: float
    hit_cost: float
    hit_cost_source: str
    runs: list = field(default_factory=list)
    per_block: list = field(default_factory=list)

    def markdown(self) -> str:
        out = [f"`{self.shader}` × `{self.session}`, `{self.node}`, {self.resolution[0]}×{self.resolution[1]}, "
               f"{self.frames} frames; hit cost {self.hit_cost:.3f} of the original ({self.hit_cost_source}); "
               f"each cell: the hit rate kept at {self.level_db:g} dB, and the speed-up it allows", ""]
        blocks = [r["block"] for r in self.runs[0]["rows"] if r["rule"] == "oracle"] if self.runs else []
        out.append("| Δn | measured PSNR dB | pooled | hit rate | "
                   + " | ".join(f"oracle {b}×{b}" for b in blocks) + " | " +
                   " | ".join(f"contrast {b}×{b}" for b in blocks) + " |")
        out.append("|---" * (4 + 2 * len(blocks)) + "|")
        for run in self.runs:
            cells = {(r["block"], r["rule"]): f"{r['hit_rate']:.3f}: {r['speedup_bound']:.2f}×" for r in run["rows"]}
            out.append(f"| {run['period']} | {run['measured_psnr']:.1f} | {run['pooled_psnr']:.1f} | "
                       f"{run['measured_hit_rate']:.3f} | "
                       + " | ".join(cells[(b, "oracle")] for b in blocks) + " | "
                       + " | ".join(cells[(b, "contrast")] for b in blocks) + " |")
        if self.per_block:
            out += ["", "A period per block (of " + ", ".join(str(r["period"]) for r in self.runs) + ", or 1):", "",
                    "| block | hit rate kept | speed-up at most | blocks per period |", "|---|---|---|---|"]
            for r in self.per_block:
                counts = ", ".join(f"Δn={p}: {c}" for p, c in r["counts"].items() if c)
                out.append(f"| {r['block']}×{r['block']} | {r['hit_rate']:.3f} | {r['speedup_bound']:.2f}× | {counts} |")
        return "\n".join(out)


def measure(shader: str, session_path: str, node: str, periods: Sequence[int], frames: int, level_db: float = 35.0,
            resolution=None, blocks: Sequence[int] = BLOCKS, filter: str = "bilinear",
            algorithm: str = "three-pass", hit_cost: Optional[float] = None) -> Bound:
    """One exact run of ``node`` at each of ``periods`` over the first ``frames`` frames, then
    both oracles and the contrast rule for each block size (module docstring). ``hit_cost`` (a
    share of the original's time) is measured with :func:`~rrcache.harness.limit.all_hit_limit`
    in the timing format when not given."""
    from rrcache.harness.cached import compare
    from rrcache.harness.limit import all_hit_limit, probe_frames
    from rrcache.pipeline import load_for_session, variant_for
    from rrcache.session import load_session

    session = load_session(session_path)
    work = load_for_session(shader, session)
    variant = variant_for(work, node, algorithm, filter=filter)
    indices = list(range(min(frames, session.frames)))
    if hit_cost is None:
        limit = all_hit_limit(variant, session, work.prepared, probe_frames(indices), resolution,
                              color_format=DEFAULT_TIMING_FORMAT)
        hit_cost, source = limit.limit_ms / limit.original_median_ms, f"all-hit limit, {DEFAULT_TIMING_FORMAT}"
    else:
        source = "given"
    bound = Bound(shader, session_path, node, [], len(indices), float(level_db), float(hit_cost), source)
    runs = {}
    for period in periods:
        kept: list[FrameErrors] = []

        def on_frame(row, cached, original):
            if row.index != indices[0]:  # the first frame has no cache (Comparison.skip_first)
                kept.append(frame_errors(cached.image, original.image, cached.hit_map, cached.mask))

        run = compare(variant, session, work.prepared, indices, period=int(period), resolution=resolution,
                      hit_maps=True, on_frame=on_frame, color_format=ERROR_FORMAT)
        bound.resolution = list(run.resolution)
        runs[int(period)] = kept
        pixels = sum(f.se.size for f in kept)
        rows = [{"block": int(b), "rule": rule, "hit_rate": h, "speedup_bound": speedup_bound(h, hit_cost)}
                for b in blocks for rule in RULES for h in [kept_hit_rate(kept, level_db, b, rule)]]
        bound.runs.append({"period": int(period), "measured_psnr": float(run.psnr),
                           "pooled_psnr": _psnr(sum(f.total_se for f in kept), pixels),
                           "measured_hit_rate": float(run.hit_rate), "rows": rows})
    if len(runs) > 1:
        for b in blocks:
            h, counts = per_block_periods(runs, level_db, int(b))
            bound.per_block.append({"block": int(b), "hit_rate": h, "speedup_bound": speedup_bound(h, hit_cost),
                                    "counts": {str(p): c for p, c in counts.items()}})
    return bound


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("shader")
    ap.add_argument("session")
    ap.add_argument("--node", required=True)
    ap.add_argument("--periods", required=True, help="refresh periods to run, e.g. 2,4,8,16,32,50")
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--level", type=float, default=35.0, help="the PSNR level in dB (default 35)")
    ap.add_argument("--resolution", default=None, help="WxH (default: the session's)")
    ap.add_argument("--blocks", default=",".join(map(str, BLOCKS)))
    ap.add_argument("--hit-cost", type=float, default=None,
                    help="the node's all-hit cost as a share of the original's time (default: measured)")
    ap.add_argument("--json", action="store_true", help="print JSON instead of Markdown")
    args = ap.parse_args(argv)
    resolution = tuple(int(v) for v in args.resolution.lower().split("x")) if args.resolution else None
    bound = measure(args.shader, args.session, args.node, [int(p) for p in args.periods.split(",") if p.strip()],
                    args.frames, args.level, resolution, [int(b) for b in args.blocks.split(",") if b.strip()],
                    hit_cost=args.hit_cost)
    print(json.dumps(asdict(bound), indent=1) if args.json else bound.markdown())
    return 0


if __name__ == "__main__":
    sys.exit(main())
