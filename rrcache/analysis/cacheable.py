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
``derivative`` its value needs screen-space derivatives: the expression, or a value it reads
               through local variables, calls ``dFdx``/``dFdy``/``fwidth`` or an implicit-LOD
               texture lookup; or it is inside the argument of such a call.
``uniform``    the same for every pixel: it depends only on literals, constants and uniforms.
``duplicate``  the same value as a node listed earlier on every path to it: an identical
               expression reading the same definitions of the same variables, or a read of a
               local variable that has exactly one reaching definition (that definition's
               expression is the node kept).
``cheap``      its cost (below) is under ``cheap_below`` (default
               :data:`rrcache.analysis.cost.CACHE_LOOKUP_COST`): a cache lookup costs more.

The *cost* of a node is the work a cache hit saves: the static cost
(:mod:`rrcache.analysis.cost`) of its expression tree plus that of every definition of a local
variable it depends on, transitively, each counted once. The *final colour* (the last
assignment of the whole colour output at the top level of ``main``) is always listed unless it
is ``type``/``dynamic``/``derivative``/``uniform``, and is flagged ``final``.

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

from rrcache.deep import deep
from rrcache.errors import RRCacheError
from rrcache.glsl import ast as A
from rrcache.glsl.printer import print_expr

from rrcache.analysis._tree import chain_of, is_live_flag, iter_exprs, paused_gc, written_roots
from rrcache.analysis.cost import CACHE_LOOKUP_COST, op_cost
from rrcache.analysis.pipeline import analyse
from rrcache.analysis.unroll import DEFAULT_MAX_ITERATIONS

__all__ = ["REASONS", "CacheableNode", "ExcludedNode", "NodeTable", "cacheable_nodes",
           "find_node", "node_ids"]

REASONS = ("type", "dynamic", "derivative", "uniform", "duplicate", "cheap")


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

    def to_json(self) -> dict:
        return {"id": self.id, "type": self.type, "line": self.line, "column": self.column,
                "text": self.text, "cost": self.cost, "call_chain": list(self.call_chain),
                "final": self.final}


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

    def to_json(self) -> dict:
        return {"id": self.id, "reason": self.reason, "line": self.line, "column": self.column,
                "text": self.text, "type": self.type, "cost": self.cost,
                "call_chain": list(self.call_chain)}


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
                    cheap_below: int = CACHE_LOOKUP_COST, analysed: bool = False) -> NodeTable:
    """Enumerate the cacheable nodes of ``shader`` (a checked :class:`Shader`).

    The shader is first analysed (:func:`analyse`: inlining, unrolling loops of at most
    ``max_iterations`` iterations) unless ``analysed`` says it already is. Nodes whose cost is
    below ``cheap_below`` are left out as ``cheap``. See the module docstring for the rules.

    >>> from rrcache.glsl.frontend import parse_shader
    >>> t = cacheable_nodes(parse_shader("uniform float u;\\nvoid main() {"
    ...                                  " gl_FragColor = vec4(sin(u)); }"))
    >>> [(x.text, x.reason) for x in t.excluded]
    [('vec4(sin(u))', 'uniform'), ('sin(u)', 'uniform'), ('u', 'uniform')]
    """
    with paused_gc():
        target = shader if analysed else analyse(shader, max_iterations)
        return _Classifier(target, cheap_below).run()


# ----------------------------------------------------------------------------- classification

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

    def text(e) -> str:
        n = size.get(id(e), 0)
        if n <= _TEXT_NODES:
            return print_expr(e)
        if isinstance(e, A.Binary) and size.get(id(e.right), _TEXT_NODES + 1) <= _TEXT_NODES:
            return f"(... {n:,} nodes ...) {e.op} {print_expr(e.right)}"
        return f"(expression of {n:,} nodes)"

    return text



class _Def:
    """One definition of a variable: the value expression (None when unknown)."""

    __slots__ = ("expr", "uniform", "deriv", "own", "closure", "closure_cost")

    def __init__(self, expr, uniform: bool, deriv: bool, own: int, reads: frozenset):
        self.expr = expr
        self.uniform = uniform
        self.deriv = deriv
        self.own = own
        if len(reads) == 1:        # the common chain: no Python-level sum over the closure
            (r,) = reads
            self.closure = r.closure | {self}
            self.closure_cost = own + r.closure_cost
        else:
            closure = {self}
            for d in reads:
                closure |= d.closure
            self.closure = frozenset(closure)
            self.closure_cost = sum(d.own for d in closure)


class _Info:
    __slots__ = ("uniform", "deriv", "effects", "reads", "own", "key")

    def __init__(self, uniform, deriv, effects, reads, own, key):
        self.uniform = uniform
        self.deriv = deriv
        self.effects = effects
        self.reads = reads
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


_EMPTY: frozenset = frozenset()


def _is_cacheable_type(t) -> bool:
    return (t is not None and t.base == "float" and not t.dims and not t.cols
            and 1 <= t.size <= 4)


def _var_key(sym) -> tuple:
    return (id(sym.decl), sym.name)


class _Classifier:
    def __init__(self, shader, cheap_below: int):
        self.shader = shader
        self.cheap_below = cheap_below
        # id(expr) -> k of its id "n<k>" (pre-order index)
        self.order = {id(e): k for k, e in enumerate(iter_exprs(shader.unit))}
        self.state: dict[tuple, tuple] = {}    # var key -> reaching defs
        self.records: list[tuple] = []        # (expr, reason or None, info, ctx, dup_of_def)
        self.intern: dict[tuple, int] = {}
        self.seen: dict[int, tuple] = {}       # structural key -> region of first listing
        self.cost_memo: dict[frozenset, int] = {}
        self.final: Optional[A.Expr] = None
        info = shader.info
        outs = list(info.outputs)
        self.output = outs[0] if outs else ("gl_FragData" if "gl_FragData" in info.used_globals
                                             else "gl_FragColor")

    # ------------------------------------------------------------------ driver
    def run(self) -> NodeTable:
        unit = self.shader.unit
        for d in unit.decls:
            if isinstance(d, A.FunctionDecl) and d.body is not None:
                if d.name == "main":
                    self.block(d.body.stmts, _Ctx())
                else:
                    for e in iter_exprs(d.body):
                        self.records.append((e, "type" if not _is_cacheable_type(e.type)
                                             else "dynamic", None, None, None))
            elif isinstance(d, A.VariableDecl):
                for decl in d.declarators:
                    if decl.init is not None:
                        for e in iter_exprs(decl.init):
                            self.records.append((e, "type" if not _is_cacheable_type(e.type)
                                                 else "uniform", None, None, None))
                        self.state[(id(d), decl.name)] = (
                            _Def(decl.init, True, False, 0, _EMPTY),)
        return self.finish()

    def finish(self) -> NodeTable:
        nodes: list[CacheableNode] = []
        excluded: list[ExcludedNode] = []
        order = self.order
        self.records.sort(key=lambda r: order[id(r[0])])
        final, cheap_below = self.final, self.cheap_below
        type_names: dict = {}
        text = _bounded_texts([r[0] for r in self.records])
        for e, reason, info, ctx, dup in self.records:
            cost = self.cost(info) if info is not None else 0
            is_final = e is final
            if reason is None and not is_final:
                if dup:
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
                nodes.append(CacheableNode(node_id, tname, line, column, text(e), cost,
                                           chain, e, is_final))
            else:
                excluded.append(ExcludedNode(node_id, reason, line, column, text(e), e,
                                             tname, cost, chain))
        return NodeTable(self.shader, nodes, excluded)

    def cost(self, info: _Info) -> int:
        reads = info.reads
        if len(reads) == 1:
            (r,) = reads
            return info.own + r.closure_cost
        extra = self.cost_memo.get(reads)
        if extra is None:
            closure: set = set()
            for d in reads:
                closure |= d.closure
            extra = sum(d.own for d in closure)
            self.cost_memo[reads] = extra
        return info.own + extra

    # ------------------------------------------------------------------ variables
    def read_defs(self, sym) -> tuple:
        return self.state.get(_var_key(sym), ())

    def define(self, sym_key: tuple, expr, info: Optional[_Info], ctx: _Ctx) -> None:
        if info is None:
            d = _Def(None, False, False, 0, _EMPTY)
        else:
            d = _Def(expr, info.uniform and not ctx.varying, info.deriv, info.own, info.reads)
        self.state[sym_key] = (d,)

    def clobber(self, node, ctx: _Ctx) -> None:
        """Variables written somewhere under ``node`` (a loop) get an unknown definition too."""
        for root in written_roots(node):
            if root.symbol is not None:
                key = _var_key(root.symbol)
                self.state[key] = self.state.get(key, ()) + (_Def(None, False, False, 0, _EMPTY),)

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
        for s in stmts:
            self.stmt(s, ctx)

    def stmt(self, s, ctx: _Ctx) -> None:
        if isinstance(s, A.Compound):
            self.block(s.stmts, ctx)
        elif isinstance(s, A.DeclStmt):
            if isinstance(s.decl, A.VariableDecl):
                for d in s.decl.declarators:
                    if d.array_dims:
                        for x in d.array_dims:
                            if x is not None:
                                self.expr(x, ctx)
                    info = self.expr(d.init, ctx) if d.init is not None else None
                    self.define((id(s.decl), d.name), d.init, info, ctx)
        elif isinstance(s, A.ExprStmt):
            if s.expr is not None:
                self.top_expr(s.expr, ctx)
        elif isinstance(s, A.If):
            self.branch(s, ctx)
        elif isinstance(s, (A.For, A.While, A.DoWhile)):
            self.loop(s, ctx)
        elif isinstance(s, A.Switch):
            info = self.expr(s.expr, ctx)
            inner = ctx.but(dynamic=ctx.dynamic or not info.uniform,
                            varying=ctx.varying or not info.uniform,
                            region=ctx.region + ((id(s), 0),))
            before = dict(self.state)
            self.clobber(s.body, inner)
            self.block(s.body.stmts, inner)
            self.state = self.merge(before, self.state)
        elif isinstance(s, A.Return) and s.expr is not None:
            self.expr(s.expr, ctx)

    def branch(self, s: A.If, ctx: _Ctx) -> None:
        info = self.expr(s.cond, ctx)
        guard = isinstance(s.cond, A.Ident) and is_live_flag(s.cond.name)
        varying = not info.uniform
        inner_dyn = ctx.dynamic or (varying and not guard)
        before = dict(self.state)
        results = []
        for k, sub in enumerate((s.then, s.else_)):
            self.state = dict(before)
            if sub is not None:
                self.stmt(sub, ctx.but(dynamic=inner_dyn, varying=ctx.varying or varying,
                                       region=ctx.region + ((id(s), k),)))
            results.append(self.state)
        self.state = self.merge(results[0], results[1])

    def loop(self, s, ctx: _Ctx) -> None:
        if isinstance(s, A.For) and s.init is not None:
            self.stmt(s.init, ctx)
        inner = ctx.but(dynamic=True, varying=True, region=ctx.region + ((id(s), 0),))
        before = dict(self.state)
        self.clobber(s, inner)
        cond = s.cond
        if isinstance(s, A.DoWhile):
            self.stmt(s.body, inner)
            self.expr(cond, inner)
        else:
            if isinstance(cond, A.VariableDecl):
                self.stmt(A.DeclStmt(cond, loc=cond.loc), inner)
            elif cond is not None:
                self.expr(cond, inner)
            self.stmt(s.body, inner)
            if isinstance(s, A.For) and s.step is not None:
                self.top_expr(s.step, inner)
        self.state = self.merge(before, self.state)

    # ------------------------------------------------------------------ expressions
    def top_expr(self, e, ctx: _Ctx) -> None:
        """An expression statement: an assignment's value is a node, the assignment is not."""
        if isinstance(e, A.Assign):
            self.assign(e, ctx, top=True)
        elif isinstance(e, A.Unary) and e.op in ("++", "--"):
            self.lvalue(e.operand, ctx)
            self.write(e.operand, None, None, ctx)
        elif isinstance(e, A.Sequence):
            for x in e.exprs:
                self.top_expr(x, ctx)
        else:
            self.expr(e, ctx)

    def assign(self, e: A.Assign, ctx: _Ctx, top: bool = False) -> None:
        info = self.expr(e.value, ctx)
        self.lvalue(e.target, ctx)
        whole = e.op == "=" and isinstance(e.target, A.Ident)
        self.write(e.target, e.value if whole else None, info if whole else None, ctx)
        if top and e.op == "=" and not ctx.dynamic and not ctx.region and self.is_output(e.target):
            self.final = e.value

    def is_output(self, target) -> bool:
        if isinstance(target, A.Ident):
            return target.name == self.output
        return (isinstance(target, A.Index) and isinstance(target.obj, A.Ident)
                and target.obj.name == "gl_FragData" == self.output
                and isinstance(target.index, A.IntLit) and target.index.value == 0)

    def write(self, target, value, info, ctx: _Ctx) -> None:
        root = target
        while isinstance(root, (A.Field, A.Index)):
            root = root.obj
        if not isinstance(root, A.Ident) or root.symbol is None:
            return
        key = _var_key(root.symbol)
        if value is not None:
            self.define(key, value, info, ctx)
            return
        # a partial write (swizzle, element, ++): a new unknown-valued definition that still
        # depends on the old value
        old = self.state.get(key, ())
        d = _Def(None, all(x.uniform for x in old) and bool(old) and not ctx.varying
                 and (info is None or info.uniform), any(x.deriv for x in old),
                 0, frozenset(old))
        self.state[key] = (d,)

    def lvalue(self, e, ctx: _Ctx) -> None:
        """Visit the index expressions of an l-value (they are values)."""
        while isinstance(e, (A.Field, A.Index)):
            if isinstance(e, A.Index):
                self.expr(e.index, ctx)
            e = e.obj

    def intern_key(self, key: tuple) -> int:
        got = self.intern.get(key)
        if got is None:
            got = len(self.intern)
            self.intern[key] = got
        return got

    def expr(self, e, ctx: _Ctx) -> _Info:
        """Visit a value expression (evaluation order), record it, return what it is."""
        if isinstance(e, A.Ident):
            info, dup = self.ident(e)
        elif isinstance(e, (A.IntLit, A.FloatLit, A.BoolLit)):
            info = _Info(True, False, False, _EMPTY, 0,
                         self.intern_key(("lit", type(e).__name__, e.value)))
            dup = False
        elif isinstance(e, A.Assign):
            self.assign(e, ctx)
            info = _Info(False, False, True, _EMPTY, 0, self.intern_key(("fx", id(e))))
            dup = False
        elif isinstance(e, A.Unary) and e.op in ("++", "--"):
            self.lvalue(e.operand, ctx)
            self.write(e.operand, None, None, ctx)
            info = _Info(False, False, True, _EMPTY, 1, self.intern_key(("fx", id(e))))
            dup = False
        else:
            info = self.compound_expr(e, ctx)
            dup = False
        self.record(e, info, ctx, dup)
        return info

    def ident(self, e: A.Ident):
        sym = e.symbol
        kind = sym.kind if sym is not None else "in"
        if kind == "builtin":
            kind = sym.qualifiers[0] if sym.qualifiers else "in"
        if kind in ("uniform", "const"):
            return _Info(True, False, False, _EMPTY, 0, self.intern_key(("id", e.name))), False
        if kind == "in":
            return _Info(False, False, False, _EMPTY, 0, self.intern_key(("id", e.name))), False
        defs = self.read_defs(sym)
        uniform = bool(defs) and all(d.uniform for d in defs)
        deriv = any(d.deriv for d in defs)
        reads = frozenset(defs)
        key = self.intern_key(("var", e.name, tuple(id(d) for d in defs)))
        dup = len(defs) == 1 and defs[0].expr is not None
        return _Info(uniform, deriv, False, reads, 0, key), dup

    def compound_expr(self, e, ctx: _Ctx) -> _Info:
        uniform, deriv, effects = True, False, False
        reads: set = set()
        own = op_cost(e)
        keys: list = [type(e).__name__, getattr(e, "op", None), getattr(e, "name", None)]
        call_deriv = isinstance(e, A.Call) and bool(getattr(e.target, "derivative", False))
        out_pos = set()
        if isinstance(e, A.Call):
            if e.kind == "function":
                uniform, effects = False, True
            if getattr(e.target, "side_effects", False):
                effects = True
            quals = getattr(e.target, "qualifiers", ())
            out_pos = {i for i, q in enumerate(quals) if q != "in"}
        if isinstance(e, A.Ternary) or (isinstance(e, A.Binary) and e.op in ("&&", "||")):
            first = e.cond if isinstance(e, A.Ternary) else e.left
            infos = [self.expr(first, ctx)]
            rest = [e.then, e.else_] if isinstance(e, A.Ternary) else [e.right]
            inner = ctx.but(dynamic=ctx.dynamic or not infos[0].uniform,
                            varying=ctx.varying or not infos[0].uniform)
            infos += [self.expr(x, inner) for x in rest]
        else:
            sub = ctx.but(in_deriv=True) if call_deriv else ctx
            infos = []
            for i, c in enumerate(_value_children(e)):
                if i in out_pos:
                    self.lvalue(c, ctx)
                    self.write(c, None, None, ctx)
                    effects = True
                    continue
                infos.append(self.expr(c, sub))
        for inf in infos:
            uniform = uniform and inf.uniform
            deriv = deriv or inf.deriv
            effects = effects or inf.effects
            reads |= inf.reads
            own += inf.own
            keys.append(inf.key)
        if call_deriv:
            deriv = True
        if isinstance(e, A.Call) and e.kind == "function":
            keys.append(id(e))
        return _Info(uniform, deriv, effects, frozenset(reads), own,
                     self.intern_key(tuple(keys)))

    def record(self, e, info: _Info, ctx: _Ctx, dup: bool) -> None:
        reason = None
        if not _is_cacheable_type(e.type):
            reason = "type"
        elif ctx.dynamic or info.effects:
            reason = "dynamic"
        elif info.deriv or ctx.in_deriv:
            reason = "derivative"
        elif info.uniform:
            reason = "uniform"
        else:
            first = self.seen.get(info.key)
            if first is not None and ctx.region[:len(first)] == first:
                dup = True
            elif first is None:
                self.seen[info.key] = ctx.region
        self.records.append((e, reason, info, ctx, dup))


def _value_children(e) -> list:
    if isinstance(e, A.Call):
        return list(e.args)
    if isinstance(e, A.Binary):
        return [e.left, e.right]
    if isinstance(e, A.Unary):
        return [e.operand]
    if isinstance(e, (A.Field, A.Length)):
        return [e.obj]
    if isinstance(e, A.Index):
        return [e.obj, e.index]
    if isinstance(e, A.Sequence):
        return list(e.exprs)
    if isinstance(e, A.InitList):
        return list(e.items)
    return []
