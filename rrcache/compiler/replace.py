"""Pass: put an expression where the cached node was.

In the prepared unit (:mod:`rrcache.compiler.locate`) E is the placeholder identifier inside S;
:func:`replace_node` substitutes it (in S only) by a fresh expression: ``rr_node`` in the passes
that bind the value to a variable, ``<unpack>(rr_current())`` in the final three-pass pass.

>>> from rrcache.compiler.locate import PLACEHOLDER
>>> from rrcache.glsl.printer import print_expr
>>> s = A.ExprStmt(A.Binary("*", A.Ident(PLACEHOLDER), A.Ident("k")))
>>> replace_node(s, lambda: A.Ident("rr_node"))
>>> print_expr(s.expr)
'rr_node * k'
"""
from __future__ import annotations

from typing import Callable

from rrcache.errors import UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.ast import is_ident, substitute
from rrcache.compiler.locate import PLACEHOLDER
from rrcache.compiler.outputs import unpack

#: The variable that holds the cached value in the passes that bind it.
NODE_VAR = "rr_node"


def replace_node(stmt: A.Stmt, make: Callable[[], A.Expr]) -> None:
    """Replace the placeholder inside ``stmt`` by ``make()`` (exactly one occurrence)."""
    count = substitute(stmt, is_ident(PLACEHOLDER), lambda n: _located(make(), n))
    if count != 1:
        raise UnsupportedShaderError(
            f"the cached node occurs {count} times in its statement; expected once", stmt.loc,
            "this is a bug in rrcache; please report it")


def _located(e: A.Expr, placeholder: A.Node) -> A.Expr:
    if e.loc is None:
        e.loc = placeholder.loc
    return e


def node_variable() -> A.Expr:
    """``rr_node``"""
    return A.Ident(NODE_VAR)


def current_value(components: int) -> A.Expr:
    """``<unpack>(rr_current())``: this frame's payload at this pixel (three-pass, pass 3)."""
    return unpack(A.Call("rr_current", []), components)


def previous_value(components: int) -> A.Expr:
    """``<unpack>(rr_previous())``: the value reprojected from the previous frame."""
    return unpack(A.Call("rr_previous", []), components)


def previous_payload() -> A.Expr:
    """``rr_previous()``, the whole reprojected payload."""
    return A.Call("rr_previous", [])

