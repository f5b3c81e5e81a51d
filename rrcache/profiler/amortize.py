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


from rrcache import kinds
from rrcache.compiler.amortize import HISTORIES
from rrcache.compiler.slots import PAYLOAD_COMPONENTS
from rrcache.errors import GLSLError, RRCacheError
from rrcache.harness.execute import Bench, LocalExecutor
from rrcache.model.amortize import TRAIN_BLENDS, fit_amortized_time, fit_error, training_samples
from rrcache.profiler.collect import Collector
from rrcache.profiler.events import ProgressFn
from rrcache.profiler.jobs import Meter, RunShapes
from rrcache.profiler.train import timing_frame_indices
from rrcache.profiles.amortize import EstimatorProfile, HistoryRuns


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
                     clock=time.perf_counter, executor=None) -> list[EstimatorProfile]:
    """Train every estimator of ``work`` the budget allows, each history at its m (module
    docstring), and return their records, trained or with a ``note`` saying why not. ``result``
    is the nodes' :class:`~rrcache.profiler.train.TrainingResult` (its plan, algorithm and
    original time). The runs go to ``executor`` (default: in this process), their results to the
    store through the :class:`~rrcache.profiler.collect.Collector`."""
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
    timing = timing_frame_indices(session.frames, settings.timing_frames)
    shapes = RunShapes.of(settings, session, plan, timing)
    meter = Meter(progress)
    own = executor is None
    executor = executor or LocalExecutor(Bench(work, session))
    stage = _Stage(executor, Collector(store), store, shapes, settings, algorithm, meter)
    try:
        for k, (est, rec) in enumerate(zip(found, records)):
            if est.samples < 2:
                rec.note = "not trained: a loop of one term has nothing to amortize"
                continue
            if est.components > 4:
                rec.note = f"not trained: its accumulators need {est.components} payload components (at most 4)"
                continue
            spent = store.spent_s() + store.amortize_spent_s()
            started = any(store.amortize_rows(est.id, kind, store_history(history, payload))
                          for kind in ("error", "timing") for history in HISTORIES
                          for payload in {"f4", _payload(est, history)})
            if k > 0 and not started and spent >= settings.budget_s:
                rec.note = "not reached within the training budget (--budget)"
                continue
            rec.slots = _slots_record(est)
            plans = [(history, training_samples(int(est.samples), history, int(est.components)))
                     for history in HISTORIES]
            for history, ms_list in [(h, m) for h, m in plans if m]:
                target = rec.runs(history)
                payload = _payload(est, history)
                try:
                    try:
                        stage.train(est, ms_list, history, payload)
                    except _PayloadFallback as err:  # the 8-bit range did not hold on the GPU: train in floats
                        payload = target.payload = "f4"
                        meter.step("amortize", f"{err}; slots in 32 bits", 0)
                        stage.train(est, ms_list, history, payload)
                except RRCacheError as err:  # a variant that does not compile or run: say why, go on
                    target.note = f"not trained: {err}"
                    continue
                _fit(target, store, result.original_ms, est.id, int(est.samples), history,
                     store_history(history, payload))
    finally:
        if own:
            executor.close()
    return records


class _PayloadFallback(RRCacheError):
    """The renderer kept a float payload where an 8-bit one was asked for (its values left the
    terms' range): no row was stored, the history trains again in floats."""


class _Stage:
    """One history's runs of an estimator: planned as RunSpecs (the amortize kind's:
    :meth:`rrcache.kinds.amortize.AmortizeKind.training`), those not stored yet executed, each
    result collected; the reference frames of the error runs first."""

    def __init__(self, executor, collector, store, shapes, settings, algorithm, meter):
        self.executor, self.collector, self.store, self.shapes = executor, collector, store, shapes
        self.settings, self.algorithm, self.meter = settings, algorithm, meter
        self.refs = False

    def train(self, est, ms_list, history: str, payload: str) -> None:
        key = store_history(history, payload)
        have = {(r["samples"], round(r["blend"], 6)) for r in self.store.amortize_rows(est.id, "error", key)}
        errors = [(m, [lam for lam in TRAIN_BLENDS if (m, round(lam, 6)) not in have]) for m in ms_list]
        errors = [(m, lams) for m, lams in errors if lams]
        timed_have = {r["samples"] for r in self.store.amortize_rows(est.id, "timing", key)}
        timed = [m for m in ms_list if m not in timed_have] if self.shapes.timing_frames else []
        kind = kinds.get("amortize")
        runs = []
        for measure, spec, run_key in kind.training((est.id, history, payload, errors, timed), self.settings,
                                                     self.algorithm):
            label = _label(est, spec.samples, history, payload) + (f" λ={spec.blend:g}" if measure == "error"
                                                                  else " timing")
            runs.append(self.shapes.run(measure, spec, run_key, label, strict_payload=True))
        if not runs:
            return
        if errors and not self.refs:  # the reference frames, rendered once for every estimator
            runs.insert(0, self.shapes.run("reference", None, ("reference",), "reference frames"))
            self.refs = True
        self.meter.grow(sum(r.cost for r in runs))
        for result in self.executor.run(runs, on_frame=self.meter.on_frame("amortize")):
            if result.spec.measure == "reference":
                continue
            if not result.complete:  # the 8-bit range did not hold: nothing of it stored
                raise _PayloadFallback(next((n for n in result.notes if "outside the range" in n or "beyond" in n),
                                            f"the cache kept {result.payload}, not {payload}"))
            self.collector.add(result)


def _payload(est, history: str) -> str:
    return slots_payload(est) if history == "slots" else "f4"


def _label(est, m: int, history: str, payload: str = "f4") -> str:
    return f"{est.id} m={m}" + (" slots" if history == "slots" else "") + ("" if payload == "f4" else f" {payload}")


def _fit(rec, store, original_ms: float, estimator: str, total: int, history: str = "blend",
         key: Optional[str] = None) -> None:
    """The models of one history of an estimator from its stored runs (module docstring, step
    3; ``key``: the store's history key, :func:`store_history`), into ``rec`` (the
    :class:`EstimatorProfile` for ``blend``, its :class:`HistoryRuns` for ``slots``)."""
    errors = store.amortize_rows(estimator, "error", key or history)
    timed = store.amortize_rows(estimator, "timing", key or history)
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
