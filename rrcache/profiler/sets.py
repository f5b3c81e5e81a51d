"""The profiler's set stage: sets of k ≥ 2 cached nodes predicted from the single-node models,
the few that can improve the front trained, within the profile's budget.

After the single nodes are trained and fitted (:mod:`rrcache.profiler.train`), :func:`train_sets`

1. predicts every set built from the nodes on or near the single-node Pareto front
   (:func:`rrcache.model.sets.search`: pairs, and triples only from the pairs that come within
   :data:`~rrcache.model.sets.TRAIN_MARGIN` of the front: the rule's measured error) with the combination rule of :mod:`rrcache.model.sets`, given which node feeds which
   (:func:`feeds`: inside its expression, or read through a variable) and the layout the
   profile's algorithm compiles to on this shader (:func:`layout_for`);
2. picks at most ``max_sets`` of them (:func:`rrcache.model.sets.pick`: per level the fastest
   admissible set predicted faster than the level's single-node choice, then by gain);
3. trains each like a single node, at its one period combination: an error run over the
   training frames in the error window (mean RGB L2 and PSNR against the original, as the
   nodes' error runs) and a timing run on the timing frames, each frame beside the original
   (its time as a share of the original's, times the profile's original time).

The stage spends at most what is left of ``settings.budget_s`` or :data:`SET_SHARE` of it,
whichever is more (so a profile whose nodes spent the budget still tries its best set), and
stops before a set that would not fit at the seconds the last one took. What it trained is kept
in the store (its ``set_run`` table, :mod:`rrcache.kinds.nodes`), so a resumed profile does not train it again, and in
``profile.json`` (``sets``); :meth:`rrcache.profiles.Profile.select` and ``select_psnr`` then
return a trained set where it was measured faster than the single-node choice at the level, and
validation measures it beside the original as any selection (a set measured slower than the
original falls back along the single-node front).
"""
from __future__ import annotations

import statistics
import time
from typing import Optional

import numpy as np

from rrcache import kinds
from rrcache.errors import RRCacheError
from rrcache.harness.execute import Bench, LocalExecutor
from rrcache.model.sets import DEFAULT_MAX_SETS, TRAIN_MARGIN, SetOption, pick, search
from rrcache.profiler.collect import Collector
from rrcache.profiler.jobs import Meter, RunShapes

#: the share of the training budget the set stage may spend even when the nodes spent it all
SET_SHARE = 0.15


def feeds(table, ids: list[str]) -> set[tuple[int, int]]:
    """(i, j) for the nodes ``ids[i]`` whose value reaches node ``ids[j]``'s: inside its
    expression, or assigned to a variable ``ids[j]`` reads (through the shader's local
    definitions; every definition counted, so conservative) when it comes first in the shader."""
    from rrcache.glsl import ast as A
    from rrcache.profiler.order import dependency_map

    unit = table.shader.unit
    by_id = {n.id: n for n in table.nodes}
    deps = dependency_map(unit)
    holders: dict[str, set[str]] = {}  # node id -> the variables assigned from an expression holding it
    inside = {i: {id(x) for x in A.walk(by_id[i].node)} for i in ids}
    order = {}
    for k, n in enumerate(A.walk(unit)):
        order[id(n)] = k
    for n in A.walk(unit):
        if isinstance(n, A.Declarator) and n.init is not None:
            name, value = n.name, n.init
        elif isinstance(n, A.Assign):
            root = n.target
            while isinstance(root, (A.Field, A.Index)):
                root = root.obj
            if not isinstance(root, A.Ident):
                continue
            name, value = root.name, n.value
        else:
            continue
        held = {id(x) for x in A.walk(value)}
        for i in ids:
            if id(by_id[i].node) in held:
                holders.setdefault(i, set()).add(name)
    out = set()
    for j, outer in enumerate(ids):
        reads, todo = set(), [x.name for x in A.walk(by_id[outer].node) if isinstance(x, A.Ident)]
        while todo:
            name = todo.pop()
            if name not in reads:
                reads.add(name)
                todo.extend(deps.get(name, ()))
        for i, inner in enumerate(ids):
            if i == j:
                continue
            if id(by_id[inner].node) in inside[outer]:
                out.add((i, j))
            # through a variable: only a value computed before the outer one can reach it (the
            # names merge every definition, e.g. a loop's accumulator, so the order decides)
            elif holders.get(inner, set()) & reads and order[id(by_id[inner].node)] < order[id(by_id[outer].node)]:
                out.add((i, j))
    return out


def layout_for(work, algorithm: str, ids: list[str]) -> str:
    """``per-node`` (three-pass without a discard or a node needing derivatives: two passes per
    node, each pixel paying only for the nodes that miss there) or ``union``."""
    from rrcache.glsl import ast as A

    if algorithm != "three-pass":
        return "union"
    by_id = {n.id: n for n in work.table.nodes}
    if any("one-pass" in getattr(by_id[i], "invalid", {}) for i in ids if i in by_id):
        return "union"
    main = A.main_function(work.table.shader.unit)
    if main is not None and any(isinstance(n, A.Discard) for n in A.walk(main.body)):
        return "union"
    return "per-node"


def _levels(prof) -> list[tuple]:
    """(max_error, min_psnr, single ms) of each of the profile's levels."""
    return [(c.max_error if c.min_psnr is None else None, c.min_psnr, float(c.predicted_ms))
            for c in prof.threshold_selections()]


def plan_sets(prof, work, max_sets: int = DEFAULT_MAX_SETS) -> tuple[list[SetOption], list[SetOption]]:
    """(every set predicted to improve the front or within :data:`~rrcache.model.sets.TRAIN_MARGIN`
    of it, the ones picked to train), from the profile's models alone."""
    table = prof.table
    ids = table.node_ids
    layout = layout_for(work, prof.algorithm, ids)
    relation = feeds(work.table, ids)
    max_nodes = 3
    # within the rule's measured error of the front: a set that may be on it is worth measuring
    options = search(table, prof.psnr_fits(), relation, layout, max_nodes=max_nodes, min_gain=-TRAIN_MARGIN)
    return options, pick(options, _levels(prof), max_sets, min_gain=-TRAIN_MARGIN)


def train_sets(prof, work, session, settings, store, progress=None, max_sets: int = DEFAULT_MAX_SETS,
               clock=time.perf_counter, executor=None) -> list[SetOption]:
    """Predict, pick and train the sets (see the module docstring); returns every set predicted
    to improve the front, the trained ones with their measurements. Nothing when ``max_sets`` is
    0, fewer than two nodes were trained or the ceiling stopped the profile."""
    if max_sets <= 0 or prof.verdict is not None or len(prof.trained_nodes) < 2:
        return []
    options, picked = plan_sets(prof, work, max_sets)
    allowance = max(settings.budget_s - store.spent_s(), SET_SHARE * settings.budget_s)
    train_options(prof, work, session, settings, store, picked, progress, allowance, clock, executor)
    return options


def train_options(prof, work, session, settings, store, options: list[SetOption], progress=None,
                  allowance: float = float("inf"), clock=time.perf_counter, executor=None) -> list[SetOption]:
    """Train each of ``options`` (in place; see :func:`train_set`) unless the store holds it
    already (then its stored figures are taken) or the seconds spent so far plus the last set's
    would pass ``allowance`` (then ``note`` says so); a set the compiler refuses gets its reason
    in ``note``. Every outcome is kept in the store (``set_run``, through the collector). The
    runs go to ``executor`` (default: in this process). Returns ``options``."""
    stored = {(tuple(d["nodes"]), tuple(d["periods"])): SetOption.from_json(d) for d in store.set_runs()}
    spent, last = 0.0, 0.0
    own = executor is None
    collector = Collector(store)
    meter = Meter(progress)
    try:
        for option in options:
            key = (tuple(option.nodes), tuple(option.periods))
            if key in stored and (stored[key].trained or stored[key].note):
                done = stored[key]
                option.trained, option.note = done.trained, done.note
                option.trained_error, option.trained_psnr = done.trained_error, done.trained_psnr
                option.trained_ms, option.trained_hit_rates, option.trained_s = \
                    done.trained_ms, done.trained_hit_rates, done.trained_s
                continue
            if spent + last > allowance:
                option.note = "not trained: the training budget (--budget) was spent"
                continue
            if executor is None:
                executor = LocalExecutor(Bench(work, session))
            start = clock()
            try:
                train_set(prof, settings, session, option, executor, meter)
            except RRCacheError as err:  # a nest the compiler refuses, a target budget
                option.note = f"not trained: {err.message}"
            last = clock() - start
            spent += last
            option.trained_s = last if option.trained else None
            stored[key] = option
            collector.add_set(option.to_json())
    finally:
        if own and executor is not None:
            executor.close()
    return options


def train_set(prof, settings, session, option: SetOption, executor, meter: Meter) -> None:
    """A set's error run (over the training frames in the error window, against the original)
    and timing run (each timing frame beside the original), planned by the nodes kind
    (:meth:`rrcache.kinds.nodes.NodesKind.training`) and run by ``executor``; the figures into
    ``option``."""
    from rrcache.profiler.plan import Plan
    from rrcache.profiler.train import timing_frame_indices

    plan = Plan.from_json(prof.plan) if prof.plan else None
    shapes = RunShapes.of(settings, session, plan, timing_frame_indices(session.frames, settings.timing_frames))
    label = option.describe()
    runs = [shapes.run(measure, spec, key, f"{label} {measure}")
            for measure, spec, key in kinds.get("nodes").training((option.nodes, option.periods), settings,
                                                                  prof.algorithm, prof.filter)]
    meter.grow(sum(r.cost for r in runs))
    errors, psnrs, hits, counted, ratios = [], [], np.zeros(len(option.periods)), 0, []
    for result in executor.run(runs, on_frame=meter.on_frame("sets")):
        if result.spec.measure == "error":
            for row in result.frames[1:]:  # the first frame has no cache
                errors.append(float(row.error))
                psnrs.append(float(row.psnr))
                if row.hits is not None and row.covered:  # each node's share: the frame's hit rate
                    hits += row.hits / row.covered
                    counted += 1
        else:
            ratios = [row.ms / row.original_ms for row in result.frames if row.original_ms > 0]
    if not errors or not ratios:
        raise RRCacheError("too few frames to train a set", "settings",
                           hint="profile with --frames >= 2 and --timing-frames >= 1")
    option.trained = True
    option.trained_error = float(np.mean(errors))
    option.trained_psnr = float(np.mean(psnrs))
    option.trained_ms = float(statistics.median(ratios)) * float(prof.original_ms)
    option.trained_hit_rates = [float(v) for v in (hits / counted)] if counted else []


def single_choices(prof) -> dict:
    """Label → the selection each level makes with the profile's sets left out (the single-node
    choice a set displaced)."""
    saved = prof.sets
    prof.sets = []
    try:
        return {s.label: s for s in prof.threshold_selections()}
    finally:
        prof.sets = saved


def keep_faster(prof, work, session, settings, store, measured: list, progress=None, window=None,
                executor=None) -> list:
    """After validation: each level whose selection is a set is measured again with the choice
    it displaced (the single-node choice at the level, validated the same way, as
    ``<label>~single``), and the set stands only when its measured speed-up (the repeats'
    median) is at least the single choice's; otherwise the single choice stands, its
    ``fallback`` saying what the set measured. A set is chosen on its training measurement
    (one sample per timing frame) against the single node's model, and on Marble one that
    training put at 2.23× measured 1.70–1.94× beside a single choice measured at 2.34–2.92×:
    a set must beat what it displaced where it counts, in the validation (its renders run by
    ``executor``, None: one in this process)."""
    from rrcache.profiler.validate import validate

    def measure(sel):
        return validate(work, session, settings, store, [sel], progress, window, candidates=prof.front_candidates,
                        executor=executor)[0]

    def decided(row, stood) -> None:
        if stood is not row:
            store.add_validation(row.replace(label=f"{row.label}~set"))
        store.add_validation(stood)

    return prefer_singles(prof, measured, measure, decided)


def prefer_singles(prof, rows: list, measure, decided=None) -> list:
    """The rule of :func:`keep_faster` with any measurement: each measured set in ``rows`` is
    measured again as the single-node choice it displaced (``measure(selection)``, labelled
    ``<label>~single``) and stands only where its speed-up is at least that one's; otherwise the
    single choice stands, its ``fallback`` saying what the set measured. ``decided(set_row,
    standing_row)`` is called for each set measured again. The bench uses it with its own
    measurements (it profiles without validation)."""
    if not any(r.multi for r in rows):
        return rows
    singles = single_choices(prof)
    out = []
    for row in rows:
        single = singles.get(row.label)
        if not row.multi or single is None or not row.measured:
            out.append(row)
            continue
        alt = measure(single.replace(label=f"{row.label}~single")).replace(label=row.label)
        mine, theirs = float(row.measured_speedup or 0.0), float(alt.measured_speedup or 1.0)
        stood = row
        if mine < theirs:
            lo, hi = row.speedup_range or (mine, mine)
            stood = alt.replace(fallback=f"{row.describe()} measured {mine:.2f}× ({lo:.2f}–{hi:.2f}), below the "
                                         f"single-node choice's {theirs:.2f}×: {alt.describe()} stands")
        if decided is not None:
            decided(row, stood)
        out.append(stood)
    return out

