"""Runs on a Dask cluster, their results back to the client as they complete.

:class:`DaskRuns` is the cluster side of an executor: :meth:`~DaskRuns.open` sends a profile's
context (an object with ``run(spec)``, pickled once) to every worker as a
:class:`~rrcache.cluster.worker.ProfileContext`; :meth:`~DaskRuns.map` submits runs (a spec and
its kind, ``error`` or ``timing``) as tasks of :func:`~rrcache.cluster.worker.run_task` and yields
each ``(spec, Placed)`` as it completes, in completion order. The client keeps the results: the
worker returns plain data and writes nothing. A run whose worker died is started again elsewhere
by the scheduler (a bounded number of times, :data:`rrcache.cluster.client.ALLOWED_FAILURES`); a
run that still fails, or raises, is yielded as a :class:`RunFailure` in its place while the
others go on, so that one bad run costs nothing already computed.

Every placement (host, worker, start and end) is kept in :attr:`DaskRuns.placements`.
"""
from __future__ import annotations

import hashlib
import itertools
import uuid
from dataclasses import dataclass
from typing import Iterable, Iterator, Optional

from rrcache.cluster.worker import CONTEXT_PREFIX, Placed, ProfileContext, run_task


@dataclass
class RunFailure:
    """A run that did not complete: ``spec``, ``kind`` and ``error`` (the exception; a
    ``KilledWorker`` when its workers died more than the allowed number of times)."""

    spec: object
    kind: str
    error: BaseException


class DaskRuns:
    """Runs on ``cluster`` (a :class:`rrcache.cluster.client.Cluster`; see the module docstring)."""

    def __init__(self, cluster):
        self.cluster = cluster
        self.client = cluster.client
        self.placements: list[Placed] = []
        self._contexts: list[str] = []
        # task keys unique over every map() of this object and across clients
        self._numbers, self._token = itertools.count(), uuid.uuid4().hex[:8]

    def open(self, key: str, context) -> str:
        """Send ``context`` (pickled here, with cloudpickle) to every worker once, under ``key``;
        returns the context's name for :meth:`map`."""
        import cloudpickle

        payload = cloudpickle.dumps(context)
        digest = hashlib.sha256(payload).hexdigest()[:16]
        plugin = ProfileContext(f"{key}-{digest}", payload)
        if plugin.name not in self._contexts:
            self.client.register_plugin(plugin)
            self._contexts.append(plugin.name)
        return plugin.name

    def close(self, name: Optional[str] = None) -> None:
        """Remove the context ``name`` (every one opened here when None) from the workers,
        releasing what it built there."""
        for context in [name] if name is not None else list(self._contexts):
            if context in self._contexts:
                self._contexts.remove(context)
                try:
                    self.client.unregister_worker_plugin(context)
                except Exception:  # a worker gone meanwhile: nothing of it is left to release
                    pass

    def map(self, context: str, runs: Iterable[tuple[object, str]], label=None) -> Iterator[tuple[object, object]]:
        """Submit every ``(spec, kind)`` of ``runs`` to the workers and yield ``(spec, Placed)``
        as each completes (a :class:`RunFailure` in the place of ``Placed`` for one that failed).
        ``label(spec, kind)`` names a task on the dashboard. Leaving the loop early (an
        interruption) cancels the runs not yet done."""
        from distributed import as_completed

        if not context.startswith(CONTEXT_PREFIX):
            raise ValueError(f"{context!r} is not a context opened by DaskRuns.open")
        futures, names = {}, {}
        for spec, kind in runs:
            text = label(spec, kind) if label is not None else kind
            name = text.replace(" ", "_")
            future = self.client.submit(run_task, context, spec, kind, pure=False,
                                        key=f"{name}-{self._token}-{next(self._numbers)}")
            futures[future] = (spec, kind)
            names[future] = text
        pending = set(futures)
        try:
            for future in as_completed(list(futures)):
                pending.discard(future)
                spec, kind = futures[future]
                try:
                    placed = future.result()
                except Exception as err:  # a run that raised, or whose workers kept dying
                    yield spec, RunFailure(spec, kind, err)
                    continue
                where = Placed(None, placed.host, placed.worker, placed.pid, placed.started, placed.finished,
                               placed.kind, names[future])
                self.placements.append(where)
                self.cluster.placements.append(where)
                yield spec, placed
        finally:
            if pending:
                self.client.cancel(list(pending))


class BenchContext:
    """A profile's context on a worker: the shader work and the session travel (pickled once per
    worker); the worker's :class:`rrcache.harness.execute.Bench` over them is made on first use
    and keeps the compiled variants and reference frames for the worker's next runs."""

    def __init__(self, work, session):
        self.work, self.session = work, session
        self._bench = None

    def __getstate__(self):
        return {"work": self.work, "session": self.session}

    def __setstate__(self, state):
        self.work, self.session, self._bench = state["work"], state["session"], None

    def run(self, spec):
        from rrcache.harness.execute import Bench, execute

        if self._bench is None:
            self._bench = Bench(self.work, self.session)
        return execute(spec, self._bench)

    def release(self) -> None:
        if self._bench is not None:
            self._bench.close()
            self._bench = None


class DaskExecutor:
    """The executor interface (:class:`rrcache.harness.execute.LocalExecutor`'s) on a Dask
    cluster, for one profile's ``work`` over ``session``: :meth:`run` submits the specs and yields
    each :class:`~rrcache.runs.RunResult` as it completes (not in the specs' order) with its
    ``host``, ``started`` and ``finished`` (inside the host lock; a timed spec holds its host
    alone). A run that failed on every try is raised (its own :class:`~rrcache.errors.RRCacheError`,
    else one naming it) after the batch's other results have been yielded, so the collector keeps
    them. ``on_frame(spec, units)`` hears of each run as it completes (its whole cost at once).
    :meth:`close` releases what the workers built for the profile; a later :meth:`run` sends the
    context again."""

    def __init__(self, cluster, work, session, on_frame=None):
        self.runs = DaskRuns(cluster)
        self.on_frame = on_frame
        self.key = f"{work.hash[:12]}-{session.hash[:12]}"
        self.context = BenchContext(work, session)
        self.name: Optional[str] = None

    @property
    def placements(self) -> list[Placed]:
        return self.runs.placements

    def run(self, specs, on_frame=None):
        import dataclasses

        from rrcache.errors import RRCacheError

        if self.name is None:
            self.name = self.runs.open(self.key, self.context)
        tell = on_frame or self.on_frame
        failed = []
        runs = [(spec, "timing" if spec.timed else "error") for spec in specs]
        for spec, placed in self.runs.map(self.name, runs, label=lambda s, kind: f"{s.measure} {s.label}"):
            if isinstance(placed, RunFailure):
                failed.append(placed)
                continue
            if tell is not None:
                tell(spec, spec.cost)
            where = {"host": placed.host, "started": placed.started, "finished": placed.finished}
            known = {f.name for f in dataclasses.fields(placed.result)}
            yield dataclasses.replace(placed.result, **{k: v for k, v in where.items() if k in known})
        if failed:
            first = failed[0]
            if isinstance(first.error, RRCacheError):
                raise first.error
            raise RRCacheError(f"the {first.spec.measure} run {first.spec.label} failed on the cluster "
                               f"({type(first.error).__name__}: {first.error})", "--workers",
                               hint="its workers died on every try (out of memory? a driver crash?): see the "
                                    "workers' logs; the runs already made are stored: run the command again "
                                    "to resume") from first.error

    def record(self, capacity=None) -> dict:
        """What profile.json keeps of the cluster (``Profile.cluster``): its workers and hosts,
        what their ``capacity`` bought (:class:`rrcache.profiler.capacity.CapacityPlan`: the
        training frames, the budget's factor) and, per host, the timed runs it made."""
        cluster = self.runs.cluster
        timed: dict = {}
        for p in self.placements:
            if p.kind == "timing":
                timed.setdefault(p.host, []).append(p.label)
        return {"workers": len(cluster.workers), "hosts": cluster.hosts, "dashboard": cluster.dashboard,
                "capacity": capacity.to_json() if capacity is not None else None, "timing_hosts": timed}

    def close(self) -> None:
        if self.name is not None:
            self.runs.close(self.name)
            self.name = None
