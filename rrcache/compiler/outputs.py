"""Pass: the cache outputs and the colour output of a pass.

- :func:`pack` / :func:`unpack` convert between the cached value and the ``vec4`` payload:
  ``vec4(x, 0.0, 0.0, 0.0)`` / ``vec4(v, 0.0, 0.0)`` / ``vec4(v, 0.0)`` / ``v`` and ``.x`` /
  ``.xy`` / ``.xyz`` / the whole ``vec4``.
- :func:`cache_writes` is ``rr_outPayload = <payload>; rr_outInvDepth = gl_FragCoord.w;`` and
  :func:`cache_init` the ``rr_outInvDepth = 0.0; rr_outPayload = vec4(0.0);`` put at the start
  of ``main`` so that an early ``return`` leaves an invalid cache entry (0 inverse depth: the next
  frame misses there). With the inverse depth packed into the payload
  (:func:`rrcache.runtime.glsl.depth_channel_for`) both write ``rr_outPayload`` alone.
- :func:`set_color_output` removes the shader's colour output (the variable stays, as a plain
  global that dead-code elimination then removes with every write to it) or pins it to
  ``layout(location = 0)`` for the passes that write colour beside the cache.

>>> from rrcache.glsl.printer import print_expr
>>> print_expr(pack(A.Ident("v"), 2)), print_expr(unpack(A.Call("rr_current", []), 3))
('vec4(v, 0.0, 0.0)', 'rr_current().xyz')
"""
from __future__ import annotations

from typing import Optional

from rrcache.glsl import ast as A
from rrcache.runtime import glsl as G

_SWIZZLE = {1: "x", 2: "xy", 3: "xyz"}


def float_lit(value: float) -> A.FloatLit:
    """A float literal (``0.0``)."""
    return A.FloatLit(float(value), text=repr(float(value)))


def pack(value: A.Expr, components: int) -> A.Expr:
    """``value`` (float or vec2-4) padded with zeros to the vec4 payload."""
    if components == 4:
        return value
    return A.Call("vec4", [value] + [float_lit(0.0) for _ in range(4 - components)])


def unpack(payload: A.Expr, components: int) -> A.Expr:
    """The cached value from a vec4 payload expression."""
    if components == 4:
        return payload
    return A.Field(payload, _SWIZZLE[components])


def _assign(name: str, value: A.Expr) -> A.ExprStmt:
    return A.ExprStmt(A.Assign("=", A.Ident(name), value))


def cache_writes(payload: A.Expr, state: Optional[A.Expr] = None) -> list[A.Stmt]:
    """``rr_outPayload = payload; rr_outInvDepth = gl_FragCoord.w;`` (and ``rr_outState =
    state;`` for an adaptive variant, :mod:`rrcache.runtime.adaptive`)"""
    writes = [_assign(G.OUT_PAYLOAD, payload),
              _assign(G.OUT_INVDEPTH, A.Field(A.Ident("gl_FragCoord"), "w"))]
    if state is not None:
        writes.append(_assign("rr_outState", state))
    return writes


def packed_writes(value: A.Expr, components: int) -> list[A.Stmt]:
    """The cache writes with the inverse depth packed into the payload's channel
    ``components`` (:func:`rrcache.runtime.glsl.depth_channel_for`):
    ``rr_outPayload = vec4(value, gl_FragCoord.w[, 0.0…]);``

    >>> from rrcache.glsl.printer import print_expr
    >>> print_expr(packed_writes(A.Ident("v"), 1)[0].expr.value)
    'vec4(v, gl_FragCoord.w, 0.0, 0.0)'
    """
    if not 1 <= components <= 3:
        raise ValueError(f"a {components}-component value leaves no payload channel for the inverse depth")
    rest = [float_lit(0.0) for _ in range(3 - components)]
    return [_assign(G.OUT_PAYLOAD, A.Call("vec4", [value, A.Field(A.Ident("gl_FragCoord"), "w")] + rest))]


def cache_init(packed: bool = False, adaptive: bool = False) -> list[A.Stmt]:
    """``rr_outInvDepth = 0.0; rr_outPayload = vec4(0.0);`` (``packed``: the inverse depth is in
    the payload, whose zero then marks the entry invalid: ``rr_outPayload = vec4(0.0);``;
    ``adaptive``: and ``rr_outState = 0.0;``)."""
    init = [_assign(G.OUT_PAYLOAD, A.Call("vec4", [float_lit(0.0)]))]
    if not packed:
        init.insert(0, _assign(G.OUT_INVDEPTH, float_lit(0.0)))
    if adaptive:
        init.append(_assign("rr_outState", float_lit(0.0)))
    return init


def color_outputs(unit: A.TranslationUnit) -> list[A.VariableDecl]:
    """The global ``out`` declarations of the shader (after legacy conversion: its colour
    output; the runtime's own outputs are not in the unit yet)."""
    return [d for d in unit.decls
            if isinstance(d, A.VariableDecl) and d.declarators and "out" in d.type.qualifiers]


def set_color_output(unit: A.TranslationUnit, keep: bool, location: Optional[int] = None) -> None:
    """Remove the colour output (``keep=False``: it becomes an ordinary global) or keep it,
    pinned to ``location`` when given. Declaration types may be shared with other copies of the
    tree, so they are replaced, never modified."""
    for decl in color_outputs(unit):
        quals = decl.type.qualifiers
        if not keep:
            new_quals: list = [q for q in quals if q == "const"]
        elif location is None:
            continue
        else:
            others = []
            for q in quals:
                if isinstance(q, A.Layout):
                    items = [(k, v) for k, v in q.items if k != "location"]
                    if items:
                        others.append(A.Layout(items, loc=q.loc))
                else:
                    others.append(q)
            new_quals = [A.Layout([("location", A.IntLit(location, text=str(location)))])] + others
        decl.type = A.FullType(new_quals, decl.type.spec, loc=decl.type.loc)
