"""The window check: one error run where validation measures, before validation, so that the
first level is already judged with the models' bias in the error window known.

A profile whose original is costly trains its error models in an error window, a part of the frame
(:mod:`rrcache.profiler.plan`); validation measures the whole frame (or the timing window). Where
the window's cached pixels err less than the frame's, every node's model predicts too high a PSNR
by about the same factor on the error: on Trashcan's default profile (7af0467) every validated
node measured 7–8 dB under its prediction. The window did not err less for its borders (content
flowing in from outside the window misses and is shaded exactly): n2085 at Δn = 2 over the 150
frames, the steady frames of the corner window it trained in measured 0.00835 run in that window
and 0.00849 inside the frame rendered whole; it erred less for its place: the frame's covered
pixels measured 0.01331 (validation: 0.01331), the centre quarter's 0.0103
(``tools/window_regions.py``, docs/levels.md).

So when the error runs were windowed, with validation or without (a profile that only predicts
then predicts with the check's calibration), :func:`check_window` makes one ``error`` run (no
timing) of each node the levels cache alone, with the first of the levels' choices caching it at
Δn > 1 (:func:`probe_choices`), over the training frames, at the full resolution in the region
validation measures, and adds each to the validation's calibration as a point of its node
(:mod:`rrcache.model.calibration`: the models' predicted PSNR against the measured mean PSNR of
the steady frames, as validation measures it). The checks move the predictions, so the levels
choose again with them, and a choice not checked yet is checked in a second round
(:data:`ROUNDS`; sdf at 804d438: the check of n1139 made n241 e2's choice, which, borrowing
n1139's −1.7 dB, was predicted 2.5 dB under what validation measured). Cached nodes without
points of their own (a candidate validation tries after a miss) borrow their shift until
validation measures points of theirs. Why every level's node, not only the first's: a node's miss in the window is not only
the window's but its model's, and a node borrowing another's shift missed by up to 3 dB
(many_lights at 3f32fb5: the check of n3235 at Δn = 50 measured 5.6 dB under its model and
n10886 at Δn = 2, predicted with that shift, 3.0 dB over it; sdf: n1139's −1.7 dB moved n240's
prediction 2.5 dB under what validation measured). An exact result (no error: PSNR ∞) carries
nothing, as in validation. The measurements are kept in the store (meta ``window_check``): a
resumed profile does not run them again (the prediction is taken anew: more trained nodes move
the coverage offset). The original's frames are rendered once for all of them and released
after. Its cost is one error run per checked choice over the region validation measures, without
timing: on the default profiles, a node's training at one period in the region validation
measures, one to three times.

An amortized estimator is checked the same way, in a run of its own, when the levels choose one
(:func:`probe_estimator`): its calibration family is not the nodes'
(:mod:`rrcache.model.calibration`), so it borrows no shift from their checks, and without a
point of its own its first prediction was the window's. On Trashcan's default profile (3f32fb5)
`e1 m=4 λ=0` measured 41.7 dB in its training window and 35.9 dB in validation: the window's
−5.7 dB, as the node's check measured −7.4 dB there.
"""
from __future__ import annotations

import json
import math
from typing import Optional

from rrcache.gl.formats import ERROR_FORMAT
from rrcache.harness.cached import runtime_spec
from rrcache.profiler.events import ProgressEvent
from rrcache.runs import RunSpec

#: the store's meta key of the window check's point
META = "window_check"
#: what a window check's calibration point is keyed by, before the choice's words
CHECK_PREFIX = "window check: "


#: at most this many cached nodes are checked per round (the levels choose at most four)
MAX_NODES = 4
#: rounds of checks: after each, the levels choose again with the calibration, and a choice of a
#: node not checked yet is checked in the next (:func:`rrcache.profiler.run._selections`)
ROUNDS = 2


def probe_choice(choices) -> Optional[object]:
    """The first of ``choices`` (the levels' selections, the highest level first) that caches one
    node with a PSNR prediction and a refresh period over 1 (at Δn = 1 every pixel is shaded
    anew: its PSNR is capped, a point of no use); None when there is none."""
    found = probe_choices(choices)
    return found[0] if found and found[0].kind == "cache" else None


def probe_estimator(choices) -> Optional[object]:
    """The first of ``choices`` that amortizes an estimator with a PSNR prediction (its models are
    another family's: :func:`rrcache.model.calibration.family`); None when there is none."""
    for sel in choices:
        if sel.parts and not sel.exact and sel.kind == "amortize" and sel.predicted_psnr is not None:
            return sel
    return None


def probe_choices(choices, estimators: bool = True) -> list:
    """What the window check measures: for each node the levels cache alone (at most
    :data:`MAX_NODES`), the first of ``choices`` caching it as :func:`probe_choice` asks, then
    :func:`probe_estimator`'s choice (unless not ``estimators``)."""
    out, nodes = [], set()
    for sel in choices:
        if (sel.parts and not sel.exact and not sel.multi and sel.kind == "cache" and sel.predicted_psnr is not None
                and int(sel.period or 0) > 1 and sel.node not in nodes and len(nodes) < MAX_NODES):
            nodes.add(sel.node)
            out.append(sel)
    estimator = probe_estimator(choices) if estimators else None
    return out + ([estimator] if estimator is not None else [])


def check_window(validator, choices, frames, estimators: bool = True) -> list:
    """Run the window check (module docstring) on ``validator`` (a
    :class:`rrcache.profiler.validate.Validator`: its work, session, settings, store, region and
    executor) for :func:`probe_choices` of ``choices`` over the training ``frames``; add their
    points to ``validator.calibration`` (unless exact) and return them (``key``, ``node``,
    ``predicted``, ``measured``, ``error``, ``frames``): none when no choice is of either kind.
    ``estimators`` False leaves the estimator out (a profile that only predicts applies no
    estimator's shift: :meth:`rrcache.profiles.document.Profile.threshold_selections`)."""
    probes = probe_choices(choices, estimators)
    measured = [_stored(validator.store, CHECK_PREFIX + c.describe()) for c in probes]
    missing = [i for i, m in enumerate(measured) if m is None]
    if missing:
        def keep(i: int, point: dict) -> None:  # each as it arrives: an interrupted check keeps the others
            measured[i] = point
            validator.store.set_meta(META, json.dumps(_stored_all(validator.store, exclude=point["key"]) + [point],
                                                      allow_nan=False))

        _measure(validator, [(i, probes[i]) for i in missing], frames, keep)
    return [_add_point(validator, c, m) for c, m in zip(probes, measured)]


def _measure(validator, probes, frames, keep) -> None:
    """One ``error`` run of each of ``probes`` (``(index, choice)`` pairs) over ``frames`` at the
    full resolution in the validator's region, with a progress stage of its own; ``keep(index,
    measurement)`` as each run ends (an executor may end them in any order)."""
    from rrcache.pipeline import variant_for_selection

    runs = {}
    for i, choice in probes:
        key = CHECK_PREFIX + choice.describe()
        variant, period = variant_for_selection(validator.work, choice)
        spec = runtime_spec(variant, None, period=period, **validator.settings.cache_options())
        runs[("window check", key)] = (i, RunSpec("error", spec, tuple(int(f) for f in frames),
                                                  tuple(validator.session.resolution), validator.window, ERROR_FORMAT,
                                                  key=("window check", key), label=key))
    total = sum(run.cost for _, run in runs.values())
    executor = validator._executor()
    done = [0]

    def step(run, units):  # the progress of a stage of its own (not validation's)
        done[0] += units
        if validator.progress is not None:
            validator.progress(ProgressEvent("check", min(done[0], total), total, run.label))

    for result in executor.run([run for _, run in runs.values()], on_frame=step):
        i, run = runs[result.spec.key]
        keep(i, {"key": run.label, "measured": float(result.steady_psnr), "error": float(result.steady_error),
                 "frames": len(frames)})
    if getattr(executor, "release", None) is not None:  # the original's frames: validation draws its own
        executor.release()


def _add_point(validator, choice, measured: dict) -> dict:
    """``measured`` as a point of ``choice``'s calibration group (the choice's raw prediction
    beside it), added to ``validator.calibration`` unless exact or not finite."""
    from rrcache.profiler.validate import calibration_group

    raw = float(choice.predicted_psnr) - float(choice.calibration_db or 0.0)
    point = dict(measured, node=calibration_group(choice), predicted=raw)
    if measured["error"] > 0.0 and math.isfinite(raw) and math.isfinite(measured["measured"]):
        validator.calibration = validator.calibration.add(point["node"], raw, measured["measured"],
                                                          key=measured["key"])
    return point


def _stored(store, key: str) -> Optional[dict]:
    """The store's window-check measurement of ``key`` (None when absent or unreadable)."""
    return next((p for p in _stored_all(store) if p["key"] == key), None)


def _stored_all(store, exclude: Optional[str] = None) -> list:
    """The store's window-check measurements, readable ones only, but that of ``exclude`` (the
    meta holds a list of them, or one, as written before every level's node was checked)."""
    raw = store.meta().get(META)
    try:
        points = json.loads(raw) if raw else []
    except ValueError:
        return []
    out = []
    for point in points if isinstance(points, list) else [points]:
        try:
            if point["key"] != exclude:
                out.append({"key": str(point["key"]), "measured": float(point["measured"]),
                            "error": float(point["error"]), "frames": int(point["frames"])})
        except (KeyError, TypeError, ValueError):
            continue
    return out
