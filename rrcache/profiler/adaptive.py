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
only where it was *measured* faster at the same level; the measurements are not stored in the
profile store (a resumed profile measures them again).

:func:`sweep` is the measurement alone (the command line's ``rrcache profile --adaptive`` and
the docs' equal-time comparisons use it); :func:`extend` the hook :func:`rrcache.profiler.run.
profile` calls after validation.
"""
from __future__ import annotations

import statistics
from dataclasses import dataclass
from typing import Optional, Sequence

from rrcache.gl.formats import ERROR_FORMAT
from rrcache.runtime.adaptive import DEFAULT_FAST_PERIOD
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


def sweep(work, session, node: str, period: int, thresholds: Sequence[float], frames, timed_frames=None,
          fast_period: int = DEFAULT_FAST_PERIOD, algorithm: str = "three-pass", filter: Optional[str] = None,
          cache_options: Optional[dict] = None, window=None, resolution=None, timing_format: str = "rgba8",
          repeats: int = 1, on_frame=None) -> list[AdaptivePoint]:
    """Measure node ``node`` with adaptive refresh at each of ``thresholds`` (max age ``period``)
    beside the original: the error over ``frames`` (exact colour), the time over
    ``timed_frames`` (default: the first :data:`TIMED_FRAMES` of ``frames``) ``repeats`` times."""
    from rrcache.harness.cached import compare
    from rrcache.pipeline import variant_for

    frames = list(frames)
    timed = list(timed_frames) if timed_frames is not None else frames[:max(2, min(TIMED_FRAMES, len(frames)))]
    variant = variant_for(work, node, algorithm, filter=filter, adaptive=True)
    common = dict(cache_options or {}, period=int(period), window=window, resolution=resolution,
                  fast_period=int(fast_period), on_frame=on_frame)
    points = []
    for threshold in thresholds:
        exact = compare(variant, session, work.prepared, frames, color_format=ERROR_FORMAT, threshold=float(threshold),
                        **common)
        runs = [compare(variant, session, work.prepared, timed, color_format=timing_format,
                        threshold=float(threshold), **common) for _ in range(max(1, int(repeats)))]
        ratio = statistics.median(r.ms_per_frame / r.original_ms_per_frame for r in runs)
        points.append(AdaptivePoint(node, int(period), float(threshold), int(fast_period), float(exact.mean_error),
                                    float(min(exact.psnr, PSNR_CAP)), float(ratio), float(exact.hit_rate),
                                    tuple(float(r.speedup) for r in runs)))
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
           window=None) -> list[Selection]:
    """The profile's selections, each replaced by its node's adaptive variant where one was
    measured faster at the same level (see the module docstring); ``prof.adaptive_points`` keeps
    every point measured (per node and period)."""
    frames = list(range(settings.validation_frames or session.frames))
    measured: dict = {}
    out = []
    for sel in prof.selections:
        part = sel.parts[0] if len(sel.parts) == 1 else None
        if not isinstance(part, CachedNode) or sel.measured_speedup is None:
            out.append(sel)
            continue
        key = (part.node, int(part.period))
        if key not in measured:
            measured[key] = sweep(work, session, part.node, int(part.period), thresholds, frames,
                                  fast_period=fast_period, algorithm=sel.algorithm or "three-pass",
                                  cache_options=settings.cache_options(), window=window,
                                  timing_format=settings.timing_format)
        best = best_at_level(sel, measured[key])
        if best is None:
            out.append(sel)
            continue
        out.append(sel.replace(parts=(best.part(part.text),), measured_error=best.error, measured_psnr=best.psnr,
                               measured_speedup=best.speedup, speedups=best.speedups, hit_rate=best.hit_rate,
                               measured_ms=None, fallback=None))
    prof.adaptive_points = [p for pts in measured.values() for p in pts]
    return out
