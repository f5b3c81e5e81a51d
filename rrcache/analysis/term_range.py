"""Pass: the range of an estimator's terms, by interval arithmetic over the loop body.

An amortized variant that keeps subset sums in an 8-bit payload must map them into [0, 1], so it
needs a bound on what one iteration adds. :func:`term_range` gives a hull ``(lo, hi)`` that every
iteration's *contribution* to every component of every accumulator lies in (float64, before the
float32 rounding of the GPU), or ``None`` and the reason, naming the sub-expression that has no
known range as the user wrote it.

The contribution of one iteration to an accumulator is the sum of what its accumulation
statements (``acc += t``, ``acc -= t``, ``acc = acc ± t``, ``acc = t + acc``; ``-=`` adds ``-t``)
add in that iteration: a statement that may be skipped (under an ``if``, a ``switch``, a ``?:``,
``&&``/``||``, or in a body with a ``continue``) adds ``hull(0, t)``; one in an inner loop with a
constant trip count ``n`` adds ``n × t``.

The ranges of expressions are computed conservatively (every rule is a true bound):

- literals; ``+ - * /`` (a divisor whose range holds 0 is unknown; an integer quotient is rounded
  outwards); unary ``-``; ``c ? a : b`` → hull(a, b); comparisons and ``&& || !`` → [0, 1];
  integer ``%`` of non-negative operands;
- vectors, matrices, arrays and structs keep one hull over all their components: a swizzle, a field
  or an index gives that hull; a constructor gives the hull of its arguments (a matrix built from
  one argument adds its 0 and 1 entries); a matrix product adds up ``k`` products (``k`` the inner
  dimension);
- a variable declared in the loop body: the hull of every value assigned to it in the body (its
  initializer, each plain ``=`` to it or to a component of it, in nested blocks too); one that is
  also updated by ``+=``/``++``/an ``out`` argument is unknown, as is one whose values depend on
  itself (reading a variable before any assignment is undefined in GLSL and is not considered);
- the loop index: ``start + k·step``, ``k = 0..N-1``; the index of an inner loop with a constant
  header that its body does not write likewise (in the inner loop's own condition and step, its
  exit value too);
- ``const`` variables with a folded value (:mod:`rrcache.glsl.constfold`): their value; fields,
  swizzles and indices of one select from it, any index standing for every element
  (``TAPS[i].weight``: the hull of every element's ``weight``);
- built-ins: ``fract step smoothstep`` → [0, 1]; ``sin cos`` → [-1, 1]; ``normalize`` → [-1, 1]
  (or [0, 1] for a non-negative argument); ``clamp min max abs sign floor ceil trunc round
  roundEven mod`` (a positive divisor) ``exp exp2 log log2 sqrt inversesqrt`` (on their domain)
  ``pow`` (a non-negative base, a positive exponent) ``mix`` (weights in [0, 1]: the hull of the
  ends; else ``a + t(b − a)``) ``dot length distance cross fma radians degrees asin acos atan
  sinh tanh asinh``; relational and ``any all not isnan isinf`` → [0, 1];
- everything else (textures, uniforms, inputs, values computed before the loop, derivatives, other
  built-ins) is unknown, as is an integer expression whose range leaves its type's values (it
  would wrap around).

The bounds are those of exact arithmetic on finite values (a NaN or an infinity has no range,
and an interval beyond ±FLT_MAX, an infinity in 32 bits, is unknown). The GPU's float32 rounding
can leave them by an amount that grows with the intermediate values, not with the bound
(``(5.0 * fract(x) + 1.0e8) - 1.0e8`` is bounded by [0, 5] here and can be 8 in 32 bits): the
8-bit payload's check of its first frames (:mod:`rrcache.harness.cached`) is the guard.

>>> from rrcache.glsl.frontend import parse_shader
>>> from rrcache.analysis.estimators import find_estimators
>>> s = parse_shader("varying vec2 uv;\\n"
...                  "void main() { float s = 0.0;\\n"
...                  "  for (int i = 0; i < 8; i++) s += 0.25 * clamp(uv.x * float(i), 0.0, 1.0);\\n"
...                  "  gl_FragColor = vec4(s); }")
>>> e = find_estimators(s).estimators[0]
>>> e.term_range, e.range_source
((0.0, 0.25), 'analysis')
"""
from __future__ import annotations

import math
from typing import Callable, Optional, Sequence

from rrcache.glsl import ast as A
from rrcache.glsl.constfold import const_value
from rrcache.glsl.printer import print_expr
from rrcache.glsl.types import swizzle_indices
from rrcache.glsl.defuse import definitions, lvalue_root, out_qualifiers, written_roots
from rrcache.glsl.visitor import NodeVisitor

__all__ = ["term_range", "signed_term", "Interval", "FLT_MAX"]

Interval = tuple[float, float]
#: loop header parser: ``(index, start, step, samples)`` of a constant-bound ``for``, else None
HeaderFn = Callable[[A.For], Optional[tuple[str, int, int, int]]]

#: the largest finite 32-bit float
FLT_MAX = 3.4028234663852886e38
_INT32 = (-2.0 ** 31, 2.0 ** 31 - 1)
_UINT32 = (0.0, 2.0 ** 32 - 1)
_BOOL: Interval = (0.0, 1.0)
_UNIT: Interval = (0.0, 1.0)
_SIGNED_UNIT: Interval = (-1.0, 1.0)
_TEXT_WIDTH = 80
#: texture built-ins whose result is not a texel value
_TEXTURE_QUERIES = {"textureSize", "textureQueryLevels", "textureQueryLod", "textureSamples"}


class _Unknown(Exception):
    """An expression without a known range; ``reason`` says why, for the user."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


def signed_term(e: A.Assign, accs) -> Optional[tuple[int, A.Expr]]:
    """``(sign, term)`` when ``e`` adds a term to an accumulator: ``acc += t`` / ``acc = acc + t`` /
    ``acc = t + acc`` (sign +1), ``acc -= t`` / ``acc = acc - t`` (sign −1); else None."""
    if not isinstance(e.target, A.Ident) or e.target.name not in accs:
        return None
    if e.op in ("+=", "-="):
        return (1 if e.op == "+=" else -1), e.value
    if e.op == "=" and isinstance(e.value, A.Binary) and e.value.op in ("+", "-"):
        v = e.value
        if isinstance(v.left, A.Ident) and v.left.name == e.target.name:
            return (1 if v.op == "+" else -1), v.right
        if v.op == "+" and isinstance(v.right, A.Ident) and v.right.name == e.target.name:
            return 1, v.left
    return None


# ----------------------------------------------------------------------------- interval helpers

def _hull(*xs: Interval) -> Interval:
    return min(x[0] for x in xs), max(x[1] for x in xs)


def _add(a: Interval, b: Interval) -> Interval:
    return a[0] + b[0], a[1] + b[1]


def _sub(a: Interval, b: Interval) -> Interval:
    return a[0] - b[1], a[1] - b[0]


def _neg(a: Interval) -> Interval:
    return -a[1], -a[0]


def _mul(a: Interval, b: Interval) -> Interval:
    ps = [x * y for x in a for y in b]
    return min(ps), max(ps)


def _scale(n: float, a: Interval) -> Interval:
    return (n * a[0], n * a[1]) if n >= 0 else (n * a[1], n * a[0])


def _abs(a: Interval) -> Interval:
    if a[0] >= 0:
        return a
    if a[1] <= 0:
        return -a[1], -a[0]
    return 0.0, max(-a[0], a[1])


def _monotone(f, a: Interval) -> Interval:
    return f(a[0]), f(a[1])


def _flatten(v) -> list:
    if isinstance(v, (tuple, list)):
        return [x for item in v for x in _flatten(item)]
    return [v]


def _components(t) -> int:
    """The scalars in one value of type ``t`` (1 when unknown)."""
    if t is None:
        return 1
    if getattr(t, "is_matrix", False):
        return t.cols * t.rows
    return t.size if getattr(t, "is_vector", False) else 1


# ----------------------------------------------------------------------------- the pass

class _Body(NodeVisitor):
    """The facts about one estimator loop's body that the ranges need; visiting an expression
    gives its range (:meth:`eval`, which checks it) or raises :class:`_Unknown`."""

    def __init__(self, loop: A.For, index: str, start: int, step: int, samples: int,
                 accumulators: Sequence[str], header: HeaderFn, display: Callable[[str], str]):
        self.loop = loop
        self.accumulators = set(accumulators)
        self.display = display
        self.header = header
        body = loop.body
        self.parent: dict[int, A.Node] = {}
        nodes = list(A.walk(body))
        for n in nodes:
            for c in A.children(n):
                self.parent[id(c)] = n
        self.has_continue = any(isinstance(n, A.Continue) for n in nodes)
        # the variables declared in the body, by (declaration, name)
        self.locals: dict[tuple[int, str], A.Declarator] = {}
        self.values: dict[tuple[int, str], list[A.Expr]] = {}
        self.bad: dict[tuple[int, str], str] = {}
        for n in nodes:
            if isinstance(n, A.VariableDecl):
                for d in n.declarators:
                    key = (id(n), d.name)
                    self.locals[key] = d
                    self.values[key] = [d.init] if d.init is not None else []
        # loop indices: the estimator's, and those of inner loops with a constant header
        self.fixed: dict[tuple[int, str], tuple[Interval, Interval, set[int]]] = {}
        last = start + (samples - 1) * step
        span = (float(min(start, last)), float(max(start, last)))
        self.fixed[(id(loop.init.decl), index)] = (span, span, set())
        for n in nodes:
            if isinstance(n, A.For):
                self._inner_index(n)
        notes = _WriteNotes(self)
        for n in nodes:
            notes.visit(n)
        self.memo: dict[tuple[int, str], object] = {}
        self.active: set[tuple[int, str]] = set()

    # ---- facts

    def text(self, e: A.Node) -> str:
        t = self.display(print_expr(e)) if isinstance(e, A.Expr) else "?"
        return t if len(t) <= _TEXT_WIDTH else t[: _TEXT_WIDTH - 3] + "..."

    def _inner_index(self, loop: A.For) -> None:
        h = self.header(loop)
        if h is None or not isinstance(loop.init, A.DeclStmt):
            return
        name, start, step, n = h
        inner_writes = {id(r.symbol.decl) for r in written_roots(loop.body)
                        if r.name == name and r.symbol is not None}
        decl = loop.init.decl
        if id(decl) in inner_writes:
            return
        last = start + (n - 1) * step
        body_span = (float(min(start, last)), float(max(start, last)))
        end = start + n * step
        header_span = (float(min(start, end)), float(max(start, end)))
        in_header = {id(x) for part in (loop.cond, loop.step) if part is not None for x in A.walk(part)}
        self.fixed[(id(decl), name)] = (body_span, header_span, in_header)

    def inner_count(self, loop: A.For) -> Optional[int]:
        h = self.header(loop)
        if h is None or not isinstance(loop.init, A.DeclStmt):
            return None
        if any(r.name == h[0] and r.symbol is not None and r.symbol.decl is loop.init.decl
               for r in written_roots(loop.body)):
            return None
        return h[3]

    def local_key(self, target: A.Expr):
        """The key of the body's local variable that ``target`` writes, or None."""
        root = lvalue_root(target)
        sym = getattr(root, "symbol", None) if root is not None else None
        if sym is None:
            return None
        key = (id(sym.decl), sym.name)
        return key if key in self.locals else None

    # ---- the contributions

    def contribution(self) -> Interval:
        """The hull of one iteration's contribution to every accumulator component."""
        per_acc: dict[str, Interval] = {}
        accepted: set[int] = set()
        for n in A.walk(self.loop.body):
            if not isinstance(n, A.Assign):
                continue
            st = signed_term(n, self.accumulators)
            if st is None:
                continue
            accepted.add(id(n))
            sign, term = st
            r = self.eval(term)
            if sign < 0:
                r = _neg(r)
            r = self._placed(n, r)
            name = n.target.name
            per_acc[name] = _add(per_acc[name], r) if name in per_acc else r
        for d in definitions(self.loop.body):
            if d.root.name in self.accumulators and id(d.node) not in accepted:
                raise _Unknown(f"`{self.text(d.node)}` changes the accumulator "
                               f"`{self.display(d.root.name)}` otherwise than by adding a term")
        if not per_acc:
            raise _Unknown("the body adds no term to its accumulators")
        out = _hull(*per_acc.values())
        return self.finite(out, self.loop)

    def _placed(self, stmt: A.Assign, r: Interval) -> Interval:
        """What an accumulation adding ``r`` adds in one iteration, given where it stands."""
        conditional = self.has_continue
        count = 1
        child: A.Node = stmt
        node = self.parent.get(id(stmt))
        placement = _Placement(self, stmt)
        while node is not None:
            cond, times = placement.visit(node, child)
            conditional = conditional or cond
            count *= times
            child = node
            node = self.parent.get(id(node))
        r = _scale(count, r)
        return _hull(r, (0.0, 0.0)) if conditional else r

    # ---- expressions

    def finite(self, r: Interval, e: A.Node, base: Optional[str] = None) -> Interval:
        """``r`` as floats; unknown when it is not finite as a 32-bit float (the GPU's: beyond
        ±FLT_MAX it is an infinity there), or when it leaves the values of the integer type
        ``base`` (``int``/``uint`` arithmetic wraps)."""
        lo, hi = r
        if not (abs(lo) <= FLT_MAX and abs(hi) <= FLT_MAX):
            raise _Unknown(f"`{self.text(e)}` has no finite bound (as a 32-bit float)")
        limits = _INT32 if base == "int" else _UINT32 if base == "uint" else None
        if limits is not None and (lo < limits[0] or hi > limits[1]):
            raise _Unknown(f"`{self.text(e)}` may wrap around (a 32-bit {base} holds "
                           f"[{limits[0]:.0f}, {limits[1]:.0f}], its range is [{lo:g}, {hi:g}])")
        return float(lo), float(hi)

    def eval(self, e: A.Expr) -> Interval:
        try:
            r = self.visit(e)
        except (OverflowError, ValueError, ZeroDivisionError):
            raise _Unknown(f"`{self.text(e)}` has no finite bound") from None
        t = getattr(e, "type", None)
        base = t.base if t is not None and t.base in ("int", "uint") and not t.dims else None
        return self.finite(r, e, base)

    def generic_visit(self, e) -> Interval:
        raise _Unknown(f"`{self.text(e)}` has no known range")

    def visit_IntLit(self, e) -> Interval:
        v = e.value & 0xFFFFFFFF if isinstance(e, A.IntLit) and e.unsigned else e.value
        v = float(v)
        return v, v

    visit_FloatLit = visit_BoolLit = visit_IntLit

    def visit_Ident(self, e: A.Ident) -> Interval:
        sym = e.symbol
        name = self.display(e.name)
        if sym is None:
            raise _Unknown(f"`{name}` is not resolved")
        if sym.kind in ("const", "builtin") and sym.const_value is not None:
            vals = _flatten(sym.const_value)
            if vals and all(isinstance(v, (int, float)) for v in vals):
                return float(min(vals)), float(max(vals))
        key = (id(sym.decl), sym.name)
        if key in self.fixed:
            body_span, header_span, in_header = self.fixed[key]
            return header_span if id(e) in in_header else body_span
        if key in self.locals:
            return self._local(key, name)
        if e.name in self.accumulators:
            raise _Unknown(f"`{name}` is an accumulator (the term reads the running sum)")
        if sym.kind == "uniform":
            raise _Unknown(f"`{name}` is a uniform (its value is not known to the analysis)")
        if sym.kind == "in":
            raise _Unknown(f"`{name}` is a shader input (its value is not known to the analysis)")
        if sym.kind == "builtin":
            raise _Unknown(f"`{name}` is a built-in variable with no known range")
        raise _Unknown(f"`{name}` is computed before the loop (only constants, loop indices and "
                       "values computed in the loop body have known ranges)")

    def _local(self, key, name: str) -> Interval:
        done = self.memo.get(key)
        if isinstance(done, _Unknown):
            raise done
        if done is not None:
            return done  # type: ignore[return-value]
        if key in self.active:
            raise _Unknown(f"`{name}` is assigned a value computed from itself")
        self.active.add(key)
        try:
            if key in self.bad:
                raise _Unknown(f"`{name}` has no known range: {self.bad[key]}")
            values = self.values[key]
            if not values:
                raise _Unknown(f"`{name}` is never assigned in the loop body")
            r = _hull(*(self.eval(v) for v in values))
        except _Unknown as err:
            self.memo[key] = err
            raise
        finally:
            self.active.discard(key)
        self.memo[key] = r
        return r

    def visit_Unary(self, e: A.Unary) -> Interval:
        if e.op == "-":
            return _neg(self.eval(e.operand))
        if e.op == "+":
            return self.eval(e.operand)
        if e.op == "!":
            return _BOOL
        raise _Unknown(f"`{self.text(e)}` has no known range")

    def visit_Binary(self, e: A.Binary) -> Interval:
        op = e.op
        if op in ("<", "<=", ">", ">=", "==", "!=", "&&", "||", "^^"):
            return _BOOL
        if op not in ("+", "-", "*", "/", "%"):
            raise _Unknown(f"`{self.text(e)}` has no known range (`{op}`)")
        a, b = self.eval(e.left), self.eval(e.right)
        if op == "+":
            return _add(a, b)
        if op == "-":
            return _sub(a, b)
        lt, rt = e.left.type, e.right.type
        if op == "*":
            p = _mul(a, b)
            if lt is None or rt is None:
                raise _Unknown(f"`{self.text(e)}` has no known range (its operands are not typed)")
            if (lt.is_matrix or rt.is_matrix) and not (lt.is_scalar or rt.is_scalar):
                # a linear-algebra product: each component adds up `inner` products
                inner = lt.cols if lt.is_matrix else rt.rows  # mat·x: left columns; vec·mat: rows
                return _scale(inner, p)
            return p
        integer = e.type is not None and e.type.base in ("int", "uint")
        if op == "%":
            if integer and a[0] >= 0 and b[0] > 0:
                return 0.0, min(a[1], b[1] - 1)
            raise _Unknown(f"`{self.text(e)}` has no known range (`%` of values that may be negative "
                           "or zero)")
        if b[0] <= 0 <= b[1]:
            raise _Unknown(f"`{self.text(e)}` divides by `{self.text(e.right)}`, whose range "
                           f"[{b[0]:g}, {b[1]:g}] holds 0")
        if integer:
            qs = [x / y for x in a for y in b]
            return float(math.floor(min(qs))), float(math.ceil(max(qs)))
        return _mul(a, (1.0 / b[1], 1.0 / b[0]))

    def visit_Ternary(self, e: A.Ternary) -> Interval:
        return _hull(self.eval(e.then), self.eval(e.else_))

    def visit_Sequence(self, e: A.Sequence) -> Interval:
        return self.eval(e.exprs[-1])

    def visit_Assign(self, e: A.Assign) -> Interval:
        if e.op == "=":
            return self.eval(e.value)
        raise _Unknown(f"`{self.text(e)}` has no known range")

    def visit_Field(self, e: A.Field) -> Interval:
        if isinstance(e.obj, A.Call) and _is_texture(e.obj):
            raise _Unknown(_texture_reason(self.text(e)))
        known = _const_hull(e)
        return known if known is not None else self.eval(e.obj)

    def visit_Index(self, e: A.Index) -> Interval:
        known = _const_hull(e)
        return known if known is not None else self.eval(e.obj)

    def visit_Length(self, e: A.Length) -> Interval:
        v = const_value(e)
        if isinstance(v, int):
            return float(v), float(v)
        raise _Unknown(f"`{self.text(e)}` has no known range")

    def visit_InitList(self, e: A.InitList) -> Interval:
        return _hull(*(self.eval(x) for x in e.items))

    def visit_Call(self, e: A.Call) -> Interval:
        if e.kind == "constructor":
            return self._construct(e)
        if e.kind == "builtin":
            if _is_texture(e):
                raise _Unknown(_texture_reason(self.text(e)))
            rule = _BUILTINS.get(e.name)
            if rule is not None:
                return rule(self, e)
            raise _Unknown(f"`{self.text(e)}` has no known range (the analysis has no rule for "
                           f"`{e.name}`)")
        raise _Unknown(f"`{self.text(e)}` has no known range (a call that was not inlined)")

    def _construct(self, e: A.Call) -> Interval:
        t = e.type
        if t is not None and (t.is_sampler or t.is_opaque):
            raise _Unknown(f"`{self.text(e)}` has no range (not a number)")
        args = [self.eval(a) for a in e.args]
        r = _hull(*args)
        if t is not None and t.is_matrix and len(args) == 1:
            r = _hull(r, (0.0, 1.0))  # the identity's 0s and 1s around or below the argument
        if t is not None and not t.dims and t.base != "struct":
            if t.base == "bool":
                return _BOOL
            if t.base == "int":
                return float(math.trunc(r[0])), float(math.trunc(r[1]))
            if t.base == "uint":
                if r[0] < 0:
                    raise _Unknown(f"`{self.text(e)}` may wrap a negative value to a large uint")
                return float(math.trunc(r[0])), float(math.trunc(r[1]))
        return r

    # ---- built-ins

    def arg(self, e: A.Call, k: int) -> Interval:
        return self.eval(e.args[k])


def _possible(e: A.Expr) -> Optional[list]:
    """The values ``e`` may take when it selects from a ``const`` value by fields, swizzles and
    indices (any index: every element), e.g. ``TAPS[i].weight``; None when it does not."""
    v = const_value(e)
    if v is not None:
        return [v]
    if isinstance(e, A.Index):
        objs = _possible(e.obj)
        if objs is None or not all(isinstance(o, tuple) for o in objs):
            return None
        return [x for o in objs for x in o]
    if isinstance(e, A.Field):
        objs, t = _possible(e.obj), e.obj.type
        if objs is None or t is None or t.dims or t.is_matrix:
            return None
        if t.base == "struct":
            names = [name for name, _ in t.fields]
            if e.name not in names or not all(isinstance(o, tuple) for o in objs):
                return None
            return [o[names.index(e.name)] for o in objs]
        try:
            picks = swizzle_indices(e.name)
        except ValueError:
            return None
        out = []
        for o in objs:
            comps = list(o) if isinstance(o, tuple) else [o]
            if any(k >= len(comps) for k in picks):
                return None
            out.extend(comps[k] for k in picks)
        return out
    return None


def _const_hull(e: A.Expr) -> Optional[Interval]:
    vals = _possible(e)
    if vals is None:
        return None
    flat = _flatten(vals)
    if not flat or not all(isinstance(v, (int, float)) for v in flat):
        return None
    return float(min(flat)), float(max(flat))


def _is_texture(e: A.Call) -> bool:
    return (e.kind == "builtin" and getattr(e.target, "category", None) == "texture"
            and e.name not in _TEXTURE_QUERIES)


def _texture_reason(text: str) -> str:
    return f"`{text}` has no known range (a texture's values depend on its format)"


def _const_rule(r: Interval):
    return lambda self, e: r


def _monotone_rule(f, domain: Callable[[Interval], bool] = lambda a: True, what: str = ""):
    def rule(self: _Body, e: A.Call) -> Interval:
        a = self.arg(e, 0)
        if not domain(a):
            raise _Unknown(f"`{self.text(e)}` has no known range (`{self.text(e.args[0])}` in "
                           f"[{a[0]:g}, {a[1]:g}] may be outside {what})")
        return _monotone(f, a)
    return rule


def _b_abs(self: _Body, e: A.Call) -> Interval:
    return _abs(self.arg(e, 0))


def _b_sign(self: _Body, e: A.Call) -> Interval:
    a = self.arg(e, 0)
    s = lambda x: float((x > 0) - (x < 0))  # noqa: E731
    return s(a[0]), s(a[1])


def _b_round(self: _Body, e: A.Call) -> Interval:
    a = self.arg(e, 0)
    return float(math.floor(a[0])), float(math.ceil(a[1]))


def _b_min(self: _Body, e: A.Call) -> Interval:
    a, b = self.arg(e, 0), self.arg(e, 1)
    return min(a[0], b[0]), min(a[1], b[1])


def _b_max(self: _Body, e: A.Call) -> Interval:
    a, b = self.arg(e, 0), self.arg(e, 1)
    return max(a[0], b[0]), max(a[1], b[1])


def _b_clamp(self: _Body, e: A.Call) -> Interval:
    lo, hi = self.arg(e, 1), self.arg(e, 2)
    try:
        x = self.arg(e, 0)
    except _Unknown:
        # min(max(x, lo), hi) ≤ hi; ≥ min(lo, hi) whatever x (GLSL needs lo ≤ hi)
        return min(lo[0], hi[0]), hi[1]
    m = max(x[0], lo[0]), max(x[1], lo[1])
    return min(m[0], hi[0]), min(m[1], hi[1])


def _b_mix(self: _Body, e: A.Call) -> Interval:
    a, b = self.arg(e, 0), self.arg(e, 1)
    wt = e.args[2].type
    if wt is not None and wt.base == "bool":
        return _hull(a, b)
    t = self.arg(e, 2)
    if 0.0 <= t[0] and t[1] <= 1.0:
        return _hull(a, b)
    return _add(a, _mul(t, _sub(b, a)))


def _b_mod(self: _Body, e: A.Call) -> Interval:
    y = self.arg(e, 1)
    if y[0] > 0:
        return 0.0, y[1]
    raise _Unknown(f"`{self.text(e)}` has no known range (the divisor `{self.text(e.args[1])}` may "
                   "not be positive)")


def _b_pow(self: _Body, e: A.Call) -> Interval:
    x, y = self.arg(e, 0), self.arg(e, 1)
    if x[0] >= 0 and y[0] > 0:
        # x**y is monotone in x (y > 0) and in y (for a fixed x): the extremes are at the corners
        ps = [math.pow(a, b) for a in x for b in y]
        return min(ps), max(ps)
    raise _Unknown(f"`{self.text(e)}` has no known range (pow needs a base ≥ 0 and an exponent > 0 "
                   "here)")


def _b_inversesqrt(self: _Body, e: A.Call) -> Interval:
    a = self.arg(e, 0)
    if a[0] > 0:
        return 1.0 / math.sqrt(a[1]), 1.0 / math.sqrt(a[0])
    raise _Unknown(f"`{self.text(e)}` has no known range (its argument may be ≤ 0)")


def _b_length(self: _Body, e: A.Call) -> Interval:
    a = self.arg(e, 0)
    return _length_of(a, _components(e.args[0].type))


def _b_distance(self: _Body, e: A.Call) -> Interval:
    d = _sub(self.arg(e, 0), self.arg(e, 1))
    return _length_of(d, _components(e.args[0].type))


def _length_of(a: Interval, n: int) -> Interval:
    m = _abs(a)
    return math.sqrt(n) * m[0], math.sqrt(n) * m[1]


def _b_dot(self: _Body, e: A.Call) -> Interval:
    return _scale(_components(e.args[0].type), _mul(self.arg(e, 0), self.arg(e, 1)))


def _b_cross(self: _Body, e: A.Call) -> Interval:
    p = _mul(self.arg(e, 0), self.arg(e, 1))
    return _sub(p, p)


def _b_fma(self: _Body, e: A.Call) -> Interval:
    return _add(_mul(self.arg(e, 0), self.arg(e, 1)), self.arg(e, 2))


def _b_normalize(self: _Body, e: A.Call) -> Interval:
    try:
        a = self.arg(e, 0)
    except _Unknown:
        return _SIGNED_UNIT
    if a[0] >= 0:
        return _UNIT
    if a[1] <= 0:
        return -1.0, 0.0
    return _SIGNED_UNIT


def _b_atan(self: _Body, e: A.Call) -> Interval:
    return (-math.pi / 2, math.pi / 2) if len(e.args) == 1 else (-math.pi, math.pi)


_BUILTINS: dict[str, Callable[[_Body, A.Call], Interval]] = {
    "fract": _const_rule(_UNIT), "step": _const_rule(_UNIT), "smoothstep": _const_rule(_UNIT),
    "sin": _const_rule(_SIGNED_UNIT), "cos": _const_rule(_SIGNED_UNIT),
    "asin": _const_rule((-math.pi / 2, math.pi / 2)), "acos": _const_rule((0.0, math.pi)),
    "atan": _b_atan,
    "radians": _monotone_rule(math.radians), "degrees": _monotone_rule(math.degrees),
    "sinh": _monotone_rule(math.sinh), "tanh": _monotone_rule(math.tanh),
    "asinh": _monotone_rule(math.asinh),
    "exp": _monotone_rule(math.exp), "exp2": _monotone_rule(lambda x: math.pow(2.0, x)),
    "log": _monotone_rule(math.log, lambda a: a[0] > 0, "(0, ∞)"),
    "log2": _monotone_rule(math.log2, lambda a: a[0] > 0, "(0, ∞)"),
    "sqrt": _monotone_rule(math.sqrt, lambda a: a[0] >= 0, "[0, ∞)"),
    "inversesqrt": _b_inversesqrt,
    "abs": _b_abs, "sign": _b_sign,
    "floor": _monotone_rule(lambda x: float(math.floor(x))),
    "ceil": _monotone_rule(lambda x: float(math.ceil(x))),
    "trunc": _monotone_rule(lambda x: float(math.trunc(x))),
    "round": _b_round, "roundEven": _b_round,
    "mod": _b_mod, "min": _b_min, "max": _b_max, "clamp": _b_clamp, "mix": _b_mix,
    "pow": _b_pow, "length": _b_length, "distance": _b_distance, "dot": _b_dot,
    "cross": _b_cross, "normalize": _b_normalize, "fma": _b_fma,
    "lessThan": _const_rule(_BOOL), "lessThanEqual": _const_rule(_BOOL),
    "greaterThan": _const_rule(_BOOL), "greaterThanEqual": _const_rule(_BOOL),
    "equal": _const_rule(_BOOL), "notEqual": _const_rule(_BOOL), "any": _const_rule(_BOOL),
    "all": _const_rule(_BOOL), "not": _const_rule(_BOOL), "isnan": _const_rule(_BOOL),
    "isinf": _const_rule(_BOOL),
}

class _WriteNotes(NodeVisitor):
    """What a write of a local variable of the body says about its range: a plain ``=`` gives it
    a value; anything else (``+=``, ``++``, an ``out`` argument) leaves it unknown."""

    def __init__(self, body: _Body):
        self.body = body

    def generic_visit(self, n) -> None:
        pass

    def visit_Assign(self, n: A.Assign) -> None:
        body = self.body
        key = body.local_key(n.target)
        if key is None:
            return
        if n.op == "=":
            body.values[key].append(n.value)
        else:
            body.bad.setdefault(key, f"it is updated by `{body.text(n)}` (only plain `=` "
                                     "assignments give a known range)")

    def visit_Unary(self, n: A.Unary) -> None:
        body = self.body
        key = body.local_key(n.operand) if n.op in ("++", "--") else None
        if key is not None and key not in body.fixed:
            body.bad.setdefault(key, f"it is updated by `{body.text(n)}`")

    def visit_Call(self, n: A.Call) -> None:
        if n.target is None:
            return
        for q, arg in zip(out_qualifiers(n), n.args):
            if q != "in":
                key = self.body.local_key(arg)
                if key is not None:
                    self.body.bad.setdefault(key, f"`{self.body.text(n)}` writes it (an {q} argument)")


class _Placement(NodeVisitor):
    """What an accumulation ``stmt`` standing under a node (through ``child``) makes of what it
    adds: ``(conditional, times)``."""

    def __init__(self, body: _Body, stmt: A.Assign):
        self.body, self.stmt = body, stmt

    def generic_visit(self, node, child) -> tuple[bool, int]:
        return False, 1

    def visit_If(self, node, child) -> tuple[bool, int]:
        return True, 1

    visit_Switch = visit_Ternary = visit_If

    def visit_Binary(self, node: A.Binary, child) -> tuple[bool, int]:
        return node.op in ("&&", "||", "^^"), 1

    def visit_While(self, node, child) -> tuple[bool, int]:
        raise _Unknown(f"`{self.body.text(self.stmt)}` is inside a while loop of the body (how many "
                       "times it adds is not known)")

    visit_DoWhile = visit_While

    def visit_For(self, node: A.For, child) -> tuple[bool, int]:
        if child is node.body:
            n = self.body.inner_count(node)
            if n is None:
                raise _Unknown(f"`{self.body.text(self.stmt)}` is inside a loop of the body without a "
                               "constant trip count")
            return False, n
        if child is not node.init:
            raise _Unknown(f"`{self.body.text(self.stmt)}` is in the header of a loop of the body")
        return False, 1


def term_range(loop: A.For, index: str, start: int, step: int, samples: int,
               accumulators: Sequence[str], *, header: HeaderFn,
               display: Callable[[str], str] = str) -> tuple[Optional[Interval], str]:
    """``((lo, hi), "")``: a hull of every iteration's contribution to every component of every
    accumulator of the estimator loop ``loop`` (of a checked, inlined program: ``Ident.symbol``
    and ``Expr.type`` set), whose index ``index`` takes ``start + k·step``, ``k < samples``; or
    ``(None, reason)``, the reason naming the sub-expression without a known range (through
    ``display``, which turns the inliner's names back into the user's). ``header`` parses the
    header of an inner ``for`` loop (:func:`rrcache.analysis.estimators.loop_header`)."""
    try:
        body = _Body(loop, index, start, step, samples, accumulators, header, display)
        return body.contribution(), ""
    except _Unknown as err:
        return None, err.reason
