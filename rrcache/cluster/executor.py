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
from dataclasses import dataclass
from typing import Iterable, Iterator, Optional

from rrcache.cluster.client import Cluster
from rrcache.cluster.worker import CONTEXT_PREFIX, Placed, ProfileContext, run_task


@dataclass
class RunFailure:
    """A run that did not complete: ``spec``, ``kind`` and ``error`` (the exception; a
    ``KilledWorker`` when its workers died more than the allowed number of times)."""

    spec: object
    kind: str
    error: BaseException


class DaskRuns:
    """Runs on ``cluster`` (see the module docstring)."""

    def __init__(self, cluster: Cluster):
        self.cluster = cluster
        self.client = cluster.client
        self.placements: list[Placed] = []
        self._contexts: list[str] = []

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
        futures = {}
        for i, (spec, kind) in enumerate(runs):
            name = (label(spec, kind) if label is not None else kind).replace(" ", "_")
            future = self.client.submit(run_task, context, spec, kind, pure=False,
                                        key=f"{name}-{context[len(CONTEXT_PREFIX):]}-{i}")
            futures[future] = (spec, kind)
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
                self.placements.append(Placed(None, placed.host, placed.worker, placed.pid, placed.started,
                                              placed.finished, placed.kind))
                yield spec, placed
        finally:
            if pending:
                self.client.cancel(list(pending))
