"""An optional per-frame watchdog (``rrcache --frame-timeout S ...``).

A shader can loop for a very long time; a GL draw cannot be interrupted from Python, and without
a watchdog only the driver's own limits (if any) stop it. With a timeout set, every frame a
renderer draws runs under :func:`frame`: a frame that is still running after ``S`` seconds stops
the process with one line on stderr and exit code 2. What was computed before stays: images
already written, profile runs already committed to the store (each is its own transaction), and
the store's lock goes with the process. A frame that finishes late but finishes is refused the
same way, as an :class:`~rrcache.errors.RRCacheError`.

>>> set_timeout(None)
>>> with frame("frame 3"):
...     pass
"""
from __future__ import annotations

import contextlib
import os
import threading
import time
from typing import Optional

from rrcache.errors import RRCacheError

_timeout: Optional[float] = None
_done = 0
_lock = threading.Lock()
_deadline: Optional[tuple[float, str]] = None
_wake = threading.Condition(_lock)
_thread: Optional[threading.Thread] = None


def set_timeout(seconds: Optional[float]) -> None:
    """Set (None: remove) the per-frame timeout."""
    global _timeout, _done
    _timeout = None if seconds is None else float(seconds)
    _done = 0


def timeout() -> Optional[float]:
    return _timeout


_HINT = ("raise --frame-timeout, render at a smaller resolution, or look for a loop that runs too long "
         "in the shader")


def _text(what: str) -> str:
    return (f"{what} ran longer than the {_timeout:g} s frame timeout (--frame-timeout); the run was "
            f"stopped after {_done} finished frames, and what they computed is kept")


def _message(what: str) -> str:
    return f"rrcache: error: {_text(what)} (hint: {_HINT})\n"


def _watch() -> None:
    while True:
        with _wake:
            while _deadline is None or time.monotonic() < _deadline[0]:
                wait = None if _deadline is None else max(0.0, _deadline[0] - time.monotonic())
                _wake.wait(wait)
            what = _deadline[1]
        os.write(2, _message(what).encode("utf-8", "replace"))
        os._exit(2)


@contextlib.contextmanager
def frame(what: str):
    """Run one frame's draws under the watchdog (a no-op without a timeout)."""
    global _deadline, _thread, _done
    if _timeout is None:
        yield
        return
    start = time.monotonic()
    with _wake:
        if _thread is None:
            _thread = threading.Thread(target=_watch, name="rrcache-frame-watchdog", daemon=True)
            _thread.start()
        _deadline = (start + _timeout, what)
        _wake.notify()
    try:
        yield
    finally:
        with _wake:
            _deadline = None
            _wake.notify()
    if time.monotonic() - start > _timeout:
        raise RRCacheError(_text(what), hint=_HINT)
    _done += 1
