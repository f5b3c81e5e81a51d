"""Model accuracy at held-out refresh periods (main paper §4.4): predicted against measured.

:func:`held_out` takes a trained :class:`~rrcache.profiles.document.Profile`, picks the nodes that
matter — the nodes on the predicted Pareto front of error against frame time, which are the only
ones selection can ever choose, plus the four selections' nodes — and measures each at refresh
periods that training did not use (default Δn = 6, 14, 30), exactly as training measures: the
error over the training frames inside the profile's error window, the frame time on the timing
frames at full resolution (each after one warm-up frame, alternating with the original; in the
profile's timing window, if it has one, against the prediction for the window's pixels). Per
point it reports the predicted and measured error and frame time; overall, the mean relative
error of the predicted frame time and the R² of the error model over the held-out points
(1 − Σ(measured − predicted)² / Σ(measured − mean)²), beside each node's R² on its own training
periods.

>>> report = held_out(load_profile("marble-marble.rrprofile"), periods=(6, 14, 30))   # doctest: +SKIP
>>> round(report.time_mean_relative_error, 3), round(report.error_r2, 3)               # doctest: +SKIP
(0.041, 0.97)
"""
from __future__ import annotations

import statistics
from dataclasses import asdict, dataclass, field
from typing import Callable, Optional, Sequence

import numpy as np

from rrcache import kinds
from rrcache.errors import RRCacheError
from rrcache.harness.execute import Bench, LocalExecutor
from rrcache.profiler.jobs import Meter, RunShapes
from rrcache.profiler.plan import Plan
from rrcache.profiler.train import timing_frame_indices
from rrcache.choice import load_work
from rrcache.runtime.spec import VariantSpec

DEFAULT_PERIODS = (6, 14, 30)
#: at most this many front nodes are measured (the front's nodes spread over its time range)
MAX_NODES = 8


@dataclass
class AccuracyPoint:
    node: str
    period: int
    predicted_error: float
    measured_error: float
    predicted_ms: float
    measured_ms: float
    hit_rate: float

    @property
    def time_relative_error(self) -> float:
        return abs(self.predicted_ms - self.measured_ms) / self.measured_ms if self.measured_ms > 0 else float("nan")


@dataclass
class AccuracyReport:
    """``points`` (one per node and held-out period), ``training_r2`` (node → the error fit's
    R² on its training periods), the summary figures and how the nodes were chosen."""

    periods: list[int]
    nodes: list[str]
    points: list[AccuracyPoint] = field(default_factory=list)
    training_r2: dict = field(default_factory=dict)
    chosen_by: str = ""

    @property
    def time_mean_relative_error(self) -> float:
        errs = [p.time_relative_error for p in self.points]
        return float(np.mean(errs)) if errs else float("nan")

    @property
    def time_max_relative_error(self) -> float:
        errs = [p.time_relative_error for p in self.points]
        return float(np.max(errs)) if errs else float("nan")

    @property
    def error_r2(self) -> float:
        """R² of the predicted against the measured errors over every held-out point."""
        measured = np.array([p.measured_error for p in self.points])
        predicted = np.array([p.predicted_error for p in self.points])
        if measured.size < 2:
            return float("nan")
        total = float(np.sum((measured - measured.mean()) ** 2))
        if total <= 0:
            return float("nan")
        return 1.0 - float(np.sum((measured - predicted) ** 2)) / total

    def to_json(self) -> dict:
        return {"periods": self.periods, "nodes": self.nodes, "chosen_by": self.chosen_by,
                "time_mean_relative_error": self.time_mean_relative_error,
                "time_max_relative_error": self.time_max_relative_error,
                "error_r2_held_out": self.error_r2, "error_r2_training": self.training_r2,
                "points": [dict(asdict(p), time_relative_error=p.time_relative_error) for p in self.points]}


FRONT = "the predicted Pareto front and the selections"
SPREAD = "no node is predicted faster than the original: trained nodes spread over the cost range"


def _spread(items: list, limit: int) -> list:
    if len(items) <= limit:
        return items
    picks = np.linspace(0, len(items) - 1, limit).round().astype(int)
    return [items[i] for i in dict.fromkeys(picks.tolist())]


def nodes_that_matter(profile, limit: int = MAX_NODES) -> tuple[list[str], str]:
    """(node ids, how they were chosen): the nodes of the predicted Pareto front (spread over its
    time range when there are more than ``limit``), then the selections' nodes; when no node is
    predicted faster than the original, trained nodes spread over the static cost range."""
    from rrcache.model import pareto_front

    front = [p.node for p in sorted(pareto_front(profile.table), key=lambda p: p.predicted_ms) if p.node]
    distinct = _spread(list(dict.fromkeys(front)), limit)
    for sel in profile.selections:
        for node in sel.nodes:
            if node not in distinct:
                distinct.append(node)
    if distinct:
        return distinct, FRONT
    by_cost = [n.id for n in sorted(profile.trained_nodes, key=lambda n: -n.cost)]
    return _spread(by_cost, limit), SPREAD


def held_out(profile, periods: Sequence[int] = DEFAULT_PERIODS, nodes: Optional[Sequence[str]] = None,
             progress: Optional[Callable] = None) -> AccuracyReport:
    """Measure ``nodes`` (default :func:`nodes_that_matter`) of ``profile`` at ``periods`` and
    compare with the models' predictions (see the module docstring)."""
    from rrcache.profiles.inputs import check_inputs

    check_inputs(profile)  # what profile.json names is the profiled shader, before anything reads it
    table = profile.table
    settings = profile.settings
    periods = [int(p) for p in periods]
    bad = [p for p in periods if not 1 <= p <= table.max_period]
    if bad:
        raise RRCacheError(f"held-out periods {bad} are outside 1..{table.max_period}", "--periods",
                           hint="the models predict periods up to the selection's limit, 50")
    if nodes is not None:
        nodes, chosen_by = list(nodes), "given"
    else:
        nodes, chosen_by = nodes_that_matter(profile)
    index = {nid: i for i, nid in enumerate(table.node_ids)}
    unknown = [n for n in nodes if n not in index]
    if unknown:
        raise RRCacheError(f"nodes {unknown} are not trained in this profile", str(profile.path or "profile"),
                           hint="give trained node ids (profile.json lists them)")
    work, session = load_work(profile)
    plan = Plan.from_json(profile.plan or {})
    train_frames = plan.error_frames(settings.frames)  # the profile's error frames (rrcache.profiler.plan)
    timing = timing_frame_indices(session.frames, settings.timing_frames)
    meter = Meter(progress, len(train_frames) * (1 + len(nodes) * len(periods)) + 3 * len(timing) * len(nodes) * len(periods))
    report = AccuracyReport(periods, nodes, chosen_by=chosen_by)
    shapes = RunShapes.of(settings, session, plan, timing)
    kind = kinds.get("cache")
    runs = [shapes.run("reference", None, ("reference",), "reference frames")]
    for nid in nodes:  # each node's held-out periods: error runs, then timing runs (one variant serves all)
        runs += [shapes.run(measure, spec.with_runtime(periods=(p,)), ("node", nid, p), f"{nid} Δn={p}")
                 for measure in ("error", "timing") for p in periods
                 for spec in [VariantSpec(kind.name, (nid,), profile.algorithm, profile.filter,
                                          **settings.cache_options())]]
    with Bench(work, session) as bench:
        results = list(LocalExecutor(bench, on_frame=meter.on_frame()).run(runs))
    measured = {}
    for result in results[1:]:
        _, nid, p = result.spec.key
        if result.spec.measure == "error":
            measured[(nid, p)] = [result.steady_error]
        else:
            frames = result.frames
            counted = sum((f.hits or 0) + (f.misses or 0) for f in frames)
            measured[(nid, p)] += [statistics.median(f.ms for f in frames),
                                   sum(f.hits or 0 for f in frames) / counted if counted else 0.0,
                                   counted / max(1, len(frames))]
    for nid in nodes:
        report.training_r2[nid] = profile.node(nid).error_r2
        i = index[nid]
        for p in periods:
            error, ms, rate, covered = measured[(nid, p)]
            predicted_ms = float(table.T[i, p - 1])
            if plan.timing_window is not None:
                # timed in a window: the prediction for the window's covered pixels
                overhead = float(table.t_overhead[i])
                predicted_ms = overhead + (predicted_ms - overhead) * covered / table.pixels
            report.points.append(AccuracyPoint(nid, p, float(table.E[i, p - 1]), float(error),
                                               predicted_ms, float(ms), float(rate)))
    return report
