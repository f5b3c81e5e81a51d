"""The one recogniser of counted loops: ``for (i = a; i OP b; i += c)`` with constant ``a, b, c``.

The unroller (which loops to copy), the cost model (how often a loop left rolled runs its body)
and the estimator search (which loops sum samples) all ask the same question of a ``for``
loop's header, and all answer it here:

- the init declares (``int i = 0``) or assigns (``i = 0``) one ``int``/``uint``/``float``
  scalar, its *index*, to a constant;
- the condition compares the index (``< <= > >= != ==``, on either side) with a constant;
- the step is ``i++``, ``++i``, ``i--``, ``--i``, ``i += c``, ``i -= c``, ``i = i + c`` or
  ``i = i - c`` with a constant ``c``;
- the trip count is what the loop does in the index's own type (:meth:`CountedLoop.values`:
  ``int``/``uint`` wrap to 32 bits, a ``float`` index steps in single precision).

"Constant" is what a :class:`Constants` folds: literals, names its ``lookup`` knows (``const``
globals; the unroller adds locals initialised with a constant), and ``+ - * /``, unary ``- + !``,
comparisons, ``&& || ^^`` and ``int()``/``uint()``/``float()`` of constants, evaluated as GLSL
does. Whether the body writes the index or leaves the loop early is the caller's question
(:func:`body_exits` answers the second).

>>> from rrcache.glsl.parser import parse_source
>>> unit = parse_source("const int N = 4; void main() { for (int i = 1; i <= N * 2; i += 3) {} }")
>>> loop = unit.decls[1].body.stmts[0]
>>> head, why = counted_loop(loop, Constants({"N": ("int", 4)}.get))
>>> head.index, head.start, head.op, head.bound, head.step, head.values(100)
('i', 1, '<=', 8, 3, [1, 4, 7])
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from rrcache.glsl import ast as A
from rrcache.glsl.visitor import NodeVisitor

__all__ = ["COMPARE", "Constants", "CountedLoop", "counted_loop", "body_exits", "scalar",
           "global_scalars"]

#: the comparisons a counted loop's condition may make, evaluated in the index's type
COMPARE = {"<": np.less, "<=": np.less_equal, ">": np.greater, ">=": np.greater_equal,
           "!=": np.not_equal, "==": np.equal}
_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "!=": "!=", "==": "=="}
_DTYPE = {"int": np.int32, "uint": np.uint32, "float": np.float32}

Scalar = tuple[str, object]


def scalar(base: str, value) -> Optional[Scalar]:
    """``(base, value)`` with ``value`` converted as GLSL does: ``int``/``uint`` wrap to 32 bits
    (``-1u`` is 4294967295), ``float`` is rounded to single precision; a ``float`` too large
    for an integer type (undefined in GLSL) gives None.

    >>> scalar("uint", -1), scalar("int", 2 ** 31), scalar("float", 0.1)
    (('uint', 4294967295), ('int', -2147483648), ('float', 0.10000000149011612))
    """
    if base == "float":
        return ("float", float(np.float32(value)))
    if isinstance(value, float):
        if not np.isfinite(value) or not -2.0 ** 31 <= value < 2.0 ** 32:
            return None
        value = int(value)   # towards zero, as GLSL converts
    value = int(value)
    if base == "uint":
        return ("uint", value & 0xFFFFFFFF)
    return ("int", (value + 2 ** 31) % 2 ** 32 - 2 ** 31)


def global_scalars(info) -> dict[str, Scalar]:
    """The scalar ``const`` globals of a checked shader (its :class:`SemanticInfo`), typed."""
    out: dict[str, Scalar] = {}
    if info is None:
        return out
    for name, sym in info.globals.items():
        v = sym.const_value
        if sym.kind != "const" or not isinstance(v, (int, float, bool)) or sym.type.dims:
            continue
        if isinstance(v, bool):
            out[name] = ("bool", v)
        else:
            got = scalar("float" if isinstance(v, float) else sym.type.base, v)
            if got is not None:
                out[name] = got
    return out


class Constants(NodeVisitor):
    """Folds constant scalar expressions: ``constants(e)`` is ``(base, value)`` or None.
    ``lookup(name)`` gives a name's ``(base, value)`` (or None when it is not constant)."""

    def __init__(self, lookup: Callable[[str], Optional[Scalar]]):
        self.lookup = lookup

    def __call__(self, e) -> Optional[Scalar]:
        return None if e is None else self.visit(e)

    def generic_visit(self, e) -> None:
        return None

    def visit_IntLit(self, e: A.IntLit) -> Optional[Scalar]:
        return scalar("uint" if e.unsigned else "int", e.value)

    def visit_FloatLit(self, e: A.FloatLit) -> Optional[Scalar]:
        return None if e.double else scalar("float", e.value)

    def visit_BoolLit(self, e: A.BoolLit) -> Scalar:
        return ("bool", bool(e.value))

    def visit_Ident(self, e: A.Ident) -> Optional[Scalar]:
        return self.lookup(e.name)

    def visit_Unary(self, e: A.Unary) -> Optional[Scalar]:
        if e.op not in ("-", "+", "!"):
            return None
        v = self.visit(e.operand)
        if v is None:
            return None
        if e.op == "!":
            return ("bool", not v[1]) if v[0] == "bool" else None
        if v[0] not in _DTYPE:
            return None
        return scalar(v[0], -v[1] if e.op == "-" else v[1])

    def visit_Binary(self, e: A.Binary) -> Optional[Scalar]:
        op = e.op
        if op not in ("+", "-", "*", "/") and op not in COMPARE and op not in ("&&", "||", "^^"):
            return None
        a, b = self.visit(e.left), self.visit(e.right)
        if a is None or b is None or a[0] != b[0]:
            return None
        if op in ("&&", "||", "^^"):
            if a[0] != "bool":
                return None
            return ("bool", a[1] and b[1] if op == "&&" else a[1] or b[1] if op == "||"
                    else a[1] != b[1])
        if a[0] not in _DTYPE:
            return None
        if op in COMPARE:
            return ("bool", bool(COMPARE[op](a[1], b[1])))
        if op == "/":
            if b[1] == 0:
                return None
            if a[0] == "float":
                with np.errstate(all="ignore"):
                    return scalar("float", np.float32(a[1]) / np.float32(b[1]))
            q = abs(a[1]) // abs(b[1])   # integer division truncates towards zero
            return scalar(a[0], q if (a[1] < 0) == (b[1] < 0) else -q)
        x, y = _DTYPE[a[0]](a[1]), _DTYPE[a[0]](b[1])
        with np.errstate(all="ignore"):
            r = x + y if op == "+" else x - y if op == "-" else x * y
        return (a[0], r.item())

    def visit_Call(self, e: A.Call) -> Optional[Scalar]:
        if e.name not in _DTYPE or len(e.args) != 1:
            return None
        v = self.visit(e.args[0])
        if v is None or v[0] not in _DTYPE:
            return None
        return scalar(e.name, v[1])


@dataclass(frozen=True)
class CountedLoop:
    """A ``for`` loop with a constant header: its index ``index`` of type ``base`` (``int``,
    ``uint`` or ``float``), declared in the header (``declared``) or assigned there, starts at
    ``start`` and moves by ``step`` while ``index op bound`` holds (the index on the left)."""

    loop: A.For
    index: str
    base: str
    declared: bool
    start: object
    op: str
    bound: object
    step: object

    def run(self, limit: int) -> tuple[Optional[list], object]:
        """``(values, exit)``: the index's value in each iteration and after the last, computed
        in the index's type; ``(None, None)`` when the loop runs more than ``limit`` times."""
        dtype = _DTYPE[self.base]
        v, b, dv = dtype(self.start), dtype(self.bound), dtype(self.step)
        compare = COMPARE[self.op]
        values: list = []
        with np.errstate(all="ignore"):
            while bool(compare(v, b)):
                values.append(v.item())
                if len(values) > limit:
                    return None, None
                v = dtype(v + dv)
        return values, v.item()

    def values(self, limit: int) -> Optional[list]:
        """The index's value in each iteration, or None past ``limit`` iterations."""
        return self.run(limit)[0]

    def trips(self, limit: int) -> Optional[int]:
        """How many times the body runs, or None past ``limit``."""
        values = self.values(limit)
        return None if values is None else len(values)


def _an(bases: tuple[str, ...]) -> str:
    return "an " + (" or ".join(bases) if len(bases) < 3 else ", ".join(bases[:-1]) + " or "
                    + bases[-1])


def counted_loop(loop, constants: Callable[[A.Expr], Optional[Scalar]], *,
                 declared_only: bool = False,
                 bases: tuple[str, ...] = ("int", "uint", "float")
                 ) -> tuple[Optional[CountedLoop], str]:
    """``(CountedLoop, "")`` for a ``for`` loop with a constant header (module docstring), else
    ``(None, reason)``. ``constants`` folds an expression to ``(base, value)`` (a
    :class:`Constants`); ``declared_only`` refuses an index assigned rather than declared in the
    header; ``bases`` are the index types accepted."""
    if not isinstance(loop, A.For):
        return None, "not a for loop"
    init = loop.init
    if isinstance(init, A.DeclStmt) and isinstance(init.decl, A.VariableDecl) \
            and len(init.decl.declarators) == 1:
        d = init.decl.declarators[0]
        name, base, start_expr, declared = d.name, init.decl.type.spec.name, d.init, True
        if d.array_dims or init.decl.type.spec.array_dims:
            base = None
    elif not declared_only and isinstance(init, A.ExprStmt) and isinstance(init.expr, A.Assign) \
            and init.expr.op == "=" and isinstance(init.expr.target, A.Ident):
        t = init.expr.target
        name, start_expr, declared = t.name, init.expr.value, False
        ty = getattr(t, "type", None)
        base = ty.base if ty is not None and ty.size == 1 and not ty.dims else None
    else:
        return None, "the loop does not declare its index in its header"
    if base not in bases:
        return None, f"the loop index is not {_an(bases)}"
    start = constants(start_expr) if start_expr is not None else None
    start = scalar(base, start[1]) if start is not None and start[0] in _DTYPE else None
    if start is None:
        return None, "the loop index does not start at a constant"
    cond = loop.cond
    if not isinstance(cond, A.Binary) or cond.op not in COMPARE:
        return None, "the loop condition is not a comparison of the index with a constant"
    if isinstance(cond.left, A.Ident) and cond.left.name == name:
        op, bound_expr = cond.op, cond.right
    elif isinstance(cond.right, A.Ident) and cond.right.name == name:
        op, bound_expr = _FLIP[cond.op], cond.left
    else:
        return None, "the loop condition does not compare the index"
    bound = constants(bound_expr)
    bound = scalar(base, bound[1]) if bound is not None and bound[0] in _DTYPE else None
    if bound is None:
        return None, "the loop bound is not constant"
    step = _step(loop.step, name, constants, base)
    if not step:
        return None, "the loop step is not a constant increment of the index"
    return CountedLoop(loop, name, base, declared, start[1], op, bound[1], step), ""


def _step(s, name: str, constants, base: str):
    """The increment of the step expression in the index's type (0 or None: not one)."""
    sign, amount = 0, None
    if isinstance(s, A.Unary) and s.op in ("++", "--") and isinstance(s.operand, A.Ident) \
            and s.operand.name == name:
        return scalar(base, 1 if s.op == "++" else -1)[1]
    if isinstance(s, A.Assign) and isinstance(s.target, A.Ident) and s.target.name == name:
        if s.op in ("+=", "-="):
            sign, amount = (1 if s.op == "+=" else -1), s.value
        elif s.op == "=" and isinstance(s.value, A.Binary) and s.value.op in ("+", "-") \
                and isinstance(s.value.left, A.Ident) and s.value.left.name == name:
            sign, amount = (1 if s.value.op == "+" else -1), s.value.right
    if amount is None:
        return None
    v = constants(amount)
    if v is None or v[0] not in _DTYPE:
        return None
    v = scalar(v[0], -v[1] if sign < 0 else v[1])
    got = scalar(base, v[1]) if v is not None else None
    return None if got is None else got[1]


class _Exits(NodeVisitor):
    """Whether a loop body has a ``break``/``continue`` of its own loop."""

    def generic_visit(self, node) -> bool:
        return False

    def visit_Break(self, s) -> bool:
        return True

    visit_Continue = visit_Break

    def visit_Compound(self, s: A.Compound) -> bool:
        return any(self.visit(x) for x in s.stmts)

    def visit_If(self, s: A.If) -> bool:
        return self.visit(s.then) or (s.else_ is not None and self.visit(s.else_))

    def visit_Switch(self, s: A.Switch) -> bool:
        # a ``break`` leaves the switch; a ``continue`` the loop
        return any(isinstance(n, A.Continue) for n in A.walk(s.body, decl_types=False))


def body_exits(body: A.Stmt) -> bool:
    """Whether ``body`` (a loop's) has a ``break`` or ``continue`` that leaves or restarts that
    loop (those of inner loops, and a ``break`` of a ``switch``, do not count).

    >>> from rrcache.glsl.parser import parse_source
    >>> loop = parse_source("void main() { for (;;) { for (;;) break; } }").decls[0].body.stmts[0]
    >>> body_exits(loop.body), body_exits(loop.body.stmts[0].body)
    (False, True)
    """
    return _Exits().visit(body)
