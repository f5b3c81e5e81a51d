"""Pass: bind the cached value to ``rr_node`` right before S.

Two forms (the lead's transformation, see the package docstring):

- hoist form (the usual one): ``T rr_node = E;`` (or ``T rr_node;`` followed by a statement that
  sets it) is inserted right before S, then the statements of ``then`` (the cache writes), and E
  in S becomes ``rr_node``;
- inline form, when S has side effects evaluated before E inside the statement itself (an
  assignment, ``++``, a call with ``out`` arguments or to a user function, an earlier declarator
  of the same declaration that E may read): ``T rr_node;`` before S, E becomes ``(rr_node = E)``
  in place and ``then`` goes right after S.

>>> from rrcache.compiler.locate import PLACEHOLDER
>>> from rrcache.glsl.printer import print_glsl
>>> from rrcache.glsl.parser import parse_source
>>> unit = parse_source("void main() { float y = 2.0 * rr_cachedNodePlaceholder; }")
>>> block = unit.decls[0].body
>>> hoist(Site(block, 0, block.stmts[0]), "float", A.Call("sin", [A.Ident("x")]))
'hoist'
>>> print(print_glsl(unit).strip().splitlines()[2:4])
['    float rr_node = sin(x);', '    float y = 2.0 * rr_node;']
"""
from __future__ import annotations

from typing import Optional

from rrcache.glsl import ast as A
from rrcache.glsl.visitor import NodeVisitor
from rrcache.glsl.ast import own_parts, post_order
from rrcache.compiler.locate import PLACEHOLDER, Site
from rrcache.compiler.replace import NODE_VAR, node_variable, replace_node


class _HasEffect(NodeVisitor):
    """Whether evaluating a node itself has a side effect (its operands not included)."""

    def generic_visit(self, n) -> bool:
        return False

    def visit_Assign(self, n) -> bool:
        return True

    visit_Declarator = visit_Assign

    def visit_Unary(self, n: A.Unary) -> bool:
        return n.op in ("++", "--")

    def visit_Call(self, n: A.Call) -> bool:
        if n.kind == "function" or isinstance(n.target, A.FunctionDecl):
            return True
        target = n.target
        return target is not None and (getattr(target, "side_effects", False)
                                       or any(q != "in" for q in getattr(target, "qualifiers", ())))


_has_effect = _HasEffect().visit


def side_effect_before(stmt: A.Stmt) -> bool:
    """Whether something with a side effect is evaluated before the placeholder in ``stmt``'s
    own expressions (:func:`rrcache.glsl.ast.own_parts`, in evaluation order: operands left to
    right, then the operator). S holds the placeholder in its own parts, and in a ``for`` only in
    the init (:func:`rrcache.compiler.locate.find_site` refuses a condition or step), so the
    search stops there before a condition or step is looked at."""
    for root in own_parts(stmt):
        for n in post_order(root):
            if isinstance(n, A.Ident) and n.name == PLACEHOLDER:
                return False
            if _has_effect(n):
                return True
    return False


def declare(type_name: str, name: str, init: Optional[A.Expr] = None) -> A.DeclStmt:
    """``T name [= init];``"""
    return A.DeclStmt(A.VariableDecl(A.FullType([], A.TypeSpecifier(type_name)),
                                     [A.Declarator(name, None, init)]))


def insert_before(site: Site, stmts: list[A.Stmt]) -> None:
    """Insert ``stmts`` right before S (``site.index`` follows S)."""
    site.block.stmts[site.index:site.index] = stmts
    site.index += len(stmts)


def insert_after(site: Site, stmts: list[A.Stmt]) -> None:
    """Insert ``stmts`` right after S."""
    site.block.stmts[site.index + 1:site.index + 1] = stmts


def hoist(site: Site, type_name: str, value: A.Expr, then: Optional[list[A.Stmt]] = None,
          setter: Optional[A.Stmt] = None) -> str:
    """Bind the node's value to ``rr_node`` before S (see the module docstring); returns the
    form used, ``"hoist"`` or ``"inline"``.

    ``value`` is the expression giving the value; ``setter``, when given, is the statement used
    in the hoist form instead of the initialiser (the one-pass branch), ``value`` then being its
    equivalent expression for the inline form.
    """
    then = list(then or [])
    if side_effect_before(site.stmt):
        insert_before(site, [declare(type_name, NODE_VAR)])
        replace_node(site.stmt, lambda: A.Assign("=", node_variable(), value))
        insert_after(site, then)
        return "inline"
    if setter is None:
        before = [declare(type_name, NODE_VAR, value)]
    else:
        before = [declare(type_name, NODE_VAR), setter]
    insert_before(site, before + then)
    replace_node(site.stmt, node_variable)
    return "hoist"
