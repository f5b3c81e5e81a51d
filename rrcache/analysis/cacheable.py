"""Pass: enumerate the cacheable nodes of the analysed program.

A *node* is an expression node of the analysed AST (:func:`rrcache.analysis.pipeline.analyse`:
calls inlined, constant loops unrolled). Node ids are ``n<k>``, ``k`` the index of the
expression in a pre-order walk of the analysed translation unit: stable for the same source and
defines, and resolved by :func:`find_node`. Values flow through local variables, so a node is an
expression *at its program point*; caching it means replacing that expression by a cache fetch.

Every expression in a value position of ``main`` is either listed or left out with one reason
(the first that applies, in this order):

``type``       not a ``float``/``vec2``/``vec3``/``vec4`` (ints, bools, matrices, structs...).
``dynamic``    inside code that a pixel may run zero or several times: a loop left after
               unrolling, a branch of ``if``/``?:``/``switch``/``&&``/``||`` on a per-pixel
               condition, or a function the inliner kept. Expressions with side effects
               (assignments, ``++``/``--``, calls of side-effecting built-ins or kept
               functions) are not pure values and get this reason too. Code after a per-pixel
               ``discard``/``return`` (and under the inliner's early-return guards
               ``_rr_live_<n>``) is *not* dynamic: it runs exactly where the original does.
``screen``     it depends on the pixel's screen position (``gl_FragCoord``, and so on
               ``gl_FragCoord.xy / u_resolution``). Such a value is attached to the screen, not
               to the surface: reprojection fetches it from where the surface was last frame,
               a different pixel as soon as anything moves. A value of ``gl_FragCoord`` and
               constants alone is the same at a pixel every frame, but it is not the same at
               the *surface point*, and the cache is indexed by surface point; so it is
               excluded too (such values are cheap to recompute or belong in a screen-space
               texture, not in a reprojection cache).
``derivative`` caching it would change a screen-space derivative: it is inside the
               coordinate of an implicit-LOD texture lookup or the operand of
               ``dFdx``/``dFdy``/``fwidth``, or it is written into a variable that such an
               argument reads (the pass that uses a cached value reads it at helper pixels
               too, where the cache holds another surface's value).
``uniform``    the same for every pixel: it depends only on literals, constants and uniforms.
``duplicate``  the same value as a node listed earlier on every path to it: an identical
               expression reading the same definitions of the same variables, or a read of a
               local variable that has exactly one reaching definition (that definition's
               expression is the node kept).
``cheap``      its cost (below) is under ``cheap_below`` (default
               :data:`rrcache.analysis.cost.CACHE_LOOKUP_COST`): a cache lookup costs more.

The *cost* of a node is the work a cache hit saves: the static cost
(:mod:`rrcache.analysis.cost`) of its expression tree plus that of every definition of a local
variable it depends on, transitively, each counted once; a definition inside a loop the unroller
left rolled counts once per iteration of the loop's constant trip bound
(:func:`rrcache.analysis.cost.loop_trips`; 1 when the bound is not constant), so the result of a
64-step ray march with an early ``break`` costs 64 steps, not one. Every write makes a definition: a
whole assignment, and also a partial one (a component ``c.rgb += ...``, a member
``m.albedo.rgb = ...``, an element ``a[i] = ...``, ``++``/``--``, an ``out``/``inout`` argument;
the inliner turns calls into such assignments), whose definition reads the variable's previous
definitions besides the value written; so a variable partly written from a varying is not
``uniform`` and costs everything written into it. The *final colour* (the last assignment of
the whole colour output at the top level of ``main``) is always listed unless it is
``type``/``dynamic``/``screen``/``derivative``/``uniform``, and is flagged ``final``.

A listed node is valid for every cache algorithm unless its value needs screen-space
derivatives (an implicit-LOD lookup or ``dFdx``/``dFdy``/``fwidth`` among what it is computed
from): three-pass and two-pass compute it in a pass that draws whole primitives (pixels not
computed are culled by the depth test, so the 2x2 quads keep their helper pixels), but one-pass
computes it inside a per-pixel branch, where derivatives are undefined. Such a node's
``invalid`` maps ``one-pass`` to the reason, :attr:`CacheableNode.algorithms` lists the valid
ones, and :func:`rrcache.compiler.instance` refuses the others.

L-values (assignment targets, ``out`` arguments) and expression statements that only assign are
not values and appear in neither list. Expressions outside ``main`` (in functions the inliner
kept) are left out as ``dynamic``, global initialisers as ``uniform`` (or ``type``).

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("varying vec3 n;\\nvoid main() { vec3 c = sin(n) * cos(n);"
...                  " gl_FragColor = vec4(c, 1.0); }")
>>> table = cacheable_nodes(s)
>>> [(x.text, x.cost) for x in table.nodes]
[('sin(n) * cos(n)', 51), ('vec4(c, 1.0)', 51)]
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional, Union

import numpy as np

from rrcache.deep import deep
from rrcache.errors import RRCacheError
from rrcache.glsl import ast as A
from rrcache.glsl.printer import memo_printer, print_expr

from rrcache.glsl.ast import children, iter_exprs
from rrcache.glsl.visitor import NodeVisitor
from rrcache.glsl.rewrite import chain_of, is_live_flag, paused_gc
from rrcache.glsl.defuse import out_qualifiers, written_roots
from rrcache.analysis.cost import CACHE_LOOKUP_COST, loop_trips, op_cost
from rrcache.analysis.loops import Constants, global_scalars
from rrcache.analysis.pipeline import analyse
from rrcache.analysis.source_text import attach_source_text
from rrcache.analysis.static_parts import name_static_parts
from rrcache.analysis.sums import name_partial_sums
from rrcache.analysis.unroll import DEFAULT_MAX_ITERATIONS

__all__ = ["REASONS", "CacheableNode", "ExcludedNode", "NodeTable", "cacheable_nodes",
           "find_node", "node_ids"]

REASONS = ("type", "dynamic", "screen", "derivative", "uniform", "duplicate", "cheap")

#: every cache algorithm, in the order the node table lists them
ALGORITHMS = ("three-pass", "two-pass", "one-pass")

#: why a node that needs screen-space derivatives cannot be cached by the one-pass algorithm
ONE_PASS_DERIVATIVE = (
    "derivative: the value needs screen-space derivatives (an implicit-LOD texture lookup or "
    "dFdx/dFdy/fwidth), and one-pass computes it inside a per-pixel branch, where they are "
    "undefined; three-pass and two-pass compute it over whole primitives")


@dataclass
class CacheableNode:
    """A node a reprojection cache can hold."""

    id: str
    type: str
    line: int
    column: int
    text: str
    cost: int
    call_chain: list[str]
    node: A.Expr = field(repr=False, compare=False)
    final: bool = False
    file: Optional[str] = None  # the included file the node was written in (None: the main file)
    #: the algorithms that cannot cache this node, each with the reason
    invalid: dict = field(default_factory=dict)

    @property
    def algorithms(self) -> list[str]:
        """The cache algorithms whose variants of this node are valid."""
        return [a for a in ALGORITHMS if a not in self.invalid]

    def valid_for(self, algorithm: str) -> bool:
        """Whether ``algorithm`` can cache this node (see :attr:`invalid` for why not)."""
        return algorithm not in self.invalid

    def to_json(self) -> dict:
        return {"id": self.id, "type": self.type, "line": self.line, "column": self.column,
                "text": self.text, "cost": self.cost, "call_chain": list(self.call_chain),
                "final": self.final, "algorithms": self.algorithms,
                "not_valid": dict(self.invalid), "file": self.file}


@dataclass
class ExcludedNode:
    """A node left out, with the reason (one of :data:`REASONS`)."""

    id: str
    reason: str
    line: int
    column: int
    text: str
    node: A.Expr = field(repr=False, compare=False)
    type: str = ""
    cost: int = 0
    call_chain: list[str] = field(default_factory=list)
    file: Optional[str] = None  # the included file the node was written in (None: the main file)

    #: a node left out is valid for no algorithm
    algorithms = property(lambda self: [])
    invalid = property(lambda self: {a: self.reason for a in ALGORITHMS})

    def to_json(self) -> dict:
        return {"id": self.id, "reason": self.reason, "line": self.line, "column": self.column,
                "text": self.text, "type": self.type, "cost": self.cost,
                "call_chain": list(self.call_chain), "algorithms": [], "file": self.file}


@dataclass
class NodeTable:
    """The result of :func:`cacheable_nodes`: ``shader`` is the analysed shader the ids refer
    to, ``nodes`` the listed nodes and ``excluded`` the others, both in program order."""

    shader: Any
    nodes: list[CacheableNode]
    excluded: list[ExcludedNode]

    def find(self, node_id: str) -> A.Expr:
        """The expression node with id ``node_id`` in :attr:`shader`."""
        return find_node(self.shader, node_id)

    def counts(self) -> dict[str, int]:
        """How many nodes are listed (``listed``) and left out for each reason."""
        out = {"listed": len(self.nodes)}
        for r in REASONS:
            out[r] = sum(1 for x in self.excluded if x.reason == r)
        return out

    def to_json(self, path: Optional[str] = None) -> dict:
        """``{"shader": path, "nodes": [...], "excluded": [...]}``."""
        return {"shader": path if path is not None else self.shader.path,
                "nodes": [n.to_json() for n in self.nodes],
                "excluded": [n.to_json() for n in self.excluded]}


def node_ids(unit: A.TranslationUnit) -> dict[int, str]:
    """``id(expr) -> "n<k>"`` for every expression of ``unit`` (pre-order)."""
    return {id(e): f"n{k}" for k, e in enumerate(iter_exprs(unit))}


def find_node(analysed: Union[Any, A.TranslationUnit], node_id: str) -> A.Expr:
    """The expression node ``node_id`` (``"n42"``) of an analysed shader, a
    :class:`NodeTable` or a translation unit. Raises :class:`RRCacheError` for an unknown id.

    >>> from rrcache.glsl.frontend import parse_shader
    >>> table = cacheable_nodes(parse_shader("varying float x;\\n"
    ...                                      "void main() { gl_FragColor = vec4(exp(x)); }"))
    >>> print_expr(find_node(table.shader, table.nodes[0].id))
    'vec4(exp(x))'
    """
    if isinstance(analysed, NodeTable):
        analysed = analysed.shader
    unit = analysed if isinstance(analysed, A.TranslationUnit) else analysed.unit
    k = -1
    if isinstance(node_id, str) and node_id[:1] == "n" and node_id[1:].isdigit():
        k = int(node_id[1:])
        for i, e in enumerate(iter_exprs(unit)):
            if i == k:
                return e
    raise RRCacheError(f"no node '{node_id}' in this shader",
                       hint="node ids look like 'n42'; list them with 'rrcache nodes SHADER'")


@deep
def cacheable_nodes(shader, *, max_iterations: int = DEFAULT_MAX_ITERATIONS,
                    cheap_below: int = CACHE_LOOKUP_COST, analysed: bool = False, moving=(),
                    scores=None) -> NodeTable:
    """Enumerate the cacheable nodes of ``shader`` (a checked :class:`Shader`).

    The shader is first analysed (:func:`analyse`: inlining, unrolling loops of at most
    ``max_iterations`` iterations, the terms of sums ordered by ``moving`` and ``scores``: see
    :mod:`rrcache.analysis.sums`) unless ``analysed`` says it already is. Nodes whose cost is
    below ``cheap_below`` are left out as ``cheap``. A partial sum of a reordered sum is named by
    the terms it holds (``radiance: 24 of 25 terms, all but (i=2, j=2)``). See the module
    docstring for the rules.

    >>> from rrcache.glsl.frontend import parse_shader
    >>> t = cacheable_nodes(parse_shader("uniform float u;\\nvoid main() {"
    ...                                  " gl_FragColor = vec4(sin(u)); }"))
    >>> [(x.text, x.reason) for x in t.excluded]
    [('vec4(sin(u))', 'uniform'), ('sin(u)', 'uniform'), ('u', 'uniform')]
    """
    with paused_gc():
        target = shader if analysed else analyse(shader, max_iterations, moving=moving, scores=scores)
        table = _Classifier(target, cheap_below).run()
        if not analysed:  # the text as written, and the file, of nodes from inlined code
            attach_source_text(table, shader.unit)
        name_partial_sums(table, target.unit, moving, scores)
        name_static_parts(table, target.unit, moving)
        return table


# ----------------------------------------------------------------------------- classification
#
# Data flow. Every write of a variable (whole, component, member, element, ``++``/``--``, an
# ``out``/``inout`` argument) makes a *definition* (:class:`_Def`); a partial write's definition
# reads the variable's previous definitions besides the value written. The definitions form a
# DAG; a node's cost is the own cost of its expression tree plus the own costs of every
# definition reachable from the definitions it reads, each counted once. Reachable sets are
# bitsets (Python ints, bit k = definition k): a union is an ``|`` and the cost of what a union
# adds is summed over the bits it adds, so nothing is ever copied element by element. Only the
# definitions still visible (in scope, reaching) keep their bitset; variables are forgotten at
# the end of their block.

_DERIV = 1    # the value needs screen-space derivatives (invalid under one-pass)
_SCREEN = 2   # the value depends on the pixel's screen position

#: a node's text is printed whole up to this many syntax nodes; a larger one (a generated chain of
#: thousands of terms) is abbreviated, so that listing every node of a chain stays linear
_TEXT_NODES = 400


def _bounded_texts(exprs):
    """``text(e)`` for the expressions ``exprs``: the printed expression, abbreviated to its last
    operand when its subtree is over ``_TEXT_NODES`` nodes (sizes counted once, without recursion)."""
    size: dict[int, int] = {}
    for root in exprs:
        if id(root) in size:
            continue
        stack = [(root, False)]
        while stack:
            node, done = stack.pop()
            if done:
                size[id(node)] = 1 + sum(size[id(c)] for c in node.children())
                continue
            if id(node) in size:
                continue
            stack.append((node, True))
            stack.extend((c, False) for c in node.children() if id(c) not in size)

    # each node's text is its operands' texts put together: printed once each (a node of at most
    # _TEXT_NODES nodes has operands no larger, so the recursion is bounded)
    pe = memo_printer()

    def text(e) -> str:
        n = size.get(id(e), 0)
        if n <= _TEXT_NODES:
            return pe(e)
        if isinstance(e, A.Binary) and size.get(id(e.right), _TEXT_NODES + 1) <= _TEXT_NODES:
            return f"(... {n:,} nodes ...) {e.op} {pe(e.right)}"
        return f"(expression of {n:,} nodes)"

    return text



class _Def:
    """One definition of a variable: ``expr`` the value expression (None when the write is
    partial or its value unknown), ``mask`` the definitions it depends on (itself included),
    ``cost`` their own costs summed."""

    __slots__ = ("expr", "uniform", "flags", "idx", "mask", "cost")

    def __init__(self, expr, uniform: bool, flags: int, idx: int, mask: int, cost: int):
        self.expr = expr
        self.uniform = uniform
        self.flags = flags
        self.idx = idx
        self.mask = mask
        self.cost = cost


class _Info:
    """What an expression is: ``mask``/``rcost`` the definitions it reads (transitively) and
    their cost, ``own`` the cost of its own tree."""

    __slots__ = ("uniform", "flags", "effects", "mask", "rcost", "own", "key")

    def __init__(self, uniform, flags, effects, mask, rcost, own, key):
        self.uniform = uniform
        self.flags = flags
        self.effects = effects
        self.mask = mask
        self.rcost = rcost
        self.own = own
        self.key = key


class _Ctx:
    __slots__ = ("dynamic", "varying", "region", "in_deriv")

    def __init__(self, dynamic=False, varying=False, region=(), in_deriv=False):
        self.dynamic = dynamic
        self.varying = varying
        self.region = region
        self.in_deriv = in_deriv

    def but(self, **kw) -> "_Ctx":
        c = _Ctx(self.dynamic, self.varying, self.region, self.in_deriv)
        for k, v in kw.items():
            setattr(c, k, v)
        return c


class _Record:
    __slots__ = ("expr", "reason", "cost", "flags", "dup", "sink", "key", "region", "dup_of")

    def __init__(self, expr, reason, cost, flags, dup=False, key=-1, region=(), dup_of=None):
        self.expr = expr
        self.reason = reason
        self.cost = cost
        self.flags = flags
        self.dup = dup          # a read of a variable whose one definition is ``dup_of``
        self.sink = None        # the definition this value is written into (its index)
        self.key = key          # structural key (same key, same value)
        self.region = region    # the branches it is in
        self.dup_of = dup_of


def _is_cacheable_type(t) -> bool:
    return (t is not None and t.base == "float" and not t.dims and not t.cols
            and 1 <= t.size <= 4)


def _var_key(sym) -> tuple:
    return (id(sym.decl), sym.name)


def _differentiated_args(call) -> tuple:
    """The argument positions whose screen-space derivatives ``call`` takes (the coordinate of
    an implicit-LOD lookup, the operand of ``dFdx``...), or () for other calls."""
    target = call.target
    if not getattr(target, "derivative", False):
        return ()
    if getattr(target, "category", "") == "derivative":
        return (0,)
    return (1,)


_SCREEN_BUILTINS = frozenset({"gl_FragCoord"})


class _Classifier(NodeVisitor):
    """Visiting a statement runs the data flow through it; visiting an expression (through
    :meth:`expr`, which records it) returns ``(_Info, the definition it duplicates or None)``."""

    def __init__(self, shader, cheap_below: int):
        self.shader = shader
        self.cheap_below = cheap_below
        # id(expr) -> k of its id "n<k>" (pre-order index)
        self.order = {id(e): k for k, e in enumerate(iter_exprs(shader.unit))}
        self.state: dict[tuple, tuple] = {}    # var key -> reaching defs
        self.records: list[_Record] = []
        self.intern: dict[tuple, int] = {}
        self.final: Optional[A.Expr] = None
        self.own: list[int] = []                  # own cost of definition k
        self.own_np = np.zeros(1024, dtype=np.int64)
        self.deriv_mask = 0                       # definitions read by differentiated arguments
        # a definition inside a loop left rolled costs its own cost times the loop's trip bound
        # (loop_trips; nested loops multiply): what a value after the loop saves when cached
        self.repeat = 1
        self.consts = Constants(global_scalars(shader.info).get)
        info = shader.info
        outs = list(info.outputs)
        self.output = outs[0] if outs else ("gl_FragData" if "gl_FragData" in info.used_globals
                                             else "gl_FragColor")
        self.top_expr = _TopLevel(self).visit

    # ------------------------------------------------------------------ driver
    def run(self) -> NodeTable:
        for d in self.shader.unit.decls:
            self.visit(d, None)
        return self.finish()

    def visit_FunctionDecl(self, d: A.FunctionDecl, ctx) -> None:
        if d.body is None:
            return
        if d.name == "main":
            self.block(d.body.stmts, _Ctx())
            return
        for e in iter_exprs(d.body):     # a function the inliner kept: its nodes are dynamic
            self.records.append(_Record(e, "type" if not _is_cacheable_type(e.type)
                                        else "dynamic", 0, 0))

    def visit_VariableDecl(self, d: A.VariableDecl, ctx) -> None:
        """A global declaration (a local one is a statement: :meth:`visit_DeclStmt`)."""
        for decl in d.declarators:
            if decl.init is not None:
                for e in iter_exprs(decl.init):
                    self.records.append(_Record(e, "type" if not _is_cacheable_type(e.type)
                                                else "uniform", 0, 0))
                self.state[(id(d), decl.name)] = (self.new_def(decl.init, True, 0, 0, 0, 0),)

    def visit_Node(self, node, ctx) -> None:
        """Other declarations, and the statements with nothing to evaluate (``break``...)."""

    def finish(self) -> NodeTable:
        nodes: list[CacheableNode] = []
        excluded: list[ExcludedNode] = []
        order = self.order
        deriv_mask = self.deriv_mask
        # in evaluation order: values written into a definition that a differentiated argument
        # reads are excluded (caching them would change the derivative), then duplicates of
        # the first listed occurrence
        seen: dict[int, tuple] = {}
        feeds: set = set()
        for r in self.records:
            if r.reason is not None:
                continue
            if r.sink is not None and (deriv_mask >> r.sink) & 1:
                r.reason = "derivative"
                feeds.add(id(r.expr))
                continue
            if r.dup and id(r.dup_of) in feeds:
                r.dup = False
            first = seen.get(r.key)
            if first is not None and r.region[:len(first)] == first:
                r.dup = True
            elif first is None:
                seen[r.key] = r.region
        self.records.sort(key=lambda r: order[id(r.expr)])
        final, cheap_below = self.final, self.cheap_below
        type_names: dict = {}
        text = _bounded_texts([r.expr for r in self.records])
        for r in self.records:
            e, reason, cost = r.expr, r.reason, r.cost
            is_final = e is final
            if reason is None and not is_final:
                if r.dup:
                    reason = "duplicate"
                elif cost < cheap_below:
                    reason = "cheap"
            loc = e.loc
            t = e.type
            if t is None:
                tname = "void"
            else:
                tname = type_names.get(t)
                if tname is None:
                    tname = type_names[t] = t.glsl_name()
            node_id = f"n{order[id(e)]}"
            line, column = (loc.line, loc.col) if loc else (0, 0)
            chain = list(chain_of(loc))
            if reason is None:
                invalid = {"one-pass": ONE_PASS_DERIVATIVE} if r.flags & _DERIV else {}
                nodes.append(CacheableNode(node_id, tname, line, column, text(e), cost,
                                           chain, e, is_final, invalid=invalid))
            else:
                excluded.append(ExcludedNode(node_id, reason, line, column, text(e), e,
                                             tname, cost, chain))
        return NodeTable(self.shader, nodes, excluded)

    # ------------------------------------------------------------------ definitions and costs
    def new_def(self, expr, uniform: bool, flags: int, own: int, mask: int, cost: int) -> _Def:
        """A new definition of own cost ``own`` reading ``mask`` (of cost ``cost``)."""
        idx = len(self.own)
        own = own * self.repeat
        self.own.append(own)
        if idx >= self.own_np.size - 64:
            grown = np.zeros(self.own_np.size * 2, dtype=np.int64)
            grown[:self.own_np.size] = self.own_np
            self.own_np = grown
        self.own_np[idx] = own
        return _Def(expr, uniform, flags, idx, mask | (1 << idx), cost + own)

    def weight(self, mask: int) -> int:
        """The own costs of the definitions in ``mask``, summed."""
        if mask.bit_count() <= 24:
            own, w = self.own, 0
            while mask:
                low = mask & -mask
                w += own[low.bit_length() - 1]
                mask ^= low
            return w
        raw = mask.to_bytes((mask.bit_length() + 7) // 8, "little")
        bits = np.unpackbits(np.frombuffer(raw, dtype=np.uint8), bitorder="little")
        return int(self.own_np[:bits.size][bits.view(bool)].sum())

    def join(self, m1: int, c1: int, m2: int, c2: int) -> tuple[int, int]:
        """The union of two dependency sets and its cost (each definition counted once)."""
        if not m2 or m1 == m2:
            return m1, c1
        if not m1:
            return m2, c2
        u = m1 | m2
        if u == m1:
            return m1, c1
        if u == m2:
            return m2, c2
        if c1 >= c2:
            return u, c1 + self.weight(m2 & ~m1)
        return u, c2 + self.weight(m1 & ~m2)

    def defs_mask(self, defs) -> tuple[int, int]:
        m, c = 0, 0
        for d in defs:
            m, c = self.join(m, c, d.mask, d.cost)
        return m, c

    # ------------------------------------------------------------------ variables
    def read_defs(self, sym) -> tuple:
        return self.state.get(_var_key(sym), ())

    def define(self, sym_key: tuple, expr, info: Optional[_Info], ctx: _Ctx) -> _Def:
        if info is None:   # declared without a value: undefined, contributes nothing
            d = self.new_def(None, not ctx.varying, 0, 0, 0, 0)
        else:
            d = self.new_def(expr, info.uniform and not ctx.varying, info.flags, info.own,
                             info.mask, info.rcost)
        self.state[sym_key] = (d,)
        return d

    def clobber(self, node, ctx: _Ctx) -> None:
        """Variables written somewhere under ``node`` (a loop) get an unknown definition too."""
        for root in written_roots(node):
            if root.symbol is not None:
                key = _var_key(root.symbol)
                self.state[key] = self.state.get(key, ()) + (self.new_def(None, False, 0, 0, 0, 0),)

    def merge(self, a: dict, b: dict) -> dict:
        out = dict(a)
        for k, v in b.items():
            old = out.get(k)
            if old is None:
                out[k] = v
            elif old is not v:
                out[k] = old + tuple(d for d in v if d not in old)
        return out

    # ------------------------------------------------------------------ statements
    def block(self, stmts: list, ctx: _Ctx) -> None:
        declared = []
        for s in stmts:
            self.visit(s, ctx)
            if isinstance(s, A.DeclStmt) and isinstance(s.decl, A.VariableDecl):
                declared.extend((id(s.decl), d.name) for d in s.decl.declarators)
        for key in declared:     # out of scope: their definitions can no longer be read
            self.state.pop(key, None)

    def visit_Compound(self, s: A.Compound, ctx: _Ctx) -> None:
        self.block(s.stmts, ctx)

    def visit_DeclStmt(self, s: A.DeclStmt, ctx: _Ctx) -> None:
        if not isinstance(s.decl, A.VariableDecl):
            return
        for d in s.decl.declarators:
            if d.array_dims:
                for x in d.array_dims:
                    if x is not None:
                        self.expr(x, ctx)
            start = len(self.records)
            info = self.expr(d.init, ctx) if d.init is not None else None
            made = self.define((id(s.decl), d.name), d.init, info, ctx)
            self.sink(start, made)

    def visit_ExprStmt(self, s: A.ExprStmt, ctx: _Ctx) -> None:
        if s.expr is not None:
            self.top_expr(s.expr, ctx)

    def visit_Switch(self, s: A.Switch, ctx: _Ctx) -> None:
        info = self.expr(s.expr, ctx)
        inner = ctx.but(dynamic=ctx.dynamic or not info.uniform,
                        varying=ctx.varying or not info.uniform,
                        region=ctx.region + ((id(s), 0),))
        before = dict(self.state)
        self.clobber(s.body, inner)
        self.block(s.body.stmts, inner)
        self.state = self.merge(before, self.state)

    def visit_Return(self, s: A.Return, ctx: _Ctx) -> None:
        if s.expr is not None:
            self.expr(s.expr, ctx)

    def sink(self, start: int, made: Optional[_Def]) -> None:
        """The values recorded since ``start`` are written into definition ``made``."""
        if made is None:
            return
        records = self.records
        for k in range(start, len(records)):
            if records[k].sink is None:
                records[k].sink = made.idx

    def visit_If(self, s: A.If, ctx: _Ctx) -> None:
        info = self.expr(s.cond, ctx)
        guard = isinstance(s.cond, A.Ident) and is_live_flag(s.cond.name)
        varying = not info.uniform
        inner_dyn = ctx.dynamic or (varying and not guard)
        before = dict(self.state)
        results = []
        for k, sub in enumerate((s.then, s.else_)):
            self.state = dict(before)
            if sub is not None:
                self.visit(sub, ctx.but(dynamic=inner_dyn, varying=ctx.varying or varying,
                                       region=ctx.region + ((id(s), k),)))
            results.append(self.state)
        self.state = self.merge(results[0], results[1])

    def visit_For(self, s, ctx: _Ctx) -> None:
        """A loop left rolled (``for``, ``while``, ``do``): its nodes are dynamic."""
        if isinstance(s, A.For) and s.init is not None:
            self.visit(s.init, ctx)
        inner = ctx.but(dynamic=True, varying=True, region=ctx.region + ((id(s), 0),))
        outer_repeat = self.repeat
        self.repeat = outer_repeat * loop_trips(s, self.consts)
        before = dict(self.state)
        self.clobber(s, inner)
        cond = s.cond
        if isinstance(s, A.DoWhile):
            self.visit(s.body, inner)
            self.expr(cond, inner)
        else:
            if isinstance(cond, A.VariableDecl):
                self.visit(A.DeclStmt(cond, loc=cond.loc), inner)
            elif cond is not None:
                self.expr(cond, inner)
            self.visit(s.body, inner)
            if isinstance(s, A.For) and s.step is not None:
                self.top_expr(s.step, inner)
        self.repeat = outer_repeat
        self.state = self.merge(before, self.state)

    visit_While = visit_DoWhile = visit_For

    # ------------------------------------------------------------------ expressions
    def step(self, e: A.Unary, ctx: _Ctx) -> None:
        """``x++``/``x--``: a partial write of ``x``."""
        index = self.lvalue(e.operand, ctx)
        self.write(e.operand, None, self.step_info(index), ctx)

    def step_info(self, index: Optional[_Info]) -> _Info:
        """The value an increment adds (one ALU operation), with its l-value's indices."""
        info = _Info(True, 0, False, 0, 0, 1, -1)
        return self.combine(info, index) if index is not None else info

    def combine(self, a: _Info, b: _Info) -> _Info:
        m, c = self.join(a.mask, a.rcost, b.mask, b.rcost)
        return _Info(a.uniform and b.uniform, a.flags | b.flags, a.effects or b.effects, m, c,
                     a.own + b.own, -1)

    def assign(self, e: A.Assign, ctx: _Ctx, top: bool = False) -> None:
        start = len(self.records)
        info = self.expr(e.value, ctx)
        index = self.lvalue(e.target, ctx)
        whole = e.op == "=" and isinstance(e.target, A.Ident)
        if whole:
            made = self.write(e.target, e.value, info, ctx)
        else:      # a component, member or element, or an operator not expanded: partial
            if e.op != "=":
                info = self.combine(info, _Info(True, 0, False, 0, 0, op_cost(
                    A.Binary(e.op[:-1], e.target, e.value, loc=e.loc, type=e.target.type)), -1))
            made = self.write(e.target, None, self.combine(info, index) if index else info, ctx)
        self.sink(start, made)
        if top and e.op == "=" and not ctx.dynamic and not ctx.region and self.is_output(e.target):
            self.final = e.value

    def is_output(self, target) -> bool:
        if isinstance(target, A.Ident):
            return target.name == self.output
        return (isinstance(target, A.Index) and isinstance(target.obj, A.Ident)
                and target.obj.name == "gl_FragData" == self.output
                and isinstance(target.index, A.IntLit) and target.index.value == 0)

    def write(self, target, value, info: Optional[_Info], ctx: _Ctx,
              whole: bool = False) -> Optional[_Def]:
        """Write ``info`` into the variable under ``target``. ``value`` given (``x = value``)
        or ``whole`` (an ``out`` argument) replaces the variable's value; otherwise the write is
        partial and the new definition also reads the previous ones."""
        root = target
        while isinstance(root, (A.Field, A.Index)):
            root = root.obj
        if not isinstance(root, A.Ident) or root.symbol is None:
            return None
        key = _var_key(root.symbol)
        if value is not None:
            return self.define(key, value, info, ctx)
        if whole and root is target:
            d = self.new_def(None, info.uniform and not ctx.varying, info.flags, info.own,
                             info.mask, info.rcost)
            self.state[key] = (d,)
            return d
        old = self.state.get(key, ())
        m, c = self.defs_mask(old)
        m, c = self.join(m, c, info.mask, info.rcost)
        flags = info.flags
        for x in old:
            flags |= x.flags
        d = self.new_def(None, all(x.uniform for x in old) and info.uniform and not ctx.varying,
                         flags, info.own, m, c)
        self.state[key] = (d,)
        return d

    def lvalue(self, e, ctx: _Ctx) -> Optional[_Info]:
        """Visit the index expressions of an l-value (they are values); what they read."""
        got = None
        while isinstance(e, (A.Field, A.Index)):
            if isinstance(e, A.Index):
                info = self.expr(e.index, ctx)
                got = info if got is None else self.combine(got, info)
            e = e.obj
        return got

    def intern_key(self, key: tuple) -> int:
        got = self.intern.get(key)
        if got is None:
            got = len(self.intern)
            self.intern[key] = got
        return got

    def expr(self, e, ctx: _Ctx) -> _Info:
        """Visit a value expression (evaluation order), record it, return what it is."""
        info, dup = self.visit(e, ctx)
        self.record(e, info, ctx, dup)
        return info

    def visit_Ident(self, e: A.Ident, ctx: _Ctx):
        return self.ident(e)

    def visit_IntLit(self, e, ctx: _Ctx):
        return _Info(True, 0, False, 0, 0, 0,
                     self.intern_key(("lit", type(e).__name__, e.value))), None

    visit_FloatLit = visit_BoolLit = visit_IntLit

    def visit_Assign(self, e: A.Assign, ctx: _Ctx):
        self.assign(e, ctx)
        return _Info(False, 0, True, 0, 0, 0, self.intern_key(("fx", id(e)))), None

    def visit_Unary(self, e: A.Unary, ctx: _Ctx):
        if e.op not in ("++", "--"):
            return self.compound_expr(e, ctx), None
        self.step(e, ctx)
        return _Info(False, 0, True, 0, 0, 1, self.intern_key(("fx", id(e)))), None

    def visit_Ternary(self, e: A.Ternary, ctx: _Ctx):
        return self.compound_expr(e, ctx, first=e.cond, rest=(e.then, e.else_)), None

    def visit_Binary(self, e: A.Binary, ctx: _Ctx):
        if e.op in ("&&", "||"):
            return self.compound_expr(e, ctx, first=e.left, rest=(e.right,)), None
        return self.compound_expr(e, ctx), None

    def visit_Expr(self, e, ctx: _Ctx):
        return self.compound_expr(e, ctx), None

    def ident(self, e: A.Ident):
        sym = e.symbol
        kind = sym.kind if sym is not None else "in"
        if kind == "builtin":
            kind = sym.qualifiers[0] if sym.qualifiers else "in"
            if e.name in _SCREEN_BUILTINS:
                return _Info(False, _SCREEN, False, 0, 0, 0,
                             self.intern_key(("id", e.name))), None
        if kind in ("uniform", "const"):
            return _Info(True, 0, False, 0, 0, 0, self.intern_key(("id", e.name))), None
        if kind == "in":
            return _Info(False, 0, False, 0, 0, 0, self.intern_key(("id", e.name))), None
        defs = self.read_defs(sym)
        uniform = bool(defs) and all(d.uniform for d in defs)
        flags = 0
        for d in defs:
            flags |= d.flags
        if len(defs) == 1:
            mask, cost = defs[0].mask, defs[0].cost
        else:
            mask, cost = self.defs_mask(defs)
        key = self.intern_key(("var", e.name, tuple(d.idx for d in defs)))
        dup_of = defs[0].expr if len(defs) == 1 else None
        return _Info(uniform, flags, False, mask, cost, 0, key), dup_of

    def visit_Call(self, e: A.Call, ctx: _Ctx):
        return self.compound_expr(e, ctx, e.args, call=True), None

    def compound_expr(self, e, ctx: _Ctx, operands=None, first=None, rest=(),
                      call: bool = False) -> _Info:
        """An operation on its ``operands`` (default: its syntax children); ``first``: the
        condition that decides whether ``rest`` is evaluated (``?:``, ``&&``, ``||``);
        ``call``: ``e`` is a call (an array constructor's sizes are not operands)."""
        uniform, flags, effects = True, 0, False
        own = op_cost(e)
        keys: list = [type(e).__name__, getattr(e, "op", None), getattr(e, "name", None)]
        out_pos: dict = {}
        diff_pos: tuple = ()
        if call:
            if e.kind == "function":
                uniform, effects = False, True
            if getattr(e.target, "side_effects", False):
                effects = True
            out_pos = {i: q for i, q in enumerate(out_qualifiers(e)) if q != "in"}
            diff_pos = _differentiated_args(e)
        outs = []
        if first is not None:
            infos = [self.expr(first, ctx)]
            inner = ctx.but(dynamic=ctx.dynamic or not infos[0].uniform,
                            varying=ctx.varying or not infos[0].uniform)
            infos += [self.expr(x, inner) for x in rest]
        else:
            infos = []
            for i, c in enumerate(children(e, decl_types=False) if operands is None else operands):
                if i in out_pos:
                    index = self.lvalue(c, ctx)
                    outs.append((c, out_pos[i], index))
                    effects = True
                    continue
                if i in diff_pos:
                    info = self.expr(c, ctx.but(in_deriv=True))
                    self.deriv_mask |= info.mask
                else:
                    info = self.expr(c, ctx)
                infos.append(info)
        mask, rcost = 0, 0
        for inf in infos:
            uniform = uniform and inf.uniform
            flags |= inf.flags
            effects = effects or inf.effects
            mask, rcost = self.join(mask, rcost, inf.mask, inf.rcost)
            own += inf.own
            keys.append(inf.key)
        if diff_pos:
            flags |= _DERIV
        if call and e.kind == "function":
            keys.append(id(e))
        info = _Info(uniform, flags, effects, mask, rcost, own, self.intern_key(tuple(keys)))
        for target, qual, index in outs:      # out/inout arguments: written by the call
            value = _Info(uniform and e.kind != "function", flags, False, mask, rcost, own, -1)
            if index is not None:
                value = self.combine(value, index)
            self.write(target, None, value, ctx, whole=qual == "out")
        return info

    def record(self, e, info: _Info, ctx: _Ctx, dup_of) -> None:
        reason = None
        if not _is_cacheable_type(e.type):
            reason = "type"
        elif ctx.dynamic or info.effects:
            reason = "dynamic"
        elif info.flags & _SCREEN:
            reason = "screen"
        elif ctx.in_deriv:
            reason = "derivative"
        elif info.uniform:
            reason = "uniform"
        self.records.append(_Record(e, reason, info.own + info.rcost, info.flags,
                                    dup_of is not None, info.key, ctx.region, dup_of))


class _TopLevel(NodeVisitor):
    """An expression statement: an assignment's value is a node, the assignment is not."""

    def __init__(self, classifier: _Classifier):
        self.c = classifier

    def visit_Assign(self, e: A.Assign, ctx: _Ctx) -> None:
        self.c.assign(e, ctx, top=True)

    def visit_Unary(self, e: A.Unary, ctx: _Ctx) -> None:
        if e.op in ("++", "--"):
            self.c.step(e, ctx)
        else:
            self.c.expr(e, ctx)

    def visit_Sequence(self, e: A.Sequence, ctx: _Ctx) -> None:
        for x in e.exprs:
            self.visit(x, ctx)

    def generic_visit(self, e, ctx: _Ctx) -> None:
        self.c.expr(e, ctx)
