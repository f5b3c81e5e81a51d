"""The analysed program: inline → unroll → expand compound assignments → order the terms of sums,
checked once.

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("float f(float x) { return x * 2.0; }\\nvoid main() {"
...                  " float a = 0.0; for (int i = 0; i < 3; i++) a += f(float(i));"
...                  " gl_FragColor = vec4(a); }")
>>> from rrcache.glsl.printer import print_glsl
>>> text = print_glsl(analyse(s).unit)
>>> "for" in text, "f(" in text
(False, False)
"""
from __future__ import annotations

import dataclasses

from rrcache.glsl.semantic import check

from rrcache.glsl.rewrite import paused_gc
from rrcache.analysis.compound import expand_unit
from rrcache.analysis.inline import inline_unit
from rrcache.analysis.sums import reorder_sums
from rrcache.analysis.unroll import (
    DEFAULT_MAX_ITERATIONS, DEFAULT_MAX_SIZE, DEFAULT_MAX_TOTAL, unroll_unit,
)

__all__ = ["analyse"]


def analyse(shader, max_iterations: int = DEFAULT_MAX_ITERATIONS,
            max_total: int = DEFAULT_MAX_TOTAL, max_size: int = DEFAULT_MAX_SIZE, moving=(), scores=None):
    """The analysed copy of ``shader``: every call inlined, constant loops unrolled (at most
    ``max_iterations`` per loop, ``max_total`` body copies and ``max_size`` syntax nodes of
    copies in all; see :mod:`rrcache.analysis.unroll`), compound assignments expanded, the terms
    of every sum the unrolling separated put in the order that makes its partial sums good to
    cache (the ``moving`` inputs' terms last, the lightest first, else by measured ``scores``;
    :mod:`rrcache.analysis.sums`), type-checked again. A valid program equivalent to the input
    up to the rounding of the sums it reordered; node ids (:func:`rrcache.analysis.find_node`)
    refer to it. The input is not modified.
    """
    with paused_gc():
        unit = inline_unit(shader.unit)
        unit = unroll_unit(unit, shader.info, max_iterations, max_total, max_size)
        unit = expand_unit(unit)
        reorder_sums(unit, moving, scores)
        info = check(unit, shader.path or "<string>")
    return dataclasses.replace(shader, unit=unit, info=info)
