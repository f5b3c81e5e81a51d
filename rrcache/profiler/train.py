"""Training: the measurements behind the error and performance models (main paper §4.2–4.3).

:func:`train` fills a :class:`~rrcache.profiles.store.ProfileStore`, skipping whatever it already
holds, and fits the models from what is stored:

0. **Order and plan.** The nodes worth training, in the order of :mod:`rrcache.profiler.order`
   (too-cheap nodes skipped, the rest diversity first). The original is timed at full resolution
   on the timing frames, and the windows and error frames of :mod:`rrcache.profiler.plan` are
   chosen (once; kept in the store). With ``algorithm="auto"`` the ceiling's per-algorithm
   limits decide which algorithm serves the whole profile when they differ beyond their noise;
   else the three-pass and two-pass variants of the first node are timed beside the original
   (:func:`choose_algorithm`) and the faster serves when the difference exceeds its noise, else
   the higher ceiling (kept in the plan too, with the reason).
1. **Reference frames.** The original shader over the training frames inside the error window
   (full pixel density), rendered once and kept in memory for the run.
2. **Error runs.** Per node one :class:`~rrcache.harness.cached.CachedRenderer` inside the same
   window serves every period (``.period = Δn; .reset()``): the training frames are rendered in
   order from an empty cache and each frame's mean RGB L2 error over covered pixels, PSNR, hits
   and misses recorded. A run's error is the mean over the frames after the first (which has no
   cache).
3. **Timing.** At the session's full resolution the original is timed once on the L timing frames
   (spread evenly over the session), then every node at each timing period: per timing frame f
   the original renders f, then the variant renders f − 1 untimed (an empty cache filled once)
   and f timed. The refresh schedule makes a frame's hit/miss mix independent of how long the
   cache has run, so one warm-up frame gives the steady-state mix at two renders per sample,
   and alternating with the original per frame lets machine noise touch both alike.
4. **Overhead.** The cached pipeline's frame time with almost nothing covered: the costliest
   trained node's variant rendered at 8×8 (geometry still processed, every pass issued), median
   over the timing frames. DESIGN §3: with constant coverage h + m is nearly constant and the
   hit/miss/overhead system is rank-deficient, so the overhead is measured, not solved for.
5. **Fits** through :mod:`rrcache.model`: α, λ per node; μ over every node's hit rates in the
   timing runs (whole frames: the error window's edges miss more than a frame's, as pixels
   reproject from outside it); t_hit and t_miss per node given the overhead.

The budget (``settings.budget_s``) counts the seconds of every stored run, earlier invocations
included: once spent, no new node is started (a started node is finished); the nodes never
started are reported as untrained. Every run is committed as it completes, so an interruption
(SIGINT, a kill) loses at most the run in flight; ``KeyboardInterrupt`` propagates after the
store is left consistent.

>>> result = train(work, session, settings.resolved(session), store)       # doctest: +SKIP
>>> result.trained[:2], result.hit_fit.mu                                    # doctest: +SKIP
(['n102', 'n115'], 0.93)
"""
from __future__ import annotations

import statistics
import time
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from rrcache.errors import RRCacheError
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.metrics import mean_l2, psnr
from rrcache.harness.renderer import Renderer
from rrcache.pipeline import ShaderWork, variant_for
from rrcache.model.ceiling import Ceiling
from rrcache.profiler.ceiling import measure_ceiling
from rrcache.profiler.filters import choose_filter, steps as filter_steps
from rrcache.runtime.cache import DEFAULT_FILTER
from rrcache.profiler.order import (TrainingOrder, cost_filter, dependency_map, diversity_order, per_frame_uniforms,
                                    shader_inputs, signature)
from rrcache.profiler.plan import (Plan, algorithm_by_ceiling, algorithm_by_timing, make_plan as _make_plan,
                                   rendered_frames, restart, run_order)
from rrcache.profiles.settings import TrainingSettings
from rrcache.profiles.store import ErrorFrame, ErrorRun, ProfileStore, TimingFrame

#: a ceiling below ``min_gain`` but within this factor of it is measured a second time
CEILING_RECHECK = 1.3
#: the resolution of the overhead measurement
OVERHEAD_SIZE = (8, 8)
PSNR_CAP = 100.0


@dataclass
class ProgressEvent:
    """Sent to the ``progress`` callback: ``stage`` (``reference``, ``error``, ``timing``,
    ``overhead``, ``validate``), frames rendered ``done`` of ``total`` planned (the plan shrinks
    when the budget stops the training), and a short ``detail`` (node and period)."""

    stage: str
    done: int
    total: int
    detail: str = ""


ProgressFn = Callable[[ProgressEvent], None]


class _Meter:
    def __init__(self, progress: Optional[ProgressFn], total: int):
        self.progress, self.total, self.done = progress, max(0, total), 0

    def step(self, stage: str, detail: str = "", n: int = 1) -> None:
        self.done += n
        self.total = max(self.total, self.done)
        if self.progress is not None:
            self.progress(ProgressEvent(stage, self.done, self.total, detail))

    def shrink(self, by: int, stage: str = "train", detail: str = "budget spent") -> None:
        self.total = max(self.done, self.total - by)
        if self.progress is not None:
            self.progress(ProgressEvent(stage, self.done, self.total, detail))

    def grow(self, by: int) -> None:
        self.total += by


@dataclass
class TrainingResult:
    """What training produced: ``order`` (every node id: the training order, then the skipped
    nodes), ``trained`` (ids with every error and timing run stored), ``untrained`` (the rest),
    ``notes`` (id → why an untrained node was not trained), ``plan`` (the windows), the fits (``error_fits`` and
    ``perf_fits`` by node id, ``hit_fit``), ``overhead_ms``, ``original_ms`` (median original
    frame time at full resolution), ``pixels`` (mean covered pixels M at full resolution),
    ``counts`` (runs computed and skipped by this invocation), ``wall_s`` (this invocation) and
    ``spent_s`` (every stored run's seconds)."""

    order: list[str]
    trained: list[str]
    untrained: list[str]
    error_fits: dict = field(default_factory=dict)
    perf_fits: dict = field(default_factory=dict)
    hit_fit: object = None
    overhead_ms: float = float("nan")
    original_ms: float = float("nan")
    pixels: float = 0.0
    counts: dict = field(default_factory=dict)
    wall_s: float = 0.0
    spent_s: float = 0.0
    budget_stopped: bool = False
    notes: dict = field(default_factory=dict)
    plan: Optional[Plan] = None
    #: the measured ceiling (:mod:`rrcache.profiler.ceiling`), and whether it stopped the profile
    #: before training (nothing can reach ``settings.min_gain``)
    ceiling: Optional[Ceiling] = None
    stopped: bool = False
    #: the relative noise of the original's repeated timings (:func:`_original_noise`)
    noise: float = 0.0


def training_order(work: ShaderWork, session, settings: TrainingSettings) -> TrainingOrder:
    """The nodes to train in order, and the skipped ones with their reasons
    (:mod:`rrcache.profiler.order`)."""
    nodes = [n for _, n in sorted(enumerate(work.table.nodes), key=lambda item: (-item[1].cost, item[0]))]
    # a fixed algorithm trains only the nodes it can cache ('auto' chooses among
    # AUTO_CANDIDATES, which every listed node allows)
    algorithm = settings.fixed_algorithm
    invalid = {n.id: f"{algorithm} cannot cache it: {n.invalid[algorithm]}"
               for n in nodes if algorithm in getattr(n, "invalid", {})}
    if settings.algorithm != "auto":
        nodes = [n for n in nodes if n.id not in invalid]
    else:
        invalid = {}
    keep, skipped = cost_filter(nodes, settings.min_saving)
    skipped.update(invalid)
    changing = per_frame_uniforms(session)
    deps = dependency_map(work.table.shader.unit)
    inputs = shader_inputs(work.prepared.source)
    signatures = {n.id: signature(n.node, deps, inputs, changing) for n in keep}
    return TrainingOrder(diversity_order(keep, signatures), skipped, signatures)


def make_plan(work: ShaderWork, session, settings: TrainingSettings, original_ms: float, frames=None) -> Plan:
    """Choose the error and timing windows and the error frames (:func:`rrcache.profiler.plan.make_plan`:
    sized from the original's CPU time, which load moves little) for a shader whose full frame
    measured ``original_ms``. ``frames`` is ignored (the plan chooses the error frames)."""
    return _make_plan(work, session, settings, original_ms, Renderer)


def timing_frame_indices(session_frames: int, count: int) -> list[int]:
    """``count`` frames spread evenly over ``1 .. session_frames − 1`` (each timed frame needs the
    one before it to warm the cache).

    >>> timing_frame_indices(150, 4)
    [1, 50, 100, 149]
    >>> timing_frame_indices(5, 12)
    [1, 2, 3, 4]
    """
    if session_frames < 2:
        return []
    count = max(1, min(count, session_frames - 1))
    return sorted({int(round(x)) for x in np.linspace(1, session_frames - 1, count)})


def _error_run(cached: CachedRenderer, node_id: str, period: int, refs: list, meter: _Meter) -> tuple[ErrorRun, list]:
    """One error run of ``node_id`` at ``period`` over the frames of ``refs`` (the original's
    reference frames): each segment of consecutive frames from an empty cache, after the warm-up
    frames that give the cache at its first frame what a run from frame 0 holds there
    (:func:`rrcache.profiler.plan.run_order`). The run's figures are over the compared frames
    but frame 0 (which has no cache)."""
    start = time.perf_counter()
    cached.period = period
    by_index = {r.index: r for r in refs}
    frames: list[ErrorFrame] = []
    for segment in run_order([r.index for r in refs], period):
        restart(cached, segment[0][0])
        for index, compared in segment:
            got = cached.render_frame(index)
            meter.step("error", f"{node_id} Δn={period}")
            if not compared:
                continue
            ref = by_index[index]
            err, left_out = mean_l2(got.image, ref.image, ref.mask)
            frames.append(ErrorFrame(ref.index, float(err), min(float(psnr(got.image, ref.image)), PSNR_CAP),
                                     int(got.hits), int(got.misses), int(got.covered_pixels), int(left_out)))
    steady = [f for f in frames if f.frame != 0] or frames
    hits, misses = sum(f.hits for f in steady), sum(f.misses for f in steady)
    run = ErrorRun(node_id, int(period), float(np.mean([f.mean_error for f in steady])),
                   float(np.mean([f.psnr for f in steady])), hits / (hits + misses) if hits + misses else 0.0,
                   hits, misses, sum(f.covered for f in steady), len(frames), time.perf_counter() - start)
    return run, frames


def timed_beside(cached: CachedRenderer, original: Renderer, index: int):
    """(cached frame, original frame) of frame ``index``: the original just before, and the cache
    restarted and filled by frame ``index - 1`` so that frame ``index`` is a steady frame."""
    ref = original.render_frame(index)
    cached.reset()
    cached.render_frame(index - 1)
    return cached.render_frame(index), ref


def _timing_run(cached: CachedRenderer, original: Renderer, node_id: str, period: int, indices: list[int],
                meter: _Meter) -> list[TimingFrame]:
    cached.period = period
    out = []
    for index in indices:
        got, ref = timed_beside(cached, original, index)
        out.append(TimingFrame(index, int(got.hits), int(got.misses), float(got.ms), float(ref.ms)))
        meter.step("timing", f"{node_id} Δn={period}", 3)
    return out


#: what ``algorithm="auto"`` chooses from: one-pass is left out (its dynamic branch runs in
#: lock-step across SIMD lanes on llvmpipe: 1.1x on Marble, never the fastest)
AUTO_CANDIDATES = ("three-pass", "two-pass")


def choose_algorithm(work: ShaderWork, session, settings: TrainingSettings, node_id: str, original: Renderer,
                     timing: list[int], window, meter: _Meter) -> tuple[str, dict, dict]:
    """Time the :data:`AUTO_CANDIDATES` variants of ``node_id`` on the timing frames at the
    middle timing period, each frame beside the original as the timing runs are, and return the
    faster median, each one's median time as a fraction of the original's, and each one's
    per-frame fractions (whether their difference exceeds its noise is
    :func:`rrcache.profiler.plan.algorithm_by_timing`'s to say; profiles decide from the
    ceiling's limits first, :func:`rrcache.profiler.plan.algorithm_by_ceiling`). The three-pass
    algorithm is the paper's choice for GPUs, where a pass over the geometry is cheap and
    multiple render targets are not; on llvmpipe the geometry is set up on one thread, and the
    two-pass variant, one pass over the geometry fewer, measured 8-10% faster on Marble."""
    period = settings.timing_periods[len(settings.timing_periods) // 2]
    full = tuple(int(v) for v in session.resolution)
    fractions, ratios = {}, {}
    for algorithm in AUTO_CANDIDATES:
        variant = variant_for(work, node_id, algorithm)
        with CachedRenderer(variant, session, work.prepared, full, period=period, window=window,
                            color_format=settings.timing_format, **settings.cache_options()) as cached:
            frames = _timing_run(cached, original, f"{node_id} {algorithm}", period, timing, meter)
        ratios[algorithm] = [f.ms / f.original_ms for f in frames if f.original_ms > 0]
        fractions[algorithm] = float(statistics.median(ratios[algorithm]))
    return min(fractions, key=fractions.get), fractions, ratios


def _node_complete(store: ProfileStore, node_id: str, settings: TrainingSettings) -> bool:
    return (all(store.has_error_run(node_id, p) for p in settings.periods)
            and all(store.has_timing_run(node_id, p) for p in settings.timing_periods))


def _node_started(store: ProfileStore, node_id: str, settings: TrainingSettings) -> bool:
    return (any(store.has_error_run(node_id, p) for p in settings.periods)
            or any(store.has_timing_run(node_id, p) for p in settings.timing_periods))


def train(work: ShaderWork, session, settings: TrainingSettings, store: ProfileStore,
          progress: Optional[ProgressFn] = None, clock: Callable[[], float] = time.perf_counter) -> TrainingResult:
    """Measure what ``store`` lacks for ``work`` over ``session`` with the *resolved*
    ``settings`` (:meth:`TrainingSettings.resolved`), then fit the models (see the module
    docstring). Returns a :class:`TrainingResult`."""
    start = clock()
    if not work.table.nodes:
        raise RRCacheError("the shader has no cacheable node to train", str(work.shader.path or "<shader>"),
                           hint="'rrcache nodes SHADER --all' lists the values left out and why")
    order = training_order(work, session, settings)
    if not order.nodes and settings.algorithm != "auto" and any(
            settings.fixed_algorithm in getattr(n, "invalid", {}) for n in work.table.nodes):
        raise RRCacheError(f"no listed node of the shader can be cached with {settings.fixed_algorithm}",
                           str(work.shader.path or "<shader>"),
                           hint="'rrcache nodes SHADER' says why in its algorithms column; profile with "
                                "--algorithm auto, three-pass or two-pass")
    ids = [n.id for n in order.nodes]
    train_frames: list[int] = []  # the plan's error frames, once the plan is known
    timing = timing_frame_indices(session.frames, settings.timing_frames)
    full = tuple(int(v) for v in session.resolution)

    todo_error = {i: [p for p in settings.periods if not store.has_error_run(i, p)] for i in ids}
    todo_timing = {i: [p for p in settings.timing_periods if not store.has_timing_run(i, p)] for i in ids}
    skipped_error = sum(len(settings.periods) - len(v) for v in todo_error.values())
    skipped_timing = sum(len(settings.timing_periods) - len(v) for v in todo_timing.values())
    store.count_skipped(skipped_error, skipped_timing)

    need_refs = any(todo_error.values())
    need_ref_timing = not store.reference_timing()
    need_overhead = store.overhead() is None

    def training_total() -> int:
        return ((len(train_frames) if need_refs else 0)
                + sum(rendered_frames(train_frames, p) for v in todo_error.values() for p in v)
                + sum(len(v) * 3 * len(timing) for v in todo_timing.values())
                + (len(timing) if need_overhead else 0))

    # the training is planned once the ceiling has said whether it happens, and for which nodes
    meter = _Meter(progress, len(timing) if need_ref_timing else 0)
    budget_stopped = False
    notes = dict(order.skipped)

    original: Optional[Renderer] = None
    timed_original: Optional[Renderer] = None
    ceiling: Optional[Ceiling] = None
    fmt = settings.timing_format
    try:
        original = Renderer(work.prepared, session, full, color_format=fmt)
        if need_ref_timing:
            rows = []
            for index in timing:
                got = original.render_frame(index)
                rows.append((index, got.ms, got.covered_pixels))
                meter.step("reference", f"timing frame {index}")
            store.add_reference_timing(rows)
        stored_plan = store.plan()
        if stored_plan is None:
            plan = make_plan(work, session, settings, min(ms for _, ms, _ in store.reference_timing()))
            store.set_plan(plan.to_json())
        else:
            plan = Plan.from_json(stored_plan)
        train_frames[:] = plan.error_frames(settings.frames)
        if plan.timing_window is not None:
            original.release()
            original = Renderer(work.prepared, session, full, window=plan.timing_window, color_format=fmt)
        timed_original = original
        if order.nodes and len(timing) > 0:
            ceiling = _ceiling(work, session, settings, store, plan, order.nodes[0], timing, meter)
            if settings.min_gain > 0 and not ceiling.reaches:
                # nothing can pay: answer now, before any training
                if plan.algorithm is None:
                    plan.algorithm = ceiling.algorithm if settings.algorithm == "auto" else settings.algorithm
                    store.set_plan(plan.to_json())
                meter.shrink(meter.total - meter.done, "ceiling", f"{ceiling.speedup:.2f}× < {settings.min_gain:.2f}×: stop")
                notes.update({n.id: f"not trained: the ceiling ({ceiling.speedup:.2f}×) is below --min-gain "
                                    f"{settings.min_gain:.2f}×" for n in order.nodes})
                result = TrainingResult(order=ids + [i for i in _skipped_ids(work, order)], trained=[],
                                        untrained=ids + _skipped_ids(work, order), notes=notes, plan=plan,
                                        ceiling=ceiling, stopped=True)
                fit_models(store, settings, result)
                result.counts = store.counts()
                result.wall_s = clock() - start
                result.spent_s = store.spent_s()
                return result
            pruned = _prune(work, order, ceiling, settings)
            for nid, why in pruned.items():
                notes[nid] = why
                todo_error[nid], todo_timing[nid] = [], []
            order.nodes = [n for n in order.nodes if n.id not in pruned]
            order.skipped.update(pruned)
            ids = [n.id for n in order.nodes]
            if pruned and progress is not None:
                progress(ProgressEvent("ceiling", meter.done, meter.total, f"{len(pruned)} nodes cannot pay"))
        meter.grow(training_total())
        if plan.algorithm is None:
            if settings.algorithm == "auto" and order.nodes and len(timing) > 0:
                # the ceiling's per-algorithm limits decide when they differ beyond their noise;
                # else a timing of the first node, when its difference exceeds its noise
                chosen, why = algorithm_by_ceiling(ceiling.algorithms if ceiling is not None else {},
                                                   ceiling.noise if ceiling is not None else 0.0)
                if chosen is None:
                    meter.grow(len(AUTO_CANDIDATES) * 3 * len(timing))
                    _, plan.algorithm_times, ratios = choose_algorithm(
                        work, session, settings, order.nodes[0].id, timed_original, timing, plan.timing_window, meter)
                    chosen, why = algorithm_by_timing(ratios, ceiling.algorithm if ceiling is not None
                                                      else settings.fixed_algorithm)
                plan.algorithm, plan.algorithm_reason = chosen, why
            else:
                plan.algorithm = settings.fixed_algorithm
            store.set_plan(plan.to_json())
        algorithm = plan.algorithm
        if plan.filter is None:
            if settings.filter == "auto" and order.nodes and len(timing) > 0:
                meter.grow(filter_steps(settings, timing))
                plan.filter, plan.filter_times = choose_filter(work, session, settings, order.nodes[0].id, algorithm,
                                                               timed_original, timing, plan, meter, _timing_run)
            else:
                plan.filter = DEFAULT_FILTER if settings.filter == "auto" else settings.filter
            store.set_plan(plan.to_json())
        # every variant compiled for this profile from here on (training, validation, the sets,
        # the selections' files) uses the profile's filter
        work.filter = plan.filter

        refs = []
        if need_refs:
            with Renderer(work.prepared, session, settings.resolution, window=plan.error_window) as renderer:
                for index in train_frames:
                    refs.append(renderer.render_frame(index))
                    meter.step("reference", f"frame {index}")
            store.add_reference({r.index: r.covered_pixels for r in refs})

        for node in order.nodes:
            nid = node.id
            if not todo_error[nid] and not todo_timing[nid]:
                continue
            if not _node_started(store, nid, settings) and store.spent_s() >= settings.budget_s:
                budget_stopped = True
                meter.shrink(sum(rendered_frames(train_frames, p) for p in todo_error[nid])
                             + len(todo_timing[nid]) * 3 * len(timing))
                continue
            # one compiled variant serves every period: the period is the runtime's (set per run)
            variant = variant_for(work, nid, algorithm)
            if todo_error[nid]:
                built = clock()
                with CachedRenderer(variant, session, work.prepared, settings.resolution,
                                    period=todo_error[nid][0], window=plan.error_window,
                                    **settings.cache_options()) as cached:
                    compile_s = clock() - built
                    for period in todo_error[nid]:
                        run, frames = _error_run(cached, nid, period, refs, meter)
                        run.wall_s += compile_s
                        compile_s = 0.0
                        store.add_error_run(run, frames)
            if todo_timing[nid]:
                built = clock()
                with CachedRenderer(variant, session, work.prepared, full, period=todo_timing[nid][0],
                                    window=plan.timing_window, color_format=fmt, **settings.cache_options()) as cached:
                    compile_s = clock() - built
                    for period in todo_timing[nid]:
                        t0 = clock()
                        frames = _timing_run(cached, timed_original, nid, period, timing, meter)
                        store.add_timing_run(nid, period, frames, clock() - t0 + compile_s)
                        compile_s = 0.0
            _plan_within_budget(meter, store, settings, order.nodes, node, todo_error, todo_timing,
                                len(train_frames), len(timing))
    finally:
        if original is not None:
            original.release()

    trained = [i for i in ids if _node_complete(store, i, settings)]
    for i in ids:
        if i not in trained:
            notes[i] = "not reached within the training budget (--budget)"
    if trained and need_overhead:
        _measure_overhead(work, session, settings, store, trained[0], timing, meter, plan.algorithm)

    skipped_ids = _skipped_ids(work, order)
    result = TrainingResult(order=ids + skipped_ids, trained=trained,
                            untrained=[i for i in ids + skipped_ids if i not in trained],
                            budget_stopped=budget_stopped, notes=notes, plan=plan, ceiling=ceiling)
    fit_models(store, settings, result)
    result.counts = store.counts()
    result.wall_s = clock() - start
    result.spent_s = store.spent_s()
    return result


def _plan_within_budget(meter: _Meter, store: ProfileStore, settings: TrainingSettings, nodes, last, todo_error,
                        todo_timing, n_frames: int, n_timing: int) -> None:
    """After each trained node, plan only the nodes the budget is expected to reach (at the mean
    seconds per node stored so far), so that the progress's total and ETA are those of the run
    that will happen, not of every node in the order."""
    done_nodes = sum(1 for n in nodes if _node_complete(store, n.id, settings))
    spent = store.spent_s()
    if not done_nodes or spent <= 0:
        return
    per_node_s = spent / done_nodes
    index = [n.id for n in nodes].index(last.id)
    rest = [n.id for n in nodes[index + 1:] if todo_error[n.id] or todo_timing[n.id]]
    fit = max(0, int((settings.budget_s - spent) / per_node_s) + 1) if per_node_s > 0 else len(rest)
    per_node = len(settings.periods) * n_frames + len(settings.timing_periods) * 3 * n_timing
    planned = sum(len(todo_error[n]) * n_frames + len(todo_timing[n]) * 3 * n_timing for n in rest)
    expected = min(len(rest), fit) * per_node
    tail = n_timing if store.overhead() is None else 0  # the overhead measurement still to come
    meter.total = max(meter.done, meter.done + min(planned, expected) + tail)


def _skipped_ids(work: ShaderWork, order: TrainingOrder) -> list[str]:
    return [n.id for n in sorted(work.table.nodes, key=lambda n: -n.cost) if n.id in order.skipped]


def _ceiling(work, session, settings: TrainingSettings, store: ProfileStore, plan: Plan, node, timing, meter) -> Ceiling:
    """The plan's ceiling, measured once (kept in the store's plan; ``min_gain`` is the settings')."""
    if plan.ceiling is not None:
        ceiling = Ceiling.from_json(plan.ceiling)
        ceiling.min_gain = settings.min_gain
        return ceiling
    ref = store.reference_timing()
    pixels = float(np.mean([c for _, _, c in ref])) if ref else 0.0
    algorithms = AUTO_CANDIDATES if settings.algorithm == "auto" else (settings.algorithm,)
    meter.grow(2 * len(algorithms))
    ceiling = measure_ceiling(work, session, settings, node, algorithms, timing, pixels, plan.timing_window,
                              step=lambda detail: meter.step("ceiling", detail))
    if settings.min_gain > 0 and ceiling.speedup < settings.min_gain <= ceiling.speedup * CEILING_RECHECK:
        # near the line a loaded machine decides: measure again and keep the higher ceiling, so
        # that noise does not stop a profile that could pay
        meter.grow(2 * len(algorithms))
        again = measure_ceiling(work, session, settings, node, algorithms, timing, pixels, plan.timing_window,
                                step=lambda detail: meter.step("ceiling", f"again: {detail}"))
        again.wall_s += ceiling.wall_s
        ceiling = max(ceiling, again, key=lambda c: c.speedup)
    plan.ceiling = ceiling.to_json()
    store.set_plan(plan.to_json())
    return ceiling


def _prune(work: ShaderWork, order: TrainingOrder, ceiling: Ceiling, settings: TrainingSettings) -> dict[str, str]:
    """{node id: reason} of the nodes to train whose best case (:meth:`Ceiling.node_speedup` from
    their share of the costliest node's static cost) is below ``settings.min_gain``."""
    if settings.min_gain <= 0 or not order.nodes:
        return {}
    top = max(n.cost for n in work.table.nodes) or 1
    out = {}
    for n in order.nodes[1:]:  # the measured node itself is bounded by the ceiling, which reaches
        best = ceiling.node_speedup(n.cost / top)
        if best < settings.min_gain:
            out[n.id] = (f"its best case ({best:.2f}× with every pixel hitting, from its {n.cost / top:.0%} "
                         f"of the static cost and the measured ceiling) is below --min-gain {settings.min_gain:.2f}×")
    return out


def _measure_overhead(work, session, settings, store, node_id, timing, meter, algorithm: str) -> None:
    variant = variant_for(work, node_id, algorithm)
    times = []
    with CachedRenderer(variant, session, work.prepared, OVERHEAD_SIZE, period=settings.timing_periods[-1],
                        color_format=settings.timing_format, **settings.cache_options()) as cached:
        for index in timing:
            cached.reset()
            cached.render_frame(index - 1)
            times.append(cached.render_frame(index).ms)
            meter.step("overhead", f"{node_id} at {OVERHEAD_SIZE[0]}×{OVERHEAD_SIZE[1]}")
    store.set_overhead(node_id, OVERHEAD_SIZE, len(times), statistics.median(times))


def _original_times(store: ProfileStore, nodes, settings: TrainingSettings) -> dict[int, list[float]]:
    """Per timing frame, every time of the original measured beside the variants of ``nodes``."""
    samples: dict[int, list[float]] = {}
    for nid in nodes:
        for period, frames in store.timing_frames(nid).items():
            if period in settings.timing_periods:
                for f in frames:
                    samples.setdefault(f.frame, []).append(f.original_ms)
    return samples


def _typical_originals(store: ProfileStore, nodes, settings: TrainingSettings) -> dict[int, float]:
    """Per timing frame, the median of the original's times measured beside the variants."""
    return {frame: float(statistics.median(v)) for frame, v in _original_times(store, nodes, settings).items()}


def _original_noise(store: ProfileStore, nodes, settings: TrainingSettings) -> float:
    """The noise of the training's timings: every timing run renders the original on the same
    timing frames, so per frame the spread of its times (1.4826 × MAD / median) is the machine's
    noise; the median over the frames (0 when nothing was timed twice)."""
    samples = _original_times(store, nodes, settings)
    spreads = []
    for values in samples.values():
        if len(values) > 2:
            med = float(np.median(values))
            if med > 0:
                spreads.append(1.4826 * float(np.median(np.abs(np.asarray(values) - med))) / med)
    return float(np.median(spreads)) if spreads else 0.0


def fit_models(store: ProfileStore, settings: TrainingSettings, result: TrainingResult) -> None:
    """Fit α, λ (per trained node), μ (every trained node's hit rates in the timing runs) and
    t_hit, t_miss (per trained node, with the measured overhead) from ``store``, into ``result``.

    Each variant frame time enters the performance fit *relative to the original timed just
    before it on the same frame*: ``ms × typical / original_ms``, ``typical`` being the median of
    every original time of that frame. Other work on a shared machine slows both renders of a
    pair alike, so the ratio keeps what the cache changes and drops most of the noise (on a
    loaded machine single variant times varied 2-3× while their ratios held). The original's
    frame time is the median over the timing frames of ``typical`` (whole frames), else of the
    reference timing."""
    from rrcache.model import fit_error, fit_hit_rate, fit_performance

    overhead = store.overhead()
    result.overhead_ms = float(overhead["ms"]) if overhead else float("nan")
    ref_timing = store.reference_timing()
    if ref_timing:
        result.pixels = float(np.mean([c for _, _, c in ref_timing]))
    typical = _typical_originals(store, result.trained, settings)
    result.noise = _original_noise(store, result.trained, settings)
    # timed in a window, the original's timing-run times are the window's, not a frame's
    windowed = result.plan is not None and result.plan.timing_window is not None
    periods, rates = [], []
    for nid in result.trained:
        runs = [r for r in store.error_runs(nid) if r.period in settings.periods]
        result.error_fits[nid] = fit_error([r.period for r in runs], [r.mean_error for r in runs])
        hits, misses, times = [], [], []
        for period, frames in sorted(store.timing_frames(nid).items()):
            if period not in settings.timing_periods:
                continue
            for f in frames:
                hits.append(f.hits)
                misses.append(f.misses)
                scale = typical[f.frame] / f.original_ms if f.original_ms > 0 else 1.0
                times.append(f.ms * scale)
            counted = sum(f.hits + f.misses for f in frames)
            if counted:
                periods.append(period)
                rates.append(sum(f.hits for f in frames) / counted)
        result.perf_fits[nid] = fit_performance(hits, misses, times,
                                                overhead_ms=result.overhead_ms if overhead else None)
    if periods:
        result.hit_fit = fit_hit_rate(periods, rates)
    if typical and not windowed:
        originals = list(typical.values())
    elif typical and ref_timing:
        # timed in a window: the window's typical original scaled to the whole frame's covered
        # pixels, from the same timing runs as the variants' times. The reference timing (one
        # pass before any node) was measured under other load: on a fresh-clone Marble run it
        # read 207 ms while the timing runs' originals read 134 ms, and the speed-up predicted
        # from it (4.58×) was nearly twice the measured one (2.48×)
        fixed = float(result.ceiling.original_fixed_ms) if result.ceiling is not None else 0.0
        originals = window_to_frame(typical, _window_pixels(store, result.trained, settings),
                                    {frame: covered for frame, _, covered in ref_timing}, fixed)
        originals = originals or [ms for _, ms, _ in ref_timing]
    else:
        originals = [ms for _, ms, _ in ref_timing]
    result.original_ms = float(statistics.median(originals)) if originals else float("nan")


def _window_pixels(store: ProfileStore, nodes, settings: TrainingSettings) -> dict[int, int]:
    """Per timing frame, the covered pixels inside the timing window (hits + misses of the
    timing runs: every run of a frame draws the same geometry)."""
    out: dict[int, int] = {}
    for nid in nodes:
        for period, frames in store.timing_frames(nid).items():
            if period in settings.timing_periods:
                for f in frames:
                    out[f.frame] = max(out.get(f.frame, 0), int(f.hits + f.misses))
    return out


def window_to_frame(window_ms: dict, window_pixels: dict, frame_pixels: dict, fixed_ms: float = 0.0) -> list[float]:
    """The whole frame's time per frame from its time in a window: the fixed per-frame cost
    ``fixed_ms`` (geometry) plus the per-pixel rest scaled from the window's covered pixels to
    the frame's; frames without both pixel counts are left out.

    >>> window_to_frame({1: 52.0}, {1: 1000}, {1: 4000}, fixed_ms=2.0)
    [202.0]
    """
    out = []
    for frame, ms in sorted(window_ms.items()):
        inside, whole = window_pixels.get(frame, 0), frame_pixels.get(frame, 0)
        if inside > 0 and whole > 0:
            fixed = min(max(float(fixed_ms), 0.0), float(ms))
            out.append(fixed + (float(ms) - fixed) * whole / inside)
    return out
