"""Validation: the four selections rendered beside the original, predicted against measured.

After training, :func:`validate` takes four error thresholds from the models
(``rrcache.model.thresholds(table, 4)``, labelled ``e1`` … ``e4``), selects at each, renders the
selection with :func:`rrcache.harness.cached.compare` side by side with the original at the
session's full resolution over ``settings.validation_frames`` consecutive frames (alternating
per frame), and stores the measured error, PSNR, hit rate and speed-up beside the prediction
(main paper §4.4, Fig. 6). Shaders timed in a window (:mod:`rrcache.profile.plan`: a full frame
costs more than 150 ms) are validated in the same window. A selection of the original shader (node ``None``) is not rendered:
its error is 0 and its speed-up 1. A (node, period) already measured in the store is not rendered again.

>>> rows = validate(work, session, settings, store, table)     # doctest: +SKIP
>>> [(r.label, r.node, r.period) for r in rows]                 # doctest: +SKIP
[('e1', 'n104', 50), ('e2', 'n102', 34), ...]
"""
from __future__ import annotations

from typing import Optional

from rrcache.harness.cached import compare
from rrcache.pipeline import ShaderWork, variant_for
from rrcache.profile.settings import TrainingSettings
from rrcache.profile.store import ProfileStore, ValidationRow
from rrcache.profile.train import PSNR_CAP, ProgressEvent, ProgressFn

LABELS = ("e1", "e2", "e3", "e4")


def validate(work: ShaderWork, session, settings: TrainingSettings, store: ProfileStore, table,
             progress: Optional[ProgressFn] = None, window=None, algorithm: Optional[str] = None) -> list[ValidationRow]:
    """Select at four thresholds of ``table`` (a ``rrcache.model.ModelTable``), measure each
    selection with ``algorithm`` (default: the settings'; the profile passes its plan's choice)
    inside ``window`` when given, store and return the rows (in label order)."""
    algorithm = algorithm or settings.fixed_algorithm
    from rrcache.model import select, thresholds

    levels = [float(t) for t in thresholds(table, len(LABELS))]
    frames = list(range(settings.validation_frames))
    choices = [(label, level, select(table, level)) for label, level in zip(LABELS, levels)]
    # measurements already stored (a resumed run) are reused, keyed by (node, period)
    measured: dict[tuple, tuple] = {}
    for row in store.validations():
        if row.node is not None:
            measured[(row.node, row.period)] = (row.measured_error, row.measured_psnr, row.measured_ms,
                                                row.measured_original_ms, row.measured_speedup, row.hit_rate,
                                                row.frames)
    todo = {(c.node, int(c.period)) for _, _, c in choices if c.node is not None} - set(measured)
    total = 2 * len(frames) * len(todo)
    done = 0
    rows = []
    for label, level, choice in choices:
        if choice.node is None:
            row = ValidationRow(label, level, None, None, float(choice.predicted_error), float(choice.predicted_ms),
                                float(choice.predicted_speedup), 0.0, PSNR_CAP, float(choice.predicted_ms),
                                float(choice.predicted_ms), 1.0, 0.0, 0)
        else:
            key = (choice.node, int(choice.period))
            if key not in measured:
                variant = variant_for(work, choice.node, int(choice.period), algorithm)

                def step(*_, detail=f"{label}: {choice.node} Δn={choice.period}"):
                    nonlocal done
                    done += 2
                    if progress is not None:
                        progress(ProgressEvent("validate", done, total, detail))

                result = compare(variant, session, work.prepared, frames, period=int(choice.period),
                                 block=settings.block, refresh=settings.refresh,
                                 depth_epsilon=settings.depth_epsilon, on_frame=step, window=window,
                                 color_format=settings.timing_format)
                measured[key] = (result.mean_error, min(result.psnr, PSNR_CAP), result.ms_per_frame,
                                 result.original_ms_per_frame, result.speedup, result.hit_rate, len(result.frames))
            row = ValidationRow(label, level, choice.node, int(choice.period), float(choice.predicted_error),
                                float(choice.predicted_ms), float(choice.predicted_speedup), *measured[key])
        store.add_validation(row)
        rows.append(row)
    return rows
