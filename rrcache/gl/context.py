"""The one OpenGL context of the process.

Every GL object rrcache creates lives in the context returned by :func:`get_context`; nothing else
in the package (and no test) creates a context. The context is a headless moderngl context on EGL
with at least OpenGL 3.3 core (on the development machines: Mesa llvmpipe, GL 4.5 core).

llvmpipe reads its thread count from ``LP_NUM_THREADS`` when the context is created, so
``get_context(threads=1)`` sets that variable first; asking for another count once the context
exists only warns, since the running context cannot change it.

>>> ctx = get_context()
>>> ctx.version_code >= 330
True
"""
from __future__ import annotations

import os
import warnings

import moderngl

from rrcache.errors import GLError

_INSTALL_HINT = (
    "install Mesa's EGL and GL drivers (Debian/Ubuntu: apt-get install libegl1 libgl1-mesa-dri "
    "libegl-mesa0) or a GPU driver that provides EGL"
)

_ctx: moderngl.Context | None = None
_threads: str | None = None
_default_fbo: moderngl.Framebuffer | None = None


def get_context(threads: int | None = None) -> moderngl.Context:
    """The process-wide headless GL context (created on first use, then cached).

    ``threads`` sets ``LP_NUM_THREADS`` (llvmpipe's rasteriser threads) before the context is
    created; if the context already exists with another setting a ``RuntimeWarning`` says so.
    Raises :class:`GLError` when EGL or OpenGL 3.3 core is not available.

    >>> get_context() is get_context()
    True
    """
    global _ctx, _threads
    wanted = None if threads is None else str(int(threads))
    if _ctx is not None:
        if wanted is not None and wanted != _threads:
            warnings.warn(
                f"the GL context already exists with LP_NUM_THREADS={_threads or 'unset'}; "
                f"threads={wanted} takes effect only after release_context()",
                RuntimeWarning,
                stacklevel=2,
            )
        return _ctx
    if wanted is not None:
        os.environ["LP_NUM_THREADS"] = wanted
    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=330)
    except Exception as err:  # moderngl/glcontext raise plain Exceptions with the loader's message
        raise GLError(f"cannot create a headless OpenGL 3.3 context through EGL: {err}", hint=_INSTALL_HINT) from err
    if ctx.version_code < 330:
        version = ctx.version_code
        ctx.release()
        raise GLError(f"the OpenGL driver offers only version {version // 100}.{version % 100 // 10}, 3.3 core is needed",
                      hint=_INSTALL_HINT)
    _ctx = ctx
    _threads = os.environ.get("LP_NUM_THREADS")
    return ctx


def context_threads() -> str | None:
    """The ``LP_NUM_THREADS`` value the current context was created with (None: unset or no context)."""
    return _threads if _ctx is not None else None


def bind_default_framebuffer(ctx: moderngl.Context) -> None:
    """Bind GL's default framebuffer (name 0).

    A headless context has no ``ctx.screen``; moderngl re-binds the *current* framebuffer after
    creating a new one, so releasing the bound framebuffer without this would leave a
    ``GL_INVALID_OPERATION`` behind. :class:`rrcache.gl.resources.GLScope` calls it for you.

    >>> bind_default_framebuffer(get_context())
    """
    global _default_fbo
    if _default_fbo is None or _default_fbo.ctx is not ctx:
        _default_fbo = ctx.detect_framebuffer(0)
    _default_fbo.use()


def release_context() -> None:
    """Release the process-wide context (if any); the next :func:`get_context` creates a new one.

    Every GL object made in the old context becomes invalid, so the example is not run (it
    would invalidate the objects of whoever runs it, a test suite's shared context among them).

    >>> release_context()    # doctest: +SKIP
    """
    global _ctx, _threads, _default_fbo
    if _ctx is not None:
        _ctx.release()
    _ctx = None
    _threads = None
    _default_fbo = None
