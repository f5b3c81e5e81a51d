"""A training stage as a plan of runs: which runs, in which groups, and how budget, resume and
progress follow from the plan.

A trainer says *what* to measure as :class:`~rrcache.runs.RunSpec` records (the kinds say which
runs a subject needs: :meth:`rrcache.kinds.base.Kind.training`; :class:`RunShapes` gives them the
frames, windows, formats and clock of the profile's plan), grouped into :class:`Group` s (a node's
runs, a set's, an estimator history's): a group once started is finished. :class:`RunPlan` then

- **resumes**: a run whose result the store holds (``done(spec)``) is left out, and so is a group
  with nothing left;
- keeps the **budget**: before a group that has not started, ``spent()`` is compared with the
  budget; once it is reached the group is skipped (``skipped`` lists it) and its runs leave the
  total;
- gives the **progress**: the total is the frames of every run left (:attr:`RunSpec.cost`), and
  after each group the groups the budget is still expected to reach (at the seconds per group
  so far);
- hands the runs to an **executor** (:class:`rrcache.harness.execute.LocalExecutor` in this
  process) and each result to the **collector** (:class:`rrcache.profiler.collect.Collector`,
  the only writer of the store).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Optional

from rrcache.gl.formats import ERROR_FORMAT
from rrcache.runs import RunResult, RunSpec


@dataclass
class Group:
    """Runs that belong together (``name``: a node, a set, an estimator's history), and whether
    any of them was measured before (a resumed group is finished whatever the budget)."""

    name: str
    runs: list
    started: bool = False


@dataclass(frozen=True)
class RunShapes:
    """The frames, resolutions, windows, formats and clock of a profile's runs: ``error`` runs
    over the training frames at the training resolution in the error window (drawn exactly),
    ``timing`` runs on the timing frames at the session's resolution in the timing window, in
    the timing format, with the settings' clock."""

    train_frames: tuple
    resolution: tuple
    error_window: Optional[tuple]
    timing_frames: tuple
    full: tuple
    timing_window: Optional[tuple]
    timing_format: str
    clock: str

    @classmethod
    def of(cls, settings, session, plan, timing_frames) -> "RunShapes":
        # the error frames the plan chose (rrcache.profiler.plan: the session, or segments of it)
        frames = plan.error_frames(settings.frames) if plan is not None else range(settings.frames)
        return cls(tuple(frames), tuple(settings.resolution),
                   plan.error_window if plan is not None else None, tuple(timing_frames),
                   tuple(int(v) for v in session.resolution), plan.timing_window if plan is not None else None,
                   settings.timing_format, settings.clock)

    def run(self, measure: str, variant, key: tuple = (), label: str = "", strict_payload: bool = False) -> RunSpec:
        """The :class:`RunSpec` of ``measure`` (``reference``, ``error``, ``timing``) for ``variant``."""
        if measure in ("reference", "error"):
            return RunSpec(measure, variant, self.train_frames, self.resolution, self.error_window, ERROR_FORMAT,
                           self.clock, key, label, strict_payload)
        return RunSpec(measure, variant, self.timing_frames, self.full, self.timing_window, self.timing_format,
                       self.clock, key, label, strict_payload)


class Meter:
    """Frames rendered of frames planned, sent as :class:`~rrcache.profiler.train.ProgressEvent`."""

    def __init__(self, progress, total: int = 0, event=None):
        from rrcache.profiler.events import ProgressEvent

        self.progress, self.total, self.done = progress, max(0, total), 0
        self.event = event or ProgressEvent

    def step(self, stage: str, detail: str = "", n: int = 1) -> None:
        self.done += n
        self.total = max(self.total, self.done)
        if self.progress is not None:
            self.progress(self.event(stage, self.done, self.total, detail))

    def shrink(self, by: int, stage: str = "train", detail: str = "budget spent") -> None:
        self.total = max(self.done, self.total - by)
        if self.progress is not None:
            self.progress(self.event(stage, self.done, self.total, detail))

    def grow(self, by: int) -> None:
        self.total += by

    def on_frame(self, stage: Optional[str] = None):
        """An executor's ``on_frame(spec, units)`` stepping this meter (stage: the run's measure)."""
        return lambda spec, n: self.step(stage or spec.measure, spec.label, n)


class RunPlan:
    """Groups of runs executed in order within a budget (see the module docstring).

    ``done(spec)``: the store holds this run's result (resume); ``spent()``: seconds the budget has
    spent; ``budget``: seconds (None: no limit); ``completed()``: groups complete, earlier
    invocations included (the progress's estimate of the seconds per group)."""

    def __init__(self, groups: list, done: Callable[[RunSpec], bool] = lambda spec: False,
                 budget: Optional[float] = None, spent: Callable[[], float] = lambda: 0.0,
                 completed: Optional[Callable[[], int]] = None):
        self.groups = []
        self.skipped: list[Group] = []
        #: groups an error dropped (``on_error`` of :meth:`execute`)
        self.dropped: list[Group] = []
        self.resumed = 0
        for group in groups:
            todo = [r for r in group.runs if not done(r)]
            self.resumed += len(group.runs) - len(todo)
            if todo:
                self.groups.append(Group(group.name, todo, group.started or len(todo) < len(group.runs)))
        self.budget = budget
        self.spent = spent
        #: groups complete so far, earlier invocations included (default: this execution's)
        self.completed = completed

    @property
    def total(self) -> int:
        """Frames of every run left to do."""
        return sum(r.cost for g in self.groups for r in g.runs)

    def execute(self, executor, collect: Callable[[RunResult], None], meter: Optional[Meter] = None,
                after_group: Optional[Callable[[Group], None]] = None,
                on_error: Optional[Callable[[Group, BaseException], bool]] = None) -> list[RunResult]:
        """Run every group the budget reaches (results to ``collect`` as they come); returns the
        results. A group whose run raises an error ``on_error(group, err)`` takes (returns True:
        a variant the driver refuses) is dropped, its runs not done leaving the total
        (``dropped`` lists it); any other error propagates."""
        out = []
        finished = 0
        for k, group in enumerate(self.groups):
            if self.budget is not None and not group.started and self.spent() >= self.budget:
                self.skipped.append(group)
                if meter is not None:
                    meter.shrink(sum(r.cost for r in group.runs))
                continue
            done = 0
            try:
                for result in executor.run(group.runs, on_frame=meter.on_frame() if meter is not None else None):
                    collect(result)
                    out.append(result)
                    done += 1
            except Exception as err:
                if on_error is None or not on_error(group, err):
                    raise
                self.dropped.append(group)
                if meter is not None:
                    meter.shrink(sum(r.cost for r in group.runs[done:]))
                continue
            finished += 1
            if after_group is not None:
                after_group(group)
            if meter is not None:
                self._expect(meter, self.completed() if self.completed is not None else finished,
                             self.groups[k + 1:])
        return out

    def _expect(self, meter: Meter, finished: int, rest: list) -> None:
        """After each group, plan only the groups the budget is expected to reach (at the mean
        seconds per group so far), so the progress's total and ETA are those of the run that will
        happen."""
        if self.budget is None or not finished:
            return
        spent = self.spent()
        if spent <= 0:
            return
        per_group = spent / finished
        fit = max(0, int((self.budget - spent) / per_group) + 1)
        costs = [sum(r.cost for r in g.runs) for g in rest]
        planned = sum(costs)
        expected = sum(sorted(costs)[:fit]) if fit < len(costs) else planned
        meter.total = max(meter.done, meter.done + min(planned, expected) + self.tail)

    #: frames still to come after the plan (a measurement the stage makes last)
    tail = 0
