"""An optional per-frame watchdog (``rrcache --frame-timeout S ...``).

A shader can loop for a very long time, and a GL draw cannot be interrupted from Python: while
the driver works, the calling thread holds the interpreter lock, so no thread of the same process
can even notice. The command line therefore runs, with a timeout set, under a small supervisor
(:func:`supervise`): the real command is a child process that reports the start and the end of
every frame on a pipe (:func:`frame`); when a frame is still running after ``S`` seconds the
supervisor kills the child, prints one line and exits with code 2. What was computed before
stays: images already written, profile runs already committed to the store (each is its own
transaction); the store's lock goes with the child. A frame that ends late but ends (in a
process without a supervisor, e.g. the library used directly) is refused after the fact with an
:class:`~rrcache.errors.RRCacheError`.

>>> set_timeout(None)
>>> with frame("frame 3"):
...     pass
"""
from __future__ import annotations

import contextlib
import os
import select
import signal
import subprocess
import sys
import time
from typing import Optional

from rrcache.errors import RRCacheError, printable

#: the environment variable naming the pipe a supervised child reports frames on
PIPE_ENV = "RRCACHE_WATCHDOG_FD"

_timeout: Optional[float] = None
_done = 0

_HINT = ("raise --frame-timeout, render at a smaller resolution, or look for a loop that runs too long "
         "in the shader")


def set_timeout(seconds: Optional[float]) -> None:
    """Set (None: remove) the per-frame timeout."""
    global _timeout, _done
    _timeout = None if seconds is None else float(seconds)
    _done = 0


def timeout() -> Optional[float]:
    return _timeout


def _text(what: str, timeout_s: float, done: int) -> str:
    return (f"{what} ran longer than the {timeout_s:g} s frame timeout (--frame-timeout); the run was "
            f"stopped after {done} finished frames, and what they computed is kept")


def _report(line: str) -> None:
    fd = os.environ.get(PIPE_ENV)
    if fd is None:
        return
    try:
        os.write(int(fd), (line.replace("\n", " ") + "\n").encode("utf-8", "replace"))
    except (OSError, ValueError):  # the supervisor is gone: nothing to tell
        pass


@contextlib.contextmanager
def frame(what: str):
    """Run one frame's draws under the watchdog (a no-op without a timeout)."""
    global _done
    if _timeout is None:
        yield
        return
    start = time.monotonic()
    _report(f"B {_done} {what}")
    try:
        yield
    finally:
        _report("E")
    if time.monotonic() - start > _timeout:
        raise RRCacheError(_text(what, _timeout, _done), hint=_HINT)
    _done += 1


def supervise(argv: list[str], timeout_s: float) -> int:
    """Run ``python -m rrcache ARGV`` as a child that reports its frames, kill it when a frame
    runs past ``timeout_s``; the child's exit code (2 after a kill, with one line on stderr)."""
    read_fd, write_fd = os.pipe()
    env = {**os.environ, PIPE_ENV: str(write_fd)}
    old_int = signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the child, which handles it
    try:
        child = subprocess.Popen([sys.executable, "-m", "rrcache", *argv], env=env, pass_fds=(write_fd,))
    finally:
        os.close(write_fd)
    # a SIGTERM sent to this process is passed on: the child stops as it would itself (its message,
    # its store marked interrupted) and its exit code is this one's
    old_term = signal.signal(signal.SIGTERM, lambda signum, frame: child.send_signal(signal.SIGTERM))
    running: Optional[tuple[float, int, str]] = None
    buffer = b""
    try:
        while True:
            wait = None if running is None else max(0.0, running[0] - time.monotonic())
            ready, _, _ = select.select([read_fd], [], [], 0.5 if wait is None else min(wait, 0.5))
            if ready:
                chunk = os.read(read_fd, 65536)
                if not chunk:  # the child closed the pipe: it has ended
                    break
                buffer += chunk
                *lines, buffer = buffer.split(b"\n")
                for raw in lines:
                    line = raw.decode("utf-8", "replace")
                    if line.startswith("B "):
                        _, done, what = line.split(" ", 2)
                        running = (time.monotonic() + timeout_s, int(done), what)
                    elif line == "E":
                        running = None
            if running is not None and time.monotonic() >= running[0] and child.poll() is None:
                child.kill()
                child.wait()
                sys.stderr.write(f"rrcache: error: {printable(_text(running[2], timeout_s, running[1]))} "
                                 f"(hint: {_HINT})\n")
                sys.stderr.flush()
                return 2
            if child.poll() is not None and not ready:
                break
        code = child.wait()
        return code if code >= 0 else 128 - code
    finally:
        os.close(read_fd)
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGTERM, old_term)
