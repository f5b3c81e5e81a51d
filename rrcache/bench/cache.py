"""The cache benchmark (`rrcache bench-cache`): one node of one scene, side by side with the
original in one run (issue 4; Sitthi-amorn 2008a Figs. 8–9).

- the node cached at several refresh periods (three-pass, k = 4): speed-up, hit rate, mean error,
  PSNR;
- the three algorithms at one period;
- refresh block sizes k = 1, 2, 4 at that period;
- the limit: the cached pipeline's frame time when every pixel hits (the frame shown again with
  nothing moving and no refresh), as a fraction of the original's, and the speed-up that bounds;
  measured like the rows, alternating with the original frame by frame;
- the node at the compared period with refresh off: what disocclusions alone cost;
- the hit test and reconstruction filters (``bilinear``, ``edge``, ``plane``) at the compared period, timed, and for
  each the misses sorted by cause (:mod:`rrcache.runtime.misses`: refresh, the depth-edge band,
  disocclusion, off screen), as shares of the covered pixels and of the covered 4×4 blocks (on
  llvmpipe a miss costs its whole block), measured in an untimed run that reads the hit maps.

Every speed-up is a ratio of median frame times measured in the same run, the original and the
variant rendered alternately frame by frame (:func:`rrcache.harness.cached.compare`). Each
configuration is measured ``repeats`` times, the repeats going round all configurations so that
the machine's drift spreads over them; a row shows the median run and the range of the
repeats' speed-ups. (Rendering every configuration in one interleaved loop was tried: the
working sets of ten renderers thrashed the CPU caches and made the original 25% slower than it
runs alone, so it measured a different machine.) The three tables share a configuration (Δn =
16, three-pass, k = 4), measured as three rows: their spread is the run's noise too.
"""
from __future__ import annotations

import statistics
from dataclasses import asdict, dataclass, field
from typing import Callable, Optional

from rrcache.gl.formats import DEFAULT_TIMING_FORMAT
from rrcache.harness.cached import compare
from rrcache.harness.limit import all_hit_limit, probe_frames
from rrcache.pipeline import load_for_session, variant_for
from rrcache.runtime.cache import DEFAULT_FILTER
from rrcache.session import load_session


def _range(row: "BenchRow") -> str:
    lo, hi = row.speedup_range
    return "n/a" if lo != lo else f"{lo:.2f}–{hi:.2f}"


#: a refresh period longer than any session: no pixel is refreshed, only disocclusions miss
NO_REFRESH = 2 ** 30


@dataclass
class BenchRow:
    label: str
    algorithm: str
    period: int
    block: int
    speedup: float
    hit_rate: float
    mean_error: float
    psnr: float
    ms_per_frame: float
    original_ms_per_frame: float
    #: the lowest and highest speed-up of the repeats (the row is the median repeat)
    speedup_range: tuple[float, float] = (float("nan"), float("nan"))
    #: the payload's reconstruction filter and hit test (rrcache.runtime.glsl.FILTERS)
    filter: str = DEFAULT_FILTER


@dataclass
class MissRow:
    """Why one filter's cache missed, over the run's steady frames
    (:func:`rrcache.runtime.misses.summarise`, added up): ``pixels`` and ``blocks`` per cause
    (:data:`rrcache.runtime.misses.MISS_CAUSES`), against ``covered`` pixels and
    ``covered_blocks`` 4×4 blocks; the error of the same run."""

    filter: str
    period: int
    covered: int
    covered_blocks: int
    pixels: dict
    blocks: dict
    hit_rate: float
    mean_error: float
    psnr: float

    def pixel_share(self, cause: Optional[str] = None) -> float:
        n = sum(self.pixels.values()) if cause is None else self.pixels[cause]
        return n / self.covered if self.covered else float("nan")

    def block_share(self, cause: Optional[str] = None) -> float:
        n = sum(self.blocks.values()) if cause is None else self.blocks[cause]
        return n / self.covered_blocks if self.covered_blocks else float("nan")


def miss_row(filter_: str, period: int, comparison) -> MissRow:
    """The :class:`MissRow` of a comparison measured with ``miss_causes=True``."""
    total = comparison.miss_causes
    return MissRow(filter_, int(period), total["covered"], total["covered_blocks"], total["pixels"], total["blocks"],
                   comparison.hit_rate, comparison.mean_error, comparison.psnr)


def miss_table(rows: list) -> list[str]:
    """The Markdown lines of a miss breakdown (one row per :class:`MissRow`)."""
    from rrcache.runtime.misses import MISS_CAUSES

    causes = [c for c in MISS_CAUSES if any(r.pixels[c] for r in rows)] or ["refresh"]
    lines = ["| filter | Δn | hit rate | missing pixels | " + " | ".join(causes) + " | 4×4 blocks holding a miss | "
             + " | ".join(causes) + " | mean error | PSNR dB |",
             "|---|---|---|---|" + "---|" * len(causes) + "---|" + "---|" * len(causes) + "---|---|"]
    for r in rows:
        lines.append(f"| {r.filter} | {r.period} | {r.hit_rate:.3f} | {100 * r.pixel_share():.2f}% | "
                     + " | ".join(f"{100 * r.pixel_share(c):.2f}%" for c in causes)
                     + f" | {100 * r.block_share():.2f}% | " + " | ".join(f"{100 * r.block_share(c):.2f}%" for c in causes)
                     + f" | {r.mean_error:.4f} | {r.psnr:.1f} |")
    return lines


@dataclass
class CacheBench:
    shader: str
    session: str
    node: str
    node_text: str
    resolution: tuple[int, int]
    frames: int
    compare_period: int = 16
    periods: list[BenchRow] = field(default_factory=list)
    algorithms: list[BenchRow] = field(default_factory=list)
    blocks: list[BenchRow] = field(default_factory=list)
    limit_ms: float = float("nan")
    limit_original_ms: float = float("nan")
    #: the node at the compared period with refresh turned off: only disocclusions miss (the
    #: gap between this row and the limit is what disocclusions cost, the rest is the refresh)
    no_refresh: Optional[BenchRow] = None
    #: the colour target every render drew into
    color_format: str = DEFAULT_TIMING_FORMAT
    #: the filters at the compared period (three-pass, k = 4), timed
    filters: list[BenchRow] = field(default_factory=list)
    #: per filter, the misses sorted by cause (an untimed run reading the hit maps)
    misses: list[MissRow] = field(default_factory=list)

    @property
    def limit_fraction(self) -> float:
        """The all-hit cached frame time as a fraction of the original's."""
        return self.limit_ms / self.limit_original_ms

    @property
    def limit_speedup(self) -> float:
        return self.limit_original_ms / self.limit_ms

    def to_json(self) -> dict:
        doc = asdict(self)
        doc["limit_fraction"] = self.limit_fraction
        doc["limit_speedup"] = self.limit_speedup
        return doc

    def markdown(self) -> str:
        """The tables as Markdown (for the README)."""
        lines = [f"`{self.shader}` × `{self.session}`, caching `{self.node}` (`{self.node_text}`), "
                 f"{self.resolution[0]}×{self.resolution[1]}, {self.frames} frames, {self.color_format} colour target", ""]
        header = "| | algorithm | Δn | k | speed-up (repeats) | hit rate | mean error | PSNR dB | ms | original ms |"
        rule = "|---|---|---|---|---|---|---|---|---|---|"
        for title, rows in (("refresh period", self.periods), ("algorithm", self.algorithms),
                            ("refresh block", self.blocks), ("filter (hit test and reconstruction)", self.filters)):
            if not rows:
                continue
            lines += [f"**{title}**", "", header, rule]
            for r in rows:
                lines.append(f"| {r.label} | {r.algorithm} | {r.period} | {r.block} | {r.speedup:.2f}× ({_range(r)}) | "
                             f"{'n/a' if r.hit_rate != r.hit_rate else format(r.hit_rate, '.3f')} | {r.mean_error:.4f} | {r.psnr:.1f} | {r.ms_per_frame:.1f} | "
                             f"{r.original_ms_per_frame:.1f} |")
            lines.append("")
        lines.append(f"Limit (every pixel hits): {self.limit_ms:.1f} ms against {self.limit_original_ms:.1f} ms, "
                     f"{100 * self.limit_fraction:.0f}% of the original: at most {self.limit_speedup:.2f}×.")
        same = [r.speedup for r in self.periods + self.algorithms + self.blocks + self.filters
                if (r.algorithm, r.period, r.block) == ("three-pass", self.compare_period, 4)
                and r.filter == (self.periods[0].filter if self.periods else DEFAULT_FILTER)]
        if self.no_refresh is not None and same:
            r, achieved = self.no_refresh, statistics.median(same)
            lines += ["", f"Where the time between the limit and Δn={self.compare_period} goes (three-pass, k=4): "
                      f"with refresh off only disocclusions miss (hit rate {r.hit_rate:.3f}): {r.speedup:.2f}×, "
                      f"{100 * r.speedup / self.limit_speedup:.0f}% of the limit; with refresh every "
                      f"Δn={self.compare_period} frames: {achieved:.2f}× (the median of the {len(same)} rows of "
                      f"that configuration), {100 * achieved / self.limit_speedup:.0f}% of the limit."]
        if self.misses:
            lines += ["", f"**Why pixels miss** (three-pass, k=4, frames after the first; an untimed run reading the hit "
                      "maps; a block is counted under the cause of most of its missing pixels, refresh only when all "
                      "are refreshes)", ""] + miss_table(self.misses)
        return "\n".join(lines)


def run(shader_path: str, session_path: str, node_id: str, periods=(8, 16, 32), compare_period: int = 16,
        frames: int = 60, start: int = 0, resolution: Optional[tuple[int, int]] = None,
        progress: Optional[Callable[[str, int, int], None]] = None, blocks=(1, 2, 4), repeats: int = 3,
        limit_algorithm: str = "three-pass", color_format: str = DEFAULT_TIMING_FORMAT, vertex: Optional[str] = None,
        include_dirs=(), filters=(), misses: bool = False, limit_filter: str = DEFAULT_FILTER,
        algorithms=("three-pass", "two-pass", "one-pass"), base_filter: str = DEFAULT_FILTER,
        term_scores=None) -> CacheBench:
    """Run the benchmark; ``frames`` consecutive frames from ``start`` per configuration
    (``periods=()`` or ``blocks=()`` leave those rows out); the limit is that of
    ``limit_algorithm`` and ``limit_filter``; every render draws into a ``color_format`` colour
    target (the errors are then those of that format). ``base_filter``: the filter of every row
    but the filters' own (a profile's); ``term_scores``: a profile's measured order of sums (its node
    ids refer to it). ``algorithms``: those compared at the
    compared period (the ones the node allows). ``filters``: the filters timed at the
    compared period; ``misses``: each of them (bilinear when none) measured again with the misses
    sorted by cause. ``progress(message, done, total)`` after each step. ``vertex``: the user's
    vertex shader (None: the session's, else generated)."""
    step = {"done": 0}
    session = load_session(session_path)
    work = load_for_session(shader_path, session, include_dirs=include_dirs, vertex=vertex, term_scores=term_scores)
    entry = work.node(node_id)
    indices = range(start, min(start + frames, session.frames))
    size = resolution or session.resolution
    bench = CacheBench(shader_path, session_path, node_id, entry.text, tuple(size), len(indices),
                       compare_period=compare_period, color_format=color_format)

    plan = [("periods", f"Δn={period}", "three-pass", period, 4, period, base_filter) for period in periods]
    # only the algorithms the node table allows for this node (one-pass cannot cache a value
    # that needs screen-space derivatives)
    plan += [("algorithms", algorithm, algorithm, compare_period, 4, compare_period, base_filter)
             for algorithm in algorithms
             if algorithm in getattr(entry, "algorithms", ("three-pass", "two-pass", "one-pass"))]
    plan += [("blocks", f"k={block}", "three-pass", compare_period, block, compare_period, base_filter)
             for block in blocks]
    if periods:
        plan.append(("no_refresh", "no refresh", "three-pass", compare_period, 4, NO_REFRESH, base_filter))
    plan += [("filters", filter_, "three-pass", compare_period, 4, compare_period, filter_) for filter_ in filters]
    variants = {}
    for _group, _label, algorithm, period, _block, _run, filter_ in plan:
        if (algorithm, filter_) not in variants:
            variants[(algorithm, filter_)] = variant_for(work, node_id, algorithm, filter=filter_)
    miss_filters = list(filters or (base_filter,)) if misses else []
    total = len(plan) * repeats + len(miss_filters) + 1

    def say(message):  # after each step: the reporter counts finished work
        step["done"] += 1
        if progress is not None:
            progress(message, step["done"], total)

    runs: list[list] = [[] for _ in plan]
    for repeat in range(repeats):
        for i, (_group, label, algorithm, period, block, run_period, filter_) in enumerate(plan):
            runs[i].append(compare(variants[(algorithm, filter_)], session, work.prepared, indices, period=run_period,
                                   resolution=resolution, block=block, color_format=color_format))
            say(f"[{repeat + 1}/{repeats}] {label}: {algorithm}, Δn={period}, k={block}, {filter_}")
    for (group, label, algorithm, period, block, _run, filter_), repeated in zip(plan, runs):
        speedups = sorted(c.speedup for c in repeated)
        c = sorted(repeated, key=lambda c: c.speedup)[len(repeated) // 2]  # the median run
        row = BenchRow(label, algorithm, period, block, c.speedup, c.hit_rate, c.mean_error, c.psnr,
                       c.ms_per_frame, c.original_ms_per_frame, (speedups[0], speedups[-1]), filter_)
        if group == "no_refresh":
            bench.no_refresh = row
        else:
            getattr(bench, group).append(row)
    bench.misses = [miss_breakdown(work, session, node_id, indices, compare_period, filter_, resolution,
                                   color_format, say) for filter_ in miss_filters]

    variant = variant_for(work, node_id, limit_algorithm, filter=limit_filter)
    limit = all_hit_limit(variant, session, work.prepared, probe_frames(indices), resolution, period=compare_period,
                          color_format=color_format)
    bench.limit_ms = limit.limit_ms
    bench.limit_original_ms = limit.original_median_ms
    say("limit: every pixel hits")
    return bench


def miss_breakdown(work, session, node_id: str, frames, period: int, filter_: str = DEFAULT_FILTER,
                   resolution=None, color_format: str = DEFAULT_TIMING_FORMAT, say=None, algorithm: str = "three-pass",
                   **options) -> MissRow:
    """One untimed run of ``node_id`` at ``period`` with ``filter_`` beside the original, its
    misses sorted by cause (:class:`MissRow`)."""
    variant = variant_for(work, node_id, algorithm, filter=filter_)
    c = compare(variant, session, work.prepared, frames, period=period, resolution=resolution,
                color_format=color_format, miss_causes=True, **options)
    if say is not None:
        say(f"misses by cause: {filter_}, Δn={period}")
    return miss_row(filter_, period, c)


@dataclass
class BreakdownRow:
    """One configuration's all-hit frame, stage by stage (:func:`rrcache.harness.limit.all_hit_breakdown`)."""

    algorithm: str
    color_format: str
    cached: dict
    original: dict
    payload: str = "f4"

    @property
    def speedup(self) -> float:
        return self.original["plain_ms"] / self.cached["plain_ms"] if self.cached["plain_ms"] else float("nan")


@dataclass
class Breakdown:
    """The all-hit cost per stage of each (algorithm, colour format), measured side by side with
    the original, ``repeats`` times (each row the median repeat by speed-up; ``ranges`` the
    repeats' speed-ups)."""

    shader: str
    session: str
    node: str
    resolution: tuple[int, int]
    frames: list[int]
    rows: list[BreakdownRow] = field(default_factory=list)
    ranges: list = field(default_factory=list)

    def to_json(self) -> dict:
        return asdict(self)

    def markdown(self) -> str:
        lines = [f"All-hit frame of `{self.shader}` caching `{self.node}`, {self.resolution[0]}×{self.resolution[1]}, "
                 f"frames {self.frames}; each stage waited for (ctx.finish) before the next; fixed = the same stage "
                 f"at 8×8 (geometry, state changes); per pixel = (ms − fixed) / covered pixels.", ""]
        lines += ["| algorithm | colour | payload | stage | ms | fixed ms | ns per covered pixel |",
                  "|---|---|---|---|---|---|---|"]
        for row in self.rows:
            for who, data in (("cached", row.cached), ("original", row.original)):
                for stage, ms in data["full_ms"].items():
                    lines.append(f"| {row.algorithm} | {row.color_format} | {row.payload} | {who}: {stage} | {ms:.2f} | "
                                 f"{data['fixed_ms'].get(stage, float('nan')):.2f} | {data['per_pixel_ns'][stage]:.1f} |")
        lines += ["", "| algorithm | colour | payload | all-hit ms (no waits) | original ms | limit speed-up (repeats) "
                  "| covered pixels |", "|---|---|---|---|---|---|---|"]
        for row, (lo, hi) in zip(self.rows, self.ranges):
            lines.append(f"| {row.algorithm} | {row.color_format} | {row.payload} | {row.cached['plain_ms']:.2f} | "
                         f"{row.original['plain_ms']:.2f} | {row.speedup:.2f}× ({lo:.2f}–{hi:.2f}) | "
                         f"{row.cached['pixels']:.0f} |")
        return "\n".join(lines)


#: the payload layouts ``breakdown`` compares: precision, and ``f4-packed`` for the inverse depth
#: in the payload's free channel instead of its own render target (``instance(pack_depth=True)``)
PAYLOAD_LAYOUTS = ("f4", "f2", "f4-packed")


def _layout_variant(work, node_id: str, algorithm: str, layout: str):
    from rrcache.compiler import instance

    if layout not in PAYLOAD_LAYOUTS:
        raise ValueError(f"payload layout must be one of {PAYLOAD_LAYOUTS}, not {layout!r}")
    dtype, _, packed = layout.partition("-")
    return instance(work.table, node_id, algorithm, DEFAULT_FILTER, dtype, work.vertex, pack_depth=bool(packed))


def breakdown(shader_path: str, session_path: str, node_id: str, algorithms=("three-pass", "two-pass"),
              formats=("rgba32f", "rgba8"), frames: int = 60, resolution: Optional[tuple[int, int]] = None,
              period: int = 16, repeats: int = 3, payloads=("f4",),
              progress: Optional[Callable[[str, int, int], None]] = None, vertex: Optional[str] = None,
              include_dirs=()) -> Breakdown:
    """Measure the all-hit frame stage by stage for every algorithm, colour format and payload
    layout (:data:`PAYLOAD_LAYOUTS`; see :class:`Breakdown`); the configurations take turns
    within each repeat. (A 16-bit payload is used as asked: its range is not checked here.)"""
    from rrcache.harness.limit import all_hit_breakdown

    session = load_session(session_path)
    work = load_for_session(shader_path, session, include_dirs=include_dirs, vertex=vertex)
    work.node(node_id)
    indices = probe_frames(range(min(frames, session.frames)), 3)
    size = tuple(resolution or session.resolution)
    out = Breakdown(shader_path, session_path, node_id, size, list(indices))
    configs = [(a, f, p) for a in algorithms for p in payloads for f in formats]
    variants = {(a, p): _layout_variant(work, node_id, a, p) for a in algorithms for p in payloads}
    measured = {c: [] for c in configs}
    done, total = 0, len(configs) * repeats
    for repeat in range(repeats):
        for algorithm, fmt, payload in configs:
            cached, original = all_hit_breakdown(variants[(algorithm, payload)], session, work.prepared, indices,
                                                 resolution, period=period, color_format=fmt)
            cj, oj = cached.to_json(), original.to_json()
            # the original's frame without waits: clear + draw (its stages are one of each)
            oj["plain_ms"] = original.frame_ms
            measured[(algorithm, fmt, payload)].append(BreakdownRow(algorithm, fmt, cj, oj, payload))
            done += 1
            if progress is not None:
                progress(f"[{repeat + 1}/{repeats}] breakdown {algorithm} {fmt} payload {payload}", done, total)
    for config in configs:
        rows = sorted(measured[config], key=lambda r: r.speedup)
        out.rows.append(rows[len(rows) // 2])
        out.ranges.append((rows[0].speedup, rows[-1].speedup))
    return out
