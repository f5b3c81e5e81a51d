"""Pass: put the terms of a sum in the order that makes its partial sums good to cache.

After unrolling, an accumulation ``acc += t_k`` over a constant loop is a run of blocks, one per
iteration, each adding its term into the accumulator (``acc = acc + t_k`` once compound
assignments are expanded); the partial sums in that run are ordinary nodes, but only the
*prefixes in source order*: a row-major 5×5 loop can never express "all but the centre". This
pass reorders the blocks so that the prefixes are the subsets worth caching, in this order:

1. **static terms first**: a term that reads nothing that changes between frames of the session
   (the ``moving`` inputs: keyframed uniforms, the camera and light when they move, time; an
   element of a uniform array when only that element changes) comes before every term that
   does (the paper's chess: the board and the still pieces before the king, whose occlusion is
   then recomputed every frame while the static part is cached);
2. among those, **the lightest first** where every term's weight is a constant the analysis can
   fold (a factor of the term that evaluates to a number: the Trashcan's Gaussian weights), so
   that a prefix holds the terms that contribute least (the paper's Trashcan: one sample, sixteen,
   twenty-four of twenty-five);
3. otherwise by a **measured score** when one is given (``scores``: :func:`chain_key` → term
   label → score, lower first; :func:`rrcache.profiler.terms.measure_terms` measures each
   term's contribution and change between frames in a short pass), and last the **source
   order**.

A *run* is a maximal sequence of consecutive statements of straight-line code (``main``'s body
and the blocks nested in it, not inside a branch or a loop) each of which is a *term*: a block
(an unrolled iteration) that writes only variables it declares itself, except for accumulations
``acc = acc op t`` at its top level into accumulators declared before the run, whose other
statements never read an accumulator, and that holds no ``discard``, ``return``, ``break`` or
``continue``; or a bare accumulation ``acc = acc op t``; or a block made only of terms (a nested
loop's copies: its terms join the run, flattened). Every accumulator is a ``float`` or ``vec``
and takes one kind of operator across the run, additive (``+``, ``-``) or multiplicative
(``*``, ``/`` by a scalar or a vector of its own size): reordering such terms changes only the
rounding.

**Rounding.** For ``n`` terms the float sum computed in any order is the exact sum plus at most
``(n − 1) · u · Σ|t_k|`` (``u = 2⁻²⁴``, float32, first order), so two orders differ by at most
``2 (n − 1) u Σ|t_k|``; a product of ``n`` factors differs by at most ``2 (n − 1) u`` relatively.
:func:`reassociation_bound` gives it. At Δn = 1 a reordered program matches the original within
that bound carried through the rest of the shader (the tests check it in every algorithm).

:func:`sum_chains` finds the runs (read only); :func:`reorder_sums` reorders them in place and
returns them; :func:`prefix_texts` names every partial sum of a reordered run for the node table
(``radiance: 24 of 25 terms, all but (i=2, j=2)``).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Iterable, Mapping, Optional

from rrcache.glsl import ast as A
from rrcache.glsl.constfold import const_value
from rrcache.glsl.defuse import declared, definitions, written_roots
from rrcache.glsl.rewrite import chain_of, clone
from rrcache.glsl.visitor import NodeVisitor

__all__ = ["SumChain", "Term", "sum_chains", "reorder_sums", "prefix_texts", "name_partial_sums",
           "reassociation_bound", "chain_key", "term_values", "chains_to_measure"]

_ADDITIVE, _MULTIPLICATIVE = ("+", "-"), ("*", "/")
#: the unit roundoff of float32
UNIT_ROUNDOFF = 2.0 ** -24


@dataclass
class Term:
    """One term of a run: ``stmt`` the block or bare accumulation, ``source`` its position in
    source order, ``label`` the loop iterations it came from (``(i=2, j=2)``) or its line,
    ``updates`` the accumulation statements it holds (accumulator name → statements), ``weight``
    the folded constant weight (None: not constant), ``moving`` whether it reads a moving input."""

    stmt: A.Node
    source: int
    label: str
    updates: dict = field(default_factory=dict)
    weight: Optional[float] = None
    moving: bool = False
    reads: frozenset = frozenset()
    moving_reads: frozenset = frozenset()


@dataclass
class SumChain:
    """A run of terms (:class:`Term`, in program order) and its accumulators (name → operator
    kind, ``+`` or ``*``). ``key`` says what ordered it: ``static`` (static terms first),
    ``weight``, ``measured``, ``source``; ``reordered`` whether the order differs from the
    source's."""

    terms: list
    accumulators: dict
    key: tuple = ()
    reordered: bool = False
    loc: Optional[object] = None
    #: the measured score of each term by its label (lower first), when given
    scores: dict = field(default_factory=dict)

    @property
    def moving_inputs(self) -> list[str]:
        """The moving inputs its moving terms read."""
        return sorted({r for t in self.terms for r in t.moving_reads})

    def static_count(self) -> int:
        """The number of leading terms that read no moving input."""
        k = 0
        for t in self.terms:
            if t.moving:
                break
            k += 1
        return k


def chain_key(chain: SumChain) -> str:
    """A name of a run that reordering does not change: its accumulators and the first source
    place of its terms (``radiance,weightSum@93:5``), for measured scores."""
    places = [(t.stmt.loc.line, t.stmt.loc.col) for t in chain.terms if getattr(t.stmt, "loc", None) is not None]
    where = "{}:{}".format(*min(places)) if places else "?"
    return ",".join(sorted(_display(a) for a in chain.accumulators)) + "@" + where


def reassociation_bound(magnitudes: Iterable[float], additive: bool = True) -> float:
    """The largest difference between two float32 evaluation orders of a sum of terms of these
    magnitudes, ``2 (n − 1) u Σ|t_k|`` (first order); for a product (``additive=False``) the
    relative difference ``2 (n − 1) u``.

    >>> reassociation_bound([1.0] * 25) == 48 * 25 * 2.0 ** -24
    True
    """
    mags = [abs(float(m)) for m in magnitudes]
    n = len(mags)
    if n < 2:
        return 0.0
    return 2.0 * (n - 1) * UNIT_ROUNDOFF * (sum(mags) if additive else 1.0)


# ----------------------------------------------------------------------------- recognition

def _display(name: str) -> str:
    """The source name of a renamed variable: ``_rr_occlusion_5`` -> ``occlusion``."""
    m = re.match(r"^_rr_(.+)_\d+$", name)
    return m.group(1) if m else name


def _accumulation(stmt) -> Optional[tuple[str, str, A.Expr, A.Assign]]:
    """``(accumulator, op, term, assign)`` of ``acc = acc op t`` with ``t`` not reading acc."""
    if not isinstance(stmt, A.ExprStmt) or not isinstance(stmt.expr, A.Assign):
        return None
    a = stmt.expr
    if a.op != "=" or not isinstance(a.target, A.Ident) or not isinstance(a.value, A.Binary):
        return None
    v = a.value
    if v.op not in _ADDITIVE + _MULTIPLICATIVE or not isinstance(v.left, A.Ident) or v.left.name != a.target.name:
        return None
    t_acc, t_term = a.target.type, v.right.type
    if t_acc is None or t_term is None or t_acc.base != "float" or t_acc.dims or t_acc.cols:
        return None
    if t_term.cols or t_term.dims or t_term.base != "float" or t_term.size not in (1, t_acc.size):
        return None
    if any(isinstance(n, A.Ident) and n.name == a.target.name for n in A.walk(v.right, decl_types=False)):
        return None
    return a.target.name, v.op, v.right, a


def _declared(node) -> set[str]:
    return {d.name for d in declared(node)}


_FORBIDDEN = (A.Discard, A.Return, A.Break, A.Continue)


def _leaf(stmt: A.Compound) -> Optional[dict]:
    """The accumulations (name → [(op, term, assign)]) of a self-contained block, or None."""
    own = _declared(stmt)
    updates: dict = {}
    top = []
    for s in stmt.stmts:
        acc = _accumulation(s)
        if acc is not None and acc[0] not in own:
            updates.setdefault(acc[0], []).append(acc[1:3])
            top.append(s)
    if not updates:
        return None
    accs = set(updates)
    for n in A.walk(stmt, decl_types=False):
        if isinstance(n, _FORBIDDEN):
            return None
        if isinstance(n, A.Call) and (n.kind == "function" or getattr(n.target, "side_effects", False)):
            return None
    for s in stmt.stmts:
        if any(s is t for t in top):
            continue
        for root in written_roots(s):
            if root.name not in own:
                return None
        if any(isinstance(n, A.Ident) and n.name in accs for n in A.walk(s, decl_types=False)):
            return None
    return updates


class _Terms(NodeVisitor):
    """The terms a statement holds, flattened (``[(statement, updates)]``), or None when it is
    not made of terms: a bare accumulation, a self-contained block (:func:`_leaf`), or a block of
    terms (a nested loop's copies)."""

    def generic_visit(self, stmt):
        return None

    def visit_ExprStmt(self, stmt):
        acc = _accumulation(stmt)
        return None if acc is None else [(stmt, {acc[0]: [acc[1:3]]})]

    def visit_Compound(self, stmt):
        if not stmt.stmts:
            return None
        group = []
        for s in stmt.stmts:
            inner = self.visit(s)
            if inner is None:
                break
            group.extend(inner)
        else:
            return group
        updates = _leaf(stmt)
        return [(stmt, updates)] if updates is not None else None


_TERMS = _Terms()


def _terms_of(stmt) -> Optional[list]:
    return _TERMS.visit(stmt)


def _label(stmt, source: int) -> str:
    """The loop iterations a term came from, ``(i=2, j=2)``, else its line."""
    for n in A.walk(stmt, decl_types=False):
        loc = getattr(n, "loc", None)
        steps = [s for s in chain_of(loc) if s.startswith("for ")]
        if steps:
            names = [re.sub(r"\s*\(\d+:\d+\)$", "", s[4:]) for s in steps]
            return "(" + ", ".join(_display_step(x) for x in names) + ")"
    loc = getattr(stmt, "loc", None)
    return f"(line {loc.line})" if loc is not None else f"(term {source + 1})"


def _display_step(step: str) -> str:
    name, _, value = step.partition("=")
    return f"{_display(name)}={value}"


def _runs(stmts: list) -> list[tuple[int, int, list]]:
    """``(start, end, terms)`` of the maximal runs of term statements in ``stmts``: a run ends
    before a term that reads one of its accumulators or updates one with the other kind of
    operator (``radiance /= weightSum`` after the sum)."""
    out = []
    i = 0
    while i < len(stmts):
        got = _terms_of(stmts[i])
        if got is None or _chain(got) is None:
            i += 1
            continue
        j, terms = i + 1, list(got)
        while j < len(stmts):
            more = _terms_of(stmts[j])
            if more is None or _chain(terms + more) is None or _reads_any(more, _chain(terms)):
                break
            terms.extend(more)
            j += 1
        out.append((i, j, terms))
        i = j
    return out


def _reads_any(terms: list, accumulators) -> bool:
    """Whether a term reads an accumulator other than in its own accumulations' left operand."""
    for _stmt, updates in terms:
        for ups in updates.values():
            for _op, t in ups:
                if any(isinstance(n, A.Ident) and n.name in accumulators for n in A.walk(t, decl_types=False)):
                    return True
    return False


def _chain(terms: list) -> Optional[dict]:
    """The accumulators of a run and their operator kind, or None when one mixes kinds."""
    kinds: dict = {}
    for _stmt, updates in terms:
        for name, ups in updates.items():
            for op, _t in ups:
                kind = "+" if op in _ADDITIVE else "*"
                if kinds.setdefault(name, kind) != kind:
                    return None
    return kinds


# ----------------------------------------------------------------------------- what a term reads

def _reads(expr) -> set[str]:
    """Names an expression reads; an element of an array read with a literal index also as
    ``name[k]`` (the element alone, so that one changing element of a uniform array does not make
    every term moving)."""
    out: set[str] = set()
    elements: set[int] = set()
    for n in A.walk(expr, decl_types=False):
        if isinstance(n, A.Index) and isinstance(n.obj, A.Ident) and isinstance(n.index, A.IntLit):
            out.add(f"{n.obj.name}[{n.index.value}]")
            elements.add(id(n.obj))
    for n in A.walk(expr, decl_types=False):
        if isinstance(n, A.Ident) and id(n) not in elements:
            out.add(n.name)
    return out


def _dependencies(unit) -> dict[str, set[str]]:
    """For every variable written in the program, what its values are computed from (every
    write counted: conservative; a write through a call reads all its arguments)."""
    deps: dict[str, set[str]] = {}
    for d in declared(unit):
        if d.init is not None:
            deps.setdefault(d.name, set()).update(_reads(d.init))
    for d in definitions(unit):
        node = d.node
        reads = _reads(node) - {d.root.name}
        if not d.whole:
            reads.add(d.root.name)
        deps.setdefault(d.root.name, set()).update(reads)
    return deps


def _closure(names: set[str], deps: dict, skip: set[str]) -> set[str]:
    seen: set[str] = set()
    stack = [n for n in names if n not in skip]
    while stack:
        n = stack.pop()
        if n in seen:
            continue
        seen.add(n)
        stack.extend(x for x in deps.get(n, ()) if x not in seen and x not in skip)
    return seen


# ----------------------------------------------------------------------------- weights

def _factors(e) -> list:
    if isinstance(e, A.Binary) and e.op == "*":
        return _factors(e.left) + _factors(e.right)
    return [e]


def _local_values(stmt) -> dict:
    """The last whole value written into each variable inside a term, in program order."""
    env: dict = {}
    for n in A.walk(stmt, decl_types=False):
        if isinstance(n, A.Declarator) and n.init is not None and not n.array_dims:
            env[n.name] = n.init
        elif isinstance(n, A.Assign) and n.op == "=" and isinstance(n.target, A.Ident):
            env[n.target.name] = n.value
    return env


def _fold(expr, env: dict, depth: int = 16):
    """The constant value of ``expr`` with the term's locals replaced by their values."""
    holder = A.ExprStmt(clone(expr))
    for _ in range(depth):
        if not A.substitute(holder, lambda n: isinstance(n, A.Ident) and n.name in env,
                            lambda n: clone(env[n.name])):
            break
    return const_value(holder.expr)


def _weight(stmt, ups: list) -> Optional[float]:
    """The constant weight of a term's additive updates of one accumulator: the product of its
    constant factors (the mean magnitude for a vector), summed over its updates; None when an
    update has no constant factor."""
    env = _local_values(stmt)
    total = 0.0
    for op, term in ups:
        w, found = 1.0, False
        for f in _factors(term):
            v = _fold(f, env)
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                w *= abs(float(v))
                found = True
            elif isinstance(v, tuple) and v and all(isinstance(x, (int, float)) for x in v):
                w *= sum(abs(float(x)) for x in v) / len(v)
                found = True
        if not found or not math.isfinite(w):
            return None
        total += w
    return total


# ----------------------------------------------------------------------------- the pass

def _main(unit):
    for d in unit.decls:
        if isinstance(d, A.FunctionDecl) and d.name == "main" and d.body is not None:
            return d
    return None


def _block_runs(body: A.Compound):
    """``(block, start, end, terms)`` of every run in the straight-line code of ``body`` (blocks
    nested in blocks; not inside a run, a branch or a loop), outermost first."""
    stack = [body]
    while stack:
        block = stack.pop()
        inside = set()
        for start, end, terms in _runs(block.stmts):
            counts: dict = {}
            for _stmt, updates in terms:
                for name in updates:
                    counts[name] = counts.get(name, 0) + 1
            if max(counts.values()) < 2:
                continue  # consecutive updates of different accumulators: not a sum of terms
            inside.update(range(start, end))
            yield block, start, end, terms
        stack.extend(s for k, s in enumerate(block.stmts) if isinstance(s, A.Compound) and k not in inside)


def sum_chains(unit, moving: Iterable[str] = (), scores: Optional[Mapping[str, dict]] = None,
               _with_places: bool = False) -> list:
    """The runs of ``unit`` (the analysed program), each a :class:`SumChain` with its terms in
    program order and the key its order would follow (see the module docstring)."""
    main = _main(unit)
    if main is None:
        return []
    moving = frozenset(moving)
    deps = _dependencies(unit)
    out = []
    for block, start, end, raw in _block_runs(main.body):
        kinds = _chain(raw)
        if kinds is None:
            continue
        terms = []
        for k, (stmt, updates) in enumerate(raw):
            own = _declared(stmt)
            reads = set()
            for ups in updates.values():
                for _op, t in ups:
                    reads |= _reads(t)
            if isinstance(stmt, A.Compound):
                for s in stmt.stmts:
                    reads |= _reads(s)
            reads -= set(updates)
            closure = _closure(reads, deps, set(kinds)) - own
            moving_reads = {r for r in closure if _moves(r, moving)}
            terms.append(Term(stmt, k, _label(stmt, k), updates, None, bool(moving_reads), frozenset(closure),
                              frozenset(moving_reads)))
        chain = SumChain(terms, kinds, loc=getattr(raw[0][0], "loc", None))
        _key(chain, scores)
        if _with_places:
            out.append((block, start, end, chain))
        else:
            out.append(chain)
    return out


def _moves(name: str, moving: frozenset) -> bool:
    """Whether a read changes between frames: the name itself, or (an array read whole) any of
    its elements, or (an element) the whole array or that element."""
    if name in moving:
        return True
    if "[" in name:
        return name.split("[", 1)[0] in moving
    return any(m.startswith(name + "[") for m in moving)


def _key(chain: SumChain, scores) -> None:
    """Set each term's weight and the chain's ordering key (what orders it)."""
    additive = [a for a, kind in chain.accumulators.items() if kind == "+"]
    weights = None
    for acc in additive:
        got = [_weight(t.stmt, t.updates[acc]) if acc in t.updates else None for t in chain.terms]
        if all(w is not None for w in got):
            weights = got
            break
    if weights is not None:
        for t, w in zip(chain.terms, weights):
            t.weight = w
    measured = dict(scores.get(chain_key(chain), {})) if scores else {}
    if any(t.label not in measured for t in chain.terms) or len({t.label for t in chain.terms}) < len(chain.terms):
        measured = {}
    key = []
    if any(t.moving for t in chain.terms) and not all(t.moving for t in chain.terms):
        key.append("static")
    if weights is not None and len(set(weights)) > 1:
        key.append("weight")
    elif measured:
        key.append("measured")
    chain.key = tuple(key) or ("source",)
    chain.scores = measured


def _order(chain: SumChain) -> list[int]:
    def rank(t: Term):
        r = []
        if "static" in chain.key:
            r.append(1 if t.moving else 0)
        if "weight" in chain.key:
            r.append(t.weight)
        elif "measured" in chain.key:
            r.append(chain.scores[t.label])
        r.append(t.source)
        return tuple(r)

    return [t.source for t in sorted(chain.terms, key=rank)]


def reorder_sums(unit, moving: Iterable[str] = (), scores: Optional[Mapping[str, dict]] = None) -> list:
    """Reorder, in place, every run of ``unit`` by its key (module docstring); returns the runs
    (:class:`SumChain`, terms in their new order)."""
    out = []
    for block, start, end, chain in reversed(sum_chains(unit, moving, scores, _with_places=True)):
        order = _order(chain)
        chain.reordered = order != sorted(order)
        if chain.reordered:
            chain.terms = [chain.terms[k] for k in order]
            block.stmts[start:end] = [t.stmt for t in chain.terms]
        out.append(chain)
    return list(reversed(out))


def prefix_texts(unit, moving: Iterable[str] = (), scores: Optional[Mapping[str, dict]] = None) -> dict[int, str]:
    """``id(expr) -> text`` for every partial sum of a run of ``unit`` (after
    :func:`reorder_sums`, with the same ``moving`` and ``scores``) that is ordered by something
    other than its source order: ``radiance: 24 of 25 terms, all but (i=2, j=2)``; the last
    static term of a run that has moving ones adds ``(the static part: every term but those
    reading u_kingOffset)``."""
    out: dict[int, str] = {}
    for chain in sum_chains(unit, moving, scores):
        if chain.key == ("source",):
            continue
        static = chain.static_count() if "static" in chain.key else 0
        for acc in chain.accumulators:
            for m, term in enumerate(chain.terms, start=1):
                ups = term.updates.get(acc)
                if not ups:
                    continue
                assign_value = _last_update(term.stmt, acc)
                if assign_value is None:
                    continue
                text = f"{_display(acc)}: " + _subset_text(m, chain)
                if m == static:
                    names = sorted({r for t in chain.terms[static:] for r in t.moving_reads})
                    text += ", the static part (without " + ", ".join(names) + ")"
                out[id(assign_value)] = text
    return out


def _last_update(stmt, acc: str):
    found = None
    stmts = stmt.stmts if isinstance(stmt, A.Compound) else [stmt]
    for s in stmts:
        got = _accumulation(s)
        if got is not None and got[0] == acc:
            found = got[3].value
    return found


def _subset_text(m: int, chain: SumChain) -> str:
    """Which terms the first ``m`` of a run are: named when few are in or few out, else by what
    ordered them (the lightest by weight, the least by measured score)."""
    n = len(chain.terms)
    labels = [t.label for t in chain.terms]
    if m == n:
        return f"all {n} terms"
    head = f"{m} of {n} terms"
    rest = labels[m:]
    if len(rest) <= 3 and len(rest) < m:
        return f"{head}, all but {', '.join(rest)}"
    if m <= 3:
        return f"{head}, {', '.join(labels[:m])}"
    if "weight" in chain.key:
        return f"{head}, the lightest (weight ≤ {max(t.weight for t in chain.terms[:m]):.3g})"
    if "measured" in chain.key:
        return f"{head}, the {m} that measured the least contribution and change"
    return head


def name_partial_sums(table, unit, moving: Iterable[str] = (), scores: Optional[Mapping[str, dict]] = None) -> None:
    """Give the node table's entries of the partial sums of reordered runs their
    :func:`prefix_texts` (in place)."""
    texts = prefix_texts(unit, moving, scores)
    if not texts:
        return
    for entry in list(table.nodes) + list(table.excluded):
        text = texts.get(id(entry.node))
        if text is not None:
            entry.text = text


def term_values(chain: SumChain, accumulator: str) -> dict:
    """``label -> expression`` of each term's value added into ``accumulator`` (the term
    expression, or where it reads a local of the term, that local's last value), for measuring
    the terms; a term with several updates of it, or none, is left out."""
    out = {}
    for t in chain.terms:
        ups = t.updates.get(accumulator) or []
        if len(ups) != 1:
            continue
        expr = ups[0][1]
        if isinstance(expr, A.Ident):
            expr = _local_values(t.stmt).get(expr.name, expr)
        out[t.label] = expr
    return out


def chains_to_measure(unit, moving: Iterable[str] = ()) -> list:
    """The runs of ``unit`` whose order a measurement would decide: at least three terms, no
    foldable weights, and static and moving terms not already telling them all apart (a group
    of at least two terms of the same kind)."""
    out = []
    for chain in sum_chains(unit, moving):
        if len(chain.terms) < 3 or "weight" in chain.key:
            continue
        kinds = [t.moving for t in chain.terms]
        if max(kinds.count(True), kinds.count(False)) >= 2:
            out.append(chain)
    return out
