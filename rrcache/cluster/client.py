"""Starting the Dask cluster a profile runs on, or connecting to one.

- ``workers=N``: a ``LocalCluster`` of N worker processes on this machine (one thread each: a
  worker renders on one GL context), with its dashboard;
- ``scheduler=ADDRESS`` (or ``$RRCACHE_SCHEDULER``): a running ``dask scheduler`` whose workers
  run elsewhere (``dask worker ADDRESS`` on each machine; docs/distributed.md has the recipe).

Either way every worker gets the :class:`~rrcache.cluster.worker.GLWorker` plugin (its EGL
context, opened once) before anything runs; a worker that cannot open one fails the start with
the driver's message. The scheduler retries a run whose worker died (killed, out of memory, a
driver crash) on another worker, at most :data:`ALLOWED_FAILURES` times for a cluster started
here (a scheduler started elsewhere uses its own ``distributed.scheduler.allowed-failures``), and
then reports it.

>>> with connect(workers=2, announce=print) as cluster:     # doctest: +SKIP
...     cluster.client.run(worker_info)
Dask cluster: 2 workers on 1 host (llvmpipe), dashboard http://127.0.0.1:8787/status
"""
from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from typing import Callable, Optional

from rrcache.errors import RRCacheError

#: the environment variable naming a running scheduler (as ``--scheduler``)
SCHEDULER_ENV = "RRCACHE_SCHEDULER"
#: how many times a run is started again after its worker died, before it is reported
ALLOWED_FAILURES = 2
#: seconds to wait for the first worker of a running scheduler
WORKER_WAIT_S = 60.0


def _import_distributed():
    try:
        import distributed
    except ImportError as err:  # pragma: no cover - a main dependency; a broken install only
        raise RRCacheError(f"--workers and --scheduler need Dask distributed ({err})", "dask",
                           hint="pip install 'dask[distributed]' (it is in rrcache's dependencies)") from None
    return distributed


@dataclass
class Cluster:
    """A connected cluster: ``client`` (a ``distributed.Client``), ``local`` (the
    ``LocalCluster`` started here, or None), ``dashboard`` (the link, or None), ``workers``
    ({address: info} from each worker's plugin: host, pid, renderer, ``LP_NUM_THREADS``) and
    ``placements`` (where and when every run made through it ran:
    :class:`rrcache.cluster.worker.Placed` without the results)."""

    client: object
    local: object = None
    dashboard: Optional[str] = None
    workers: dict = field(default_factory=dict)
    placements: list = field(default_factory=list)

    def executor(self, work, session, on_frame=None):
        """The executor of one profile's runs (``work`` over ``session``) on this cluster:
        :class:`rrcache.cluster.executor.DaskExecutor`. The cluster itself is the executor
        factory :func:`rrcache.profile` takes (``executor=cluster``)."""
        from rrcache.cluster.executor import DaskExecutor

        return DaskExecutor(self, work, session, on_frame)

    __call__ = executor

    @property
    def capacity(self) -> int:
        """The workers that run error runs (each one run at a time): as many as were connected
        when the cluster was reached (:mod:`rrcache.profiler.capacity` scales a profile by it)."""
        return max(1, len(self.workers))

    @property
    def hosts(self) -> list[str]:
        return sorted({info["host"] for info in self.workers.values()})

    def describe(self) -> str:
        renderers = sorted({str(info.get("renderer")) for info in self.workers.values()})
        where = "started here" if self.local is not None else f"scheduler {self.client.scheduler.address}"
        workers, hosts = len(self.workers), len(self.hosts)
        text = (f"Dask cluster ({where}): {workers} worker{'s' if workers != 1 else ''} on {hosts} "
                f"host{'s' if hosts != 1 else ''} ({', '.join(renderers)})")
        return text + (f", dashboard {self.dashboard}" if self.dashboard else ", no dashboard (install bokeh)")

    def close(self) -> None:
        try:
            self.client.close()
        finally:
            if self.local is not None:
                self.local.close()

    def __enter__(self) -> "Cluster":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def scheduler_address(scheduler: Optional[str] = None) -> Optional[str]:
    """``scheduler``, else ``$RRCACHE_SCHEDULER``, else None."""
    return scheduler or os.environ.get(SCHEDULER_ENV) or None


def connect(workers: Optional[int] = None, scheduler: Optional[str] = None, threads: int = 1,
            lock_path: Optional[str] = None, dashboard_address: str = ":8787",
            announce: Optional[Callable[[str], None]] = None) -> Cluster:
    """The cluster of ``workers`` local processes, or the one at ``scheduler``
    (see the module docstring), with every worker's GL plugin set up. ``threads``: each
    worker's ``LP_NUM_THREADS``; ``lock_path``: the host lock's file (None: each host's
    default). ``announce`` receives one line describing the cluster and its dashboard."""
    distributed = _import_distributed()
    import dask

    from rrcache.cluster.worker import GLWorker, worker_info

    address = scheduler_address(scheduler)
    if address is None and not workers:
        raise RRCacheError("no cluster asked for", "--workers", hint="give --workers N or --scheduler ADDRESS")
    local = None
    try:
        if address is None:
            with dask.config.set({"distributed.scheduler.allowed-failures": ALLOWED_FAILURES}):
                local = distributed.LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True,
                                                 dashboard_address=dashboard_address,
                                                 silence_logs=logging.ERROR)
            client = distributed.Client(local)
        else:
            try:
                client = distributed.Client(address, timeout=30)
            except (OSError, TimeoutError) as err:
                raise RRCacheError(f"cannot reach the Dask scheduler at {address} ({err})", "--scheduler",
                                   hint="start one with 'dask scheduler' and give the address it prints "
                                        "(tcp://HOST:8786)") from None
            try:
                client.wait_for_workers(1, timeout=WORKER_WAIT_S)
            except (TimeoutError, OSError):
                client.close()
                raise RRCacheError(f"the scheduler at {address} has no worker after {WORKER_WAIT_S:.0f} s",
                                   "--scheduler", hint=f"start workers with 'dask worker {address}'") from None
        client.register_plugin(GLWorker(threads=threads, lock_path=lock_path))
        info = client.run(worker_info)
    except BaseException:
        if local is not None:
            local.close()
        raise
    cluster = Cluster(client, local, client.dashboard_link if _has_dashboard(client) else None, info)
    if announce is not None:
        announce(cluster.describe())
    return cluster


def _has_dashboard(client) -> bool:
    try:
        return "dashboard" in client.scheduler_info().get("services", {})
    except Exception:  # an old scheduler without the field: trust the link
        return True
