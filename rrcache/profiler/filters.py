"""``filter="auto"``: which hit test and payload reconstruction a profile caches with.

``bilinear`` misses the one- or two-pixel band along every depth edge (its mix of foreground and
background depths matches neither), and on llvmpipe each such miss costs its whole 4×4 block;
``plane`` (:mod:`rrcache.runtime.glsl`) serves the band from the texels of the pixel's own surface,
at three more texel reads per reprojected pixel, and reuses the band's values instead of
recomputing them. Which is better depends on the scene: on chess (320×240, the static occlusion
at Δn = 50) plane cut the 4×4 blocks holding a miss from a fifth to a twentieth and made the
node 1.5× faster at 0.3 dB less; on Marble (the whole noise at Δn = 16) it was slower and lost
1.7 dB (docs/misses.md). A faster filter that adds error is only better if the slower one could
not buy the same time with a longer period at less error, so :func:`choose_filter` compares the
two at equal time: the first node to train is run with each filter at the shortest, middle and
longest training periods, timed beside the original as the timing runs are and its error
measured as the error runs are (over the first training frames, in the error window); at each of
plane's points, bilinear's error at the same time is interpolated from its own points (log error
linear in time; beyond its range, along the trend of its fastest and slowest points: a time
bilinear cannot reach at any period costs it the error that trend implies), and plane is kept
when its error is no higher at two of the three points (:func:`pick`). The choice and every point go into the plan
(``plan.filter``, ``plan.filter_times``) and the profile (``Profile.filter``), and every variant the
profile compiles uses it (``ShaderWork.filter``).
"""
from __future__ import annotations

import math
import statistics

from rrcache.gl.formats import ERROR_FORMAT
from rrcache.runs import RunSpec
from rrcache.runtime.spec import VariantSpec

#: the filters ``auto`` chooses between, the default first
CANDIDATES = ("bilinear", "plane")
#: the consecutive training frames of the error runs, at most
ERROR_FRAMES = 16


def decision_periods(settings) -> tuple:
    """The training periods the filters are compared at: the shortest, middle and longest."""
    p = settings.periods
    return tuple(sorted({p[0], p[len(p) // 2], p[-1]}))


def choose_filter(settings, node_id: str, algorithm: str, shapes, executor, meter=None) -> tuple[str, dict]:
    """Measure the :data:`CANDIDATES` on ``node_id`` and return ``(filter, {filter: [{"period",
    "time" (the median time as a fraction of the original's), "error", "psnr"}, ...]})`` (module
    docstring), as :class:`~rrcache.runs.RunSpec` runs on ``executor`` (``shapes``: the profile's
    :class:`~rrcache.profiler.jobs.RunShapes`; ``meter`` counts the progress)."""
    periods = decision_periods(settings)
    frames = tuple(range(min(ERROR_FRAMES, settings.frames)))
    runs = []
    for filter_ in CANDIDATES:
        spec = VariantSpec("cache", (node_id,), algorithm, filter_, **settings.cache_options())
        for p in periods:
            key = ("filter", filter_, int(p))
            runs.append(shapes.run("timing", spec.with_runtime(periods=(p,)), key, f"{node_id} {filter_} Δn={p}"))
            # the error as the error runs measure it, beside the original frame by frame
            runs.append(RunSpec("compare", spec.with_runtime(periods=(p,)), frames, shapes.resolution,
                                shapes.error_window, ERROR_FORMAT, shapes.clock, key, f"{node_id} {filter_} Δn={p}"))
    if meter is not None:
        meter.grow(sum(r.cost for r in runs))
    measured: dict = {f: {int(p): {"period": int(p)} for p in periods} for f in CANDIDATES}
    on_frame = meter.on_frame("filter") if meter is not None else None
    for result in executor.run(runs, on_frame=on_frame):  # in any order
        _, filter_, p = result.spec.key
        entry = measured[filter_][p]
        if result.spec.measure == "timing":
            entry["time"] = float(statistics.median(r.ms / r.original_ms for r in result.frames if r.original_ms > 0))
        else:
            entry["error"], entry["psnr"] = float(result.steady_error), float(result.steady_psnr)
    points = {f: [measured[f][int(p)] for p in periods] for f in CANDIDATES}
    return pick(points), points


def pick(measured: dict) -> str:
    """``plane`` when, at two of its three points or more, its error is no higher than
    bilinear's at the same time (module docstring), else ``bilinear``.

    >>> b = [{"time": 0.6, "error": 0.001}, {"time": 0.3, "error": 0.002}, {"time": 0.24, "error": 0.003}]
    >>> pick({"bilinear": b, "plane": [{"time": 0.5, "error": 0.001}, {"time": 0.2, "error": 0.0022},
    ...                                {"time": 0.16, "error": 0.0032}]})
    'plane'
    >>> pick({"bilinear": b, "plane": [{"time": 0.62, "error": 0.0012}, {"time": 0.31, "error": 0.0025},
    ...                                {"time": 0.25, "error": 0.0035}]})
    'bilinear'
    """
    base = sorted(measured["bilinear"], key=lambda q: q["time"])
    wins = sum(1 for q in measured["plane"] if q["error"] <= _error_at(base, q["time"]))
    return "plane" if 2 * wins > len(measured["plane"]) else "bilinear"


def _error_at(points: list, time: float) -> float:
    """The error of a filter at ``time``: its points' log error interpolated linearly in time
    (``points`` sorted by time); beyond them, extrapolated along the line through its fastest and
    slowest points (a time it cannot reach costs it the error its trend implies)."""
    logs = [math.log(max(p["error"], 1e-12)) for p in points]
    first, last = points[0], points[-1]
    if not first["time"] <= time <= last["time"]:
        span = last["time"] - first["time"]
        if span <= 0:
            return first["error"]
        slope = (logs[-1] - logs[0]) / span
        end, log_end = (first, logs[0]) if time < first["time"] else (last, logs[-1])
        return math.exp(log_end + slope * (time - end["time"]))
    for (lo, a), (hi, b) in zip(zip(points, logs), zip(points[1:], logs[1:])):
        if lo["time"] <= time <= hi["time"]:
            span = hi["time"] - lo["time"]
            w = (time - lo["time"]) / span if span > 0 else 0.0
            return math.exp(a + w * (b - a))
    return last["error"]
