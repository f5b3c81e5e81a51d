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

from rrcache.harness.cached import CachedRenderer, compare

#: the filters ``auto`` chooses between, the default first
CANDIDATES = ("bilinear", "plane")
#: the PSNR ``plane`` may lose against ``bilinear`` and still be chosen when faster (dB): about
#: the spread of repeated error measurements of one node
PSNR_SLACK_DB = 0.5
#: the consecutive training frames of the error comparison, at most
ERROR_FRAMES = 16


def choose_filter(work, session, settings, node_id: str, algorithm: str, original, timing: list, plan,
                  meter, timing_run) -> tuple[str, dict]:
    """Measure the :data:`CANDIDATES` on ``node_id`` and return ``(filter, {filter: {"time": the
    median time as a fraction of the original's, "psnr": dB}})`` (module docstring).
    ``original`` is the timed original renderer; ``timing_run`` the profiler's timing run."""
    period = settings.timing_periods[len(settings.timing_periods) // 2]
    error_period = settings.periods[len(settings.periods) // 2]
    frames = list(range(min(ERROR_FRAMES, settings.frames)))
    full = tuple(int(v) for v in session.resolution)
    measured: dict = {}
    for filter_ in CANDIDATES:
        variant = _variant(work, node_id, algorithm, filter_)
        with CachedRenderer(variant, session, work.prepared, full, period=period, window=plan.timing_window,
                            color_format=settings.timing_format, **settings.cache_options()) as cached:
            timed = timing_run(cached, original, f"{node_id} {filter_}", period, timing, meter)
        error = compare(variant, session, work.prepared, frames, period=error_period,
                        resolution=settings.resolution, window=plan.error_window,
                        on_frame=lambda *_a, f=filter_: meter.step("filter", f"{node_id} {f}"),
                        **settings.cache_options())
        measured[filter_] = {"time": float(statistics.median(t.ms / t.original_ms for t in timed if t.original_ms > 0)),
                             "psnr": float(error.psnr), "period": int(error_period)}
    return pick(measured), measured


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


def steps(settings, timing: list) -> int:
    """The progress steps :func:`choose_filter` takes."""
    return len(CANDIDATES) * (3 * len(timing) + min(ERROR_FRAMES, settings.frames))


def _variant(work, node_id, algorithm, filter_):
    from rrcache.pipeline import variant_for

    return variant_for(work, node_id, algorithm, filter=filter_)
