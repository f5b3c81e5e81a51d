"""Deterministic release of GL objects.

GL objects (buffers, textures, programs, framebuffers) hold driver memory until released; relying
on garbage collection makes memory use depend on timing. A :class:`GLScope` owns the objects made
through it and releases them in reverse order on :meth:`GLScope.release` or at the end of a
``with`` block.

>>> from rrcache.gl.context import get_context
>>> ctx = get_context()
>>> with GLScope() as scope:
...     buf = scope.own(ctx.buffer(reserve=16))
...     buf.size
16
"""
from __future__ import annotations

from typing import TypeVar

import moderngl

T = TypeVar("T")


class GLScope:
    """Owns GL objects and releases them (last made, first released) exactly once.

    A framebuffer that is still bound is unbound first (see
    :func:`rrcache.gl.context.bind_default_framebuffer`).
    """

    def __init__(self) -> None:
        self._objects: list = []

    def own(self, obj: T) -> T:
        """Take ownership of ``obj`` (anything with a ``release()`` method) and return it."""
        self._objects.append(obj)
        return obj

    def release(self) -> None:
        """Release every owned object; safe to call more than once."""
        while self._objects:
            obj = self._objects.pop()
            if isinstance(obj, moderngl.Framebuffer) and obj.ctx.fbo is obj:
                from rrcache.gl.context import bind_default_framebuffer

                bind_default_framebuffer(obj.ctx)
            obj.release()

    def __len__(self) -> int:
        return len(self._objects)

    def __enter__(self) -> "GLScope":
        return self

    def __exit__(self, *exc) -> None:
        self.release()
