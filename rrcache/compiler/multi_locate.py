"""Pass (k ≥ 2 cached nodes): find every cached node, and how they nest.

:func:`prepare_nodes` is :func:`rrcache.compiler.locate.prepare` for several nodes: a
``#version 330 core`` copy of the unit in which each node E_j not inside another cached node is
replaced by its own placeholder ``rr_cachedNodePlaceholder_j``; a node inside another cached node
(nested) is replaced by its placeholder inside the outer node's expression instead. Each
:class:`NodeSite` keeps its expression (core profile, holding its direct inner nodes'
placeholders), its type, its ``parent`` (the innermost cached node containing it, or None) and
its ``top`` (the outermost one; itself for a top-level node).

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("varying vec2 v;\\n"
...                  "void main() { float a = 2.0 * sin(v.x); gl_FragColor = vec4(a + cos(v.y)); }")
>>> calls = [n for n in s.unit.walk() if isinstance(n, A.Call) and n.name in ("sin", "cos")]
>>> outer = [n for n in s.unit.walk() if isinstance(n, A.Binary) and n.op == "*"][0]
>>> m = prepare_nodes(s, [outer, calls[0], calls[1]])
>>> [(n.text, n.parent, n.top) for n in m.nodes]
[('2.0 * sin(v.x)', None, 0), ('sin(v.x)', 0, 0), ('cos(v.y)', None, 2)]
>>> print_expr(m.nodes[0].expr)
'2.0 * rr_cachedNodePlaceholder_1'
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any, Optional, Sequence, Union

from rrcache.errors import SourceLoc, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.ast import main_function, substitute, walk
from rrcache.glsl.legacy import to_core
from rrcache.glsl.printer import print_expr
from rrcache.compiler.locate import NODE_TYPES, _shader_path, analysed_unit, resolve

_CARRIER = "rr_cachedNodesCarrier"


def placeholder(j: int) -> str:
    """The identifier standing for node ``j`` (never printed)."""
    return f"rr_cachedNodePlaceholder_{j}"


@dataclass
class NodeSite:
    """One cached node among several (see the module docstring)."""

    index: int
    expr: A.Expr
    type_name: str
    components: int
    text: str
    loc: Optional[SourceLoc]
    parent: Optional[int]
    top: int

    @property
    def name(self) -> str:
        return placeholder(self.index)

    @property
    def var(self) -> str:
        """The variable holding the node's value in the passes that bind it."""
        return f"rr_node_{self.index}"


@dataclass
class MultiLocated:
    """The prepared unit (top-level nodes replaced by their placeholders) and every node."""

    unit: A.TranslationUnit
    nodes: list[NodeSite]
    path: str

    def children(self, j: int) -> list[int]:
        return [n.index for n in self.nodes if n.parent == j]

    def depth(self, j: int) -> int:
        d, p = 0, self.nodes[j].parent
        while p is not None:
            d, p = d + 1, self.nodes[p].parent
        return d


def prepare_nodes(analysed: Any, node_ids: Sequence[Union[int, str, A.Expr]]) -> MultiLocated:
    """Locate every node of ``node_ids`` (at least two, all different) and build the unit."""
    unit = analysed_unit(analysed)
    path = _shader_path(analysed)
    nodes = [resolve(analysed, i) for i in node_ids]
    for j, node in enumerate(nodes):
        t = getattr(node, "type", None)
        name = t.glsl_name() if t is not None else None
        if name not in NODE_TYPES:
            raise UnsupportedShaderError(
                f"node '{print_expr(node)}' has type {name or 'unknown'}; only float and vec2-4 "
                "values are cached", node.loc, "pick a float or vector node from the node table")
        if any(nodes[i] is node for i in range(j)):
            raise UnsupportedShaderError(f"node '{print_expr(node)}' is given twice", node.loc,
                                         "give each node once, with its one period")
    main = main_function(unit)
    in_main = {id(n) for n in walk(main.body)} if main is not None else set()
    for node in nodes:
        if id(node) not in in_main:
            raise UnsupportedShaderError(
                f"node '{print_expr(node)}' is not in main() of the analysed shader", node.loc,
                "pass the shader returned by the analysis and node ids from its table")
    # nesting: the innermost other cached node containing each node
    inside = [{id(n) for n in walk(node)} for node in nodes]
    parents: list[Optional[int]] = []
    for j, node in enumerate(nodes):
        holders = [i for i in range(len(nodes)) if i != j and id(node) in inside[i]]
        # the innermost holder is the one inside every other holder
        inner = [i for i in holders if all(i == h or id(nodes[i]) in inside[h] for h in holders)]
        parents.append(inner[0] if inner else None)
    memo: dict[int, Any] = {}
    work = copy.deepcopy(unit, memo)
    copies = [memo[id(n)] for n in nodes]

    def depth(j: int) -> int:
        d, p = 0, parents[j]
        while p is not None:
            d, p = d + 1, parents[p]
        return d

    work_main = main_function(work)
    for j in sorted(range(len(nodes)), key=depth, reverse=True):  # innermost first
        host = work_main.body if parents[j] is None else copies[parents[j]]
        ph = A.Ident(placeholder(j), loc=nodes[j].loc)
        if substitute(host, lambda n, c=copies[j]: n is c, lambda n, p=ph: p) != 1:
            raise UnsupportedShaderError("a cached node occurs more than once in the tree", nodes[j].loc)
    # the nodes ride along in a statement of main so that to_core rewrites them alike
    work_main.body.stmts.append(A.ExprStmt(A.Sequence([A.Ident(_CARRIER), *copies])))
    core = to_core(work)
    carrier = main_function(core).body.stmts.pop()
    exprs = carrier.expr.exprs[1:]
    out = []
    for j, node in enumerate(nodes):
        top = j
        while parents[top] is not None:
            top = parents[top]
        name = node.type.glsl_name()
        out.append(NodeSite(j, exprs[j], name, NODE_TYPES[name], print_expr(node), node.loc, parents[j], top))
    return MultiLocated(core, out, path)
