"""Validation: the four selections rendered beside the original, predicted against measured, and
never a measured slowdown shipped.

After training, :func:`validate` takes the labelled selections of the profile
(:meth:`rrcache.profiles.Profile.threshold_selections`: by default predicted PSNR ≥ 45, 40, 35,
30 dB) and measures each with :func:`rrcache.harness.cached.compare`, side by side with the
original at the session's full resolution, alternating frame by frame (main paper §4.4, Fig. 6).
Shaders timed in a window (:mod:`rrcache.profiler.plan`) are validated in the same window.

**Error and repeats.** A selection's error, PSNR and hit rate are measured over
``validation_frames`` consecutive frames drawn exactly (``rgba32f``, as the error runs the
models were trained on: an 8-bit target would add its own rounding to the error); its speed-up
:data:`REPEATS` times in the settings' timing format (:mod:`rrcache.gl.formats`, ``rgba8`` by
default, as applications draw), each over :data:`SHORT_FRAMES` consecutive frames, the stretches
spread over the validation frames (the refresh schedule makes the hit/miss mix steady from a
stretch's second frame on). The measured speed-up is the median of the repeats, ``speedups``
keeps each, ``measured_noise`` the noisiest run's frame-to-frame noise of the original
(:func:`rrcache.harness.timing.frame_noise`).

**Never a measured slowdown.** A selection is *slower than the original beyond the noise* when
every repeat measured it slower (the highest repeat < 1.0). Then the next candidate on the
predicted Pareto front at the same level (:meth:`~rrcache.profiles.Profile.front_candidates`,
fastest first) is measured instead, up to :data:`MAX_FALLBACKS` of them, and failing those the
original shader stands; the selection that stands says why in ``fallback`` (the rejected
choices and what they measured). A median below 1.0 with some repeat at or above it is within
the noise and is kept, with its range shown.

A selection of the original shader is not rendered: its image is exact (PSNR ∞) and its speed-up 1.
A choice already measured in the store (a resumed run) is not rendered again.

>>> rows = validate(work, session, settings, store, prof.threshold_selections(), candidates=prof.front_candidates)  # doctest: +SKIP
>>> [(r.label, r.node, r.period, r.fallback) for r in rows]                                                       # doctest: +SKIP
[('e1', 'n104', 50, None), ('e2', None, None, 'n102 Δn=34 measured 0.94× (0.92–0.96) ...'), ...]
"""
from __future__ import annotations

import statistics
from typing import Callable, Optional

from rrcache.gl.formats import ERROR_FORMAT
from rrcache.harness.cached import compare
from rrcache.harness.timing import frame_noise
from rrcache.model.psnr import VISIBLE_DB
from rrcache.pipeline import ShaderWork, variant_for_selection
from rrcache.profiler.train import PSNR_CAP, ProgressEvent, ProgressFn
from rrcache.profiles.settings import TrainingSettings
from rrcache.profiles.store import ProfileStore
from rrcache.selection import Selection

#: side-by-side measurements of each selection, and the frames of each after the first
REPEATS = 3
SHORT_FRAMES = 24
#: at most this many further candidates of the front are measured for a level before the original
MAX_FALLBACKS = 2


def slower_beyond_noise(speedups) -> bool:
    """Whether every repeat measured the selection slower than the original.

    >>> slower_beyond_noise([0.94, 0.97, 0.92]), slower_beyond_noise([0.97, 1.01, 0.95])
    (True, False)
    """
    return bool(speedups) and max(speedups) < 1.0


def _range_text(sel: Selection) -> str:
    lo, hi = sel.speedup_range or (sel.measured_speedup, sel.measured_speedup)
    return f"{sel.measured_speedup:.2f}× ({lo:.2f}–{hi:.2f} over {len(sel.speedups) or 1} repeats)"


def validate(work: ShaderWork, session, settings: TrainingSettings, store: ProfileStore, choices: list[Selection],
             progress: Optional[ProgressFn] = None, window=None,
             candidates: Optional[Callable[[Selection], list[Selection]]] = None,
             fallback: bool = True) -> list[Selection]:
    """Measure each of ``choices`` (labelled selections with their algorithm) beside the original
    inside ``window`` when given, falling back along ``candidates(choice)`` (then to the
    original) when one measures slower than the original beyond the noise (see the module
    docstring; ``fallback=False`` keeps every choice as measured); store every measurement and
    return the selections that stand, in order."""
    frames = list(range(settings.validation_frames))
    short = frames[:max(2, min(SHORT_FRAMES, len(frames)))]
    # measurements already stored (a resumed run) are reused, keyed by what is cached
    measured = {row.key: row for row in store.validations() if row.parts}
    todo = {c.key for c in choices if c.parts} - set(measured)
    per = len(frames) + REPEATS * len(short)
    state = {"done": 0, "total": 2 * per * len(todo)}

    def measure(choice: Selection) -> Selection:
        if choice.key in measured:
            m = measured[choice.key]
            return choice.with_measurement(m.measured_error, m.measured_psnr, m.measured_ms, m.measured_original_ms,
                                           m.measured_speedup, m.hit_rate, m.frames,
                                           m.speedups or (m.measured_speedup,)).replace(
                measured_noise=m.measured_noise, exact=m.exact or m.measured_error == 0.0,
                measured_psnr=None if m.measured_error == 0.0 else m.measured_psnr)
        variant, period = variant_for_selection(work, choice)
        if choice.key not in todo:  # a fallback candidate: more work than planned
            state["total"] += 2 * per

        def step(*_, detail=""):
            state["done"] += 2
            if progress is not None:
                progress(ProgressEvent("validate", state["done"], state["total"], detail))

        common = dict(period=period, window=window, **settings.cache_options())
        # the error over every validation frame, drawn exactly (rgba32f) as the error runs are
        exact_run = compare(variant, session, work.prepared, frames, color_format=ERROR_FORMAT,
                            on_frame=lambda *a: step(detail=f"{choice.label}: {choice.describe()} error"), **common)
        # the speed-up in the timing format, REPEATS times over stretches spread over the frames
        runs = []
        for repeat in range(REPEATS):
            start = (len(frames) - len(short)) * repeat // max(1, REPEATS - 1)
            stretch = frames[start:start + len(short)]
            runs.append(compare(variant, session, work.prepared, stretch, color_format=settings.timing_format,
                                clock=settings.clock,
                                on_frame=lambda *a, r=repeat: step(
                                    detail=f"{choice.label}: {choice.describe()} timing [{r + 1}/{REPEATS}]"),
                                **common))
        speedups = tuple(r.speedup for r in runs)
        exact = exact_run.mean_error == 0.0
        psnr = None if exact else min(exact_run.psnr, PSNR_CAP)  # exact: PSNR ∞, kept as null
        sel = choice.with_measurement(exact_run.mean_error, psnr, statistics.median(r.ms_per_frame for r in runs),
                                      statistics.median(r.original_ms_per_frame for r in runs),
                                      float(statistics.median(speedups)), exact_run.hit_rate, len(exact_run.frames),
                                      speedups)
        sel = sel.replace(measured_noise=max(frame_noise([f.original_ms for f in r.frames[1:]]) for r in runs),
                          exact=exact, visible_artifacts=bool(psnr is not None and psnr < VISIBLE_DB))
        measured[choice.key] = sel
        return sel

    out = []
    rejected_count = 0
    for choice in choices:
        if not choice.parts:
            sel = _original(choice)
        else:
            sel = measure(choice)
            rejected: list[Selection] = []
            pool = list(candidates(choice)) if candidates is not None else []
            while fallback and sel.parts and slower_beyond_noise(sel.speedups or (sel.measured_speedup,)):
                rejected.append(sel)
                rejected_count += 1
                # every measurement is kept in the store (the rejected ones under their own label)
                store.add_validation(sel.replace(label=f"{choice.label}~{len(rejected)}"))
                pool = [c for c in pool if c.key not in {r.key for r in rejected}]
                if pool and len(rejected) <= MAX_FALLBACKS:
                    sel = measure(pool.pop(0))
                else:
                    sel = _original(choice)
            if rejected:
                why = "; ".join(f"{r.describe()} measured {_range_text(r)}" for r in rejected)
                sel = sel.replace(fallback=f"{why}: slower than the original in every repeat, so "
                                           f"{sel.describe()} stands")
        store.add_validation(sel)
        out.append(sel)
    return out


def _original(choice: Selection) -> Selection:
    """The original shader as a measured selection at ``choice``'s level: exact, speed-up 1."""
    base = Selection.original(float(choice.predicted_ms) if not choice.parts else float("nan"))
    original = choice if not choice.parts else base.replace(
        label=choice.label, max_error=choice.max_error, min_psnr=choice.min_psnr, algorithm=choice.algorithm,
        predicted_ms=choice.predicted_ms * choice.predicted_speedup)
    return original.with_measurement(0.0, None, float(original.predicted_ms), float(original.predicted_ms),
                                     1.0, 0.0, 0).replace(exact=True, predicted_psnr=None,
                                                          predicted_psnr_uncertainty=0.0, visible_artifacts=False,
                                                          predicted_error=0.0, predicted_speedup=1.0,
                                                          predicted_speedup_range=(1.0, 1.0))
