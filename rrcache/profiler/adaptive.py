"""The adaptive refresh threshold in the profiler: error and time against the threshold, on the
same front as Δn (:mod:`rrcache.runtime.adaptive`).

For the node of each cached selection (e1 … e4, already validated beside the original), the
adaptive variant is measured at each threshold of ``thresholds`` (max age: the selection's Δn,
fast period ``fast_period``), side by side with the original as validation measures: the error
over the validation frames drawn exactly (``rgba32f``), the time as the ratio of median frame
times in the settings' timing format over the first stretch of them. A threshold is a knob
like Δn: the measured points (error, time ratio) join the selection's own point, and the
fastest point within the selection's level (predicted-PSNR level: measured PSNR ≥ ``min_psnr``;
error level: measured error ≤ ``max_error``) stands. So an adaptive choice replaces a fixed one
only where it was *measured* faster at the same level; the points are kept in the profile store
(the adaptive kind's table, :mod:`rrcache.kinds.adaptive`), and a resumed profile reuses them.

:func:`sweep` is the measurement alone (the command line's ``rrcache profile --adaptive`` and
the docs' equal-time comparisons use it); :func:`extend` the hook :func:`rrcache.profiler.run.
profile` calls after validation.
"""
from __future__ import annotations

import statistics
import time
from dataclasses import dataclass
from typing import Optional, Sequence

from rrcache.gl.formats import ERROR_FORMAT
from rrcache.runs import RunSpec
from rrcache.runtime.adaptive import DEFAULT_FAST_PERIOD
from rrcache.runtime.spec import VariantSpec
from rrcache.selection import AdaptiveNode, CachedNode, Selection

#: thresholds measured by default (in the cached value's units: a colour or an occlusion in [0, 1])
DEFAULT_THRESHOLDS = (0.005, 0.01, 0.02, 0.05)
#: frames of the timed stretch of each point
TIMED_FRAMES = 24
PSNR_CAP = 100.0


@dataclass(frozen=True)
class AdaptivePoint:
    """One measured threshold: ``error`` (mean RGB L2), ``psnr`` (dB), ``time_ratio`` (the
    variant's median frame time over the original's), ``speedup`` (its inverse),
    ``hit_rate``, and the ``speedups`` of the timed repeats."""

    node: str
    period: int
    threshold: float
    fast_period: int
    error: float
    psnr: float
    time_ratio: float
    hit_rate: float
    speedups: tuple = ()

    @property
    def speedup(self) -> float:
        return 1.0 / self.time_ratio if self.time_ratio > 0 else float("inf")

    def part(self, text: Optional[str] = None) -> AdaptiveNode:
        return AdaptiveNode(self.node, int(self.period), float(self.threshold), int(self.fast_period), text=text)


def sweep(executor, spec: VariantSpec, thresholds: Sequence[float], frames, timed_frames=None, resolution=None,
          window=None, timing_format: str = "rgba8", repeats: int = 1, clock: str = "wall") -> list[AdaptivePoint]:
    """Measure ``spec`` (an ``adaptive`` :class:`~rrcache.runtime.spec.VariantSpec`: its node, max
    age, fast period, algorithm and filter) at each of ``thresholds`` beside the original, as
    :class:`~rrcache.runs.RunSpec` runs (``compare``) on ``executor``: the error over ``frames``
    (exact colour), the time over ``timed_frames`` (default: the first :data:`TIMED_FRAMES` of
    ``frames``) ``repeats`` times, at ``resolution`` (default: the session's) inside ``window``."""
    frames = tuple(frames)
    timed = tuple(timed_frames) if timed_frames is not None else frames[:max(2, min(TIMED_FRAMES, len(frames)))]
    size = tuple(resolution) if resolution is not None else tuple(executor.bench.session.resolution)
    node, period = spec.nodes[0], spec.periods[0]
    runs = []
    for threshold in thresholds:
        at = spec.with_runtime(threshold=float(threshold))
        label = f"{node} adaptive ≥{threshold:g}"
        runs.append(RunSpec("compare", at, frames, size, window, ERROR_FORMAT, clock,
                            ("adaptive", float(threshold), "error"), f"{label} error"))
        runs += [RunSpec("compare", at, timed, size, window, timing_format, clock,
                         ("adaptive", float(threshold), "timing", r), f"{label} timing [{r + 1}/{repeats}]")
                 for r in range(max(1, int(repeats)))]
    results: dict = {}
    for result in executor.run(runs):  # in any order (an executor may finish them so)
        results.setdefault(result.spec.key[1], {})[result.spec.key[2:]] = result
    points = []
    for threshold in thresholds:
        got = results[float(threshold)]
        exact = got[("error",)]
        timing = [got[("timing", r)] for r in range(max(1, int(repeats)))]
        ratio = statistics.median(r.ms / r.original_ms for r in timing)
        points.append(AdaptivePoint(node, int(period), float(threshold), int(spec.fast_period), exact.steady_error,
                                    exact.steady_psnr, float(ratio), float(exact.hit_rate),
                                    tuple(float(r.original_ms / r.ms) for r in timing)))
    return points


def meets(level: Selection, error: float, psnr: float) -> bool:
    """Whether a measured (error, PSNR) is within ``level``'s level (its ``min_psnr``, else its
    ``max_error``; neither: any).

    >>> meets(Selection((), 0, 1, 1, min_psnr=38.0), 0.01, 38.5), meets(Selection((), 0, 1, 1, max_error=0.01), 0.02, 40)
    (True, False)
    """
    if level.min_psnr is not None:
        return psnr >= level.min_psnr
    if level.max_error is not None:
        return error <= level.max_error
    return True


def best_at_level(selection: Selection, points: Sequence[AdaptivePoint]) -> Optional[AdaptivePoint]:
    """The fastest measured point within ``selection``'s level that is faster than the
    selection's own measurement (None: the selection stands)."""
    own = selection.measured_speedup
    if own is None:
        return None
    fitting = [p for p in points if meets(selection, p.error, p.psnr) and p.speedup > own]
    return max(fitting, key=lambda p: p.speedup) if fitting else None


def extend(prof, work, session, settings, thresholds: Sequence[float], fast_period: int = DEFAULT_FAST_PERIOD,
           window=None, store=None, executor=None) -> list[Selection]:
    """The profile's selections, each replaced by its node's adaptive variant where one was
    measured faster at the same level (see the module docstring); ``prof.adaptive_points`` keeps
    every point measured (per node and period). With ``store``, the points are kept there (the
    adaptive kind's ``adaptive_point`` table, through the collector) and a resumed profile takes
    the stored ones instead of measuring them again. The runs go to ``executor`` (default: in
    this process)."""
    from rrcache.harness.execute import Bench, LocalExecutor
    from rrcache.profiler.collect import Collector

    frames = list(range(settings.validation_frames or session.frames))
    measured: dict = {}
    own = executor is None
    out = []
    try:
        for sel in prof.selections:
            part = sel.parts[0] if len(sel.parts) == 1 else None
            if not isinstance(part, CachedNode) or sel.measured_speedup is None:
                out.append(sel)
                continue
            key = (part.node, int(part.period))
            algorithm = sel.algorithm or "three-pass"
            if key not in measured:
                stored = _stored(store, part.node, int(part.period), thresholds, fast_period, algorithm)
                todo = [t for t in thresholds if float(t) not in stored]
                if todo:
                    if executor is None:
                        executor = LocalExecutor(Bench(work, session))
                    spec = VariantSpec("adaptive", (part.node,), algorithm, work.filter, periods=(int(part.period),),
                                       fast_period=int(fast_period), **settings.cache_options())
                    start = time.perf_counter()
                    new = sweep(executor, spec, todo, frames, window=window, timing_format=settings.timing_format,
                                clock=settings.clock)
                    seconds = (time.perf_counter() - start) / max(1, len(new))
                    for point in new:
                        stored[point.threshold] = point
                        if store is not None:
                            Collector(store).add_adaptive(point, algorithm, seconds)
                measured[key] = [stored[float(t)] for t in thresholds]
            best = best_at_level(sel, measured[key])
            if best is None:
                out.append(sel)
                continue
            # its time: the point's ratio to the original, on the original's time as validation measured it
            ms = best.time_ratio * sel.measured_original_ms if sel.measured_original_ms else None
            out.append(sel.replace(parts=(best.part(part.text),), measured_error=best.error, measured_psnr=best.psnr,
                                   measured_speedup=best.speedup, speedups=best.speedups, hit_rate=best.hit_rate,
                                   measured_ms=ms, fallback=None))
    finally:
        if own and executor is not None:
            executor.close()
    prof.adaptive_points = [p for pts in measured.values() for p in pts]
    return out


def _stored(store, node: str, period: int, thresholds, fast_period: int, algorithm: str) -> dict:
    """Threshold → the stored :class:`AdaptivePoint` of ``node`` at ``period`` (none without a store)."""
    if store is None:
        return {}
    wanted = {float(t) for t in thresholds}
    return {float(r["threshold"]): AdaptivePoint(node, period, float(r["threshold"]), int(r["fast_period"]),
                                                 float(r["error"]), float(r["psnr"]), float(r["time_ratio"]),
                                                 float(r["hit_rate"]), tuple(r["speedups"]))
            for r in store.adaptive_points(node)
            if int(r["period"]) == period and int(r["fast_period"]) == int(fast_period)
            and r["algorithm"] == algorithm and float(r["threshold"]) in wanted}
