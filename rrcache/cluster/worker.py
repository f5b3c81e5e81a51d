"""What a Dask worker process holds for rrcache: its GL context and the profiles it serves.

:class:`GLWorker` is the worker plugin of every rrcache cluster (registered once by the client,
:mod:`rrcache.cluster.client`; Dask sets it up on every worker, those that join later and those
restarted after a crash included). On setup it opens the worker's one EGL context
(:func:`rrcache.gl.context.get_context`, with ``LP_NUM_THREADS`` fixed for the process) on a
thread of its own, and every GL call of the worker runs on that thread: an EGL context is current
on one thread, and Dask runs tasks on a pool thread of its choosing. It also holds the host's
timing lock (:class:`rrcache.cluster.hostlock.HostLock`).

:class:`ProfileContext` is one profile's state on a worker, a plugin of its own named by the
profile's key: the shader work, session and settings travel in it once per worker (not once per
run), are unpickled on first use, and whatever the context builds from them (compiled programs
keyed by the variant spec, reference frames) stays for the next run on that worker. The client
unregisters it when the profile ends, which releases its GL objects on every worker.

:func:`run_task` is the task a run is: on the GL thread, inside the host lock (shared for an error
run, exclusive for a timing run), it calls the context's ``run(spec)`` and returns the result
with the host, the worker and the wall-clock start and end inside the lock.
"""
from __future__ import annotations

import asyncio
import os
import pickle
import socket
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, Callable, Optional

from distributed import WorkerPlugin, get_worker

from rrcache.cluster.hostlock import HostLock

#: the name of the worker plugin every rrcache cluster registers
PLUGIN_NAME = "rrcache-gl"
#: the prefix of a profile context's plugin name
CONTEXT_PREFIX = "rrcache-profile-"


@dataclass
class Placed:
    """A run's result with where and when it ran: ``host`` (the machine's name), ``worker``
    (the Dask worker's address), ``pid``, and ``started``/``finished`` (wall clock, seconds
    since the epoch, taken inside the host lock)."""

    result: Any
    host: str
    worker: str
    pid: int
    started: float
    finished: float
    kind: str
    #: what ran (the run's label, filled in on the client)
    label: str = ""


class GLWorker(WorkerPlugin):
    """The worker plugin (see the module docstring): ``threads`` is the worker's
    ``LP_NUM_THREADS``; ``lock_path`` the host lock's file (None: the host's default)."""

    name = PLUGIN_NAME
    idempotent = True

    def __init__(self, threads: int = 1, lock_path: Optional[str] = None):
        self.threads = int(threads)
        self.lock_path = lock_path
        self.gl: Optional[ThreadPoolExecutor] = None
        self.info: dict = {}

    async def setup(self, worker) -> None:
        self.lock = HostLock(self.lock_path)
        self.address = worker.address
        self.gl = ThreadPoolExecutor(1, thread_name_prefix="rrcache-gl")
        self.info = await asyncio.get_running_loop().run_in_executor(self.gl, self._open)

    def _open(self) -> dict:
        from rrcache.gl.context import get_context

        ctx = get_context(threads=self.threads)
        return {"host": socket.gethostname(), "pid": os.getpid(), "renderer": ctx.info.get("GL_RENDERER"),
                "lp_num_threads": os.environ.get("LP_NUM_THREADS"), "thread": threading.current_thread().name}

    def teardown(self, worker) -> None:
        if self.gl is not None:
            from rrcache.gl.context import release_context

            self.gl.submit(release_context).result()
            self.gl.shutdown(wait=True)
            self.gl = None

    def call(self, fn: Callable, *args):
        """``fn(*args)`` on the worker's GL thread (where its context is current)."""
        if self.gl is None:
            raise RuntimeError("the rrcache worker plugin is not set up on this worker")
        return self.gl.submit(fn, *args).result()


class ProfileContext(WorkerPlugin):
    """One profile on a worker (see the module docstring). ``payload`` is the pickled object
    (bytes) whose ``run(spec)`` makes a run; made from it on first use, released (its
    ``release()``, on the GL thread) when the plugin is removed."""

    idempotent = True

    def __init__(self, key: str, payload: bytes):
        self.name = CONTEXT_PREFIX + key
        self.payload = payload
        self._state = None
        self._lock = threading.Lock()

    def __getstate__(self):
        return {"name": self.name, "payload": self.payload}

    def __setstate__(self, state):
        self.name, self.payload = state["name"], state["payload"]
        self._state, self._lock = None, threading.Lock()

    def setup(self, worker) -> None:
        self.worker = worker

    def state(self):
        """The unpickled payload, made once."""
        with self._lock:
            if self._state is None:
                self._state = pickle.loads(self.payload)
            return self._state

    def teardown(self, worker) -> None:
        state, self._state = self._state, None
        gl = worker.plugins.get(PLUGIN_NAME)
        if state is not None and hasattr(state, "release") and gl is not None and gl.gl is not None:
            gl.call(state.release)


def run_task(context_name: str, spec, kind: str) -> Placed:
    """The task of one run (see the module docstring): ``spec`` is run by the context named
    ``context_name`` on this worker; ``kind`` (``timing`` or ``error``) chooses how the host lock
    is held."""
    worker = get_worker()
    gl: GLWorker = worker.plugins[PLUGIN_NAME]
    context: ProfileContext = worker.plugins[context_name]
    state = context.state()
    with gl.lock.hold(kind):
        started = time.time()
        result = gl.call(state.run, spec)
        finished = time.time()
    return Placed(result, gl.info.get("host", socket.gethostname()), worker.address, os.getpid(), started, finished,
                  kind)


def worker_info(dask_worker) -> dict:
    """This worker's GL context and host, as the plugin opened them (``client.run(worker_info)``)."""
    return dict(dask_worker.plugins[PLUGIN_NAME].info)
