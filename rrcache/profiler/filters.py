"""``filter="auto"``: which hit test and payload reconstruction a profile caches with.

``bilinear`` misses the one- or two-pixel band along every depth edge (its mix of foreground and
background depths matches neither), and on llvmpipe each such miss costs its whole 4×4 block;
``plane`` (:mod:`rrcache.runtime.glsl`) serves the band from the texels of the pixel's own surface.
Which is better depends on the scene: on chess (320×240, the static occlusion at Δn = 50) plane
cut the 4×4 blocks holding a miss from a fifth to a twentieth and nearly doubled the speed-up at
nearly the same PSNR; on Marble (the whole noise at Δn = 16) it cost more per pixel than the
misses it saved and lost 1.7 dB, the band's values being reused instead of recomputed
(docs/misses.md). So a profile measures: :func:`choose_filter` runs the first node to train with
each candidate beside the original, timed as the timing runs are (at the middle timing period)
and its error measured as the error runs are (at the middle training period, over the first
training frames, in the error window), and keeps ``plane`` where it was faster and lost at most
:data:`PSNR_SLACK_DB` of PSNR, else ``bilinear``. The choice and both measurements go into the
plan (``plan.filter``, ``plan.filter_times``) and the profile (``Profile.filter``), and every
variant the profile compiles uses it (``ShaderWork.filter``).
"""
from __future__ import annotations

import statistics

from rrcache.gl.formats import ERROR_FORMAT
from rrcache.runs import RunSpec
from rrcache.runtime.spec import VariantSpec

#: the filters ``auto`` chooses between, the default first
CANDIDATES = ("bilinear", "plane")
#: the PSNR ``plane`` may lose against ``bilinear`` and still be chosen when faster (dB): about
#: the spread of repeated error measurements of one node
PSNR_SLACK_DB = 0.5
#: the consecutive training frames of the error comparison, at most
ERROR_FRAMES = 16


def choose_filter(settings, node_id: str, algorithm: str, shapes, executor, meter=None) -> tuple[str, dict]:
    """Measure the :data:`CANDIDATES` on ``node_id`` and return ``(filter, {filter: {"time": the
    median time as a fraction of the original's, "psnr": dB}})`` (module docstring), as
    :class:`~rrcache.runs.RunSpec` runs on ``executor`` (``shapes``: the profile's
    :class:`~rrcache.profiler.jobs.RunShapes`; ``meter`` counts the progress)."""
    period = settings.timing_periods[len(settings.timing_periods) // 2]
    error_period = settings.periods[len(settings.periods) // 2]
    frames = tuple(range(min(ERROR_FRAMES, settings.frames)))
    runs = []
    for filter_ in CANDIDATES:
        spec = VariantSpec("cache", (node_id,), algorithm, filter_, **settings.cache_options())
        runs.append(shapes.run("timing", spec.with_runtime(periods=(period,)), ("filter", filter_),
                               f"{node_id} {filter_}"))
        # the error as the error runs measure it, beside the original frame by frame
        runs.append(RunSpec("compare", spec.with_runtime(periods=(error_period,)), frames, shapes.resolution,
                            shapes.error_window, ERROR_FORMAT, shapes.clock, ("filter", filter_), f"{node_id} {filter_}"))
    if meter is not None:
        meter.grow(sum(r.cost for r in runs))
    measured: dict = {}
    on_frame = meter.on_frame("filter") if meter is not None else None
    for result in executor.run(runs, on_frame=on_frame):  # in any order
        entry = measured.setdefault(result.spec.key[1], {})
        if result.spec.measure == "timing":
            entry["time"] = float(statistics.median(r.ms / r.original_ms for r in result.frames if r.original_ms > 0))
        else:
            entry["psnr"], entry["period"] = float(result.steady_psnr), int(error_period)
    return pick(measured), {f: measured[f] for f in CANDIDATES}


def pick(measured: dict) -> str:
    """``plane`` when it was faster than ``bilinear`` and lost at most :data:`PSNR_SLACK_DB`.

    >>> pick({"bilinear": {"time": 0.3, "psnr": 42.5}, "plane": {"time": 0.14, "psnr": 42.2}})
    'plane'
    >>> pick({"bilinear": {"time": 0.25, "psnr": 43.5}, "plane": {"time": 0.31, "psnr": 41.8}})
    'bilinear'
    """
    base, other = measured["bilinear"], measured["plane"]
    if other["time"] < base["time"] and other["psnr"] >= base["psnr"] - PSNR_SLACK_DB:
        return "plane"
    return "bilinear"
