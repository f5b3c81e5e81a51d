"""The one rule for writing output files: regular files inside the chosen folder, whole or not at all.

Every file rrcache writes (shader passes and manifests, ``profile.json``, the store, plots,
``report.html``, rendered frames, the lock, the reference-frame cache, the benches' records) goes
through this module:

* **inside the chosen folder.** An :class:`OutputFolder` is opened once, by the path the user
  chose (created when missing); everything below it is reached from that descriptor, one name at
  a time, never following a symbolic link (``O_NOFOLLOW``, ``dir_fd``). A link placed inside a
  profile folder (``optimized`` → ``/etc``, ``profile.lock`` → ``/dev/sda``) is refused, never
  followed out of it.
* **only regular files.** A target that exists and is not a regular file (a device, a FIFO, a
  directory, a symbolic link) is an error naming it: it is never renamed over (``rrcache report
  P --out /dev/null`` run as root once replaced the machine's ``/dev/null``).
* **whole or not at all.** A file is written under a temporary name in the same folder (created
  with ``O_EXCL``, the mode ``open()`` would give), flushed to disk and renamed over the target
  (``os.replace`` is atomic within a file system): a full disk or a killed process never leaves a
  truncated file that looks like a result (``rrcache instance`` once left a 0-byte manifest). A
  failed write removes the temporary file and raises ``OSError`` naming the target (the command
  line reports it as one line, exit code 2).

Libraries that write by file name (OpenImageIO, SQLite) get one too: :meth:`OutputFolder.via_file`
hands them a file in a private temporary folder and copies what they wrote in by the rule;
:meth:`OutputFolder.regular_or_missing` checks the names SQLite will open.

>>> with OutputFolder("out") as out:                         # doctest: +SKIP
...     out.folder("optimized").folder("e1").write_text("manifest.json", "{}\\n")
>>> write_text("out/manifest.json", "{}\\n")                  # doctest: +SKIP
"""
from __future__ import annotations

import contextlib
import os
import secrets
import shutil
import stat
import tempfile
from typing import Iterator, Optional

from rrcache.errors import RRCacheError, printable
from rrcache.files import Descriptor, kind_of, read_bytes

_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_DIRECTORY = getattr(os, "O_DIRECTORY", 0)
_CLOEXEC = getattr(os, "O_CLOEXEC", 0)
_NONBLOCK = getattr(os, "O_NONBLOCK", 0)
_NOCTTY = getattr(os, "O_NOCTTY", 0)


def _refuse(path: str, what: str, hint: str) -> RRCacheError:
    return RRCacheError(what, printable(path), hint=hint)


def _check_name(name: str) -> str:
    if not name or name in (".", "..") or "/" in name or "\0" in name:
        raise ValueError(f"not a file name: {name!r}")
    return name


class OutputFolder(Descriptor):
    """A folder rrcache writes into, opened once (see the module docstring). ``path`` is the
    folder as the user named it (for messages); :meth:`folder` opens a subfolder without following
    links; :meth:`write_bytes`/:meth:`write_text` write a file by the rule. Close it (or use a
    ``with`` block) when done."""

    def __init__(self, path: "str | os.PathLike[str]", create: bool = True, _fd: Optional[int] = None):
        self.path = os.fspath(path)
        self.fd = -1
        if _fd is not None:
            self.fd = _fd
            return
        if create:
            try:
                os.makedirs(self.path, exist_ok=True)
            except FileExistsError:
                pass  # not a folder: said below
        try:
            self.fd = os.open(self.path, os.O_RDONLY | _DIRECTORY | _CLOEXEC)
        except NotADirectoryError:
            raise _refuse(self.path, "is not a folder", "give a folder to write into (--out)") from None
        except FileNotFoundError:
            raise _refuse(self.path, "no such folder", "create it, or give another --out") from None

    # ------------------------------------------------------------------ folders
    def join(self, name: str) -> str:
        """``name`` inside this folder, as a path (for messages and for readers)."""
        return os.path.join(self.path, name)

    def folder(self, name: str, create: bool = True) -> "OutputFolder":
        """The subfolder ``name`` (one name, created when missing), opened without following a
        symbolic link: a link or any other non-folder there is refused."""
        _check_name(name)
        if create:
            try:
                os.mkdir(name, 0o777, dir_fd=self.fd)
            except FileExistsError:
                pass
        try:
            fd = os.open(name, os.O_RDONLY | _DIRECTORY | _NOFOLLOW | _CLOEXEC, dir_fd=self.fd)
        except OSError as err:
            st = self._lstat(name)
            if st is not None and not stat.S_ISDIR(st.st_mode):
                raise _refuse(self.join(name), f"exists and is {kind_of(st.st_mode)}, not a folder",
                              "rrcache writes only inside the output folder and follows no link out of it; "
                              "remove it or choose another --out") from None
            raise OSError(err.errno, err.strerror, self.join(name)) from None
        return OutputFolder(self.join(name), _fd=fd)

    def _lstat(self, name: str) -> Optional[os.stat_result]:
        try:
            return os.stat(name, dir_fd=self.fd, follow_symlinks=False)
        except FileNotFoundError:
            return None

    def regular_or_missing(self, *names: str) -> None:
        """Each of ``names`` is a regular file or absent, else :class:`RRCacheError` (for files a
        library opens by name, such as SQLite's database and its ``-wal``/``-shm`` files)."""
        for name in names:
            st = self._lstat(_check_name(name))
            if st is not None and not stat.S_ISREG(st.st_mode):
                raise _refuse(self.join(name), f"exists and is {kind_of(st.st_mode)}, not a regular file",
                              "rrcache writes only regular files and follows no link; remove it or choose "
                              "another --out")

    def exists(self, name: str) -> bool:
        return self._lstat(_check_name(name)) is not None

    def remove_files(self) -> None:
        """Remove the regular files directly in this folder (a rewritten selection's old passes);
        links and other entries are left alone."""
        for entry in os.scandir(self.fd):
            if entry.is_file(follow_symlinks=False):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(entry.name, dir_fd=self.fd)

    def rename(self, name: str, new_name: str) -> None:
        """Rename the regular file ``name`` to ``new_name`` in this folder (``--fresh`` moving a
        store aside); either being something else is refused."""
        self.regular_or_missing(name, new_name)
        os.replace(name, new_name, src_dir_fd=self.fd, dst_dir_fd=self.fd)

    # ------------------------------------------------------------------ files
    def write_bytes(self, name: str, data: bytes) -> str:
        """Write ``data`` to the file ``name`` of this folder by the rule (see the module
        docstring); returns its path. An ``OSError`` names the target."""
        _check_name(name)
        target = self.join(name)
        self.regular_or_missing(name)
        stem, ext = os.path.splitext(name)
        tmp = f".{stem}.{secrets.token_hex(4)}.tmp{ext}"
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | _CLOEXEC, 0o666, dir_fd=self.fd)
        except OSError as err:
            raise OSError(err.errno, err.strerror, target) from None
        try:
            try:
                view = memoryview(data)
                while view:
                    view = view[os.write(fd, view):]
                os.fsync(fd)
            finally:
                os.close(fd)
            self.regular_or_missing(name)
            os.replace(tmp, name, src_dir_fd=self.fd, dst_dir_fd=self.fd)
        except BaseException as err:
            with contextlib.suppress(OSError):
                os.unlink(tmp, dir_fd=self.fd)
            if isinstance(err, OSError) and not isinstance(err, RRCacheError):
                raise OSError(err.errno, err.strerror, target) from None
            raise
        return target

    def write_text(self, name: str, text: str) -> str:
        """Write ``text`` as UTF-8 to ``name`` (see :meth:`write_bytes`)."""
        return self.write_bytes(name, text.encode("utf-8"))

    @contextlib.contextmanager
    def via_file(self, name: str) -> Iterator[str]:
        """For a library that writes by file name: yields a path in a private temporary folder
        (same extension as ``name``); on a clean exit what the library wrote there is written to
        ``name`` by the rule. Nothing is written to this folder when the block fails."""
        _check_name(name)
        self.regular_or_missing(name)
        private = tempfile.mkdtemp(prefix="rrcache-")
        try:
            path = os.path.join(private, "out" + os.path.splitext(name)[1])
            yield path
            self.write_bytes(name, read_bytes(path, limit=None))
        finally:
            shutil.rmtree(private, ignore_errors=True)

    def open_regular(self, name: str, flags: int = os.O_RDWR | os.O_CREAT, mode: int = 0o644) -> int:
        """A descriptor of the regular file ``name`` (created with ``flags`` including
        ``O_CREAT``), opened without following a link and checked to be a regular file (the
        profile lock)."""
        _check_name(name)
        self.regular_or_missing(name)
        try:
            fd = os.open(name, flags | _NOFOLLOW | _CLOEXEC | _NONBLOCK | _NOCTTY, mode, dir_fd=self.fd)
        except OSError as err:
            raise OSError(err.errno, err.strerror, self.join(name)) from None
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            os.close(fd)
            raise _refuse(self.join(name), f"is {kind_of(st.st_mode)}, not a regular file", "remove it")
        os.set_blocking(fd, True)
        return fd

    def proc_path(self, name: str) -> str:
        """A path to ``name`` that reaches this folder through its open descriptor (Linux's
        ``/proc/self/fd``), so a folder renamed or replaced by a link meanwhile is not followed;
        the plain path where ``/proc`` is missing."""
        through = f"/proc/self/fd/{self.fd}"
        return os.path.join(through, name) if os.path.isdir(through) else self.join(name)


def _split(path: "str | os.PathLike[str]") -> tuple[str, str]:
    folder, name = os.path.split(os.fspath(path))
    return folder or ".", name


def write_bytes(path: "str | os.PathLike[str]", data: bytes) -> str:
    """Write ``data`` to the file ``path`` by the rule (its folder is the chosen one, created
    when missing); an ``OSError`` names ``path``."""
    folder, name = _split(path)
    with OutputFolder(folder) as out:
        out.write_bytes(name, data)
    return os.fspath(path)


def write_text(path: "str | os.PathLike[str]", text: str) -> str:
    """Write ``text`` as UTF-8 to ``path`` (see :func:`write_bytes`)."""
    return write_bytes(path, text.encode("utf-8"))


@contextlib.contextmanager
def via_file(path: "str | os.PathLike[str]") -> Iterator[str]:
    """:meth:`OutputFolder.via_file` for the file ``path`` (its folder the chosen one)."""
    folder, name = _split(path)
    with OutputFolder(folder) as out, out.via_file(name) as tmp:
        yield tmp
