"""The OpenGL layer: the one context, programs with mapped errors, textures, uniforms.

>>> from rrcache.gl import get_context, build_program
>>> ctx = get_context()
>>> ctx.version_code >= 330
True
"""
from rrcache.gl.context import get_context, release_context  # noqa: F401
from rrcache.gl.program import build_program  # noqa: F401
from rrcache.gl.resources import GLScope  # noqa: F401
