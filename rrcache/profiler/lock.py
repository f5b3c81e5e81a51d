"""One store, one writer: the lock a ``profile`` run holds on its output folder.

The lock is ``profile.lock`` beside the store, locked with ``flock(2)`` for as long as the run
holds the store; the file holds the owner's process id and command line for the message a second
run gets. The kernel drops an ``flock`` when its process dies, however it dies (``SIGKILL``
included), so a killed run never leaves a stale lock: the file may stay, unlocked, and the next
run takes it. A second ``rrcache profile`` on the same ``--out`` is told which process holds the
folder and exits with code 2, or with ``--wait`` waits for it.

>>> with StoreLock.acquire("out/profile.lock"):   # doctest: +SKIP
...     pass
"""
from __future__ import annotations

import errno
import fcntl
import os
import sys
import time
from pathlib import Path
from typing import Optional

from rrcache.atomic import OutputFolder
from rrcache.errors import RRCacheError, printable

LOCK_NAME = "profile.lock"


class StoreLock:
    """A held lock (see the module docstring); :meth:`release` or a ``with`` block frees it."""

    def __init__(self, path: Path, fd: int):
        self.path = path
        self.fd: Optional[int] = fd

    @classmethod
    def acquire(cls, path: "str | os.PathLike[str]", wait: bool = False,
                poll_s: float = 0.2) -> "StoreLock":
        """Take the lock at ``path`` (created if missing). Held by another live process: raise an
        :class:`RRCacheError` naming it, or with ``wait`` block until it is free."""
        path = Path(path)
        try:
            # by rrcache.atomic's rule: a link or a device named profile.lock is refused, not opened
            with OutputFolder(path.parent) as folder:
                fd = folder.open_regular(path.name, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as err:
            raise RRCacheError(f"cannot create the lock file {printable(str(path))}: {err.strerror or err}",
                               str(path.parent), hint="choose a writable --out folder") from None
        try:
            while True:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    break
                except OSError as err:
                    if err.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                        raise RRCacheError(f"cannot lock {printable(str(path))}: {err.strerror or err}",
                                           str(path.parent)) from None
                    if not wait:
                        raise RRCacheError(
                            f"another rrcache process is writing this profile ({_owner(fd)})", str(path.parent),
                            hint="wait for it to finish (or pass --wait to wait here), or use another --out "
                                 "folder") from None
                    time.sleep(poll_s)
            owner = f"pid {os.getpid()}: {' '.join(sys.argv)[:200]}\n".encode("utf-8", "replace")
            try:
                os.ftruncate(fd, 0)
                os.pwrite(fd, owner, 0)
            except OSError:  # a full disk: the lock holds without the note
                pass
        except BaseException:
            os.close(fd)
            raise
        return cls(path, fd)

    def release(self) -> None:
        if self.fd is None:
            return
        try:
            os.ftruncate(self.fd, 0)
        except OSError:
            pass
        try:
            fcntl.flock(self.fd, fcntl.LOCK_UN)
        finally:
            os.close(self.fd)
            self.fd = None

    def __enter__(self) -> "StoreLock":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def _owner(fd: int) -> str:
    """What the lock file says about its holder."""
    try:
        text = os.pread(fd, 400, 0).decode("utf-8", "replace").strip()
    except OSError:
        text = ""
    return printable(text) if text else "its process id is not recorded yet"
