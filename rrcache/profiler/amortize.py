"""Training amortized sampling: the error and timing runs of each estimator, and its models
(Nehab et al. 2007 §6; the models are :mod:`rrcache.model.amortize`).

:func:`train_estimators` runs after the nodes are trained (:mod:`rrcache.profiler.train`), in
the same windows (:mod:`rrcache.profiler.plan`) and with the same algorithm. Each estimator is trained for both histories of the compiler
(:func:`rrcache.compiler.amortize.instance_amortized`): the paper's running ``blend`` at m of
:func:`rrcache.model.amortize.training_samples` (for 16 terms m = 1, 4, 8) and ``slots`` (the
N/m subset sums kept apart) at every m where they fit the payload
(:func:`rrcache.selection.slots_fit`: for 16 terms of one component m = 4 and 8; none for a
prime N or four components), the only m it is offered at, in 8 bits where the range of the
terms is known (:func:`slots_payload`; its runs are stored apart, :func:`store_history`). Per
history:

1. **Error runs.** Per trained m one compiled variant serves every blend (λ is the runtime's
   ``blend``): the training frames are rendered in order from an empty cache at each λ of
   :data:`~rrcache.model.amortize.TRAIN_BLENDS` and compared with the original (the error window
   at full pixel density), as a node's error runs are at each Δn; a run's error is the mean over
   the frames after the first.
2. **Timing.** Each trained m at the session's full resolution on the timing frames (the slots
   write and read N/m times the payload's components: timed, not assumed): the original renders
   frame f, the variant f − 1 (untimed, from an empty cache) and f timed; each variant time is
   taken relative to the original's beside it and scaled by the original's typical frame time,
   so machine load cancels.
3. **Fits.** The history's error model (:func:`rrcache.model.amortize.fit_error`) by nlopt over
   its error runs, the time per evaluated term by least squares through each timed m's median
   relative frame time.

The estimators are trained costliest (most terms) first; the first always, the others while the
training budget (``settings.budget_s``, node runs included) lasts. Every run is stored as it
completes (:mod:`rrcache.profiles.amortize`, keyed by history) and skipped when a profile is
resumed. The slots history adds 2 × 3 error runs and 2 timed m for a 16-term estimator (the blend
history's 3 × 3 and 3).
"""
from __future__ import annotations

import statistics
import time
from typing import Optional

import numpy as np

from rrcache.errors import GLSLError, RRCacheError
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.metrics import mean_l2, psnr
from rrcache.harness.renderer import Renderer
from rrcache.compiler.amortize import HISTORIES
from rrcache.model.amortize import TRAIN_BLENDS, fit_amortized_time, fit_error, training_samples
from rrcache.profiler.plan import restart, run_order
from rrcache.profiler.train import PSNR_CAP, ProgressEvent, ProgressFn, timed_beside, timing_frame_indices
from rrcache.profiles import amortize as data
from rrcache.profiles.amortize import EstimatorProfile, HistoryRuns
from rrcache.selection import PAYLOAD_COMPONENTS
from rrcache.runtime import DEFAULT_PERIOD


def _record(est) -> EstimatorProfile:
    """The estimator's record; its text as the user wrote it (``for (int i = 0; i < 16; i++)``,
    not the inliner's ``_rr_i_22``), as ``rrcache nodes --json`` lists it."""
    from rrcache.analysis.estimators import display_name

    return EstimatorProfile(est.id, est.line, est.column, int(est.samples), display_name(est.text),
                            components=int(est.components))


def slots_payload(est) -> str:
    """The slots' payload format the profiler trains and offers: ``u8`` (8 bits,
    :mod:`rrcache.compiler.payload_encoding`) where the range of the estimator's terms is known
    (proven by the analysis or declared with the pragma), else ``f4``."""
    return "u8" if getattr(est, "term_range", None) is not None else "f4"


def store_history(history: str, payload: str = "f4") -> str:
    """The store's history key of a history's runs: ``slots`` runs in 8 bits are kept apart
    (``slots/u8``) from float ones, so a store trained before the 8-bit payload is not read as
    8-bit runs."""
    return history if payload == "f4" else f"{history}/{payload}"


def _slots_record(est) -> Optional[HistoryRuns]:
    """The slots history's record before training: None for an estimator that is not trained at
    all; a note when the slots fit no m (:func:`rrcache.selection.slots_fit`)."""
    if training_samples(int(est.samples), "slots", int(est.components)):
        return HistoryRuns(payload=slots_payload(est))
    n = int(est.samples)
    return HistoryRuns(note=f"not offered: no m < N dividing N = {n} keeps the N/m sums of {int(est.components)} "
                            f"component(s) within the payload's {PAYLOAD_COMPONENTS}")


def estimator_table(work):
    """The estimators of ``work.shader`` (:func:`rrcache.analysis.estimators.find_estimators`),
    None where the analysis cannot take the shader; a malformed ``#pragma rrcache estimator``
    is the user's error and raises (:func:`rrcache.profiler.run.profile` asks first, before any
    training)."""
    from rrcache.analysis.estimators import find_estimators

    try:
        return find_estimators(work.shader)
    except GLSLError:
        raise
    except RRCacheError:
        return None


def train_estimators(work, session, settings, store, result, progress: Optional[ProgressFn] = None,
                     clock=time.perf_counter) -> list[EstimatorProfile]:
    """Train every estimator of ``work`` the budget allows, each history at its m (module
    docstring), and return their records, trained or with a ``note`` saying why not. ``result``
    is the nodes' :class:`~rrcache.profiler.train.TrainingResult` (its plan, algorithm and
    original time)."""
    table = estimator_table(work)
    if table is None:
        return []
    found = sorted(table.estimators, key=lambda e: -int(e.samples))
    records = [_record(e) for e in found]
    if not records:
        return []
    plan = result.plan
    if plan is None or plan.algorithm is None or result.stopped or not result.original_ms > 0:
        for r in records:
            r.note = "not trained: the profile stopped before training (see its verdict)"
        return records
    algorithm = plan.algorithm
    # the nodes' error frames (rrcache.profiler.plan), so that the options compare with theirs
    frames = plan.error_frames(settings.frames)
    timing = timing_frame_indices(session.frames, settings.timing_frames)
    full = tuple(int(v) for v in session.resolution)
    state = {"done": 0, "total": 0}

    def step(detail: str, n: int = 1) -> None:
        state["done"] += n
        state["total"] = max(state["total"], state["done"])
        if progress is not None:
            progress(ProgressEvent("amortize", state["done"], state["total"], detail))

    refs = None
    for k, (est, rec) in enumerate(zip(found, records)):
        if est.samples < 2:
            rec.note = "not trained: a loop of one term has nothing to amortize"
            continue
        if est.components > 4:
            rec.note = f"not trained: its accumulators need {est.components} payload components (at most 4)"
            continue
        spent = store.spent_s() + data.spent_s(store)
        started = any(data.rows(store, est.id, kind, store_history(history, payload))
                      for kind in ("error", "timing") for history in HISTORIES
                      for payload in {"f4", _payload(est, history)})
        if k > 0 and not started and spent >= settings.budget_s:
            rec.note = "not reached within the training budget (--budget)"
            continue
        rec.slots = _slots_record(est)
        plans = [(history, training_samples(int(est.samples), history, int(est.components))) for history in HISTORIES]
        plans = [(history, ms_list) for history, ms_list in plans if ms_list]
        state["total"] += sum(len(ms_list) * (len(TRAIN_BLENDS) * len(frames) + 3 * len(timing))
                              for _, ms_list in plans)
        for history, ms_list in plans:
            target = rec.runs(history)
            payload = _payload(est, history)
            try:
                if refs is None and _missing_errors(store, est.id, ms_list, store_history(history, payload)):
                    state["total"] += len(frames)  # the reference frames, rendered once for all
                    refs = _references(work, session, settings, plan, frames, step)
                try:
                    _runs(work, session, settings, store, plan, algorithm, est, ms_list, refs, timing, full, step,
                          clock, history, payload)
                except _PayloadFallback as err:  # the 8-bit range did not hold on the GPU: train in floats
                    payload = target.payload = "f4"
                    if progress is not None:
                        progress(ProgressEvent("amortize", state["done"], state["total"], f"{err}; slots in 32 bits"))
                    _runs(work, session, settings, store, plan, algorithm, est, ms_list, refs, timing, full, step,
                          clock, history, payload)
            except RRCacheError as err:  # a variant that does not compile or run: say why, go on
                target.note = f"not trained: {err}"
                continue
            _fit(target, store, result.original_ms, est.id, int(est.samples), history, store_history(history, payload))
    return records


class _PayloadFallback(RRCacheError):
    """The renderer kept a float payload where an 8-bit one was asked for (its values left the
    terms' range): no row was stored, the history trains again in floats."""


def _runs(work, session, settings, store, plan, algorithm, est, ms_list, refs, timing, full, step, clock,
          history: str, payload: str) -> None:
    """One history's error and timing runs in ``payload`` (those not stored yet)."""
    _error_runs(work, session, settings, store, plan, algorithm, est, ms_list, refs, step, clock, history, payload)
    _timing_runs(work, session, settings, store, plan, algorithm, est, ms_list, timing, full, step, clock, history,
                 payload)


def _settled(cached, payload: str) -> None:
    """Raise :class:`_PayloadFallback` when ``cached`` (after its first frame) did not keep ``payload``."""
    if cached.payload_dtype != payload:
        raise _PayloadFallback(cached.payload_note or f"the cache kept {cached.payload_dtype}, not {payload}")


def _payload(est, history: str) -> str:
    return slots_payload(est) if history == "slots" else "f4"


def _missing_errors(store, eid: str, ms_list, history: str = "blend") -> bool:
    have = {(r["samples"], round(r["blend"], 6)) for r in data.rows(store, eid, "error", history)}
    return any((m, round(lam, 6)) not in have for m in ms_list for lam in TRAIN_BLENDS)


def _references(work, session, settings, plan, frames, step) -> list:
    refs = []
    with Renderer(work.prepared, session, settings.resolution, window=plan.error_window) as renderer:
        for index in frames:
            refs.append(renderer.render_frame(index))
            step(f"reference frame {index}")
    return refs


def _variant(work, est, algorithm: str, m: int, history: str = "blend", payload: str = "f4"):
    from rrcache.compiler.amortize import instance_amortized

    return instance_amortized(work.shader, est.id, algorithm, samples=m, blend=0.0, history=history,
                              payload_dtype=payload, vertex=work.vertex)


def _label(est, m: int, history: str, payload: str = "f4") -> str:
    return f"{est.id} m={m}" + (" slots" if history == "slots" else "") + ("" if payload == "f4" else f" {payload}")


def _error_runs(work, session, settings, store, plan, algorithm, est, ms_list, refs, step, clock,
                history: str = "blend", payload: str = "f4") -> None:
    key = store_history(history, payload)
    have = {(r["samples"], round(r["blend"], 6)) for r in data.rows(store, est.id, "error", key)}
    for m in ms_list:
        todo = [lam for lam in TRAIN_BLENDS if (m, round(lam, 6)) not in have]
        if not todo:
            continue
        built = clock()
        with CachedRenderer(_variant(work, est, algorithm, m, history, payload), session, work.prepared, settings.resolution,
                            period=DEFAULT_PERIOD, window=plan.error_window, **settings.cache_options()) as cached:
            extra = clock() - built
            for lam in todo:
                start = clock()
                cached.runtime.blend = float(lam)
                errs, psnrs, hits, misses = [], [], 0, 0
                by_index = {r.index: r for r in refs}
                # segments of the error frames, each warmed up by the largest training period
                for segment in run_order(list(by_index), max(settings.periods)):
                    restart(cached, segment[0][0])
                    for index, compared in segment:
                        got = cached.render_frame(index)
                        _settled(cached, payload)
                        step(f"{_label(est, m, history, payload)} λ={lam:g}")
                        if not compared or index == 0:
                            continue  # a warm-up frame, or frame 0 (it has no cache)
                        ref = by_index[index]
                        errs.append(float(mean_l2(got.image, ref.image, ref.mask)[0]))
                        psnrs.append(min(float(psnr(got.image, ref.image)), PSNR_CAP))
                        hits += int(got.hits or 0)
                        misses += int(got.misses or 0)
                errs = errs or [0.0]
                psnrs = psnrs or [PSNR_CAP]
                rate = hits / (hits + misses) if hits + misses else 0.0
                wall = clock() - start + extra
                extra = 0.0
                data.add_rows(store, [(est.id, key, "error", int(m), float(lam), -1, float(np.mean(errs)),
                                       float(np.mean(psnrs)), rate, hits, misses, 0.0, 0.0, wall)])


def _timing_runs(work, session, settings, store, plan, algorithm, est, ms_list, timing, full, step, clock,
                 history: str = "blend", payload: str = "f4") -> None:
    key = store_history(history, payload)
    have = {r["samples"] for r in data.rows(store, est.id, "timing", key)}
    todo = [m for m in ms_list if m not in have]
    if not todo or not timing:
        return
    fmt = settings.timing_format
    with Renderer(work.prepared, session, full, window=plan.timing_window, color_format=fmt) as original:
        for m in todo:
            start = clock()
            with CachedRenderer(_variant(work, est, algorithm, m, history, payload), session, work.prepared, full,
                                period=DEFAULT_PERIOD, window=plan.timing_window, color_format=fmt,
                                **settings.cache_options()) as cached:
                # (the renderer's first frame draws every phase program once, untimed: a phase's
                # first draw compiles it, 100-300 ms on a 1 ms shader)
                out = []
                for index in timing:
                    got, ref = timed_beside(cached, original, index)
                    _settled(cached, payload)
                    out.append((index, got, ref.ms))
                    step(f"{_label(est, m, history, payload)} timing", 3)
            wall = (clock() - start) / max(1, len(out))
            data.add_rows(store, [(est.id, key, "timing", int(m), 0.0, int(index), 0.0, 0.0, 0.0,
                                   int(got.hits or 0), int(got.misses or 0), float(got.ms), float(ref_ms), wall)
                                  for index, got, ref_ms in out])


def _fit(rec, store, original_ms: float, estimator: str, total: int, history: str = "blend",
         key: Optional[str] = None) -> None:
    """The models of one history of an estimator from its stored runs (module docstring, step
    3; ``key``: the store's history key, :func:`store_history`), into ``rec`` (the
    :class:`EstimatorProfile` for ``blend``, its :class:`HistoryRuns` for ``slots``)."""
    errors = data.rows(store, estimator, "error", key or history)
    timed = data.rows(store, estimator, "timing", key or history)
    if not errors or not timed:
        rec.note = "not trained: runs missing"
        return
    rec.run_samples = [int(r["samples"]) for r in errors]
    rec.run_blends = [float(r["blend"]) for r in errors]
    rec.errors = [float(r["mean_error"]) for r in errors]
    rec.psnrs = [float(r["psnr"]) for r in errors]
    rec.hit_rates = [float(r["hit_rate"]) for r in errors]
    ef = fit_error(history, rec.run_samples, rec.run_blends, rec.errors, total)
    # every variant frame relative to the original beside it, on the original's typical time
    hits, covered = 0, 0
    by_m: dict[int, list] = {}
    for r in timed:
        if r["original_ms"] <= 0:
            continue
        rel = float(r["ms"]) / float(r["original_ms"]) * float(original_ms)
        n = int(r["hits"]) * int(r["samples"]) + int(r["misses"]) * total
        hits += int(r["hits"])
        covered += int(r["hits"]) + int(r["misses"])
        by_m.setdefault(int(r["samples"]), []).append((rel, float(n)))
    rec.timed_samples = sorted(by_m)
    rec.timed_ms = [float(statistics.median(v[0] for v in by_m[m])) for m in rec.timed_samples]
    rec.timed_evaluated = [float(statistics.median(v[1] for v in by_m[m])) for m in rec.timed_samples]
    # the line through each m's median (a loaded machine's outlier frames do not pull it)
    tf = fit_amortized_time(rec.timed_evaluated, rec.timed_ms)
    rec.error_fit = ef.to_json()
    rec.time_fit = {"fixed_ms": tf.fixed_ms, "t_sample": tf.t_sample, "rms": tf.rms, "n": tf.n, "quality": tf.quality}
    rec.hit_rate = hits / covered if covered else 0.0
    rec.pixels = covered / max(1, len(timed))
    rec.trained = True
    rec.note = None
