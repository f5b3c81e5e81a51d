"""One timing run per host, and no other run beside it: a reader-writer lock per host, on files.

Error runs measure images, not time: any number of them may run at once on a host, and they
take the lock *shared*. A timing run measures wall-clock frame times beside the original: it
takes the lock *exclusive*, so that while it runs no other rrcache run (an error run, another
timing run) on the same host takes CPU, memory bandwidth or the GPU from it.

Why a lock on a file and not Dask's worker resources: resources are counted per worker
process, and a host runs several worker processes (``--workers N`` on one machine, or ``dask
worker --nworkers N``). A resource can say "at most one timing run on this worker" but not "no
error run on the worker beside it on the same machine". A file lock (``flock(2)``) is per host
by nature: every process on the machine sees the same file, whoever started it (this cluster,
another cluster, another user's ``rrcache profile --workers``), and the kernel drops a lock the
moment its process dies (a killed worker leaves no stale lock; a lock held by the scheduler, as
``distributed.Lock`` is, waits for a lease to time out).

Writers are not starved: every taker first passes a *gate* (an exclusive lock on a second file)
and a timing run keeps the gate until it holds the main lock, so error runs that arrive while a
timing run waits queue behind it.

The file is ``$RRCACHE_HOST_LOCK``, else ``rrcache-host.lock`` in the system's temporary folder
(one per machine; created if missing, readable by all: a lock needs no write access).

>>> lock = HostLock(os.path.join(tempfile.mkdtemp(), "host.lock"))
>>> with lock.hold("error"):
...     pass
"""
from __future__ import annotations

import contextlib
import fcntl
import os
import stat
import tempfile

from rrcache.errors import RRCacheError

#: the environment variable naming the lock file of this host
LOCK_ENV = "RRCACHE_HOST_LOCK"


def default_path() -> str:
    """``$RRCACHE_HOST_LOCK``, else ``<temporary folder>/rrcache-host.lock``."""
    return os.environ.get(LOCK_ENV) or os.path.join(tempfile.gettempdir(), "rrcache-host.lock")


def _open(path: str) -> int:
    try:
        # never through a link (the default lives in the shared temporary folder); a regular file only
        fd = os.open(path, os.O_RDONLY | os.O_CREAT | os.O_CLOEXEC | os.O_NOFOLLOW | os.O_NONBLOCK, 0o644)
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            raise OSError(0, "not a regular file")
        return fd
    except OSError as err:
        raise RRCacheError(f"cannot open the host's timing lock: {err.strerror or err}", path,
                           hint=f"set {LOCK_ENV} to a file every rrcache worker on this machine can open") from None


class HostLock:
    """The host's lock at ``path`` (see the module docstring)."""

    def __init__(self, path: "str | None" = None):
        self.path = os.fspath(path) if path is not None else default_path()
        self.gate = self.path + ".gate"

    @contextlib.contextmanager
    def hold(self, kind: str):
        """Hold the lock for a run of ``kind``: ``timing`` alone on the host, anything else
        shared with other shared holders."""
        exclusive = kind == "timing"
        main = _open(self.path)
        try:
            gate = _open(self.gate)
            try:
                fcntl.flock(gate, fcntl.LOCK_EX)
                fcntl.flock(main, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
            finally:
                os.close(gate)  # closing drops the gate: the next taker may queue on the main lock
            yield
        finally:
            os.close(main)
