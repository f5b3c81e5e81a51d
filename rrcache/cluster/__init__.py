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
