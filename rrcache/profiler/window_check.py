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
then predicts with the check's calibration), :func:`check_window` makes one ``error`` run (no timing)
of the first of the levels' choices that caches a single node at Δn > 1, over the training
frames, at the full resolution in the region validation measures, and adds it to the
validation's calibration as a point of that node (:mod:`rrcache.model.calibration`: the models'
predicted PSNR against the measured mean PSNR of the steady frames, as validation measures it).
Cached nodes without points of their own borrow its shift until validation measures points of
theirs (the checked node keeps it beside its validation's). An exact result (no error: PSNR ∞)
carries nothing, as in validation. The measurement is kept in the store (meta ``window_check``):
a resumed profile does not run it again (the prediction is taken anew: more trained nodes move
the coverage offset). The original's frames it rendered are released after it. Its cost is one
error run of one node over the region validation measures: about a window's share fewer than one
node's training at a single period.
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


def probe_choice(choices) -> Optional[object]:
    """The first of ``choices`` (the levels' selections, the highest level first) that caches one
    node with a PSNR prediction and a refresh period over 1 (at Δn = 1 every pixel is shaded
    anew: its PSNR is capped, a point of no use); None when there is none."""
    for sel in choices:
        if (sel.parts and not sel.exact and not sel.multi and sel.kind == "cache" and sel.predicted_psnr is not None
                and int(sel.period or 0) > 1):
            return sel
    return None


def check_window(validator, choices, frames) -> Optional[dict]:
    """Run the window check (module docstring) on ``validator`` (a
    :class:`rrcache.profiler.validate.Validator`: its work, session, settings, store, region and
    executor) for the first suitable of ``choices`` over the training ``frames``; add its point to
    ``validator.calibration`` (unless exact) and return it (``key``, ``node``, ``predicted``,
    ``measured``, ``error``, ``frames``), or None when no choice caches a single node at Δn > 1."""
    from rrcache.pipeline import variant_for_selection
    from rrcache.profiler.validate import calibration_group

    choice = probe_choice(choices)
    if choice is None:
        return None
    key = CHECK_PREFIX + choice.describe()
    measured = _stored(validator.store, key)
    if measured is None:
        variant, period = variant_for_selection(validator.work, choice)
        spec = runtime_spec(variant, None, period=period, **validator.settings.cache_options())
        run = RunSpec("error", spec, tuple(int(f) for f in frames), tuple(validator.session.resolution),
                      validator.window, ERROR_FORMAT, key=("window check",), label=key)
        executor = validator._executor()
        done = [0]

        def step(_, units):  # the progress of a stage of its own (not validation's)
            done[0] += units
            if validator.progress is not None:
                validator.progress(ProgressEvent("check", min(done[0], run.cost), run.cost, key))

        (result,) = list(executor.run([run], on_frame=step))
        if getattr(executor, "release", None) is not None:  # the original's frames: validation draws its own
            executor.release()
        measured = {"key": key, "measured": float(result.steady_psnr), "error": float(result.steady_error),
                    "frames": len(frames)}
        validator.store.set_meta(META, json.dumps(measured, allow_nan=False))
    raw = float(choice.predicted_psnr) - float(choice.calibration_db or 0.0)
    point = dict(measured, node=calibration_group(choice), predicted=raw)
    if measured["error"] > 0.0 and math.isfinite(raw) and math.isfinite(measured["measured"]):
        validator.calibration = validator.calibration.add(point["node"], raw, measured["measured"], key=key)
    return point


def _stored(store, key: str) -> Optional[dict]:
    """The store's window-check measurement of ``key`` (None when absent, another choice's, or
    unreadable)."""
    raw = store.meta().get(META)
    try:
        point = json.loads(raw) if raw else None
    except ValueError:
        return None
    if not isinstance(point, dict) or point.get("key") != key:
        return None
    try:
        return {"key": key, "measured": float(point["measured"]), "error": float(point["error"]),
                "frames": int(point["frames"])}
    except (KeyError, TypeError, ValueError):
        return None
