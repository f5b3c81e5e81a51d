"""Def-use: what the code under a node defines and uses, the one account every data-flow pass
reads (the node table's reaching definitions, :mod:`rrcache.analysis.cacheable`; the
dead-code elimination's liveness, :mod:`rrcache.compiler.prune`; the estimators' accumulators
and term ranges, :mod:`rrcache.analysis.estimators` and :mod:`rrcache.analysis.term_range`; the
one-pass feeders, :mod:`rrcache.compiler.feeders`; the unroller's constants and the inliner's
effects).

- A *definition* (:class:`Def`) is a write of a variable: ``root`` the identifier of the
  variable written (``a`` in ``a[i].xy = ...``), ``node`` what writes it (an ``Assign``, a
  ``++``/``--`` ``Unary``, or a ``Call`` taking the variable as an ``out``/``inout`` argument)
  and ``whole`` when the write replaces the whole variable (``x = e``; ``x`` passed to an ``out``
  parameter) rather than a part of it or from its old value (``x.y = e``, ``x[i] = e``,
  ``x += e``, ``x++``, an ``inout`` argument). A declaration with an initialiser defines its
  variable too (:func:`declared`).
- A *use* is a read of a variable: every identifier except the target of a whole assignment
  ``x = e`` (:func:`uses`).
- :func:`var_key`: the variable an identifier names, told apart by its declaration (shadowing).

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("void f(out float a, float b) { a = b; }\\n"
...                  "void main() { float x, y, z; x = 1.0; y++; f(z, x); }")
>>> main = s.unit.decls[-1]
>>> [(d.root.name, type(d.node).__name__, d.whole) for d in definitions(main.body)]
[('x', 'Assign', True), ('y', 'Unary', False), ('z', 'Call', True)]
>>> [r.name for r in written_roots(main.body)], [u.name for u in uses(main.body)]
(['x', 'y', 'z'], ['y', 'z', 'x'])
"""
from __future__ import annotations

from typing import Iterator, NamedTuple, Optional

from rrcache.glsl import ast as A
from rrcache.glsl.visitor import NodeVisitor

__all__ = ["Def", "definitions", "defs_at", "written_roots", "uses", "declared", "var_key",
           "lvalue_root", "out_qualifiers", "param_qualifier"]


class Def(NamedTuple):
    """One write of a variable (module docstring)."""

    root: A.Ident
    node: A.Node
    whole: bool


def lvalue_root(e: A.Expr) -> Optional[A.Ident]:
    """The variable an l-value expression writes (``a`` in ``a[i].xy``)."""
    while isinstance(e, (A.Field, A.Index)):
        e = e.obj
    return e if isinstance(e, A.Ident) else None


class _DefsAt(NodeVisitor):
    """The definitions a node makes itself (not those of the nodes under it)."""

    def generic_visit(self, n) -> tuple:
        return ()

    def visit_Assign(self, n: A.Assign) -> tuple:
        root = lvalue_root(n.target)
        if root is None:
            return ()
        return (Def(root, n, n.op == "=" and root is n.target),)

    def visit_Unary(self, n: A.Unary) -> tuple:
        if n.op not in ("++", "--"):
            return ()
        root = lvalue_root(n.operand)
        return () if root is None else (Def(root, n, False),)

    def visit_Call(self, n: A.Call) -> tuple:
        if n.target is None:
            return ()
        out = []
        for q, arg in zip(out_qualifiers(n), n.args):
            if q != "in":
                root = lvalue_root(arg)
                if root is not None:
                    out.append(Def(root, n, q == "out" and root is arg))
        return tuple(out)


_DEFS_AT = _DefsAt()


def defs_at(n: A.Node) -> tuple:
    """The definitions node ``n`` makes itself (:class:`Def`; a call's in argument order)."""
    return _DEFS_AT.visit(n)


def definitions(node: A.Node) -> Iterator[Def]:
    """Every definition under ``node`` (itself included), in pre-order."""
    for n in A.walk(node, decl_types=False):
        yield from defs_at(n)


def written_roots(node: A.Node) -> Iterator[A.Ident]:
    """The variables the code under ``node`` writes: assignment targets, ``++``/``--`` operands,
    and arguments passed to ``out``/``inout`` parameters (of calls with a resolved target)."""
    for d in definitions(node):
        yield d.root


def uses(node: A.Node) -> Iterator[A.Ident]:
    """The identifiers under ``node`` that read their variable (all but whole-assignment
    targets; array sizes in declaration types included), in pre-order."""
    targets = {id(d.root) for d in definitions(node) if d.whole and isinstance(d.node, A.Assign)}
    for n in A.walk(node):
        if n.__class__ is A.Ident and id(n) not in targets:
            yield n


def declared(node: A.Node) -> Iterator[A.Declarator]:
    """The variables declared under ``node``."""
    for n in A.walk(node):
        if n.__class__ is A.Declarator:
            yield n


def var_key(ident: A.Ident) -> tuple:
    """The identity of the variable an identifier refers to: its declaration and name (its
    name alone when it is not resolved)."""
    sym = ident.symbol
    if sym is None:
        return ("name", ident.name)
    return (id(sym.decl), sym.name)


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
