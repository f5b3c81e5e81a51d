"""The collector: the one writer of a profile's measurements into its store.

The trainers plan runs (:mod:`rrcache.profiler.jobs`), an executor runs them
(:mod:`rrcache.harness.execute`), and every :class:`~rrcache.runs.RunResult` comes here:
:meth:`Collector.add` files it by its key — the original's reference frames and timings, the
overhead, and a kind's own runs, which its kind of choice writes (:meth:`rrcache.kinds.base.Kind.collect`:
a node's error and timing runs, an estimator's runs). What a stage assembles from several runs
(a set's record, an adaptive point) comes through :meth:`Collector.add_set` and
:meth:`Collector.add_adaptive`.
"""
from __future__ import annotations

import statistics

from rrcache import kinds
from rrcache.runs import RunResult


class Collector:
    """Writes results into ``store`` (a :class:`~rrcache.profiles.store.ProfileStore`)."""

    def __init__(self, store):
        self.store = store

    def add(self, result: RunResult) -> None:
        """File one result by its key (see the module docstring)."""
        spec = result.spec
        what = spec.key[0] if spec.key else None
        if what == "reference":
            self.store.add_reference({r.frame: r.covered for r in result.frames})
        elif what == "reference-timing":
            self.store.add_reference_timing([(r.frame, r.ms, r.covered) for r in result.frames])
        elif what == "overhead":
            times = [r.ms for r in result.frames]
            self.store.set_overhead(spec.key[1], tuple(spec.resolution), len(times), statistics.median(times))
        elif spec.variant is not None:
            kinds.get(spec.variant.kind).collect(self.store, result)
        else:
            raise ValueError(f"the collector has no place for a run keyed {spec.key!r}")

    def __call__(self, result: RunResult) -> None:
        self.add(result)

    def add_set(self, record: dict) -> None:
        """A set's record (:meth:`rrcache.model.sets.SetOption.to_json`), trained or with its note."""
        self.store.add_set_run(record)

    def add_adaptive(self, point, algorithm: str, wall_s: float) -> None:
        """One adaptive point (:class:`rrcache.profiler.adaptive.AdaptivePoint`)."""
        self.store.add_adaptive_point(point, algorithm, wall_s)
