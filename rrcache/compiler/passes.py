"""Pass assembly: the fragment shader of every pass of every algorithm.

Each pass starts from a copy of the prepared unit (:func:`rrcache.compiler.locate.prepare`: core
profile, E replaced by a placeholder inside S) and is transformed as follows (Sitthi-amorn et
al. 2008a §3; docs/design.md §3):

=============  ==========================================================================
``reproject``  three-pass 1: before S, ``if (!rr_hit() || rr_refreshNow()) discard;
               T rr_node = <unpack>(rr_previous()); rr_outPayload = rr_previous();
               rr_outInvDepth = gl_FragCoord.w;`` and E → ``rr_node``; no colour output
``payload``    three-pass 2: ``T rr_node = E;`` hoisted before S (or ``(rr_node = E)`` in
               place), then ``rr_outPayload = <pack>(rr_node); rr_outInvDepth = ...``; no colour
``shade``      three-pass 3: E → ``<unpack>(rr_current())``; colour output only
``hit``        two-pass 1: like ``reproject`` plus the colour output (location 0, cache at 1, 2)
``miss``       two-pass 2: like ``payload`` plus the colour output
``single``     one-pass: before S, ``if (rr_hit() && !rr_refreshNow()) rr_node =
               <unpack>(rr_previous()); else { <feeders of E>; rr_node = E; }`` and the cache
               writes; colour and cache outputs
=============  ==========================================================================

A ``discard`` after S that depends on E (an alpha test on the cached value) is kept in every
pass. Where it fires in pass 1 or 2 no depth is written, and the runtime's final pass tests depth
with ``==``, so that fragment is not shaded from an empty payload and the surface behind it is.

Every pass that writes the cache starts ``main`` with ``rr_outInvDepth = 0.0; rr_outPayload =
vec4(0.0);``. With the inverse depth packed into the payload (``depth_channel``,
:mod:`rrcache.runtime.glsl`) the cache writes are ``rr_outPayload = vec4(<value>,
gl_FragCoord.w[, 0.0…]);`` and there is no ``rr_outInvDepth``. Then the runtime's GLSL (:mod:`rrcache.runtime.glsl`) is parsed and put in front
of the unit, the whole is type-checked, dead code is eliminated
(:mod:`rrcache.compiler.prune`: the roots are the pass's outputs and every ``discard``), and the
runtime's declarations are taken out again: the emitter prints them verbatim.

>>> from rrcache.glsl.frontend import parse_shader
>>> from rrcache.compiler.locate import prepare
>>> from rrcache.glsl.printer import print_glsl
>>> s = parse_shader("#version 330\\nin vec2 v_texcoord; out vec4 c;\\n"
...                  "void main() { float a = sin(v_texcoord.x); c = vec4(a * 2.0); }")
>>> node = [n for n in s.unit.walk() if isinstance(n, A.Call) and n.name == "sin"][0]
>>> p = build_pass(prepare(s, node), "shade")
>>> print(print_glsl(p.unit).split("main()")[1].strip())
{
    float a = rr_current().x;
    c = vec4(a * 2.0);
}
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

from rrcache.errors import GLSLError, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.parser import parse_source
from rrcache.glsl.semantic import check
from rrcache.glsl.ast import main_function
from rrcache.glsl.rewrite import clone
from rrcache.compiler.feeders import move_feeders
from rrcache.compiler.hoist import declare, hoist, insert_before
from rrcache.compiler.locate import Located, find_site
from rrcache.compiler.outputs import cache_init, cache_writes, pack, packed_writes, set_color_output
from rrcache.compiler.prune import prune
from rrcache.compiler.replace import (
    NODE_VAR, current_value, node_variable, previous_payload, previous_value, replace_node,
)
from rrcache.runtime import adaptive as AD
from rrcache.runtime import glsl as G


@dataclass(frozen=True)
class PassSpec:
    """What a pass reads and writes: ``lookup`` (the previous frame's cache), ``current`` (this
    frame's payload), ``cache`` (writes the cache, first output at ``cache_location``),
    ``color`` (writes the colour, at ``color_location`` when pinned)."""

    lookup: bool
    current: bool
    cache: bool
    color: bool
    cache_location: int = 0
    color_location: Optional[int] = None


PASS_SPECS: dict[str, PassSpec] = {
    "reproject": PassSpec(lookup=True, current=False, cache=True, color=False),
    "payload": PassSpec(lookup=False, current=False, cache=True, color=False),
    "shade": PassSpec(lookup=False, current=True, cache=False, color=True),
    "hit": PassSpec(lookup=True, current=False, cache=True, color=True, cache_location=1,
                    color_location=0),
    "miss": PassSpec(lookup=False, current=False, cache=True, color=True, cache_location=1,
                     color_location=0),
    "single": PassSpec(lookup=True, current=False, cache=True, color=True, cache_location=1,
                       color_location=0),
}


@dataclass
class PassUnit:
    """One assembled, pruned pass: ``unit`` holds the shader's own declarations only (checked),
    ``runtime_glsl`` the runtime snippets the emitter puts after the ``#version`` line,
    ``spec`` what the pass does, ``form`` how the value was bound (``hoist``/``inline``, or
    ``replace`` where E is simply replaced)."""

    name: str
    unit: A.TranslationUnit
    runtime_glsl: str
    spec: PassSpec
    form: str


def runtime_snippets(spec: PassSpec, filter: str, depth_channel: Optional[int] = None,
                     adaptive: bool = False) -> str:
    """The runtime GLSL a pass needs, in the order it is emitted (``depth_channel``: the payload
    channel holding the inverse depth, None for its own texture). An adaptive variant's passes
    that write the cache all read the previous frame's too (the recomputing ones measure the
    entry's change, :mod:`rrcache.runtime.adaptive`) and write the volatility after the inverse
    depth."""
    text = ""
    if spec.lookup or (adaptive and spec.cache):
        lookup = G.lookup_glsl(filter, depth_channel)
        text += AD.lookup_glsl(lookup) if adaptive else lookup
    if spec.current:
        text += G.current_glsl()
    if spec.cache:
        text += G.output_glsl(spec.cache_location, depth_channel)
        if adaptive:
            text += AD.output_glsl(spec.cache_location + 2)
    return text


def _hit_condition() -> A.Expr:
    """``rr_hit() && !rr_refreshNow()``"""
    return A.Binary("&&", A.Call("rr_hit", []), A.Unary("!", A.Call("rr_refreshNow", [])))


def _miss_condition() -> A.Expr:
    """``!rr_hit() || rr_refreshNow()``"""
    return A.Binary("||", A.Unary("!", A.Call("rr_hit", [])), A.Call("rr_refreshNow", []))


def _set(name: str, value: A.Expr) -> A.ExprStmt:
    return A.ExprStmt(A.Assign("=", A.Ident(name), value))


def transform(loc: Located, name: str, depth_channel: Optional[int] = None,
              adaptive: bool = False) -> tuple[A.TranslationUnit, str]:
    """The transformed (not yet checked or pruned) unit of pass ``name``, and the binding form
    (``depth_channel``: the inverse depth packed into that payload channel, None: its own
    output). ``adaptive``: the cache writes carry the entry's volatility too
    (:mod:`rrcache.runtime.adaptive`: the reprojected one at hits, the measured change where the
    value is recomputed); the one-pass algorithm has no adaptive form, nor a packed depth."""
    if adaptive and name == "single":
        raise ValueError("adaptive refresh runs with the three-pass and two-pass algorithms, not one-pass")
    if adaptive and depth_channel is not None:
        raise ValueError("adaptive refresh keeps the inverse depth in its own target: not packed")
    if name not in PASS_SPECS:
        raise ValueError(f"unknown pass {name!r}; expected one of {', '.join(PASS_SPECS)}")
    spec = PASS_SPECS[name]
    unit = clone(loc.unit)
    site = find_site(unit)
    n, t = loc.components, loc.type_name

    def writes(value: A.Expr) -> list:
        return cache_writes(pack(value, n)) if depth_channel is None else packed_writes(value, n)

    if name in ("reproject", "hit"):
        insert_before(site, [
            A.If(_miss_condition(), A.Discard()),
            declare(t, NODE_VAR, previous_value(n)),
            *(cache_writes(previous_payload(), A.Ident("rr_carried") if adaptive else None)
              if depth_channel is None else packed_writes(previous_value(n), n)),
        ])
        replace_node(site.stmt, node_variable)
        form = "replace"
    elif name in ("payload", "miss"):
        fresh = (A.Call("rr_freshState", [pack(node_variable(), n)]) if adaptive else None)
        form = hoist(site, t, clone(loc.expr),
                     then=cache_writes(pack(node_variable(), n), fresh) if adaptive else writes(node_variable()))
    elif name == "shade":
        replace_node(site.stmt, lambda: current_value(n))
        form = "replace"
    else:  # single
        miss_branch = A.Compound([_set(NODE_VAR, clone(loc.expr))])
        setter = A.If(_hit_condition(), _set(NODE_VAR, previous_value(n)), miss_branch)
        value = A.Ternary(_hit_condition(), previous_value(n), clone(loc.expr))
        form = hoist(site, t, value, then=writes(node_variable()), setter=setter)
        if form == "hoist":
            move_feeders(site, setter, miss_branch, main_function(unit).body)
    if spec.cache:
        main_function(unit).body.stmts[0:0] = cache_init(packed=depth_channel is not None, adaptive=adaptive)
    set_color_output(unit, keep=spec.color, location=spec.color_location)
    return unit, form


def build_pass(loc: Located, name: str, filter: str = "bilinear", depth_channel: Optional[int] = None,
               adaptive: bool = False) -> PassUnit:
    """Transform, type-check and prune pass ``name`` for the located node (``depth_channel``:
    the inverse depth packed into that payload channel; None: its own render target;
    ``adaptive``: with the adaptive refresh's volatility, :mod:`rrcache.runtime.adaptive`)."""
    spec = PASS_SPECS.get(name)
    if spec is None:
        raise ValueError(f"unknown pass {name!r}; expected one of {', '.join(PASS_SPECS)}")
    unit, form = transform(loc, name, depth_channel, adaptive)
    runtime = runtime_snippets(spec, filter, depth_channel, adaptive)
    snippet_decls = parse_source("#version 330 core\n" + runtime, "<rrcache runtime>").decls
    unit.decls[0:0] = snippet_decls
    try:
        check(unit, loc.path)
    except GLSLError as err:
        raise UnsupportedShaderError(
            f"the {name} pass caching '{loc.text}' does not type-check: {err.message}",
            err.loc or loc.loc,
            "names starting with 'rr_' are reserved for rrcache; rename any such name in the "
            "shader") from None
    prune(unit, keep=snippet_decls)
    ids = {id(d) for d in snippet_decls}
    unit.decls = [d for d in unit.decls if id(d) not in ids]
    return PassUnit(name, unit, runtime, spec, form)

