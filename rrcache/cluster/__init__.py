"""Profiling past one process: the runs of a profile on a Dask distributed cluster.

Nothing here is imported on the default, in-process path (``rrcache profile`` without
``--workers``/``--scheduler``): the modules that import Dask are imported only when a cluster is
asked for, and this package's ``__init__`` imports none of them.

- :mod:`rrcache.cluster.hostlock`: one timing run per host and nothing beside it (a per-host
  reader-writer lock on files);
- :mod:`rrcache.cluster.worker`: the worker plugin (one EGL context per worker process, opened
  once, on a thread of its own) and the per-profile context that travels once per worker;
- :mod:`rrcache.cluster.client`: starting a ``LocalCluster`` or connecting to a scheduler.
"""
from __future__ import annotations

import contextlib
import os
from typing import Callable, Optional


@contextlib.contextmanager
def maybe_cluster(workers: Optional[int] = None, scheduler: Optional[str] = None,
                  announce: Optional[Callable[[str], None]] = None, **kwargs):
    """The cluster asked for, connected for the ``with`` block: ``workers`` local processes, or
    the scheduler at ``scheduler`` (else ``$RRCACHE_SCHEDULER``); None, without importing Dask,
    when none is asked for. ``announce`` hears the cluster's line (its dashboard link);
    ``kwargs`` go to :func:`rrcache.cluster.client.connect`."""
    from rrcache.cluster.client import SCHEDULER_ENV
    from rrcache.errors import RRCacheError

    if workers and scheduler:
        raise RRCacheError("give --workers or --scheduler, not both", "--workers",
                           hint="--workers N starts a cluster here; --scheduler ADDRESS uses a running one")
    if not workers and not scheduler and not os.environ.get(SCHEDULER_ENV):
        yield None
        return
    from rrcache.cluster.client import connect

    with connect(workers=workers, scheduler=scheduler, announce=announce, **kwargs) as cluster:
        yield cluster
