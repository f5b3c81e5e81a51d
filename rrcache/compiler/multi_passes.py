"""Pass assembly for k ≥ 2 cached nodes: the fragment shader of every pass of every algorithm.

Node j hits at a pixel when its own entry reprojects (``rr_hit_j()``) and it does not refresh
this frame (``!rr_refreshNow_j()``, its own period and phase); otherwise it misses there
(:mod:`rrcache.runtime.multi_glsl`). Each pass starts from a copy of the unit of
:func:`rrcache.compiler.multi_locate.prepare_nodes` (top-level nodes replaced by placeholders):

=============  ==========================================================================
``reproject``  three-pass 1: at the start of ``main``, ``if (miss_0 || … || miss_k-1)
               discard;`` then every node's ``rr_outPayload_j = rr_previous_j();
               rr_outInvDepth_j = gl_FragCoord.w;`` and each top-level E_j →
               ``<unpack>(rr_previous_j())``; no colour. It keeps the pixels where *every*
               node hits.
``payload``    three-pass 2, run where pass 1 left no depth (a pixel where some node misses):
               one pass over that union, which computes each node only where that node misses
               and copies the others from the reprojection. Before a top-level node's
               statement S: per node of its nest (innermost first, then itself) ``T rr_node_j;
               if (rr_hit_j() && !rr_refreshNow_j()) rr_node_j = <unpack>(rr_previous_j());
               else { rr_node_j = E_j; }`` and its cache writes; E_j in S → ``rr_node_j``. No
               colour.
``shade``      three-pass 3: each top-level E_j → ``<unpack>(rr_current_j())``; colour only.
``hit_j``      per-node three-pass (the layout three-pass uses unless the shader can discard
               or a node needs derivatives), node j's first pass, into node j's targets only
               (the depth cleared before it): where node j hits, copy and write depth; where it
               misses, discard.
``node_j``     per-node three-pass, node j's second pass (depth test ``<``): runs where
               ``hit_j`` left no depth, so early depth testing culls it where node j hits, and
               computes E_j; its inner nodes and the nodes before it (program order: the
               node passes run in the order of their statements, inner nodes first) are read
               from this frame's payloads (``rr_current_i()``). A pixel pays for node j only
               where node j misses: neither a branch nor a ``discard`` would do that on
               llvmpipe, whose fragment shader runs both sides of a branch, and the rest of a
               shader after a ``discard``, for its SIMD lanes.
``hit``        two-pass 1: ``reproject`` plus the colour output (location 0, caches from 1)
``miss``       two-pass 2: ``payload`` plus the colour output
``single``     one-pass: ``payload`` plus the colour output, run at every pixel
=============  ==========================================================================

Nested nodes (node B inside node A's expression): B is a cached value of its own, kept at its own
period, that A's recomputation reads. Where A misses, A is computed from B's value *this frame*:
B's cached value where B hits, B recomputed where B misses (so A at Δn = 4 over B at Δn = 50
recomputes A's outer part every 4 frames and B's every 50). Where A hits, A's value is
reprojected and B is not needed for this frame's colour; B is still computed where B itself
misses, so that B's entry is never older than its period when A next needs it. B's statement is
A's (B is computed right before A's), which needs A's statement to evaluate nothing with a side
effect before A and A's expression to have none: otherwise the nest is refused.

A node whose value needs screen-space derivatives (the node table marks it invalid for
one-pass) is computed unconditionally before the branch that may replace it by the reprojected
value, so its derivatives stay defined; one-pass refuses such a node as for one node.
As the one-node one-pass compiler does, the statements that only feed a node move into that
node's miss branch (:mod:`rrcache.compiler.feeders`), so a pixel where it hits does not pay for
them.
"""
from __future__ import annotations

from typing import Optional

from rrcache.errors import GLSLError, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.ast import is_ident, main_function, own_parts, post_order, substitute, walk
from rrcache.glsl.parser import parse_source
from rrcache.glsl.rewrite import clone
from rrcache.glsl.semantic import check
from rrcache.compiler.feeders import move_feeders
from rrcache.compiler.hoist import _has_effect, declare, insert_after, insert_before
from rrcache.compiler.locate import find_site
from rrcache.compiler.multi_locate import MultiLocated, NodeSite
from rrcache.compiler.outputs import float_lit, pack, set_color_output, unpack
from rrcache.compiler.passes import PASS_SPECS, PassSpec, PassUnit
from rrcache.compiler.prune import prune
from rrcache.runtime import glsl as G
from rrcache.runtime import multi_glsl as MG

#: the passes for several nodes: as for one node, except that every pass that computes values
#: reads the previous frame's cache too (a pixel there may hit for some nodes)
MULTI_PASS_SPECS: dict[str, PassSpec] = {
    **PASS_SPECS,
    "payload": PassSpec(lookup=True, current=False, cache=True, color=False),
    "miss": PassSpec(lookup=True, current=False, cache=True, color=True, cache_location=1, color_location=0),
}


def _call(name: str, j: int) -> A.Call:
    return A.Call(MG.suffixed(name, j), [])


def _hit(j: int) -> A.Expr:
    """``rr_hit_j() && !rr_refreshNow_j()``"""
    return A.Binary("&&", _call("rr_hit", j), A.Unary("!", _call("rr_refreshNow", j)))


def _miss(j: int) -> A.Expr:
    """``!rr_hit_j() || rr_refreshNow_j()``"""
    return A.Binary("||", A.Unary("!", _call("rr_hit", j)), _call("rr_refreshNow", j))


def _set(name: str, value: A.Expr) -> A.ExprStmt:
    return A.ExprStmt(A.Assign("=", A.Ident(name), value))


def cache_writes(j: int, payload: A.Expr) -> list[A.Stmt]:
    """``rr_outPayload_j = payload; rr_outInvDepth_j = gl_FragCoord.w;``"""
    return [_set(MG.suffixed(G.OUT_PAYLOAD, j), payload),
            _set(MG.suffixed(G.OUT_INVDEPTH, j), A.Field(A.Ident("gl_FragCoord"), "w"))]


def cache_init(k: int) -> list[A.Stmt]:
    """Every node's entry starts invalid: an early ``return`` or a node whose statement does not
    run leaves 0 inverse depth there (that node misses next frame)."""
    out: list[A.Stmt] = []
    for j in range(k):
        out += [_set(MG.suffixed(G.OUT_INVDEPTH, j), float_lit(0.0)),
                _set(MG.suffixed(G.OUT_PAYLOAD, j), A.Call("vec4", [float_lit(0.0)]))]
    return out


def _side_effect_before(stmt: A.Stmt, name: str) -> bool:
    for root in own_parts(stmt):
        for n in post_order(root):
            if isinstance(n, A.Ident) and n.name == name:
                return False
            if _has_effect(n):
                return True
    return False


def _replace(stmt: A.Node, name: str, make) -> int:
    return substitute(stmt, is_ident(name), lambda n: make())


def _value(loc: MultiLocated, node: NodeSite) -> A.Expr:
    """E_j with its direct inner nodes' placeholders → their ``rr_node_i`` variables."""
    expr = clone(node.expr)
    for child in loc.children(node.index):
        c = loc.nodes[child]
        if isinstance(expr, A.Ident) and expr.name == c.name:
            expr = A.Ident(c.var)
        elif _replace(expr, c.name, lambda c=c: A.Ident(c.var)) != 1:
            raise UnsupportedShaderError(f"the inner node '{c.text}' was lost in '{node.text}'", c.loc,
                                         "this is a bug in rrcache; please report it")
    return expr


def _setter(loc: MultiLocated, node: NodeSite, uniform_flow: bool) -> list[A.Stmt]:
    """Node j's value at this pixel (reprojected where it hits, computed where it misses) and its
    cache writes."""
    j, t, n = node.index, node.type_name, node.components
    previous = unpack(_call("rr_previous", j), n)
    if uniform_flow:  # derivatives inside: compute it at every pixel, outside any branch
        stmts: list[A.Stmt] = [declare(t, node.var, _value(loc, node)),
                               A.If(_hit(j), _set(node.var, previous))]
    else:
        stmts = [declare(t, node.var),
                 A.If(_hit(j), _set(node.var, previous), A.Compound([_set(node.var, _value(loc, node))]))]
    return stmts + cache_writes(j, pack(A.Ident(node.var), n))


def _move_feeders(unit: A.TranslationUnit, site, stmts: list[A.Stmt]) -> None:
    """Move into each node's miss branch the statements that only feed it (as the one-node
    one-pass compiler does: :mod:`rrcache.compiler.feeders`), so that a pixel where the node
    hits does not pay for them."""
    for s in stmts:
        if isinstance(s, A.If) and isinstance(s.else_, A.Compound):
            move_feeders(site, s, s.else_, main_function(unit).body)


def _nest(loc: MultiLocated, top: int) -> list[NodeSite]:
    """The nodes whose top-level node is ``top``, innermost first, ``top`` last."""
    members = [n for n in loc.nodes if n.top == top]
    return sorted(members, key=lambda n: -loc.depth(n.index))


def _compute(unit: A.TranslationUnit, loc: MultiLocated, derivative: set[int]) -> None:
    """The ``payload``/``miss``/``single`` form: every node bound before its statement."""
    placed = []
    for top in [n for n in loc.nodes if n.parent is None]:
        site = find_site(unit, top.name)
        nest = _nest(loc, top.index)
        if _side_effect_before(site.stmt, top.name):
            if len(nest) > 1:
                raise UnsupportedShaderError(
                    f"node '{top.text}' sits in a statement that changes a variable before it, so "
                    f"the nodes inside it cannot be computed before it", top.loc,
                    "cache the nodes separately (not nested), or pick another outer node")
            if top.index in derivative:
                raise UnsupportedShaderError(
                    f"node '{top.text}' needs screen-space derivatives and sits in a statement that "
                    "changes a variable before it: it cannot be cached beside other nodes", top.loc,
                    "cache it alone")
            j, n = top.index, top.components
            value = A.Ternary(_hit(j), unpack(_call("rr_previous", j), n), _value(loc, top))
            insert_before(site, [declare(top.type_name, top.var)])
            _replace(site.stmt, top.name, lambda: A.Assign("=", A.Ident(top.var), value))
            insert_after(site, cache_writes(j, pack(A.Ident(top.var), n)))
            continue
        if len(nest) > 1 and any(_has_effect(x) for x in walk(top.expr)):
            raise UnsupportedShaderError(
                f"node '{top.text}' changes a variable itself, so the nodes inside it cannot be "
                "computed before it", top.loc, "cache the nodes separately (not nested)")
        stmts: list[A.Stmt] = []
        for node in nest:
            stmts += _setter(loc, node, node.index in derivative)
        insert_before(site, stmts)
        _replace(site.stmt, top.name, lambda: A.Ident(top.var))
        placed.append((site, stmts))
    # only once every node is bound: a statement holding another node's placeholder would look
    # like a feeder and take that node's setter into this node's miss branch
    for site, stmts in placed:
        _move_feeders(unit, site, stmts)


def has_discard(loc: MultiLocated) -> bool:
    """Whether ``main`` can discard (then three-pass keeps one pass 2 over the union: the copy
    pass of the per-node layout could not tell where the shader discards)."""
    return any(isinstance(n, A.Discard) for n in walk(main_function(loc.unit).body))


def node_order(loc: MultiLocated) -> list[int]:
    """The order of the per-node passes: by the place of each node's top-level statement in
    ``main`` (a node can read only values computed before it), inner nodes before their outer."""
    place = {}
    for i, n in enumerate(walk(main_function(loc.unit).body)):
        if isinstance(n, A.Ident) and n.name.startswith("rr_cachedNodePlaceholder_"):
            place.setdefault(n.name, i)
    return sorted(range(len(loc.nodes)),
                  key=lambda j: (place.get(loc.nodes[loc.nodes[j].top].name, 0), -loc.depth(j)))


def _current(node: NodeSite) -> A.Expr:
    return unpack(_call("rr_current", node.index), node.components)


def _hit_pass(loc: MultiLocated, j: int) -> A.TranslationUnit:
    """Per-node three-pass, node j's first pass (``hit_j``, depth test ``<`` with writes, node j's
    targets): where node j hits, copy its reprojected value and write depth; where it misses,
    discard (so that node j's second pass runs there only, culled by the depth test elsewhere)."""
    unit = clone(loc.unit)
    body = main_function(unit).body
    body.stmts = [_set(MG.suffixed(G.OUT_INVDEPTH, j), float_lit(0.0)),
                  _set(MG.suffixed(G.OUT_PAYLOAD, j), A.Call("vec4", [float_lit(0.0)])),
                  A.If(_miss(j), A.Discard()),
                  *cache_writes(j, _call("rr_previous", j))]
    return unit


def _node_pass(loc: MultiLocated, j: int) -> A.TranslationUnit:
    """Per-node three-pass, node j's second pass (``node_j``, depth test ``<`` with writes, only
    node j's targets): it runs where ``hit_j`` left no depth (node j misses) and computes E_j
    (its inner nodes and the nodes before it read from this frame's payloads: their passes ran
    first)."""
    unit = clone(loc.unit)
    body = main_function(unit).body
    node = loc.nodes[j]
    top = loc.nodes[node.top]
    site = find_site(unit, top.name)
    value = clone(node.expr)
    for child in loc.children(j):
        c = loc.nodes[child]
        if isinstance(value, A.Ident) and value.name == c.name:
            value = _current(c)
        else:
            _replace(value, c.name, lambda c=c: _current(c))
    writes = cache_writes(j, pack(A.Ident(node.var), node.components))
    if _side_effect_before(site.stmt, top.name):
        if node.top != j:
            raise UnsupportedShaderError(
                f"node '{top.text}' sits in a statement that changes a variable before it, so the "
                f"nodes inside it cannot be computed before it", top.loc,
                "cache the nodes separately (not nested), or pick another outer node")
        insert_before(site, [declare(node.type_name, node.var)])
        _replace(site.stmt, top.name, lambda: A.Assign("=", A.Ident(node.var), value))
        insert_after(site, writes)
    else:
        insert_before(site, [declare(node.type_name, node.var, value)] + writes)
        _replace(site.stmt, top.name, lambda: A.Ident(node.var) if node.top == j else _current(top))
    for other in loc.nodes:  # the other top-level nodes: this frame's values (dead unless read)
        if other.parent is None and other.index != node.top:
            _replace(body, other.name, lambda o=other: _current(o))
    body.stmts[0:0] = [_set(MG.suffixed(G.OUT_INVDEPTH, j), float_lit(0.0)),
                       _set(MG.suffixed(G.OUT_PAYLOAD, j), A.Call("vec4", [float_lit(0.0)]))]
    set_color_output(unit, keep=False)
    return unit


def transform(loc: MultiLocated, name: str, derivative: set[int]) -> A.TranslationUnit:
    """The transformed (not yet checked or pruned) unit of pass ``name``."""
    spec = MULTI_PASS_SPECS[name]
    unit = clone(loc.unit)
    body = main_function(unit).body
    tops = [n for n in loc.nodes if n.parent is None]
    k = len(loc.nodes)
    if name in ("reproject", "hit"):
        cond = _miss(0)
        for j in range(1, k):
            cond = A.Binary("||", cond, _miss(j))
        head: list[A.Stmt] = [A.If(cond, A.Discard())]
        for j in range(k):
            head += cache_writes(j, _call("rr_previous", j))
        body.stmts[0:0] = head
        for top in tops:
            _replace(body, top.name, lambda top=top: unpack(_call("rr_previous", top.index), top.components))
    elif name == "shade":
        for top in tops:
            _replace(body, top.name, lambda top=top: unpack(_call("rr_current", top.index), top.components))
    else:  # payload, miss, single
        _compute(unit, loc, derivative)
    if spec.cache:
        body.stmts[0:0] = cache_init(k)
    set_color_output(unit, keep=spec.color, location=spec.color_location)
    return unit


def runtime_snippets(spec: PassSpec, k: int, filter: str) -> str:
    text = ""
    if spec.lookup:
        text += MG.lookup_glsl(k, filter)
    if spec.current:
        text += MG.current_glsl(k)
    if spec.cache:
        text += MG.output_glsl(k, spec.cache_location)
    return text


def build_multi_pass(loc: MultiLocated, name: str, filter: str = "bilinear",
                     derivative: Optional[set[int]] = None) -> PassUnit:
    """Transform, type-check and prune pass ``name`` for the located nodes; ``derivative`` holds
    the indices of the nodes that need screen-space derivatives."""
    k = len(loc.nodes)
    if name.startswith("node_"):  # per-node three-pass: node j's own pass
        j = int(name[5:])
        unit = _node_pass(loc, j)
        spec = PassSpec(lookup=True, current=True, cache=True, color=False)
        runtime = (MG.lookup_glsl(k, filter) + MG.current_glsl(k)
                   + MG.rename(G.output_glsl(0), j))
    elif name.startswith("hit_"):
        j = int(name[4:])
        unit = _hit_pass(loc, j)
        spec = PassSpec(lookup=True, current=False, cache=True, color=False)
        runtime = MG.lookup_glsl(k, filter) + MG.rename(G.output_glsl(0), j)
    else:
        spec = MULTI_PASS_SPECS.get(name)
        if spec is None:
            raise ValueError(f"unknown pass {name!r}; expected one of {', '.join(MULTI_PASS_SPECS)}")
        unit = transform(loc, name, set(derivative or ()))
        runtime = runtime_snippets(spec, k, filter)
    snippet_decls = parse_source("#version 330 core\n" + runtime, "<rrcache runtime>").decls
    unit.decls[0:0] = snippet_decls
    texts = " + ".join(f"'{n.text}'" for n in loc.nodes)
    try:
        check(unit, loc.path)
    except GLSLError as err:
        raise UnsupportedShaderError(
            f"the {name} pass caching {texts} does not type-check: {err.message}",
            err.loc or loc.nodes[0].loc,
            "names starting with 'rr_' are reserved for rrcache; rename any such name in the "
            "shader") from None
    prune(unit, keep=snippet_decls)
    ids = {id(d) for d in snippet_decls}
    unit.decls = [d for d in unit.decls if id(d) not in ids]
    return PassUnit(name, unit, runtime, spec, "multi")
