"""A Dask scheduler and workers started as separate processes on localhost ports, as a farm runs
them (``dask scheduler`` on one machine, ``dask worker ADDRESS`` on each of the others)."""
from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time


@contextlib.contextmanager
def local_farm(folder, workers: int = 2, env=None):
    """Start a scheduler and ``workers`` worker processes (one thread each) whose files are in
    ``folder``; yield the scheduler's address; stop them all (by their process ids)."""
    folder.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, **(env or {}))
    file = folder / "scheduler.json"
    logs, procs = [], []

    def spawn(name, args):
        log = open(folder / f"{name}.log", "w")
        logs.append(log)
        procs.append(subprocess.Popen([sys.executable, "-m", "dask", *args], stdout=log, stderr=subprocess.STDOUT,
                                      env=env, start_new_session=True))

    try:
        spawn("scheduler", ["scheduler", "--host", "127.0.0.1", "--port", "0", "--dashboard-address", ":0",
                            "--scheduler-file", str(file)])
        address = _scheduler_address(file, procs[0], folder / "scheduler.log")
        for i in range(workers):
            spawn(f"worker{i}", ["worker", address, "--nthreads", "1", "--nworkers", "1", "--host", "127.0.0.1",
                                 "--name", f"farm-{i}", "--no-dashboard"])
        yield address
    finally:
        for proc in reversed(procs):
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGTERM)
        for proc in reversed(procs):
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
        for log in logs:
            log.close()


def _scheduler_address(file, proc, log, within_s: float = 60.0) -> str:
    """The address in the scheduler's file once it is whole: the scheduler creates the file
    before it writes it, so an empty or half-written file is read again (a fresh-clone CI run at
    load 4 read it empty)."""
    deadline = time.time() + within_s
    while True:
        assert proc.poll() is None, log.read_text()
        try:
            return json.loads(file.read_text())["address"]
        except (FileNotFoundError, json.JSONDecodeError, KeyError):
            assert time.time() < deadline, f"no scheduler address in {file} after {within_s:.0f} s"
            time.sleep(0.1)


@contextlib.contextmanager
def killing_a_busy_worker(client, matching: str = "", within_s: float = 120.0):
    """While the ``with`` block runs, SIGKILL the first worker seen busy with a task whose key
    contains ``matching`` (once); yields the list that receives the killed process id."""
    import threading

    victims: list = []
    stop = threading.Event()

    def watch():
        deadline = time.time() + within_s
        while time.time() < deadline and not victims and not stop.is_set():
            busy = sorted(w for w, keys in client.processing().items() if any(matching in str(k) for k in keys))
            if busy:
                pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
                os.kill(pid, signal.SIGKILL)
                victims.append(pid)
            time.sleep(0.02)

    killer = threading.Thread(target=watch)
    killer.start()
    try:
        yield victims
    finally:
        stop.set()
        killer.join()
