"""The one rule for reading a file a user names (a shader and its includes, a session and its
meshes and textures, a vertex shader, ``profile.json``, a store, a report's plots).

1. **Open once**, without blocking (a FIFO does not hang the open) and without making a terminal
   the controlling one.
2. **Check the opened descriptor**, never the path: ``fstat`` says what it is (a FIFO, a device,
   a directory is refused as what it is, not "not found"; ``/dev/zero`` and ``/dev/stdin`` never
   get read) and how large (above the caller's budget it is refused before a byte is read: a
   sparse 100 GB file costs nothing); where the caller confines the file to folders, the
   folder the *opened* file is in (``/proc/self/fd``) must be one of them: a symbolic link flipped
   between a check and an open cannot redirect the read, because there is no second open.
3. **Read from the descriptor**, at most the budget (a file that grows meanwhile is refused), and
   **hash what was read** (``sha256``): nothing reopens the path to hash it.

A refusal is a :class:`Refused` carrying the reason (and for confinement the real path); the
caller turns it into its own error with the place (a JSON path, an ``#include`` line), so every
reader reports the same reasons in the same words.

>>> data = read_file("tests/data/sessions/minimal.json", limit=1 << 20)
>>> data.sha256 == hashlib.sha256(data.data).hexdigest(), len(data.data) == data.size
(True, True)
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import stat
from dataclasses import dataclass
from typing import Iterable, Optional


_FLAGS = (os.O_RDONLY | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_NONBLOCK", 0)
          | getattr(os, "O_NOCTTY", 0))
_CHUNK = 1 << 20


def kind_of(mode: int) -> str:
    """What a file of mode ``mode`` is, in words ("a FIFO", "a character device"...).

    >>> kind_of(stat.S_IFIFO | 0o644)
    'a FIFO (named pipe)'
    """
    for test, words in ((stat.S_ISREG, "a regular file"), (stat.S_ISDIR, "a directory"),
                        (stat.S_ISLNK, "a symbolic link"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                        (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                        (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return words
    return "not a regular file"


class Refused(Exception):
    """Why a file was not read. ``kind``: ``missing``, ``type`` (not a regular file), ``size``
    (above the budget), ``outside`` (confined, and the opened file lies elsewhere: ``real``),
    ``os`` (another operating-system error). ``str()`` is the reason in words."""

    def __init__(self, kind: str, reason: str, real: Optional[str] = None, hint: Optional[str] = None,
                 size: Optional[int] = None):
        super().__init__(reason)
        self.kind, self.reason, self.real, self.hint, self.size = kind, reason, real, hint, size


@dataclass(frozen=True)
class FileData:
    """What :func:`read_file` read: ``data``, its ``sha256``, its ``size`` and the ``real`` path
    of the file that was opened."""

    path: str
    data: bytes
    sha256: str
    size: int
    real: str


def _real(fd: int, path: str) -> str:
    """The path of the file open as ``fd`` (Linux: ``/proc/self/fd``; elsewhere the resolved
    path, which names the same file only if nothing moved meanwhile: checked by inode)."""
    try:
        real = os.readlink(f"/proc/self/fd/{fd}")
        return real[:-len(" (deleted)")] if real.endswith(" (deleted)") else real
    except OSError:
        real = os.path.realpath(path)
        st, opened = os.stat(real), os.fstat(fd)
        if (st.st_dev, st.st_ino) != (opened.st_dev, opened.st_ino):
            raise Refused("os", "the file changed while it was opened") from None
        return real


def inside(real: str, roots: Iterable[str]) -> bool:
    """Whether the real path ``real`` is one of the folders ``roots`` (real paths) or below one.

    >>> inside("/a/b/c.glsl", ["/a"]), inside("/ab/c.glsl", ["/a"])
    (True, False)
    """
    return any(real == r or real.startswith(r.rstrip(os.sep) + os.sep) for r in roots)


def _size_words(n: int) -> str:
    return f"{n:,} bytes"


class Descriptor:
    """An open file descriptor ``fd`` that closes once (``close()``, a ``with`` block, or when
    collected); -1 once closed."""

    fd = -1

    def close(self) -> None:
        if self.fd >= 0:
            with contextlib.suppress(OSError):
                os.close(self.fd)
            self.fd = -1

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self) -> None:
        self.close()


class OpenedFile(Descriptor):
    """A regular file opened by the rule and kept open (a texture decoded later, by a library
    that reads by name: :attr:`library_path` reaches this very file through the descriptor).
    ``sha256`` is computed from the descriptor once. Close it (or let it be collected)."""

    def __init__(self, path: str, fd: int, size: int, real: str):
        self.path, self.fd, self.size, self.real = path, fd, size, real
        self._sha256: Optional[str] = None

    @property
    def library_path(self) -> str:
        through = f"/proc/self/fd/{self.fd}"
        return through if os.path.exists(through) else self.real

    def read(self, limit: Optional[int] = None) -> bytes:
        """Every byte of the file, read from the descriptor (refused past ``limit``)."""
        return _read_all(self.fd, self.path, limit if limit is not None else self.size)

    @property
    def sha256(self) -> str:
        if self._sha256 is None:
            h = hashlib.sha256()
            offset = 0
            while True:
                chunk = os.pread(self.fd, _CHUNK, offset)
                if not chunk:
                    break
                h.update(chunk)
                offset += len(chunk)
            self._sha256 = h.hexdigest()
        return self._sha256


def open_file(path: "str | os.PathLike[str]", limit: Optional[int], roots: Optional[Iterable[str]] = None,
              limit_hint: Optional[str] = None) -> OpenedFile:
    """Open the regular file ``path`` by the rule (steps 1 and 2 of the module docstring): it
    must be a regular file, at most ``limit`` bytes (None: no budget), and with ``roots`` (real
    folder paths) lie inside one of them. Raises :class:`Refused`."""
    path = os.fspath(path)
    if "\0" in path:
        raise Refused("missing", "the path holds a NUL character, which no file name can")
    try:
        fd = os.open(path, _FLAGS)
    except FileNotFoundError:
        raise Refused("missing", "not found") from None
    except OSError as err:
        raise Refused("os", err.strerror or str(err)) from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise Refused("type", f"is {kind_of(st.st_mode)}, not a regular file",
                          hint="give the path of a regular file")
        real = _real(fd, path)
        if roots is not None and not inside(real, list(roots)):
            raise Refused("outside", f"resolves to {real}", real=real)
        if limit is not None and st.st_size > limit:
            raise Refused("size", f"is {_size_words(st.st_size)}, more than the budget of {_size_words(limit)}; "
                          "nothing was read", hint=limit_hint, size=int(st.st_size))
        # a regular file needs no O_NONBLOCK; clear it for plain reads
        with contextlib.suppress(OSError, AttributeError):
            os.set_blocking(fd, True)
        return OpenedFile(path, fd, int(st.st_size), real)
    except BaseException:
        os.close(fd)
        raise


def _read_all(fd: int, path: str, limit: Optional[int], hint: Optional[str] = None) -> bytes:
    """Every byte from ``fd``; past ``limit`` (one byte more is asked for) :class:`Refused`."""
    parts, total = [], 0
    while True:
        chunk = os.pread(fd, _CHUNK if limit is None else min(_CHUNK, limit + 1 - total), total)
        if not chunk:
            return b"".join(parts)
        parts.append(chunk)
        total += len(chunk)
        if limit is not None and total > limit:
            raise Refused("size", f"grew past the budget of {_size_words(limit)} while it was read", hint=hint)


def read_file(path: "str | os.PathLike[str]", limit: Optional[int], roots: Optional[Iterable[str]] = None,
              limit_hint: Optional[str] = None) -> FileData:
    """Read the regular file ``path`` whole by the rule (see the module docstring): at most
    ``limit`` bytes (None: no budget), confined to ``roots`` when given. Raises :class:`Refused`."""
    with open_file(path, limit, roots, limit_hint) as f:
        data = _read_all(f.fd, f.path, limit, limit_hint)
        return FileData(f.path, data, hashlib.sha256(data).hexdigest(), len(data), f.real)


def read_bytes(path: "str | os.PathLike[str]", limit: Optional[int]) -> bytes:
    """The bytes of the regular file ``path`` (:func:`read_file`); a refusal becomes an
    ``OSError`` naming the path (for rrcache's own files, such as a library's output)."""
    try:
        return read_file(path, limit).data
    except Refused as err:
        raise OSError(0, err.reason, os.fspath(path)) from None
