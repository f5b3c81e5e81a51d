"""Writing output files whole or not at all.

A full disk or a process killed mid-write must never leave a truncated file that looks like a
result (``rrcache instance`` once left a 0-byte manifest). :func:`write_text` writes a temporary
file in the same folder, flushes it to disk and renames it over the target (``os.replace`` is
atomic within a file system); :func:`temporary_path` does the same for writers that take a file
name (OpenImageIO). A failed write removes the temporary file and raises ``OSError`` (the command
line reports it as one line, exit code 2).

>>> write_text("out/manifest.json", "{}\\n")   # doctest: +SKIP
"""
from __future__ import annotations

import contextlib
import os
import tempfile


@contextlib.contextmanager
def temporary_path(path: "str | os.PathLike[str]"):
    """Yield a temporary file name beside ``path`` (same extension); on a clean exit it is
    renamed to ``path``, on an error removed."""
    path = os.fspath(path)
    folder, name = os.path.split(path)
    stem, ext = os.path.splitext(name)
    fd, tmp = tempfile.mkstemp(prefix=f".{stem}.", suffix=f".tmp{ext}", dir=folder or ".")
    os.close(fd)
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # as open() would have made it (mkstemp makes 0600)
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_bytes(path: "str | os.PathLike[str]", data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (see the module docstring); an ``OSError`` names
    ``path``."""
    try:
        with temporary_path(path) as tmp:
            with open(tmp, "wb") as f:
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
    except OSError as err:
        if err.filename is None or str(err.filename).endswith(".tmp" + os.path.splitext(os.fspath(path))[1]):
            raise OSError(err.errno, err.strerror, os.fspath(path)) from None
        raise


def write_text(path: "str | os.PathLike[str]", text: str) -> None:
    """Write ``text`` as UTF-8 to ``path`` atomically."""
    write_bytes(path, text.encode("utf-8"))
