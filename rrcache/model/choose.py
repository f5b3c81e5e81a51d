"""The selection rules: a profile's models turned into choices at a level, the e1…e4 levels, the
front's candidates, and each choice's predicted figures with their uncertainty.

The rules read a profile's data only (its model table, PSNR fits, sets, estimators' models,
original time, algorithm, calibration: :class:`rrcache.profiles.Profile`, passed as ``prof``); the
document keeps the data and asks here (``Profile.select`` … delegate to these functions).
"""
from __future__ import annotations

import math

from rrcache.errors import RRCacheError
from rrcache.selection import AmortizedLoop, Selection

#: the levels' labels
LABELS = ("e1", "e2", "e3", "e4")


def select(prof, max_error: float) -> Selection:
    """The choice predicted fastest with error ≤ ``max_error``, from the models only: a
    :class:`~rrcache.selection.Selection` with this profile's algorithm and the node's
    expression (no part: the original shader).

    >>> choice = load_profile("marble-marble.rrprofile").select(0.01)   # doctest: +SKIP
    """
    from rrcache.model import select as model_select

    try:
        level = float(max_error)
    except (TypeError, ValueError):
        level = float("nan")
    if not math.isfinite(level) or level < 0:
        raise RRCacheError(f"{max_error!r} is not an error threshold", "--max-error",
                           hint="give a mean RGB L2 error >= 0, e.g. 0.01 (profile.json lists the e1..e4 levels)")
    if prof.verdict is not None:  # the ceiling answered before training: the original
        return Selection.original(float(prof.original_ms), algorithm=prof.algorithm, max_error=level)
    choice = _with_sets(prof, adopt(prof, model_select(prof.table, level), max_error=level), max_error=level)
    return _amortized_or(prof, choice, max_error=level)


def _with_sets(prof, choice: Selection, max_error=None, min_psnr=None) -> Selection:
    """``choice``, or the trained set (:attr:`sets`) admissible at the level and measured
    faster in training (:func:`rrcache.model.sets.better`), with the choice's level."""
    from rrcache.model.sets import better

    found = better(choice, prof.sets, float(prof.original_ms), max_error=max_error, min_psnr=min_psnr)
    if found is None:
        return choice
    return found.selection(float(prof.original_ms), label=choice.label, max_error=choice.max_error,
                           min_psnr=choice.min_psnr, algorithm=prof.algorithm).with_texts(prof.texts())


def _amortized_or(prof, choice: Selection, max_error=None, min_psnr=None) -> Selection:
    """``choice`` (the nodes' or a set's, adopted), or the amortized option predicted faster
    at the same level, adopted with ``choice``'s label and level."""
    rival = _rival(prof, choice, max_error=max_error, min_psnr=min_psnr)
    if rival is choice:
        return choice
    bound = choice.max_error
    if min_psnr is not None:
        bound = max(_estimator_psnr(prof, rival).max_error(min_psnr), 0.0)
    return adopt(prof, rival, label=choice.label, max_error=bound, min_psnr=choice.min_psnr)


def threshold_selections(prof, labels=LABELS) -> list[Selection]:
    """The labelled choices at the profile's levels (``settings.levels``), predicted only:
    ``psnr`` (the default): predicted PSNR ≥ 45, 40, 35, 30 dB against the original
    (:data:`rrcache.model.psnr.DEFAULT_LEVELS_DB`; :meth:`select_psnr`); ``relative``: the
    paper's ε1…ε4, error thresholds spread over the errors seen (:func:`rrcache.model.thresholds`)."""
    from rrcache.model import select as model_select, thresholds
    from rrcache.model.psnr import DEFAULT_LEVELS_DB

    if prof.settings.levels == "psnr":
        return [select_psnr(prof, db).replace(label=label) for label, db in zip(labels, DEFAULT_LEVELS_DB)]
    levels = [float(t) for t in thresholds(prof.table, len(labels))]
    return [_amortized_or(prof, _with_sets(prof, adopt(prof, model_select(prof.table, level), label=label,
                                                          max_error=level), max_error=level), max_error=level)
            for label, level in zip(labels, levels)]


def select_psnr(prof, min_psnr: float) -> Selection:
    """The choice predicted fastest whose predicted PSNR against the original is ≥
    ``min_psnr`` dB (:func:`rrcache.model.psnr.select_min_psnr`), from the models only; its
    ``max_error`` is the largest error its node may have at that PSNR."""
    from rrcache.model.psnr import select_min_psnr

    try:
        level = float(min_psnr)
    except (TypeError, ValueError):
        level = float("nan")
    if not math.isfinite(level):
        raise RRCacheError(f"{min_psnr!r} is not a PSNR", "--min-psnr", hint="give decibels, e.g. 40")
    if prof.verdict is not None:
        return Selection.original(float(prof.original_ms), algorithm=prof.algorithm, min_psnr=level,
                                  max_error=0.0, exact=True, predicted_psnr_uncertainty=0.0)
    fits = prof.psnr_fits()
    choice = select_min_psnr(prof.table, fits, level)
    bound = 0.0
    if choice.parts:
        bound = max(fits[prof.table.node_ids.index(choice.node)].max_error(level), 0.0)
    choice = _with_sets(prof, adopt(prof, choice, min_psnr=level, max_error=bound), min_psnr=level)
    # an amortized estimator predicted faster at this level stands instead
    return _amortized_or(prof, choice, min_psnr=level)


def adopt(prof, choice: Selection, **changes) -> Selection:
    """``choice`` (from the models) as this profile runs it: its algorithm, the nodes'
    expressions, the predictions' uncertainty (:meth:`predictions`) and ``changes`` (label,
    max_error …)."""
    chosen = choice.with_texts(prof.texts()).replace(algorithm=prof.algorithm, **changes)
    return chosen.replace(**predictions(prof, chosen))


def predictions(prof, choice: Selection) -> dict:
    """The predicted PSNR of ``choice`` with its uncertainty (the PSNR rule's residual, the
    error model's leave-one-out error and the error's spread over the training frames:
    :func:`rrcache.model.psnr.prediction_uncertainty`), the predicted speed-up's range
    (:func:`speedup_range`: the performance fit's residual and the timing noise), ``exact`` (the original's image: PSNR ∞, kept as null) and ``visible_artifacts``
    (predicted PSNR below 30 dB)."""
    from rrcache.model.psnr import VISIBLE_DB, predicted_psnr

    if not choice.parts or not choice.predicted_error > 0:  # exact: PSNR ∞ (null in JSON)
        return {"predicted_psnr": None, "predicted_psnr_uncertainty": 0.0, "exact": True,
                "visible_artifacts": False,
                "predicted_speedup_range": (choice.predicted_speedup, choice.predicted_speedup)}
    if isinstance(choice.parts[0], AmortizedLoop):
        runs = prof.estimator(choice.parts[0].estimator).runs(choice.parts[0].history)
        value, spread = predicted_psnr(_estimator_psnr(prof, choice), choice.predicted_error)
        rms = float((runs.time_fit if runs is not None else {}).get("rms") or 0.0)
    else:
        trained = [n.id for n in prof.trained_nodes]
        i = trained.index(choice.node)
        fit = prof.psnr_fits()[i]
        value, spread = predicted_psnr(fit, choice.predicted_error, *_psnr_terms(prof, i, choice.period, fit))
        rms = float(prof.trained_nodes[i].perf_fit.get("residual_rms") or 0.0)
    ms = float(choice.predicted_ms)
    span = speedup_range(float(prof.original_ms), ms, rms, float(prof.timing_noise or 0.0))
    out = {"predicted_psnr": value if math.isfinite(value) else None,
           "predicted_psnr_uncertainty": spread if math.isfinite(spread) else None, "exact": False,
           "visible_artifacts": bool(value < VISIBLE_DB), "predicted_speedup_range": span}
    cal = prof.calibrated()
    if cal.points and not isinstance(choice.parts[0], AmortizedLoop) and math.isfinite(value):
        # psnr_fits carries the node's calibration shift: say how much, and widen the ± by its spread
        out["calibration_db"] = cal.shift(choice.node)
        if math.isfinite(spread):
            out["predicted_psnr_uncertainty"] = math.hypot(spread, cal.spread_for(choice.node))
    return out


def _psnr_terms(prof, i: int, period, fit) -> tuple[float, float]:
    """(leave-one-out dB, frame spread) of trained node ``i`` at refresh ``period``
    (:func:`rrcache.model.psnr.prediction_uncertainty`): the spread of the training run at the
    trained period nearest ``period``."""
    from rrcache.model.psnr import loo_db

    node = prof.trained_nodes[i]
    if node.id not in prof._loo:
        prof._loo[node.id] = loo_db(node.periods, node.errors, fit.b)
    spread = 0.0
    if node.frame_spreads and len(node.frame_spreads) == len(node.periods) and period is not None:
        j = min(range(len(node.periods)), key=lambda k: abs(node.periods[k] - period))
        # the error's drift over the session moves the prediction only through the frames the
        # error runs did not cover (docs/levels.md)
        spread = float(node.frame_spreads[j]) * prof.uncovered_share()
    return prof._loo[node.id], spread


def front_candidates(prof, choice: Selection) -> list[Selection]:
    """The options that could stand in for ``choice`` at its level when it measures slower
    than the original: the predicted Pareto front's points admissible at the level (error ≤
    ``max_error``, or predicted PSNR ≥ ``min_psnr``) and predicted faster than the original,
    fastest first, ``choice`` itself left out."""
    from rrcache.model import pareto_front
    from rrcache.model.amortize import front as amortized_front

    fits = prof.psnr_fits() if choice.min_psnr is not None else None
    ids = [n.id for n in prof.trained_nodes]
    out = []
    for point in pareto_front(prof.table):
        if point.node is None or not point.predicted_ms < prof.original_ms or point.period < 2:
            continue
        if fits is not None:
            ok = fits[ids.index(point.node)].predict(point.predicted_error) >= choice.min_psnr
        else:
            ok = point.predicted_error <= (choice.max_error or 0.0)
        if not ok:
            continue
        option = prof.table.option(ids.index(point.node) * prof.table.max_period + point.period - 1)
        if option.key == choice.key:
            continue
        out.append(adopt(prof, option, label=choice.label, max_error=choice.max_error, min_psnr=choice.min_psnr))
    out += [adopt(prof, option, label=choice.label, max_error=choice.max_error, min_psnr=choice.min_psnr)
            for option in amortized_front(_admissible(prof, max_error=choice.max_error if fits is None else None,
                                                           min_psnr=choice.min_psnr))
            if option.key != choice.key]
    return sorted(out, key=lambda s: s.predicted_ms)


def amortized_options(prof) -> list[Selection]:
    """Every (estimator, history, m, λ) the trained estimators' models predict
    (:meth:`rrcache.model.amortize.AmortizeModel.options`: the blend history's and, where
    they fit and were trained, the slots history's), on the same error-against-time axes as
    the cached nodes' options."""
    if not prof.original_ms:
        return []
    out = []
    for est in prof.estimators:
        for model in est.models():
            out.extend(model.options(float(prof.original_ms)))
    return out


def _admissible(prof, max_error=None, min_psnr=None) -> list[Selection]:
    from rrcache.model.amortize import admissible

    if max_error is None and min_psnr is None:
        return []
    return admissible(amortized_options(prof, ), float(prof.original_ms or 0.0), max_error, min_psnr)


def _rival(prof, choice: Selection, max_error=None, min_psnr=None) -> Selection:
    """``choice`` (the nodes' best at a level), or the amortized option predicted faster
    than it at the same level."""
    options = _admissible(prof, max_error, min_psnr)
    if options and options[0].predicted_ms < choice.predicted_ms:
        return options[0]
    return choice


def _estimator_psnr(prof, choice: Selection):
    part = choice.parts[0]
    model = prof.estimator(part.estimator).model(part.history)
    return model.psnr if model is not None else None


def speedup_range(original_ms: float, predicted_ms: float, residual_ms: float, noise: float) -> tuple:
    """The range of a predicted speed-up ``original_ms / predicted_ms``: the performance fit's
    residual (ms) on the predicted time and the timing noise (the original's relative spread
    over repeated timings of the same frame, :attr:`Profile.timing_noise`), in quadrature, as a
    relative error k of the predicted time: (S / (1 + k), S / (1 − k)); () when k ≥ 1 (no finite
    upper bound). On a loaded machine (noise 0.37) a fresh-clone Marble e1 was predicted 2.9×
    (4.58× before the original's time was taken from the same timing runs) and measured 2.48×:
    the range with the noise, 2.1–4.9×, holds it; the residual's alone did not.

    >>> [round(x, 2) for x in speedup_range(100.0, 50.0, 5.0, 0.0)]
    [1.82, 2.22]
    >>> [round(x, 2) for x in speedup_range(100.0, 50.0, 5.0, 0.3)]
    [1.52, 2.92]
    >>> speedup_range(100.0, 50.0, 60.0, 0.0)
    ()
    """
    if not predicted_ms > 0 or not math.isfinite(original_ms):
        return ()
    k = math.hypot(residual_ms / predicted_ms, noise if math.isfinite(noise) else 0.0)
    if k >= 1.0:
        return ()
    return (original_ms / (predicted_ms * (1.0 + k)), original_ms / (predicted_ms * (1.0 - k)))


# ---------------------------------------------------------------------- the declared shape
