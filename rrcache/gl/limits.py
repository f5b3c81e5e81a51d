"""Refusing render targets that cannot be made, before anything is allocated.

A resolution is checked against the driver's limits (``GL_MAX_TEXTURE_SIZE``,
``GL_MAX_RENDERBUFFER_SIZE``, ``GL_MAX_VIEWPORT_DIMS``) and against the memory it would take:
``bytes_per_pixel`` × width × height, the caller's estimate of its GL targets plus the host copies
it reads back, compared with the memory the system has available (``MemAvailable`` of
``/proc/meminfo``; on Mesa llvmpipe textures live in system memory; a GPU's own memory is not
queryable in core GL, so for it this is a bound on the read-back copies). Either way the
:class:`~rrcache.errors.GLError` says how many bytes it would need and what the limit is.

>>> from rrcache.gl.context import get_context
>>> check_target_size(get_context(), (64, 48), 57)
>>> check_target_size(get_context(), (100000, 100000), 57)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
rrcache.errors.GLError: resolution: 100000x100000 would need 570,000,000,000 bytes (530.9 GiB) ...
"""
from __future__ import annotations

import contextlib
import os
from typing import Optional

from rrcache.errors import GLError

_HINT = "render at a smaller resolution (--resolution WxH, or the session's \"resolution\")"


def available_memory() -> Optional[int]:
    """Bytes of memory the system can give without swapping (``MemAvailable``; else free pages);
    None when neither is known."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def max_target_size(ctx) -> int:
    """The largest width or height the driver accepts for a render target."""
    info = ctx.info
    limits = [int(info["GL_MAX_TEXTURE_SIZE"]), int(info["GL_MAX_RENDERBUFFER_SIZE"])]
    viewport = info.get("GL_MAX_VIEWPORT_DIMS")
    if viewport:
        limits.extend(int(v) for v in viewport)
    return min(limits)


@contextlib.contextmanager
def target_guard(size, where: str = "resolution"):
    """Turn the driver's refusal to make a render target inside the block (moderngl's
    ``framebuffer is not complete``: llvmpipe accepts 16384x16384 in its limits but cannot make a
    4 GiB float target) into a :class:`GLError` naming ``where`` and the size."""
    import moderngl

    try:
        yield
    except moderngl.Error as err:
        w, h = int(size[0]), int(size[1])
        raise GLError(f"the driver could not make the {w}x{h} render targets ({err})", where, _HINT) from None


def _gib(n: int) -> str:
    return f"{n:,} bytes ({n / 2 ** 30:.1f} GiB)"


def check_target_size(ctx, size, bytes_per_pixel: int, where: str = "resolution") -> None:
    """Raise :class:`GLError` (naming ``where``, the bytes needed and the limit) when ``size``
    (w, h) exceeds the driver's largest target or the memory available."""
    w, h = int(size[0]), int(size[1])
    need = w * h * int(bytes_per_pixel)
    largest = max_target_size(ctx)
    if w > largest or h > largest:
        raise GLError(f"{w}x{h} would need {_gib(need)} and is larger than the driver's largest render target, "
                      f"{largest}x{largest} (GL_MAX_TEXTURE_SIZE, GL_MAX_RENDERBUFFER_SIZE, GL_MAX_VIEWPORT_DIMS)",
                      where, _HINT)
    avail = available_memory()
    if avail is not None and need > avail:
        raise GLError(f"{w}x{h} would need {_gib(need)} for its render targets and read-back, more than the "
                      f"{_gib(avail)} of memory available", where, _HINT)
