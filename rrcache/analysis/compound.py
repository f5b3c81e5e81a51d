"""Pass: expand compound assignments ``x op= e`` into ``x = x op e``.

This makes running values visible as expression nodes: after unrolling, the partial sums of
``sum += amplitude * abs(noise(p))`` become the nodes ``sum + amplitude * abs(...)``, one per
octave (the paper's "sum of the three lowest octaves" node). The rewrite is applied only where
it cannot change the program: the target is a variable, a swizzle/field of one, or an element
with a literal or variable index, and the right-hand side writes nothing (no assignment,
``++``/``--`` or ``out`` argument) and calls no user function.

>>> from rrcache.glsl.frontend import parse_shader
>>> from rrcache.glsl.printer import print_glsl
>>> s = parse_shader("void main() { vec4 c = vec4(0.0); c.rgb *= 2.0; gl_FragColor = c; }")
>>> "c.rgb = c.rgb * 2.0;" in print_glsl(expand_compound_assignments(s).unit)
True
"""
from __future__ import annotations

import dataclasses

from rrcache.glsl import ast as A
from rrcache.glsl.visitor import NodeVisitor
from rrcache.glsl.semantic import check

from rrcache.glsl.ast import walk
from rrcache.glsl.rewrite import clone
from rrcache.glsl.defuse import written_roots

__all__ = ["expand_compound_assignments", "expand_unit"]

_OPS = frozenset({"+=", "-=", "*=", "/=", "%=", "<<=", ">>=", "&=", "^=", "|="})


def expand_compound_assignments(shader):
    """Return a copy of ``shader`` with compound assignments expanded (module docstring); the
    result is type-checked again.

    >>> from rrcache.glsl.frontend import parse_shader
    >>> s = parse_shader("void main() { float a = 1.0; a += 2.0; gl_FragColor = vec4(a); }")
    >>> from rrcache.glsl.printer import print_glsl
    >>> "a = a + 2.0;" in print_glsl(expand_compound_assignments(s).unit)
    True
    """
    unit = expand_unit(clone(shader.unit))
    info = check(unit, shader.path or "<string>")
    return dataclasses.replace(shader, unit=unit, info=info)


def expand_unit(unit: A.TranslationUnit) -> A.TranslationUnit:
    """The pass, in place on ``unit`` (a copy the caller owns)."""
    for node in walk(unit, decl_types=False):
        if isinstance(node, A.Assign) and node.op in _OPS and _simple_target(node.target) \
                and _pure(node.value):
            node.value = A.Binary(node.op[:-1], clone(node.target), node.value, loc=node.loc)
            node.op = "="
    return unit


class _SimpleTarget(NodeVisitor):
    """A variable, a swizzle or field of one, or an element with a literal or variable index."""

    def generic_visit(self, e) -> bool:
        return False

    def visit_Ident(self, e) -> bool:
        return True

    def visit_Field(self, e: A.Field) -> bool:
        return self.visit(e.obj)

    def visit_Index(self, e: A.Index) -> bool:
        return self.visit(e.obj) and isinstance(e.index, (A.IntLit, A.Ident))


_simple_target = _SimpleTarget().visit


def _pure(e: A.Expr) -> bool:
    if next(written_roots(e), None) is not None:
        return False
    for n in walk(e, decl_types=False):
        if isinstance(n, A.Assign) or (isinstance(n, A.Unary) and n.op in ("++", "--")):
            return False
        if isinstance(n, A.Call) and (n.kind == "function"
                                      or getattr(n.target, "side_effects", False)):
            return False
    return True
