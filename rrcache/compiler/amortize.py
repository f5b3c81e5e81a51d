"""Amortized sampling (Nehab et al. 2007 §6): an estimator's samples spread over frames.

The cached value is the estimator's accumulators right after its loop (:mod:`rrcache.analysis.
estimators`: ``a0 + Σ_i t(i)`` over ``N`` iterations), packed into the payload. Per frame:

- at a **hit**, ``m`` of the ``N`` iterations run: with ``N = s·m`` a stratified subset
  ``i_j = j·s + φ`` (``j = 0..m-1``), else the window ``i_j = (φ·m + j) mod N``; the phase ``φ``
  changes every frame, so every index is used over ``N/m`` frames (``N`` frames for a window).
  Two ways (``phase``):

  ``"frame"`` (default): ``φ = frame mod s`` (or ``mod N``), the same at every pixel. The
  passes that evaluate the subset are compiled once per phase (``hit``, ``hit@1``, ...,
  ``Variant.amortized["cycle"]`` programs), each with its subset unrolled and its indices
  constants, and the runtime runs the program of the frame's phase. The driver then folds what
  depends on the index alone (a constant array element, the ``sin``/``cos`` of a per-index
  angle), as in the original's unrolled loop. A dynamic index cost more per sample than the
  original (PCF: 0.75x the original's speed at 4 of 16), and one program branching on the phase
  still paid for most of the branches on llvmpipe (two-pass 4 of 16: 56 ms CPU against 43 ms
  for the ``pixel`` loop; measured side by side).
  ``"pixel"``: ``φ = (frame + x + 2y) mod s`` (``x, y`` the pixel): a loop with a dynamic index;
  the 2×2 pixels the cache's bilinear reconstruction mixes use different subsets.

  The subset sum, scaled by ``N/m`` around
  the start value (``x = a0 + N/m · (acc − a0)``), estimates the full sum; it is blended with the
  reprojected running estimate: ``acc = λ·c_prev + (1 − λ)·x`` (``λ`` is the runtime's
  ``blend``, uniform ``rr_lambda``).
- at a **miss** (disocclusion) all ``N`` iterations run, as in the original.

``history="slots"`` (with the ``frame`` phase and ``N = s·m``, when ``s`` times the
accumulators fit in the payload's 4 components: :func:`rrcache.compiler.slots.slots_fit`, the rule the
profiler and the models use too): the payload keeps the ``s`` subset sums
apart. A hit recomputes its phase's sum (blended with that slot's reprojected value by ``λ``;
``λ = 0`` replaces it) and the value is the start plus all ``s`` slots, so on a still image the
full sum is back after one cycle, exactly; a miss computes the ``s`` sums (all ``N``
iterations). The paper's blend weighs the phases unequally (``λ = 3/5``, 4 phases: 0.46, 0.28,
0.17, 0.10 of the estimate) and a stratified pattern's subsets differ much more than
independent samples do, so its error stays above the original's (measured on the PCF scene).

``m = N`` emits the original loop unchanged and ``λ = 0`` makes the blend ``0·c_prev + 1·x``: the
variant then computes exactly what the original does. The refresh rule is not used: every hit
takes fresh samples, and ``λ`` sets how fast old ones are forgotten.

The passes are those of :mod:`rrcache.compiler.passes` (three-pass ``reproject``/``payload``/
``shade``, two-pass ``hit``/``miss``, one-pass ``single``), with the loop in the place of the
node: pass 1 computes the blended estimate at hits and discards at misses, pass 2 runs the whole
loop where pass 1 left no depth, pass 3 reads the accumulators back from this frame's payload.

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("#version 330\\nin vec2 v_texcoord; out vec4 c;\\nvoid main() { float s = 0.0;"
...                  " for (int i = 0; i < 8; i++) s += sin(v_texcoord.x * float(i)); c = vec4(s); }")
>>> v = instance_amortized(s, "e1", samples=2, blend=0.6)
>>> sorted(v.passes), v.amortized["samples"], v.amortized["of"], v.components
(['payload', 'reproject', 'reproject@1', 'reproject@2', 'reproject@3', 'shade'], 2, 8, 1)
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any, Optional

from rrcache.deep import deep
from rrcache.errors import GLSLError, RRCacheError, SourceLoc, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.legacy import to_core
from rrcache.glsl.parser import parse_source
from rrcache.glsl.semantic import check
from rrcache.glsl.rewrite import clone, rewrite_scoped
from rrcache.glsl.defuse import written_roots
from rrcache.analysis.unroll import fold_copy
from rrcache.analysis.estimators import Estimator, EstimatorTable, display_name, find_estimators
from rrcache.glsl.ast import main_function, walk
from rrcache.compiler.emit import emit_pass
from rrcache.compiler.payload_encoding import (ENCODED_DTYPE, PayloadEncoding, decoded, encoded, encoding_glsl,
                                               slots_encoding)
from rrcache.compiler.outputs import cache_init, cache_writes, float_lit, set_color_output
from rrcache.compiler.passes import PASS_SPECS, PassUnit, runtime_snippets
from rrcache.compiler.prune import prune
from rrcache.compiler.variant import PassSource, Variant
from rrcache.runtime.cache import ALGORITHMS
from rrcache.runtime.spec import VariantSpec
from rrcache.runtime.glsl import AMORTIZE_GLSL, AMORTIZE_PIXEL_GLSL, FILTERS
from rrcache.compiler.slots import AMORTIZE_PAYLOADS, slots_fit

__all__ = ["instance_amortized", "LocatedLoop", "HISTORIES", "PHASES", "prepare_loop", "subset_indices"]

_MARKER = "rr_estimatorMarker"
_SWIZZLE = "xyzw"


@dataclass
class LocatedLoop:
    """The estimator's loop, ready for the passes: ``unit`` is the core-profile inlined program
    with a marker statement right before the loop; ``names``/``types`` the accumulators (as
    named in ``unit``), ``estimator`` the analysis record."""

    unit: A.TranslationUnit
    estimator: Estimator
    names: list[str]
    types: list[str]
    path: str

    @property
    def components(self) -> int:
        return sum(int(t[-1]) if t != "float" else 1 for t in self.types)


PHASES = ("frame", "pixel")
HISTORIES = ("blend", "slots")


def _cycle(total: int, samples: int) -> int:
    """Frames until every index has been used: ``N/m`` (stratified) or ``N`` (window)."""
    return total // samples if total % samples == 0 else total


def _subset(total: int, samples: int, phase: int) -> list[int]:
    if total % samples == 0:
        stride = total // samples
        return [j * stride + phase for j in range(samples)]
    return [(phase * samples + j) % total for j in range(samples)]


def subset_indices(total: int, samples: int, frame: int, pixel: tuple[int, int] = (0, 0),
                   phase: str = "frame") -> list[int]:
    """The iteration numbers (0-based, in loop order) a hit evaluates at ``frame`` and ``pixel``:
    what the emitted GLSL computes (for tests and documentation).

    >>> subset_indices(16, 4, 0), subset_indices(16, 4, 1), subset_indices(6, 4, 1)
    ([0, 4, 8, 12], [1, 5, 9, 13], [4, 5, 0, 1])
    >>> subset_indices(16, 4, 0, (1, 0), "pixel"), subset_indices(16, 4, 0, (1, 0))
    ([1, 5, 9, 13], [0, 4, 8, 12])
    """
    if samples >= total:
        return list(range(total))
    shift = pixel[0] + 2 * pixel[1] if phase == "pixel" else 0
    return _subset(total, samples, (frame + shift) % _cycle(total, samples))


def _parent_slot(root: A.Node, target: A.Node):
    """(parent, field name, list index or None) holding ``target``."""
    from dataclasses import fields

    for node in walk(root):
        for f in fields(node):
            value = getattr(node, f.name, None)
            if value is target:
                return node, f.name, None
            if isinstance(value, list):
                for i, item in enumerate(value):
                    if item is target:
                        return node, f.name, i
    return None


def prepare_loop(shader_or_table: Any, estimator_id: str) -> LocatedLoop:
    """Find estimator ``estimator_id`` and build the marked core-profile unit."""
    table = shader_or_table if isinstance(shader_or_table, EstimatorTable) else find_estimators(shader_or_table)
    est = table.find(estimator_id)
    unit = table.shader.unit
    memo: dict[int, Any] = {}
    work = copy.deepcopy(unit, memo)
    loop = memo[id(est.loop)]
    main = main_function(work)
    slot = _parent_slot(main.body, loop)
    if slot is None:
        raise UnsupportedShaderError("the estimator's loop is not in main()", est.loop.loc)
    parent, name, index = slot
    marker = A.ExprStmt(A.Ident(_MARKER))
    if isinstance(parent, A.Compound) and index is not None:
        parent.stmts.insert(index, marker)
    else:
        setattr(parent, name, A.Compound([marker, loop], loc=loop.loc))
    core = to_core(work)
    block, i = _find(core, remove=False)
    core_loop = block.stmts[i + 1]
    names = _accumulator_names(core_loop)
    if len(names) != len(est.accumulators):
        raise UnsupportedShaderError("the estimator's accumulators changed in the core-profile rewrite",
                                     est.loop.loc, "this is a bug in rrcache; please report it")
    path = getattr(table.shader, "path", None) or "<shader>"
    return LocatedLoop(core, est, names, list(est.types), path)


def _accumulator_names(loop: A.For) -> list[str]:
    locals_ = {n.name for n in walk(loop.body) if isinstance(n, A.Declarator)}
    order: list[str] = []
    for n in walk(loop.body):
        if isinstance(n, A.Expr):
            for root in written_roots(n):
                if root.name not in locals_ and root.name not in order:
                    order.append(root.name)
    return order


def _find(unit: A.TranslationUnit, remove: bool = True) -> tuple[A.Compound, int]:
    """The block holding the marker and the marker's index (removed with ``remove``: the index
    is then the loop's)."""
    for node in walk(main_function(unit).body):
        if isinstance(node, A.Compound):
            for i, s in enumerate(node.stmts):
                if isinstance(s, A.ExprStmt) and isinstance(s.expr, A.Ident) and s.expr.name == _MARKER:
                    if remove:
                        del node.stmts[i]
                    return node, i
    raise UnsupportedShaderError("the estimator's loop was lost while preparing the passes", None,
                                 "this is a bug in rrcache; please report it")


# ----------------------------------------------------------------------------- statements

def _ident(name: str) -> A.Ident:
    return A.Ident(name)


def _set(name: str, value: A.Expr) -> A.ExprStmt:
    return A.ExprStmt(A.Assign("=", _ident(name), value))


def _decl(type_name: str, name: str, init: Optional[A.Expr] = None) -> A.DeclStmt:
    return A.DeclStmt(A.VariableDecl(A.FullType([], A.TypeSpecifier(type_name)), [A.Declarator(name, None, init)]))


def _offsets(loc: LocatedLoop) -> list[tuple[int, int]]:
    out, at = [], 0
    for t in loc.types:
        n = 1 if t == "float" else int(t[-1])
        out.append((at, n))
        at += n
    return out


def _pack(loc: LocatedLoop) -> A.Expr:
    if len(loc.names) == 1 and loc.types[0] == "vec4":
        return _ident(loc.names[0])
    args: list[A.Expr] = [_ident(n) for n in loc.names]
    args += [float_lit(0.0) for _ in range(4 - loc.components)]
    return A.Call("vec4", args)


def _unpack(payload: A.Expr, offset: int, size: int) -> A.Expr:
    if offset == 0 and size == 4:
        return payload
    return A.Field(payload, _SWIZZLE[offset:offset + size])


def _statement(text: str) -> A.Stmt:
    """One statement parsed from GLSL text (the first statement of a throw-away ``main``)."""
    unit = parse_source("#version 330 core\nvoid main() {\n" + text + "\n}\n", "<rrcache amortize>")
    return unit.decls[-1].body.stmts[0]


def _subset_loop(loop: A.For, samples: int, total: int, start: int, step: int) -> list[A.Stmt]:
    """``int rr_phase = ...; for (int rr_j = 0; rr_j < m; rr_j++) { int i = ...; { body } }``"""
    index = loop.init.decl.declarators[0].name
    if total % samples == 0:
        stride = total // samples
        phase = f"int rr_phase = rr_amortPhase({stride});"
        k = f"rr_j * {stride} + rr_phase"
    else:
        phase = f"int rr_phase = rr_amortPhase({total});"
        k = f"(rr_phase * {samples} + rr_j) % {total}"
    head = _statement(f"for (int rr_j = 0; rr_j < {samples}; rr_j++) {{ int {index} = {start} + {step} * ({k}); }}")
    body = clone(loop.body)
    head.body.stmts.append(body if isinstance(body, A.Compound) else A.Compound([body], loc=body.loc))
    head.loc = loop.loc
    return [_statement(phase), head]


def _unrolled(loop: A.For, indices: list[int], start: int, step: int,
              unit: Optional[A.TranslationUnit] = None) -> A.Compound:
    """The loop body once per iteration number in ``indices``, its index a constant in each;
    what the constant decides (``if (i > 0)``, ``i < 8 ? ... : ...``) is folded as the unroller
    does, since the branch not taken may index an array out of range."""
    index = loop.init.decl.declarators[0].name
    copies: list[A.Stmt] = []
    for k in indices:
        body = clone(loop.body)
        body = body if isinstance(body, A.Compound) else A.Compound([body], loc=body.loc)
        rewrite_scoped(body, {index: _int_literal(start + step * k)})
        if unit is not None:
            stmts = fold_copy(body, unit)
            body = stmts[0] if len(stmts) == 1 and isinstance(stmts[0], A.Compound) else A.Compound(stmts, loc=body.loc)
        if any(isinstance(n, A.Continue) for n in walk(body)):
            # `continue` ends this iteration: a loop run once keeps that meaning
            once = _statement("for (int rr_once = 0; rr_once < 1; rr_once++) {}")
            once.body.stmts.append(body)
            body = A.Compound([once], loc=body.loc)
        copies.append(body)
    return A.Compound(copies, loc=loop.loc)


def _int_literal(value: int):
    def make(ident: A.Ident) -> A.Expr:
        lit = A.IntLit(abs(int(value)), False, loc=ident.loc)
        return A.Unary("-", lit, loc=ident.loc) if value < 0 else lit
    return make


def _hit_statements(loc: LocatedLoop, loop: A.For, samples: int, phase) -> list[A.Stmt]:
    """The loop of a hit: ``m`` iterations scaled to the full sum, blended with the cache."""
    est = loc.estimator
    total = est.samples
    out: list[A.Stmt] = []
    if samples >= total:
        out.append(clone(loop))
    else:
        for name, t in zip(loc.names, loc.types):
            out.append(_decl(t, f"rr_start_{name}", _ident(name)))
        if phase == "pixel":
            out += _subset_loop(loop, samples, total, est.start, est.step)
        else:  # one phase of the "frame" mode: its subset unrolled, the indices constants
            out.append(_unrolled(loop, _subset(total, samples, int(phase)), est.start, est.step, loc.unit))
        scale = float_lit(total / samples)
        for name in loc.names:
            start = _ident(f"rr_start_{name}")
            # the printer parenthesises by precedence: a0 + N/m * (acc - a0)
            out.append(_set(name, A.Binary("+", start, A.Binary(
                "*", scale, A.Binary("-", _ident(name), _ident(f"rr_start_{name}"))))))
    out.append(_decl("vec4", "rr_prev", A.Call("rr_previous", [])))
    for name, (offset, size) in zip(loc.names, _offsets(loc)):
        prev = _unpack(_ident("rr_prev"), offset, size)
        out.append(_set(name, A.Binary("+", A.Binary("*", _ident("rr_lambda"), prev), A.Binary(
            "*", A.Binary("-", float_lit(1.0), _ident("rr_lambda")), _ident(name)))))
    return out


# ----------------------------------------------------------------------------- "slots" history

def _zero(type_name: str) -> A.Expr:
    return A.Call(type_name, [float_lit(0.0)])


def _slot_field(loc: LocatedLoop, payload: str, slot: int, k: int) -> A.Expr:
    offset, size = _offsets(loc)[k]
    return _unpack(_ident(payload), slot * loc.components + offset, size)


def _slot_vector(loc: LocatedLoop, parts: list[list[A.Expr]]) -> A.Expr:
    """``vec4(slot 0's accumulators, slot 1's, ..., zeros)``"""
    args = [e for slot in parts for e in slot]
    args += [float_lit(0.0) for _ in range(4 - len(parts) * loc.components)]
    return A.Call("vec4", args) if len(args) > 1 else args[0]


def _sum(terms: list[A.Expr]) -> A.Expr:
    out = terms[0]
    for t in terms[1:]:
        out = A.Binary("+", out, t)
    return out


def _slots_hit(loc: LocatedLoop, loop: A.For, samples: int, phase: int, read=lambda e: e) -> list[A.Stmt]:
    """Hit, "slots" history: this frame's subset sum replaces (blended by λ) its own slot; the
    value is the start plus every slot (the other phases' sums reprojected)."""
    est = loc.estimator
    cycle = _cycle(est.samples, samples)
    out: list[A.Stmt] = []
    for name, t in zip(loc.names, loc.types):
        out += [_decl(t, f"rr_start_{name}", _ident(name)), _set(name, _zero(t))]
    out.append(_unrolled(loop, _subset(est.samples, samples, phase), est.start, est.step, loc.unit))
    out.append(_decl("vec4", "rr_prev", read(A.Call("rr_previous", []))))
    for k, (name, t) in enumerate(zip(loc.names, loc.types)):
        prev = _slot_field(loc, "rr_prev", phase, k)
        out.append(_decl(t, f"rr_new_{name}", A.Binary("+", A.Binary("*", _ident("rr_lambda"), prev), A.Binary(
            "*", A.Binary("-", float_lit(1.0), _ident("rr_lambda")), _ident(name)))))
        others = [_slot_field(loc, "rr_prev", j, k) for j in range(cycle) if j != phase]
        out.append(_set(name, _sum([_ident(f"rr_start_{name}"), *others, _ident(f"rr_new_{name}")])))
    parts = [[_ident(f"rr_new_{n}") if j == phase else _slot_field(loc, "rr_prev", j, k)
              for k, n in enumerate(loc.names)] for j in range(cycle)]
    out.append(_set("rr_slots", _slot_vector(loc, parts)))
    return out


def _slots_miss(loc: LocatedLoop, loop: A.For, samples: int) -> list[A.Stmt]:
    """Miss, "slots" history: every subset's sum on its own (all N iterations), the value their
    total plus the start."""
    est = loc.estimator
    cycle = _cycle(est.samples, samples)
    out: list[A.Stmt] = [_decl(t, f"rr_start_{n}", _ident(n)) for n, t in zip(loc.names, loc.types)]
    for j in range(cycle):
        out += [_set(n, _zero(t)) for n, t in zip(loc.names, loc.types)]
        out.append(_unrolled(loop, _subset(est.samples, samples, j), est.start, est.step, loc.unit))
        out += [_decl(t, f"rr_slot{j}_{n}", _ident(n)) for n, t in zip(loc.names, loc.types)]
    for n in loc.names:
        out.append(_set(n, _sum([_ident(f"rr_start_{n}")] + [_ident(f"rr_slot{j}_{n}") for j in range(cycle)])))
    parts = [[_ident(f"rr_slot{j}_{n}") for n in loc.names] for j in range(cycle)]
    out.append(_set("rr_slots", _slot_vector(loc, parts)))
    return out


def _slots_transform(loc: LocatedLoop, name: str, samples: int, phase: int, block: A.Compound, i: int,
                     encoding: Optional[PayloadEncoding] = None) -> None:
    loop = block.stmts[i]
    # an 8-bit payload (rrcache.compiler.payload_encoding): encoded at the write, decoded at reads
    read = decoded if encoding is not None else (lambda e: e)
    writes = cache_writes(encoded(_ident("rr_slots")) if encoding is not None else _ident("rr_slots"))
    declare = _decl("vec4", "rr_slots")
    cycle = _cycle(loc.estimator.samples, samples)
    if name in ("reproject", "hit"):
        block.stmts[i:i + 1] = [_statement("if (!rr_hit()) discard;"), declare,
                                *_slots_hit(loc, loop, samples, phase, read), *writes]
    elif name in ("payload", "miss"):
        block.stmts[i:i + 1] = [declare, *_slots_miss(loc, loop, samples), *writes]
    elif name == "shade":
        stmts: list[A.Stmt] = [_decl("vec4", "rr_cur", read(A.Call("rr_current", [])))]
        for k, n in enumerate(loc.names):
            stmts.append(_set(n, _sum([_ident(n)] + [_slot_field(loc, "rr_cur", j, k) for j in range(cycle)])))
        block.stmts[i:i + 1] = stmts
    else:  # single
        branch = A.If(A.Call("rr_hit", []), A.Compound(_slots_hit(loc, loop, samples, phase, read)),
                      A.Compound(_slots_miss(loc, loop, samples)))
        block.stmts[i:i + 1] = [declare, branch, *writes]


def transform(loc: LocatedLoop, name: str, samples: int, phase=0, history: str = "blend",
              encoding: Optional[PayloadEncoding] = None) -> A.TranslationUnit:
    """The transformed (not yet checked or pruned) unit of pass ``name``; ``phase`` is
    ``"pixel"`` or the phase number of a ``"frame"``-mode program; ``encoding``: the slots'
    8-bit payload (None: floats)."""
    spec = PASS_SPECS[name]
    unit = clone(loc.unit)
    block, i = _find(unit)
    loop = block.stmts[i]
    writes = cache_writes(_pack(loc))
    if history == "slots":
        _slots_transform(loc, name, samples, int(phase), block, i, encoding)
    elif name in ("reproject", "hit"):
        block.stmts[i:i + 1] = [_statement("if (!rr_hit()) discard;"), *_hit_statements(loc, loop, samples, phase), *writes]
    elif name in ("payload", "miss"):
        block.stmts[i + 1:i + 1] = writes
    elif name == "shade":
        current = A.Call("rr_current", [])
        block.stmts[i:i + 1] = [_decl("vec4", "rr_cur", current)] + [
            _set(n, _unpack(_ident("rr_cur"), offset, size)) for n, (offset, size) in zip(loc.names, _offsets(loc))]
    else:  # single
        branch = A.If(A.Call("rr_hit", []), A.Compound(_hit_statements(loc, loop, samples, phase)), A.Compound([loop]))
        block.stmts[i:i + 1] = [branch, *writes]
    if spec.cache:
        main_function(unit).body.stmts[0:0] = cache_init()
    set_color_output(unit, keep=spec.color, location=spec.color_location)
    return unit


def build_pass(loc: LocatedLoop, name: str, samples: int, filter: str = "bilinear",
               phase=0, history: str = "blend", encoding: Optional[PayloadEncoding] = None) -> PassUnit:
    """Transform, type-check and prune pass ``name`` of the amortized variant."""
    spec = PASS_SPECS[name]
    unit = transform(loc, name, samples, phase, history, encoding)
    runtime = runtime_snippets(spec, filter)
    if encoding is not None:
        runtime += encoding_glsl(encoding)
    if spec.lookup:
        runtime += AMORTIZE_GLSL + (AMORTIZE_PIXEL_GLSL if phase == "pixel" else "")
    snippet_decls = parse_source("#version 330 core\n" + runtime, "<rrcache runtime>").decls
    unit.decls[0:0] = snippet_decls
    try:
        check(unit, loc.path)
    except GLSLError as err:
        raise UnsupportedShaderError(
            f"the {name} pass amortizing '{display_name(loc.estimator.text)}' does not type-check: {err.message}",
            err.loc or loc.estimator.loop.loc,
            "names starting with 'rr_' are reserved for rrcache; rename any such name in the shader") from None
    prune(unit, keep=snippet_decls)
    ids = {id(d) for d in snippet_decls}
    unit.decls = [d for d in unit.decls if id(d) not in ids]
    return PassUnit(name, unit, runtime, spec, "amortize")


@deep
def instance_amortized(shader: Any, estimator_id: str, algorithm: str = "three-pass", samples: int = 4,
                       blend: float = 0.6, filter: str = "bilinear", payload_dtype: str = "f4",
                       phase: str = "frame", history: str = "blend", vertex=None,
                       term_range: Optional[tuple[float, float]] = None) -> Variant:
    """Compile the variant of ``shader`` that amortizes estimator ``estimator_id`` (``e1``...):
    ``samples`` (m) of its N iterations per frame at hits, blended with weight ``blend`` (λ,
    kept in the variant for the runtime; it can be changed there between frames). ``phase``:
    how the subset changes (``frame`` or ``pixel``, see the module doc); ``history``: ``blend``
    (the paper's running estimate) or ``slots`` (one reprojected sum per subset, see the module
    doc). ``vertex`` is the user's vertex shader (a
    :class:`rrcache.compiler.user_vertex.UserVertex`; None: generated), as for
    :func:`rrcache.compiler.instance`. ``payload_dtype="u8"`` (``slots`` only) stores the slots
    in 8 bits (:mod:`rrcache.compiler.payload_encoding`) by the range of the estimator's terms
    (``term_range``, else the analysis's or the pragma's: ``Estimator.term_range``).

    ``shader`` is a checked :class:`~rrcache.glsl.frontend.Shader` (not the analysed one: the
    loop must still be there) or an :class:`~rrcache.analysis.estimators.EstimatorTable`.
    """
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {tuple(ALGORITHMS)}, not {algorithm!r}")
    if filter not in FILTERS:
        raise ValueError(f"filter must be one of {FILTERS}, not {filter!r}")
    if payload_dtype not in AMORTIZE_PAYLOADS:
        raise ValueError(f"payload_dtype must be one of {AMORTIZE_PAYLOADS}, not {payload_dtype!r}")
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise ValueError(f"samples must be a positive int, not {samples!r}")
    if phase not in PHASES:
        raise ValueError(f"phase must be one of {PHASES}, not {phase!r}")
    if not 0.0 <= float(blend) < 1.0:
        raise ValueError(f"blend (lambda) must be in [0, 1), not {blend!r}")
    loc = prepare_loop(shader, estimator_id)
    est = loc.estimator
    if samples > est.samples:
        raise ValueError(f"estimator {est.id} has {est.samples} samples; cannot evaluate {samples} per frame")
    if history not in HISTORIES:
        raise ValueError(f"history must be one of {HISTORIES}, not {history!r}")
    payload_components = loc.components
    if history == "slots":
        why = slots_fit(est.samples, samples, loc.components, phase)
        if why is not None:
            raise ValueError(f"estimator {est.id}: {why}")
        payload_components = (est.samples // samples) * loc.components
    encoding = _encoding(est, samples, loc.components, history, payload_dtype, term_range)
    passes: dict[str, PassSource] = {}
    uniforms: dict[str, list[str]] = {}
    samplers: dict[str, list[str]] = {}
    runtime: dict[str, list[str]] = {}
    forms: dict[str, str] = {}
    cycle = _cycle(est.samples, samples) if phase == "frame" and samples < est.samples else 1
    for name in ALGORITHMS[algorithm]:
        # "frame" mode: one program per phase for the passes that evaluate the subset; the
        # runtime runs "<pass>@<k>" at frames with clock % cycle == k (k = 0: "<pass>")
        phases = range(cycle) if PASS_SPECS[name].lookup else range(1)
        for k in phases:
            built = build_pass(loc, name, samples, filter, "pixel" if phase == "pixel" else k, history, encoding)
            key = name if k == 0 else f"{name}@{k}"
            out = emit_pass(built.unit, built.runtime_glsl, built.spec.lookup, vertex)
            passes[key] = PassSource(out.vertex, out.fragment, out.line_map)
            uniforms[key], samplers[key], runtime[key] = out.uniforms, out.samplers, out.runtime
            forms[key] = built.form
    text = display_name(est.text)
    loop_loc: Optional[SourceLoc] = est.loop.loc if est.loop is not None else None
    return Variant(
        algorithm=algorithm, node_id=est.id, node_type="estimator", node_text=text,
        components=payload_components, filter=filter, payload_dtype=payload_dtype, passes=passes,
        uniforms=uniforms, samplers=samplers, runtime_uniforms=runtime, forms=forms,
        node_loc=loop_loc, shader_path=loc.path, vertex_path=getattr(vertex, "path", None),
        spec=VariantSpec("amortize", (), algorithm, filter, payload_dtype, estimator=est.id, samples=int(samples),
                         history=history, phase=phase, blend=float(blend)),
        amortized={"estimator": est.id, "samples": samples, "of": est.samples, "lambda": float(blend),
                   "phase": phase, "cycle": cycle, "history": history, "accumulators": [display_name(a) for a in est.accumulators],
                   **({"payload_encoding": encoding.to_json(),
                       "range_source": "argument" if term_range is not None else est.range_source}
                      if encoding is not None else {})})


def _encoding(est: Estimator, samples: int, components: int, history: str, payload_dtype: str,
              term_range: Optional[tuple[float, float]]) -> Optional[PayloadEncoding]:
    """The 8-bit payload's encoding (None for a float payload); RRCacheError at the loop saying
    what is missing."""
    if payload_dtype != ENCODED_DTYPE:
        return None
    where = str(est.loop.loc) if est.loop is not None and est.loop.loc is not None else est.id
    if history != "slots":
        raise RRCacheError(f"estimator {est.id}: an 8-bit payload needs the slots history (the blend history "
                           "stores the accumulators' start value too, whose range is not known)", where,
                           hint="use --history slots, or a float payload (f4, f2)")
    source = term_range if term_range is not None else est.term_range
    if source is None:
        why = est.range_reason or "the analysis could not bound its terms"
        raise RRCacheError(f"estimator {est.id}: an 8-bit payload needs the range of the loop's terms: {why}",
                           where, hint="declare it with '#pragma rrcache estimator range(LO, HI)' on a line "
                                       "before the loop, or use a float payload (f4, f2)")
    return slots_encoding(source, samples, est.samples // samples, components)
