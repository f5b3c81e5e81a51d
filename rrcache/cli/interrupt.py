"""SIGTERM handled like SIGINT: a command asked to stop by ``kill`` (a job scheduler, a
container's stop, ``timeout``) says so in one line, leaves the profile store consistent with its
run log marked ``interrupted`` (never left ``running``) and keeps everything already computed,
exactly as Ctrl-C does.

:func:`install` makes SIGTERM raise :class:`Terminated`, a :class:`KeyboardInterrupt`, so every
path that handles an interrupt (the profiler's store, the commands' messages) handles it too;
:func:`exit_code` and :func:`word` tell the two apart for the last line (exit 130 for SIGINT, 143
for SIGTERM, as shells report them).
"""
from __future__ import annotations

import signal
import threading

_received: list[int] = []


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread where the signal arrived."""


def _on_sigterm(signum, frame) -> None:
    _received.append(signum)
    raise Terminated()


def install() -> None:
    """Make SIGTERM raise :class:`Terminated` in the main thread (nothing elsewhere: only the
    main thread may set a handler)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _on_sigterm)


def terminated() -> bool:
    return bool(_received)


def exit_code() -> int:
    """130 after Ctrl-C, 143 after SIGTERM."""
    return 143 if terminated() else 130


def word() -> str:
    """'interrupted', or 'terminated (SIGTERM)'."""
    return "terminated (SIGTERM)" if terminated() else "interrupted"
