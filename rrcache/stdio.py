"""Keeping C libraries' own messages off the user's terminal.

Image codecs (libpng through OpenImageIO) and mesh loaders print warnings straight to the
process's stderr (file descriptor 2), before rrcache can say anything: a corrupt PNG showed
libpng's raw line above rrcache's one-line error. :func:`quiet_stderr` points descriptor 2 at
``/dev/null`` for the duration of such a call; errors come through the libraries' error APIs.
"""
from __future__ import annotations

import contextlib
import os
import sys
import threading

_lock = threading.RLock()


@contextlib.contextmanager
def quiet_stderr():
    """Silence file descriptor 2 (C code's stderr) inside the block; Python's ``sys.stderr`` is
    flushed first so nothing of ours is lost."""
    with _lock:
        try:
            sys.stderr.flush()
        except Exception:  # a closed or replaced stream: nothing to flush
            pass
        try:
            saved = os.dup(2)
        except OSError:  # no descriptor 2 at all: nothing to silence
            yield
            return
        try:
            with open(os.devnull, "wb") as null:
                os.dup2(null.fileno(), 2)
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
