"""The static cost model: what evaluating an expression costs, in abstract ALU units.

The weights model llvmpipe (the platform rrcache measures on), which runs shaders in SoA form:
a ``vec3`` operation is three scalar operations, so ALU costs are *per component* of the result
(or of the operands, for reductions such as ``dot``). One unit is one scalar add or multiply.

===========================  ==========================================================
operation                    cost
===========================  ==========================================================
``+ - *``, unary ``-``       ``ADD`` / ``MUL`` = 1 per component (matrix × vector:
                             cols·rows; matrix × matrix: cols·rows·inner)
``/``, ``%``                 ``DIV`` = 4 per component
comparisons, ``&& || !``,    1 per component
``?:`` (a select)
``sqrt``, ``inversesqrt``    ``SQRT`` = 4 per component
``sin cos tan asin acos      ``TRANSCENDENTAL`` = 8 per component
atan exp log exp2 log2
pow sinh ...``
``abs floor fract min max    1 per component (``clamp`` 2, ``mix`` 3, ``mod`` 6,
sign step ...``              ``smoothstep`` 8)
``dot``                      2·n − 1 for n-component operands
``length`` / ``normalize``   dot + ``SQRT`` (+ n multiplies for ``normalize``)
``distance``                 n + ``length``
``cross``                    9; ``reflect`` dot + 2·n; ``refract`` 2·dot + ``SQRT`` + 4·n
texture lookups              ``TEXTURE`` = 16 per call (plus the coordinates' cost)
``dFdx``/``dFdy``/``fwidth`` 2 per component
other built-ins              2 per component
constructors, swizzles,      0 (register moves)
fields, literals, variables
a call of a user function    ``USER_CALL`` = 32 (only calls the inliner left in place)
===========================  ==========================================================

A cache lookup costs about ``CACHE_LOOKUP_COST`` = 42: the reprojection (a divide by w and a
scale and bias, 8), two bilinear fetches (the previous depth for the hit test and the payload,
2 × ``TEXTURE``) and the depth comparison (2). Caching a node whose saved work is below that
cannot pay for itself; :mod:`rrcache.analysis.cacheable` excludes such nodes as ``cheap``.

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("uniform vec3 a;\\nvoid main() { gl_FragColor = vec4(sin(a * 2.0), 1.0); }")
>>> main = s.unit.decls[-1]
>>> subtree_cost(main.body.stmts[0].expr.value)   # vec3 multiply (3) + vec3 sine (24)
27
"""
from __future__ import annotations

from rrcache.glsl import ast as A

from rrcache.glsl.ast import walk
from rrcache.glsl.visitor import NodeVisitor
from rrcache.analysis.loops import counted_loop

__all__ = ["ADD", "MUL", "DIV", "SQRT", "TRANSCENDENTAL", "TEXTURE", "USER_CALL",
           "CACHE_LOOKUP_COST", "MAX_LOOP_TRIPS", "op_cost", "subtree_cost", "loop_trips"]

ADD = 1
MUL = 1
DIV = 4
SQRT = 4
TRANSCENDENTAL = 8
TEXTURE = 16
USER_CALL = 32
CACHE_LOOKUP_COST = 8 + 2 * TEXTURE + 2

_TRANSCENDENTAL = frozenset(
    "sin cos tan asin acos atan sinh cosh tanh asinh acosh atanh exp log exp2 log2 pow".split())
_PER_COMPONENT = {
    "sqrt": SQRT, "inversesqrt": SQRT,
    "abs": 1, "sign": 1, "floor": 1, "ceil": 1, "fract": 1, "trunc": 1, "round": 1,
    "roundEven": 1, "min": 1, "max": 1, "step": 1, "radians": 1, "degrees": 1,
    "clamp": 2, "mix": 3, "mod": 2 + DIV, "modf": 2, "smoothstep": 8, "fma": 1,
    "isnan": 1, "isinf": 1, "lessThan": 1, "lessThanEqual": 1, "greaterThan": 1,
    "greaterThanEqual": 1, "equal": 1, "notEqual": 1, "not": 1,
    "dFdx": 2, "dFdy": 2, "fwidth": 2, "dFdxFine": 2, "dFdyFine": 2, "fwidthFine": 2,
    "dFdxCoarse": 2, "dFdyCoarse": 2, "fwidthCoarse": 2,
}


def _components(e) -> int:
    t = getattr(e, "type", None)
    if t is None:
        return 1
    try:
        return max(1, t.components)
    except (TypeError, AttributeError):
        return 1


def _dot(n: int) -> int:
    return 2 * n - 1


class _OpCost(NodeVisitor):
    """The cost of the operation at an expression alone (its operands not included)."""

    def visit_Binary(self, e: A.Binary) -> int:
        if e.op == "*":
            lt, rt = getattr(e.left, "type", None), getattr(e.right, "type", None)
            if lt is not None and rt is not None and (lt.is_matrix or rt.is_matrix):
                if lt.is_matrix and rt.is_matrix:
                    return lt.cols * lt.rows * rt.cols
                m = lt if lt.is_matrix else rt
                return m.cols * m.rows
            return MUL * _components(e)
        if e.op in ("/", "%"):
            return DIV * _components(e)
        if e.op in ("+", "-"):
            return ADD * _components(e)
        if e.op in ("<", ">", "<=", ">=", "==", "!="):
            return max(_components(e.left), _components(e.right))
        return 1

    def visit_Unary(self, e: A.Unary) -> int:
        return _components(e) if e.op == "-" else (0 if e.op == "+" else 1)

    def visit_Ternary(self, e: A.Ternary) -> int:
        return _components(e)

    def visit_Call(self, e: A.Call) -> int:
        return _call_cost(e)

    def generic_visit(self, e) -> int:
        return 0


def op_cost(e: A.Expr) -> int:
    """The cost of the operation at ``e`` alone (its operands not included).

    >>> op_cost(A.Binary("/", A.Ident("a"), A.Ident("b")))   # untyped: one component
    4
    """
    return _OP_COST.visit(e)


_OP_COST = _OpCost()


def _call_cost(e: A.Call) -> int:
    if e.kind == "constructor":
        return 0
    if e.kind == "function":
        return USER_CALL
    name = e.name
    n = _components(e)
    arg_n = _components(e.args[0]) if e.args else 1
    category = getattr(e.target, "category", None)
    if category == "texture" or name.startswith(("texture", "shadow")) or name == "texelFetch":
        return 1 if name in ("textureSize", "textureQueryLevels", "textureSamples") else TEXTURE
    if name in _TRANSCENDENTAL:
        return TRANSCENDENTAL * n
    if name in _PER_COMPONENT:
        return _PER_COMPONENT[name] * n
    if name == "dot":
        return _dot(arg_n)
    if name == "length":
        return _dot(arg_n) + SQRT
    if name == "distance":
        return arg_n + _dot(arg_n) + SQRT
    if name == "normalize":
        return _dot(arg_n) + SQRT + arg_n
    if name == "cross":
        return 9
    if name == "reflect":
        return _dot(arg_n) + 2 * arg_n
    if name == "refract":
        return 2 * _dot(arg_n) + SQRT + 4 * arg_n
    if name == "faceforward":
        return _dot(arg_n) + arg_n
    if name in ("any", "all"):
        return arg_n
    if name in ("transpose",):
        return 0
    if name == "determinant":
        return 4 * arg_n
    if name == "inverse":
        return 12 * arg_n
    if name == "matrixCompMult":
        return n
    if name == "outerProduct":
        return n
    return 2 * n


def subtree_cost(e: A.Expr) -> int:
    """The cost of evaluating the expression tree ``e`` (variables read count 0; the
    cacheable-node analysis adds the work behind local variables).

    >>> subtree_cost(A.Binary("+", A.Ident("a"), A.Call("sqrt", [A.Ident("b")])))
    5
    """
    return sum(op_cost(n) for n in walk(e, decl_types=False) if isinstance(n, A.Expr))


#: the most iterations :func:`loop_trips` counts for one loop
MAX_LOOP_TRIPS = 4096


def loop_trips(loop, constants) -> int:
    """How many times the body of a loop left rolled (one with a ``break``, or over the
    unroller's budget) runs at most: the trip count of its header when it is a counted loop
    (:func:`rrcache.analysis.loops.counted_loop`, with ``constants`` folding the header's
    expressions), 1 when it cannot tell (a bound read from a uniform, a ``while`` loop). The
    static cost of what such a loop computes is its body's times this: one iteration of a
    64-step ray march is not its cost. At most :data:`MAX_LOOP_TRIPS`.

    >>> from rrcache.glsl.frontend import parse_shader
    >>> from rrcache.analysis.loops import Constants, global_scalars
    >>> s = parse_shader("#version 330\\nconst int N = 80;\\nout vec4 c;\\nvoid main() { float t = 0.0;"
    ...                  " for (int i = 0; i < N; i++) { t += 1.0; if (t > 9.0) break; } c = vec4(t); }")
    >>> loop = [n for n in s.unit.walk() if isinstance(n, A.For)][0]
    >>> loop_trips(loop, Constants(global_scalars(s.info).get))
    80
    """
    head, _why = counted_loop(loop, constants)
    if head is None:
        return 1
    trips = head.trips(MAX_LOOP_TRIPS)
    return MAX_LOOP_TRIPS if trips is None else max(trips, 1)
