"""The static part of a sum or product written in one expression, named in the node table.

:mod:`rrcache.analysis.sums` reorders the terms of sums the unroller separated into statements.
A shader that already keeps the static part apart writes it in one expression instead, as the
chess shader combines its two occlusions: ``aoStatic * aoKing``, where ``aoStatic`` (the board
and the pieces that stand still) reads nothing that changes between frames and ``aoKing`` reads
``u_kingOffset``, keyframed in the session. There the static part is a node already (``aoStatic``'s
value); :func:`static_parts` finds such chains (``a + b + c`` or ``a * b * c`` in one
expression, float or vector operands) whose operands that read per-pixel inputs but nothing
moving come first and whose others read a moving input, and names the static prefix's node:
``1.0 - clamp(...), the static part of aoStatic * aoKing (without u_kingOffset)``. Caching it
recomputes the moving part every frame (the paper's chess ε1).

Operands that are constants or uniforms are neither static nor moving parts (they cost nothing
to recompute). Chains whose static operands are not already first are left as they are:
reordering expressions would change the node ids of most shaders for little (docs/sums.md).
"""
from __future__ import annotations

from typing import Iterable, Optional

from rrcache.glsl import ast as A
from rrcache.glsl.visitor import NodeVisitor
from rrcache.analysis.sums import _closure, _dependencies, _main, _moves, _reads

__all__ = ["static_parts", "name_static_parts"]


class _Chains(NodeVisitor):
    """The maximal chains of one associative operator (``+`` or ``*``) of float or vector values."""

    decl_types = False

    def __init__(self):
        self.chains: list[tuple[A.Binary, list]] = []

    def visit_Binary(self, e: A.Binary):
        if e.op in ("+", "*") and _vector_or_float(e.type):
            self.chains.append((e, _flatten(e, e.op)))
            for operand in _flatten(e, e.op):
                self.visit(operand)
            return
        self.generic_visit(e)


def _vector_or_float(t) -> bool:
    return t is not None and t.base == "float" and not t.cols and not t.dims


def _flatten(e, op: str) -> list:
    if isinstance(e, A.Binary) and e.op == op and _vector_or_float(e.type):
        return _flatten(e.left, op) + _flatten(e.right, op)
    return [e]


def _inputs(unit) -> set[str]:
    """The fragment shader's inputs (``in``/``varying`` globals)."""
    out = set()
    for d in unit.decls:
        if isinstance(d, A.VariableDecl) and any(q in ("in", "varying") for q in d.type.qualifiers
                                                  if isinstance(q, str)):
            out.update(x.name for x in d.declarators)
    return out


def _definition(main, name: str):
    """The value of the one whole definition of local ``name`` in ``main`` (None when several)."""
    found = []
    for n in A.walk(main.body, decl_types=False):
        if isinstance(n, A.Declarator) and n.name == name and n.init is not None:
            found.append(n.init)
        elif isinstance(n, A.Assign) and isinstance(n.target, A.Ident) and n.target.name == name:
            found.append(n.value if n.op == "=" else None)
    return found[0] if len(found) == 1 else None


def static_parts(unit, moving: Iterable[str] = ()) -> list[tuple]:
    """``(static expression, chain root, moving inputs)`` for every chain of the analysed
    ``unit`` whose static operands come first (module docstring)."""
    main = _main(unit)
    moving = frozenset(moving)
    if main is None or not moving:
        return []
    deps = _dependencies(unit)
    inputs = _inputs(unit)
    finder = _Chains()
    finder.visit(main.body)
    out = []
    for root, operands in finder.chains:
        kinds = []
        for operand in operands:
            reads = _closure(_reads(operand), deps, set())
            moved = sorted(r for r in reads if _moves(r, moving))
            kinds.append("moving" if moved else "static" if reads & inputs else "constant")
        parts = [k for k in kinds if k != "constant"]
        if "moving" not in parts or "static" not in parts:
            continue
        first_moving = kinds.index("moving")
        if "static" in kinds[first_moving:] or "static" not in kinds[:first_moving]:
            continue  # the static operands are not all first: left as written
        static = _prefix(root, operands, first_moving)
        if static is None:
            continue
        if isinstance(static, A.Ident):
            static = _definition(main, static.name)
            if static is None:
                continue
        without = sorted({r for operand in operands[first_moving:]
                          for r in _closure(_reads(operand), deps, set()) if _moves(r, moving)})
        out.append((static, root, without))
    return out


def _prefix(root: A.Binary, operands: list, k: int) -> Optional[A.Expr]:
    """The sub-expression of the left-associated chain ``root`` holding its first ``k`` operands."""
    node = root
    count = len(operands)
    while isinstance(node, A.Binary) and node.op == root.op and count > k:
        node, count = node.left, count - len(_flatten(node.right, root.op))
    return node if count == k else None


def name_static_parts(table, unit, moving: Iterable[str] = ()) -> None:
    """Name, in the node table (in place), each static part that holds at least half of its
    chain's work and a tenth of the costliest node's (static cost): ``…, the static part of
    aoStatic * aoKing (without u_kingOffset)``."""
    entries = {id(e.node): e for e in list(table.nodes) + list(table.excluded)}
    top = max((e.cost for e in table.nodes), default=0)
    for static, root, without in static_parts(unit, moving):
        entry, whole = entries.get(id(static)), entries.get(id(root))
        # worth a name: most of its chain's work, and a tenth of the costliest node's at least
        if entry is None or whole is None or entry.cost < 0.5 * whole.cost or entry.cost < 0.1 * top:
            continue
        suffix = f", the static part of {whole.text} (without {', '.join(without)})"
        if suffix not in entry.text:
            entry.text += suffix
