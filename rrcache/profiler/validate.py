"""Validation: the four selections rendered beside the original, predicted against measured.

After training, :func:`validate` takes the selections at four error thresholds of the models
(:meth:`rrcache.profiles.Profile.threshold_selections`, labelled ``e1`` … ``e4``), renders each with :func:`rrcache.harness.cached.compare` side by side with the original at the
session's full resolution over ``settings.validation_frames`` consecutive frames (alternating
per frame), and stores the measured error, PSNR, hit rate and speed-up beside the prediction
(main paper §4.4, Fig. 6). Shaders timed in a window (:mod:`rrcache.profiler.plan`: a full frame
costs more than 150 ms) are validated in the same window. A selection of the original shader (node ``None``) is not rendered:
its error is 0 and its speed-up 1. A (node, period) already measured in the store is not rendered again.

>>> rows = validate(work, session, settings, store, prof.threshold_selections())   # doctest: +SKIP
>>> [(r.label, r.node, r.period) for r in rows]                                     # doctest: +SKIP
[('e1', 'n104', 50), ('e2', 'n102', 34), ...]
"""
from __future__ import annotations

from typing import Optional

from rrcache.harness.cached import compare
from rrcache.pipeline import ShaderWork, variant_for_selection
from rrcache.profiler.train import PSNR_CAP, ProgressEvent, ProgressFn
from rrcache.profiles.settings import TrainingSettings
from rrcache.profiles.store import ProfileStore
from rrcache.selection import Selection


def validate(work: ShaderWork, session, settings: TrainingSettings, store: ProfileStore, choices: list[Selection],
             progress: Optional[ProgressFn] = None, window=None) -> list[Selection]:
    """Measure each of ``choices`` (labelled selections with their algorithm) beside the original
    inside ``window`` when given, store them and return them measured, in order."""
    frames = list(range(settings.validation_frames))
    # measurements already stored (a resumed run) are reused, keyed by what is cached
    measured = {row.key: row for row in store.validations() if row.parts}
    todo = {c.key for c in choices if c.parts} - set(measured)
    total = 2 * len(frames) * len(todo)
    done = 0
    out = []
    for choice in choices:
        if not choice.parts:
            sel = choice.with_measurement(0.0, PSNR_CAP, float(choice.predicted_ms), float(choice.predicted_ms),
                                          1.0, 0.0, 0)
        else:
            if choice.key not in measured:
                variant, period = variant_for_selection(work, choice)

                def step(*_, detail=f"{choice.label}: {choice.describe()}"):
                    nonlocal done
                    done += 2
                    if progress is not None:
                        progress(ProgressEvent("validate", done, total, detail))

                result = compare(variant, session, work.prepared, frames, period=period,
                                 on_frame=step, window=window, **settings.cache_options())
                measured[choice.key] = choice.with_measurement(
                    result.mean_error, min(result.psnr, PSNR_CAP), result.ms_per_frame, result.original_ms_per_frame,
                    result.speedup, result.hit_rate, len(result.frames))
            m = measured[choice.key]
            sel = choice.with_measurement(m.measured_error, m.measured_psnr, m.measured_ms, m.measured_original_ms,
                                          m.measured_speedup, m.hit_rate, m.frames)
        store.add_validation(sel)
        out.append(sel)
    return out
