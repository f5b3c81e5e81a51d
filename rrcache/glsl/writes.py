"""What an expression or statement writes: the variables behind assignment targets, ``++``/``--``
operands and ``out``/``inout`` arguments.

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("void f(out float a, float b) { a = b; }\\n"
...                  "void main() { float x, y, z; x = 1.0; y++; f(z, x); }")
>>> main = s.unit.decls[-1]
>>> [r.name for r in written_roots(main.body)]
['x', 'y', 'z']
"""
from __future__ import annotations

from typing import Iterator, Optional

from rrcache.glsl import ast as A


def lvalue_root(e: A.Expr) -> Optional[A.Ident]:
    """The variable an l-value expression writes (``a`` in ``a[i].xy``)."""
    while isinstance(e, (A.Field, A.Index)):
        e = e.obj
    return e if isinstance(e, A.Ident) else None


def written_roots(e: A.Node) -> Iterator[A.Ident]:
    """The variables an expression (or statement) writes: assignment targets, ``++``/``--`` operands, and
    arguments passed to ``out``/``inout`` parameters (of calls with a resolved target)."""
    for n in A.walk(e, decl_types=False):
        target = None
        if isinstance(n, A.Assign):
            target = n.target
        elif isinstance(n, A.Unary) and n.op in ("++", "--"):
            target = n.operand
        elif isinstance(n, A.Call) and n.target is not None:
            for q, arg in zip(out_qualifiers(n), n.args):
                if q != "in":
                    root = lvalue_root(arg)
                    if root is not None:
                        yield root
        if target is not None:
            root = lvalue_root(target)
            if root is not None:
                yield root


def out_qualifiers(call: A.Call) -> tuple[str, ...]:
    """The parameter qualifiers (``in``/``out``/``inout``) of a resolved call."""
    target = call.target
    if target is None:
        return ()
    if isinstance(target, A.FunctionDecl):
        return tuple(param_qualifier(p) for p in target.params)
    return tuple(getattr(target, "qualifiers", ()))


def param_qualifier(p: A.Param) -> str:
    """``in``, ``out`` or ``inout`` for a parameter."""
    quals = [q for q in p.type.qualifiers if isinstance(q, str)]
    if "inout" in quals:
        return "inout"
    if "out" in quals:
        return "out"
    return "in"
