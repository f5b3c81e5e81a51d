"""Pass: find the *estimators* of a shader, loops that sum independent samples (Nehab 2007 §6).

An estimator is a ``for`` loop of ``main`` in the inlined program (:func:`inline_calls`; loops are
*not* unrolled here, since amortization keeps the loop and changes which iterations run) with

- a constant trip count ``N``: ``for (int i = c; i < K; i++)`` (``<``, ``<=``, ``>``, ``>=``,
  ``!=``; step ``++``, ``--``, ``+=``/``-=`` a constant; ``c`` and ``K`` literals, ``const``
  globals or macros), an ``int`` index the body does not write;
- a body with no ``break``, ``return`` or ``discard`` (``continue`` is allowed), not itself inside
  another loop;
- *accumulators*: the variables declared before the loop that the body writes. Every mention of
  one in the body is ``acc += term``, ``acc -= term``, ``acc = acc + term`` or ``acc = acc - term``
  where no term reads any accumulator, and the accumulators are ``float`` or ``vec2``-``vec4``
  with at most 4 components together (they must fit in the cache's payload).

Each iteration's contribution then depends only on the index and on values from before the
loop, and only adds into the accumulators: the loop computes ``a0 + Σ_i t(i)``, and any subset
of the iterations, scaled by ``N/m``, is an estimate of that sum (see
:mod:`rrcache.compiler.amortize`).

``#pragma rrcache estimator`` on a line before a loop (the next loop that starts after the pragma,
in the same file) marks a loop the analysis cannot prove: the accumulator checks are skipped
(the accumulators are still every variable from before the loop that the body writes, and the
bound must still be constant). Its amortized variant at ``m = N, λ = 0`` is the original loop,
so a run at that setting shows the marked loop is computed right; whether its terms are really
independent is the author's promise.

Each estimator has a *term range* (``term_range``): a hull ``(lo, hi)`` that every iteration's
contribution to every component of every accumulator lies in (for ``acc -= t`` the
contribution is ``-t``), for payloads that must encode subset sums in a fixed range. The
interval analysis of :mod:`rrcache.analysis.term_range` proves one where it can
(``range_source == "analysis"``; else ``range_reason`` names the sub-expression without a known
range); ``#pragma rrcache estimator range(LO, HI)`` (number literals, ``LO < HI``) marks the loop
like the bare pragma and declares the range, which wins over the proven one
(``range_source == "pragma"``: the author's promise, checked at run time by the caller). A
malformed ``rrcache estimator`` pragma raises :class:`~rrcache.errors.GLSLError` at its line.

Ids are ``e1``, ``e2``, ... for the loops of ``main`` in program order (every loop counts, so an
id does not change when another loop stops qualifying).

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("uniform sampler2D t; varying vec2 uv;\\n"
...                  "float tap(vec2 o) { return texture2D(t, uv + o).r; }\\n"
...                  "void main() { float s = 0.0;\\n"
...                  "  for (int i = 0; i < 8; i++) s += tap(vec2(float(i) * 0.01, 0.0));\\n"
...                  "  gl_FragColor = vec4(s / 8.0); }")
>>> table = find_estimators(s)
>>> [(e.id, e.samples, e.accumulators) for e in table.estimators]
[('e1', 8, ['s'])]
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any, Optional

from rrcache.deep import deep
from rrcache.glsl import ast as A
from rrcache.glsl.printer import print_expr
from rrcache.glsl.ast import main_function, walk
from rrcache.glsl.visitor import NodeVisitor
from rrcache.analysis.loops import Constants, counted_loop, global_scalars
from rrcache.analysis.term_range import FLT_MAX, signed_term, term_range
from rrcache.errors import GLSLError, printable
from rrcache.glsl.rewrite import paused_gc
from rrcache.glsl.defuse import written_roots

__all__ = ["Estimator", "NotEstimator", "EstimatorTable", "find_estimators", "estimator_loops",
           "loop_header", "display_name", "parse_pragma", "ACCUMULATOR_TYPES", "MAX_SAMPLES",
           "PRAGMA"]

#: accumulator types and their component counts
ACCUMULATOR_TYPES = {"float": 1, "vec2": 2, "vec3": 3, "vec4": 4}
#: the largest trip count considered
MAX_SAMPLES = 65536
#: the pragma text (after ``#pragma``) that marks a loop as an estimator
PRAGMA = "rrcache estimator"



@dataclass
class Estimator:
    """A loop that sums ``samples`` independent terms into ``accumulators`` (names, with their
    GLSL types in ``types``). ``start``/``step`` give the index values ``start + k * step``,
    ``k = 0..samples-1``; ``index`` is the loop variable. ``pragma``: marked by
    ``#pragma rrcache estimator`` rather than proven.

    ``term_range``: a hull ``(lo, hi)`` of every iteration's contribution to every component of
    every accumulator (``acc -= t`` contributes ``-t``), None when not known; ``range_source``:
    ``"pragma"`` (declared by ``#pragma rrcache estimator range(LO, HI)``, which wins) or
    ``"analysis"`` (proven), None when unknown; ``range_reason``: why there is none, naming the
    sub-expression as the user wrote it ("" when there is one)."""

    id: str
    line: Optional[int]
    column: Optional[int]
    samples: int
    text: str
    accumulators: list[str]
    types: list[str]
    index: str
    start: int
    step: int
    pragma: bool = False
    loop: Any = field(default=None, repr=False, compare=False)
    term_range: Optional[tuple[float, float]] = None
    range_source: Optional[str] = None
    range_reason: str = ""

    @property
    def components(self) -> int:
        return sum(ACCUMULATOR_TYPES[t] for t in self.types)

    def to_json(self) -> dict:
        out = {"id": self.id, "line": self.line, "column": self.column, "samples": self.samples,
               "text": display_name(self.text), "accumulators": [display_name(a) for a in self.accumulators],
               "pragma": self.pragma}
        out["term_range"] = list(self.term_range) if self.term_range is not None else None
        out["range_source"] = self.range_source
        if self.term_range is None:
            out["range_reason"] = self.range_reason
        return out


@dataclass
class NotEstimator:
    """A loop of ``main`` that is not an estimator, and why."""

    id: str
    line: Optional[int]
    column: Optional[int]
    text: str
    reason: str

    def to_json(self) -> dict:
        return {"id": self.id, "line": self.line, "column": self.column, "text": display_name(self.text),
                "reason": self.reason}


@dataclass
class EstimatorTable:
    """The estimators of a shader and the loops that are not, both in program order; ``shader``
    is the inlined shader whose loops the ids name."""

    shader: Any
    estimators: list[Estimator]
    rejected: list[NotEstimator]

    def find(self, estimator_id: str) -> Estimator:
        """The estimator ``estimator_id``; an unknown id or a loop that is not one raises
        :class:`~rrcache.errors.RRCacheError` saying why."""
        from rrcache.errors import RRCacheError

        for e in self.estimators:
            if e.id == estimator_id:
                return e
        for r in self.rejected:
            if r.id == estimator_id:
                raise RRCacheError(f"loop {r.id} at line {r.line} is not an estimator: {r.reason}",
                                   str(getattr(self.shader, "path", None) or "<string>"),
                                   hint="mark it with '#pragma rrcache estimator' if its terms are "
                                        "independent samples")
        raise RRCacheError(f"no loop '{estimator_id}' in the shader",
                           str(getattr(self.shader, "path", None) or "<string>"),
                           hint="estimator ids look like 'e1'; list them with 'rrcache nodes SHADER --json'")

    def to_json(self) -> dict:
        return {"estimators": [e.to_json() for e in self.estimators],
                "not_estimators": [r.to_json() for r in self.rejected]}


# ----------------------------------------------------------------------------- the loops

class _Loops(NodeVisitor):
    """Every loop of a statement in program order, with its depth."""

    def __init__(self):
        self.found: list = []

    def generic_visit(self, node, depth: int = 0) -> None:
        for child in A.children(node):
            if isinstance(child, A.Stmt):
                self.visit(child, depth)

    def visit_For(self, node, depth: int = 0) -> None:
        self.found.append((node, depth))
        self.generic_visit(node, depth + 1)

    visit_While = visit_DoWhile = visit_For


def estimator_loops(unit: A.TranslationUnit) -> list[tuple[A.For, int]]:
    """Every loop of ``main`` (``for``, ``while``, ``do``) in program order, with its depth (0: not
    inside another loop). The position in this list (from 1) is the loop's id number."""
    main = main_function(unit)
    if main is None:
        return []
    v = _Loops()
    v.visit(main.body, 0)
    return v.found


def loop_header(loop: A.For, consts: dict) -> tuple[Optional[tuple[str, int, int, int]], str]:
    """``((index, start, step, samples), "")`` for a constant-bound ``int`` loop declaring its
    index in its header (:func:`rrcache.analysis.loops.counted_loop`; ``consts`` the ``const``
    globals, :func:`rrcache.analysis.loops.global_scalars`), else ``(None, reason)``."""
    head, why = counted_loop(loop, Constants(consts.get), declared_only=True, bases=("int",))
    if head is None:
        return None, why
    n = head.trips(MAX_SAMPLES)
    if n is None:
        return None, f"the loop runs more than {MAX_SAMPLES} times (or forever)"
    if n < 2:
        return None, f"the loop runs {n} time{'s' if n != 1 else ''}"
    return (head.index, head.start, head.step, n), ""


def _declared(node) -> set[str]:
    return {n.name for n in walk(node) if isinstance(n, A.Declarator)}


def _mentions(node, names: set[str]) -> bool:
    return any(isinstance(n, A.Ident) and n.name in names for n in walk(node))


def _accumulation(e: A.Assign, accs: set[str]) -> Optional[A.Expr]:
    """The term of ``acc += t`` / ``acc -= t`` / ``acc = acc ± t`` (None when ``e`` is not one)."""
    st = signed_term(e, accs)
    return None if st is None else st[1]


def _type_name(ident: A.Ident) -> Optional[str]:
    t = getattr(ident, "type", None)
    if t is None:
        sym = getattr(ident, "symbol", None)
        t = getattr(sym, "type", None)
    return t.glsl_name() if t is not None and hasattr(t, "glsl_name") else None


_EXITS = {A.Break: "break", A.Return: "return", A.Discard: "discard"}


def classify(loop, depth: int, consts: dict, pragma: bool):
    """``(header, accumulators, types, reason)`` for one loop (reason "" when it qualifies)."""
    if not isinstance(loop, A.For):
        return None, [], [], "only for loops with a constant bound are estimators"
    if depth > 0:
        return None, [], [], "inside another loop (the outer loop may be the estimator)"
    header, why = loop_header(loop, consts)
    if header is None:
        return None, [], [], why
    index = header[0]
    body = loop.body
    for n in walk(body):
        exit_word = _EXITS.get(n.__class__)
        if exit_word is not None:
            return None, [], [], f"the body has a {exit_word}"
    locals_ = _declared(body)
    written: dict[str, A.Ident] = {}
    for n in walk(body):
        if isinstance(n, A.Expr):
            for root in written_roots(n):
                if root.name not in locals_:
                    written.setdefault(root.name, root)
    if index in written:
        return None, [], [], "the body writes the loop index"
    if not written:
        return None, [], [], "the body accumulates nothing that outlives the loop"
    accs = sorted(written, key=lambda name: _first_write(body, name))
    types = [_type_name(written[a]) for a in accs]
    for a, t in zip(accs, types):
        if t not in ACCUMULATOR_TYPES:
            return None, [], [], (f"`{display_name(a)}` is {t or 'of unknown type'}; accumulators are "
                                  "float or vec2-vec4")
    if sum(ACCUMULATOR_TYPES[t] for t in types) > 4:
        return None, [], [], "the accumulators need more than the 4 components a payload holds"
    if not pragma:
        why = _only_additions(body, set(accs))
        if why:
            return None, [], [], why
    return header, accs, types, ""


def _first_write(body, name: str) -> int:
    for k, n in enumerate(walk(body)):
        if isinstance(n, A.Expr) and any(r.name == name for r in written_roots(n)):
            return k
    return 0


def _only_additions(body, accs: set[str]) -> str:
    """"" when every mention of an accumulator in ``body`` adds a term that reads none of them."""
    allowed: set[int] = set()
    terms = []
    for n in walk(body):
        if isinstance(n, A.Assign):
            term = _accumulation(n, accs)
            if term is None:
                continue
            terms.append((n.target.name, term))
            allowed.add(id(n.target))
            if n.op == "=":
                v = n.value
                allowed.add(id(v.left if isinstance(v.left, A.Ident) and v.left.name == n.target.name else v.right))
    in_terms = {id(n) for _name, term in terms for n in walk(term)}
    for n in walk(body):
        if isinstance(n, A.Ident) and n.name in accs and id(n) not in allowed and id(n) not in in_terms:
            return (f"`{display_name(n.name)}` is carried from one iteration to the next (used otherwise "
                    "than by adding a term to it)")
    for name, term in terms:
        if _mentions(term, accs):
            return f"the term added to `{display_name(name)}` reads an accumulator (iterations are not independent)"
    return ""


_INLINED_NAME = re.compile(r"\b_rr_([A-Za-z]\w*?)_\d+\b")


def display_name(text: str) -> str:
    """A name (or text) as the user wrote it: the inliner's ``_rr_<name>_<n>`` → ``<name>``.

    >>> display_name("for (int _rr_i_13 = 0; _rr_i_13 < 16; _rr_i_13++)")
    'for (int i = 0; i < 16; i++)'
    """
    return _INLINED_NAME.sub(lambda m: m.group(1), text)


@dataclass(frozen=True)
class _Pragma:
    """One ``#pragma rrcache estimator`` line, with the range it declares (or None)."""

    file: str
    line: int
    range: Optional[tuple[float, float]]
    loc: Any = field(default=None, compare=False)


_PRAGMA_HEAD = re.compile(r"\s+".join(map(re.escape, PRAGMA.split())) + r"(?![\w.])(.*)\Z", re.S)
_NUMBER = r"[+-]?\s*(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?[fF]?"
_RANGE = re.compile(rf"\s*range\s*\(\s*({_NUMBER})\s*,\s*({_NUMBER})\s*\)\s*\Z")
_RANGE_HINT = ("write '#pragma rrcache estimator range(LO, HI)' with number literals LO < HI, e.g. "
               "range(0.0, 1.0) or range(-1, 1), or '#pragma rrcache estimator' alone")


def parse_pragma(text: str, loc=None) -> Optional[tuple[bool, Optional[tuple[float, float]]]]:
    """What a ``#pragma`` text (after ``#pragma``) says about estimators: None when it is not an
    ``rrcache estimator`` pragma, ``(True, None)`` for the bare one, ``(True, (lo, hi))`` for
    ``rrcache estimator range(LO, HI)``. Anything else after ``rrcache estimator`` raises
    :class:`~rrcache.errors.GLSLError` at ``loc`` (the pragma's place) with the right syntax.

    >>> parse_pragma("rrcache estimator range(-0.5, 2)")
    (True, (-0.5, 2.0))
    >>> parse_pragma("rrcache  estimator"), parse_pragma("optimize(on)")
    ((True, None), None)
    """
    m = _PRAGMA_HEAD.match(str(text).strip())
    if m is None:
        words = str(text).split()
        if words and words[0] == "rrcache":  # ours, misspelt: said, not silently ignored
            raise GLSLError(f"unknown '#pragma {printable(' '.join(words))}'", loc, hint=_RANGE_HINT)
        return None
    rest = m.group(1).strip()
    if not rest:
        return True, None
    shown = printable(" ".join(str(text).split()))
    r = _RANGE.match(rest)
    if r is None:
        raise GLSLError(f"malformed '#pragma {shown}': expected range(LO, HI) after "
                        "'rrcache estimator'", loc, hint=_RANGE_HINT)
    lo, hi = (float(g.replace(" ", "").replace("\t", "").rstrip("fF")) for g in r.groups())
    if not (abs(lo) <= FLT_MAX and abs(hi) <= FLT_MAX):
        raise GLSLError(f"malformed '#pragma {shown}': the range's ends must be finite 32-bit floats "
                        f"(|x| <= {FLT_MAX:g})", loc, hint=_RANGE_HINT)
    if not lo < hi:
        raise GLSLError(f"malformed '#pragma {shown}': LO ({lo:g}) must be below HI ({hi:g})", loc,
                        hint=_RANGE_HINT)
    return True, (lo, hi)


def _pragmas(shader) -> list[_Pragma]:
    """The ``#pragma rrcache estimator`` lines of ``shader`` (a malformed one raises)."""
    out = []
    for text, loc in getattr(shader, "pragmas", None) or []:
        parsed = parse_pragma(text, loc)
        if parsed is not None and loc is not None:
            out.append(_Pragma(loc.file, loc.line, parsed[1], loc))
    return out


class _LoopText(NodeVisitor):
    """A loop's header as the table shows it."""

    def generic_visit(self, loop) -> str:
        return "do ... while"

    def visit_For(self, loop: A.For) -> str:
        parts = []
        init = loop.init
        if isinstance(init, A.DeclStmt):
            d = init.decl.declarators[0]
            parts.append(f"{init.decl.type.spec.name} {d.name}"
                         + (f" = {print_expr(d.init)}" if d.init is not None else ""))
        elif isinstance(init, A.ExprStmt) and init.expr is not None:
            parts.append(print_expr(init.expr))
        else:
            parts.append("")
        parts.append(print_expr(loop.cond) if isinstance(loop.cond, A.Expr) else "")
        parts.append(print_expr(loop.step) if loop.step is not None else "")
        return f"for ({'; '.join(parts)})"

    def visit_While(self, loop: A.While) -> str:
        return f"while ({print_expr(loop.cond) if isinstance(loop.cond, A.Expr) else '...'})"


_loop_text = _LoopText().visit


def _marking(loop, pragmas: list[_Pragma], loops: list) -> list[_Pragma]:
    """The pragma lines that precede ``loop`` with no other loop of the same file in between."""
    loc = loop.loc
    if loc is None or not pragmas:
        return []
    out = []
    for p in pragmas:
        if loc.file != p.file or loc.line <= p.line:
            continue
        # the first loop after the pragma is the one it marks
        first = min((other.loc.line, other.loc.col or 0) for other, _ in loops
                    if other.loc is not None and other.loc.file == p.file and other.loc.line > p.line)
        if (loc.line, loc.col or 0) == first:
            out.append(p)
    return out


def _declared_range(marks: list[_Pragma]) -> Optional[tuple[float, float]]:
    ranges = [p for p in marks if p.range is not None]
    if len({p.range for p in ranges}) > 1:
        first = ranges[0]
        second = next(p for p in ranges if p.range != first.range)
        raise GLSLError(f"two different ranges declared for one loop (the other at line {first.line})",
                        second.loc,
                        hint="keep one '#pragma rrcache estimator range(LO, HI)' before the loop")
    return ranges[0].range if ranges else None


@deep
def find_estimators(shader, inlined: Any = None) -> EstimatorTable:
    """The estimators of ``shader`` (a checked :class:`~rrcache.glsl.frontend.Shader`): see the
    module docstring. ``inlined`` is the result of :func:`inline_calls` when the caller has it."""
    from rrcache.analysis.inline import inline_calls

    with paused_gc():
        if inlined is None:
            inlined = inline_calls(shader)
        consts = global_scalars(getattr(shader, "info", None))
        pragmas = _pragmas(shader)
        loops = estimator_loops(inlined.unit)
        found, rejected = [], []
        for k, (loop, depth) in enumerate(loops, start=1):
            loc = loop.loc
            line, column = (loc.line, loc.col) if loc is not None else (None, None)
            text = _loop_text(loop)
            marks = _marking(loop, pragmas, loops)
            declared = _declared_range(marks)
            pragma = bool(marks)
            header, accs, types, why = classify(loop, depth, consts, pragma)
            if why:
                rejected.append(NotEstimator(f"e{k}", line, column, text, why))
                continue
            index, start, step, n = header
            est = Estimator(f"e{k}", line, column, n, text, accs, types, index, start, step, pragma, loop)
            if declared is not None:
                est.term_range, est.range_source = declared, "pragma"
            else:
                proven, reason = term_range(loop, index, start, step, n, accs,
                                            header=lambda inner: loop_header(inner, consts)[0],
                                            display=display_name)
                if proven is not None:
                    est.term_range, est.range_source = proven, "analysis"
                else:
                    est.range_reason = reason
            found.append(est)
        return EstimatorTable(inlined, found, rejected)
