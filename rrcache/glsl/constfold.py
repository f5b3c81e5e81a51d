"""Constant folding of typed GLSL expressions (after semantic analysis has set ``Expr.type``).

:func:`const_value` gives the value of a constant expression, or None when the expression is not
one (or uses something this folder does not evaluate, which only ever makes it stricter). Values
are plain Python data read through the expression's static type: a scalar is an ``int``,
``float`` or ``bool``; a vector a tuple of scalars; a matrix a tuple of column tuples; an array a
tuple of its elements; a struct a tuple of its member values. That covers what array sizes,
``case`` labels and index checks need in real shaders: swizzles and indexing of ``const``
vectors, matrices, arrays and structs (``const ivec4 v = ...; float a[v.y];``), constructors,
component-wise operators and the pure built-in functions (``int(max(2.0, x))``).

>>> from rrcache.glsl.parser import parse_source
>>> from rrcache.glsl.semantic import check
>>> unit = parse_source("const ivec4 v = ivec4(1, 2, 3, 4); const int n = v.z + ~v.x;"
...                     "void main() {}")
>>> info = check(unit)
>>> info.globals["v"].const_value, info.globals["n"].const_value
((1, 2, 3, 4), 1)
"""
from __future__ import annotations

import math
from typing import Any, Callable, Optional

from rrcache.glsl import ast as A
from rrcache.glsl.types import Type, swizzle_indices

__all__ = ["const_value", "fold_binary"]


def const_value(e: A.Expr) -> Any:
    """The value of constant expression ``e`` (see the module docstring), or None."""
    fold = _FOLDERS.get(type(e))
    return fold(e) if fold is not None else None


def fold_binary(op: str, a: Any, b: Any, t: Optional[Type]) -> Any:
    """``a op b`` for scalar values, wrapped to the 32-bit result type ``t``; None when the
    operation cannot be folded (integer division by zero, a type error...)."""
    integer = isinstance(a, int) and isinstance(b, int) and not isinstance(a, bool)
    try:
        if op == "+":
            v = a + b
        elif op == "-":
            v = a - b
        elif op == "*":
            v = a * b
        elif op == "/":
            if integer:
                if b == 0:
                    return None
                q = abs(a) // abs(b)
                v = q if (a >= 0) == (b >= 0) else -q
            else:
                v = a / b
        elif op == "%":
            if not integer or b == 0:
                return None
            v = a - b * (abs(a) // abs(b) * (1 if (a >= 0) == (b >= 0) else -1))
        elif op == "<<":
            v = a << b
        elif op == ">>":
            v = a >> b
        elif op == "&":
            v = a & b
        elif op == "|":
            v = a | b
        elif op == "^":
            v = a ^ b
        elif op in ("<", ">", "<=", ">=", "==", "!="):
            v = {"<": a < b, ">": a > b, "<=": a <= b, ">=": a >= b, "==": a == b,
                 "!=": a != b}[op]
        elif op == "&&":
            v = a and b
        elif op == "||":
            v = a or b
        elif op == "^^":
            v = bool(a) != bool(b)
        else:
            return None
    except (TypeError, ZeroDivisionError, ValueError, OverflowError):
        return None
    return _wrap(v, t)


# ----------------------------------------------------------------------------- helpers

def _wrap(v: Any, t: Optional[Type]) -> Any:
    if t is not None and t.base == "uint" and isinstance(v, int):
        return v & 0xFFFFFFFF
    if t is not None and t.base == "int" and isinstance(v, int):
        return (v + 2**31) % 2**32 - 2**31
    return v


def _convert(v: Any, base: str) -> Any:
    if base == "int":
        return _wrap(int(v), Type("int"))
    if base == "uint":
        return int(v) & 0xFFFFFFFF
    if base == "bool":
        return bool(v)
    return float(v)


def _components(v: Any, t: Type) -> list:
    """The scalars of a scalar, vector or matrix value, column-major."""
    if t.is_matrix:
        return [x for col in v for x in col]
    if t.is_vector:
        return list(v)
    return [v]


def _is_composite(t: Optional[Type]) -> bool:
    return t is not None and (t.is_vector or t.is_matrix or bool(t.dims) or t.base == "struct")


def _literal(e: A.Expr) -> Any:
    if isinstance(e, A.IntLit):
        return e.value & 0xFFFFFFFF if e.unsigned else e.value
    return e.value


def _ident(e: A.Ident) -> Any:
    sym = e.symbol
    return sym.const_value if sym is not None and sym.kind in ("const", "builtin") else None


def _unary(e: A.Unary) -> Any:
    v = const_value(e.operand)
    if v is None or e.op not in ("-", "+", "!", "~"):
        return None
    t = e.operand.type
    if t is not None and t.is_matrix:
        return tuple(tuple(_unary_scalar(e.op, x, t) for x in col) for col in v) \
            if e.op in ("-", "+") else None
    if t is not None and t.is_vector:
        out = tuple(_unary_scalar(e.op, x, t) for x in v)
        return None if any(x is None for x in out) else out
    return _unary_scalar(e.op, v, t)


def _unary_scalar(op: str, v: Any, t: Optional[Type]) -> Any:
    if op == "-":
        return _wrap(-v, t)
    if op == "+":
        return v
    if op == "!":
        return not v
    return _wrap(~v, t) if isinstance(v, int) and not isinstance(v, bool) else None


def _binary(e: A.Binary) -> Any:
    a = const_value(e.left)
    if a is None:
        return None
    b = const_value(e.right)
    if b is None:
        return None
    lt, rt = e.left.type, e.right.type
    if not (_is_composite(lt) or _is_composite(rt)):
        return fold_binary(e.op, a, b, e.type)
    if e.op in ("==", "!="):
        return (a == b) == (e.op == "==")
    if lt is None or rt is None or lt.is_matrix or rt.is_matrix or lt.dims or rt.dims \
            or "struct" in (lt.base, rt.base) or e.type is None:
        return None  # matrix algebra is not folded
    xs = list(a) if lt.is_vector else [a] * rt.size
    ys = list(b) if rt.is_vector else [b] * lt.size
    out = tuple(fold_binary(e.op, x, y, e.type.scalar_type()) for x, y in zip(xs, ys))
    return None if any(v is None for v in out) else out


def _ternary(e: A.Ternary) -> Any:
    c = const_value(e.cond)
    return None if c is None else const_value(e.then if c else e.else_)


def _length(e: A.Length) -> Any:
    t = e.obj.type
    if t is not None and t.dims:
        return t.dims[0]
    if t is not None and (t.is_vector or t.is_matrix):
        return t.cols or t.size
    return None


def _field(e: A.Field) -> Any:
    obj = const_value(e.obj)
    t = e.obj.type
    if obj is None or t is None or t.dims:
        return None
    if t.base == "struct":
        names = [name for name, _ in t.fields]
        return obj[names.index(e.name)] if e.name in names else None
    if t.is_matrix:
        return None
    comps = list(obj) if t.is_vector else [obj]
    try:
        picked = tuple(comps[i] for i in swizzle_indices(e.name))
    except (ValueError, IndexError):
        return None
    return picked[0] if len(picked) == 1 else picked


def _index(e: A.Index) -> Any:
    obj = const_value(e.obj)
    i = const_value(e.index)
    if obj is None or not isinstance(i, int) or isinstance(i, bool):
        return None
    return obj[i] if isinstance(obj, tuple) and 0 <= i < len(obj) else None


def _call(e: A.Call) -> Any:
    if e.kind == "constructor" and isinstance(e.target, Type):
        return _construct(e)
    if e.kind == "builtin" and e.name in _BUILTINS:
        return _builtin(e)
    return None


def _construct(e: A.Call) -> Any:
    args = [const_value(a) for a in e.args]
    if any(v is None for v in args):
        return None
    t: Type = e.target
    if t.dims or t.base == "struct":
        return tuple(args)
    types = [a.type for a in e.args]
    if any(at is None or at.dims or at.base == "struct" or at.is_opaque for at in types):
        return None
    if t.is_matrix:
        return _construct_matrix(t, args, types)
    comps = [x for v, at in zip(args, types) for x in _components(v, at)]
    if t.is_scalar:
        return _convert(comps[0], t.base)
    if len(args) == 1 and types[0].is_scalar:
        comps = comps * t.size
    if len(comps) < t.size:
        return None
    return tuple(_convert(x, t.base) for x in comps[:t.size])


def _construct_matrix(t: Type, args: list, types: list[Type]) -> Any:
    cols, rows = t.cols, t.rows
    if len(args) == 1 and types[0].is_scalar:
        d = _convert(args[0], t.base)
        return tuple(tuple(d if c == r else _convert(0, t.base) for r in range(rows))
                     for c in range(cols))
    if len(args) == 1 and types[0].is_matrix:
        src, sc, sr = args[0], types[0].cols, types[0].rows
        return tuple(tuple(_convert(src[c][r] if c < sc and r < sr else float(c == r), t.base)
                           for r in range(rows)) for c in range(cols))
    comps = [x for v, at in zip(args, types) for x in _components(v, at)]
    if len(comps) < cols * rows:
        return None
    return tuple(tuple(_convert(comps[c * rows + r], t.base) for r in range(rows))
                 for c in range(cols))


# Pure built-ins evaluated component-wise (scalar arguments broadcast over vectors).
_MATH: dict[str, Callable[..., Any]] = {
    "radians": math.radians, "degrees": math.degrees, "sin": math.sin, "cos": math.cos,
    "tan": math.tan, "asin": math.asin, "acos": math.acos, "sinh": math.sinh,
    "cosh": math.cosh, "tanh": math.tanh, "asinh": math.asinh, "acosh": math.acosh,
    "atanh": math.atanh, "exp": math.exp, "log": math.log, "exp2": lambda x: 2.0 ** x,
    "log2": math.log2, "sqrt": math.sqrt, "inversesqrt": lambda x: 1.0 / math.sqrt(x),
    "abs": abs, "sign": lambda x: type(x)((x > 0) - (x < 0)), "floor": math.floor,
    "ceil": math.ceil, "trunc": math.trunc, "fract": lambda x: x - math.floor(x),
    "round": lambda x: math.floor(x + 0.5), "roundEven": round,
    "pow": math.pow, "mod": lambda x, y: x - y * math.floor(x / y),
    "min": min, "max": max, "clamp": lambda x, lo, hi: min(max(x, lo), hi),
    "mix": lambda x, y, a: (y if a else x) if isinstance(a, bool) else x * (1 - a) + y * a,
    "step": lambda edge, x: 0.0 if x < edge else 1.0,
    "smoothstep": lambda e0, e1, x: _smoothstep(e0, e1, x),
    "atan": lambda y, x=None: math.atan(y) if x is None else math.atan2(y, x),
}
_GEOMETRIC = {"length", "distance", "dot"}
_BUILTINS = frozenset(_MATH) | _GEOMETRIC


def _smoothstep(e0: float, e1: float, x: float) -> float:
    u = min(max((x - e0) / (e1 - e0), 0.0), 1.0)
    return u * u * (3.0 - 2.0 * u)


def _builtin(e: A.Call) -> Any:
    args = [const_value(a) for a in e.args]
    types = [a.type for a in e.args]
    if any(v is None for v in args) or e.type is None or \
            any(t is None or t.is_matrix or t.dims for t in types):
        return None
    vecs = [list(v) if t.is_vector else None for v, t in zip(args, types)]
    try:
        if e.name in _GEOMETRIC:
            xs = [v if v is not None else [a] for v, a in zip(vecs, args)]
            if e.name == "dot":
                return float(sum(p * q for p, q in zip(xs[0], xs[1])))
            if e.name == "distance":
                return math.sqrt(sum((p - q) ** 2 for p, q in zip(xs[0], xs[1])))
            return math.sqrt(sum(p * p for p in xs[0]))
        n = e.type.size
        cols = [v if v is not None else [a] * n for v, a in zip(vecs, args)]
        out = [_MATH[e.name](*vals) for vals in zip(*cols)]
    except (ValueError, ZeroDivisionError, OverflowError, TypeError):
        return None
    out = [_convert(x, e.type.base) for x in out]
    return out[0] if e.type.is_scalar else tuple(out)


def _init_list(e: A.InitList) -> Any:
    items = [const_value(i) for i in e.items]
    return None if any(v is None for v in items) else tuple(items)


_FOLDERS: dict[type, Callable[[Any], Any]] = {
    A.IntLit: _literal, A.FloatLit: _literal, A.BoolLit: _literal, A.Ident: _ident,
    A.Unary: _unary, A.Binary: _binary, A.Ternary: _ternary, A.Length: _length,
    A.Field: _field, A.Index: _index, A.Call: _call, A.InitList: _init_list,
}
