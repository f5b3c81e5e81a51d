"""Pass (one-pass algorithm): move the statements that only feed E into the miss branch.

In the one-pass shader the value is computed only on a miss::

    T rr_node;
    if (rr_hit() && !rr_refreshNow()) rr_node = <unpack>(rr_previous());
    else { <feeders>; rr_node = E; }

A statement P of S's block that comes before that branch is a *feeder*, and moves to the front
of the ``else`` block (keeping the order of the statements moved), when it is simple and nothing
else needs it:

- P is an expression statement, a local variable declaration, or a block of those (an inlined
  function body), with no ``discard``/``return``/control flow, no call of a user function or of
  a side-effecting built-in;
- every variable P writes or declares is a local of ``main`` that nothing outside the moved
  statements, P and the ``else`` block mentions;
- no statement left between P and the branch writes a variable P reads.

Variables are compared by name, which is conservative: a name used in two scopes blocks the move.

>>> from rrcache.glsl.parser import parse_source
>>> from rrcache.glsl.printer import print_glsl
>>> from rrcache.compiler.locate import Site
>>> unit = parse_source("uniform float u; void main() { float a = u * 2.0; float b = u; "
...                     "float rr_node; if (h) rr_node = 0.0; else { rr_node = a; } "
...                     "gl_FragColor = vec4(rr_node + b); }")
>>> body = unit.decls[1].body
>>> setter = body.stmts[3]
>>> move_feeders(Site(body, 4, body.stmts[4]), setter, setter.else_)
1
>>> print(print_glsl(unit).split("main()")[1].replace(" ", "").replace("\\n", ""))
{floatb=u;floatrr_node;if(h)rr_node=0.0;else{floata=u*2.0;rr_node=a;}gl_FragColor=vec4(rr_node+b);}
"""
from __future__ import annotations

from collections import Counter
from typing import Optional

from rrcache.glsl import ast as A
from rrcache.glsl.ast import main_function, walk
from rrcache.glsl.defuse import declared, written_roots
from rrcache.glsl.visitor import NodeVisitor
from rrcache.compiler.locate import Site


class _Simple(NodeVisitor):
    """Whether a statement may move: expression statements, local declarations and blocks of
    them, calling no user function and no side-effecting built-in."""

    def generic_visit(self, s) -> bool:
        return False

    def visit_Compound(self, s: A.Compound) -> bool:
        return all(self.visit(x) for x in s.stmts)

    def visit_DeclStmt(self, s: A.DeclStmt) -> bool:
        return isinstance(s.decl, A.VariableDecl) and bool(s.decl.declarators) and _pure(s)

    def visit_ExprStmt(self, s: A.ExprStmt) -> bool:
        return _pure(s)


def _pure(s: A.Stmt) -> bool:
    for n in walk(s):
        if isinstance(n, A.Call) and (n.kind == "function" or isinstance(n.target, A.FunctionDecl)
                                      or getattr(n.target, "side_effects", False)):
            return False
    return True


_simple = _Simple().visit


def _uses(node: A.Node) -> Counter:
    return Counter(n.name for n in walk(node) if isinstance(n, A.Ident))


def _writes(s: A.Stmt) -> set[str]:
    """The names ``s`` declares or writes (:mod:`rrcache.glsl.defuse`)."""
    return {d.name for d in declared(s)} | {r.name for r in written_roots(s)}


def _reads(s: A.Stmt) -> set[str]:
    return set(_uses(s))


def move_feeders(site: Site, setter: A.If, miss_branch: A.Compound,
                 unit_main: Optional[A.Compound] = None) -> int:
    """Move E's feeders (see the module docstring) from ``site.block`` into ``miss_branch``;
    returns how many statements moved. ``setter`` is the branch statement in ``site.block``;
    ``unit_main`` the body of ``main`` (found from the block when omitted: pass it when the
    block is nested)."""
    block = site.block
    j = next((i for i, s in enumerate(block.stmts) if s is setter), None)
    if j is None:
        return 0
    body = unit_main if unit_main is not None else block
    locals_ = {n.name for n in walk(body) if isinstance(n, A.Declarator)}
    total = _uses(body)
    inside = _uses(miss_branch)
    moved: list[A.Stmt] = []
    between_writes: set[str] = set()
    # block.stmts[j - 1] declares rr_node; candidates come before it
    for i in range(j - 2, -1, -1):
        p = block.stmts[i]
        if _simple(p):
            w = _writes(p)
            p_uses = _uses(p)
            outside = total - inside - p_uses
            if (w <= locals_ and not any(outside[name] for name in w)
                    and not (_reads(p) & between_writes)):
                moved.insert(0, p)
                inside = inside + p_uses
                continue
        between_writes |= _writes(p)
    if not moved:
        return 0
    ids = {id(s) for s in moved}
    block.stmts = [s for s in block.stmts if id(s) not in ids]
    site.index -= len(moved)
    miss_branch.stmts[0:0] = moved
    return len(moved)


def main_body(unit: A.TranslationUnit) -> A.Compound:
    """The body of ``main`` (for :func:`move_feeders`)."""
    return main_function(unit).body
