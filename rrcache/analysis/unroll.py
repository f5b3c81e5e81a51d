"""Pass: unroll ``for`` loops whose trip count is a compile-time constant.

The nodes inside an unrolled loop become ordinary straight-line nodes, one per iteration, and so
cacheable (the paper lists this as future work). A ``for`` loop is unrolled when

- its init declares (``int i = 0``) or assigns (``i = 0``) one ``int``/``uint``/``float``
  variable to a constant;
- its condition compares that variable (``< <= > >= != ==``) with a constant;
- its step is ``i++``, ``++i``, ``i--``, ``--i``, ``i += c``, ``i -= c``, ``i = i + c`` or
  ``i = i - c``;
- the body does not write the variable and has no ``break``/``continue`` of this loop;
- the trip count, simulated in the variable's own precision (``float`` loops in single
  precision), is at most ``max_iterations``, the total number of body copies made in the
  shader stays within ``max_total``, and the syntax nodes of all the copies stay within
  ``max_size`` (a total-size budget: a shader of many loops, or of loops whose bodies inline
  large functions, stops unrolling when the analysed program would outgrow it; loops are
  unrolled in program order while the budget lasts and the remaining ones are left rolled).

"Constant" means literals, ``const`` globals, and locals initialised with a constant and not
written before the loop (so ``int n = 5; for (int i = 0; i < n; i++)`` and an inlined parameter
``turbulence(p, 5)`` unroll). Each iteration becomes a block ``{ body }`` in which the loop
variable is replaced by its value as a literal and the body's locals get fresh names
(``_rr_<name>_<n>``); an assigned (not declared) loop variable gets its exit value after the
copies. Nested loops unroll inside out once the outer variable is a literal. Other loops are
left as they are (the cacheable-node analysis treats what is inside them as ``dynamic``).

Constants are evaluated as GLSL does: ``int``/``uint`` wrap to 32 bits (``-1u`` is
``0xFFFFFFFF``; a ``uint`` loop may count down through zero), ``float`` in single precision,
comparisons and ``&&``/``||``/``^^``/``!`` to ``bool``. An ``if`` or ``?:`` whose condition
became constant in a copy (``if (i > 0)`` with ``i`` = 0) keeps only the branch taken, since the
other may index an array out of range (``a[i - 1]``), which is a compile error once the index
is constant. A loop with a copy that still holds such an index (under a guard this pass does
not decide, ``i > 0 && a[i - 1] > x``) is left rolled.

>>> from rrcache.glsl.frontend import parse_shader
>>> from rrcache.glsl.printer import print_glsl
>>> s = parse_shader("void main() { float a = 0.0; for (int i = 0; i < 2; i++) a += float(i);"
...                  " gl_FragColor = vec4(a); }")
>>> "for" in print_glsl(unroll_loops(s).unit)
False
"""
from __future__ import annotations

import dataclasses
import re
from typing import Optional

from rrcache.glsl import ast as A
from rrcache.glsl.semantic import check

from rrcache.glsl.ast import walk
from rrcache.glsl.rewrite import InlinedLoc, NameAllocator, chain_of, clone, rewrite_scoped
from rrcache.glsl.visitor import NodeVisitor
from rrcache.glsl.defuse import written_roots
from rrcache.analysis.loops import Constants, body_exits, counted_loop, global_scalars, scalar

__all__ = ["unroll_loops", "unroll_unit", "DEFAULT_MAX_ITERATIONS", "DEFAULT_MAX_TOTAL",
           "DEFAULT_MAX_SIZE"]

DEFAULT_MAX_ITERATIONS = 64
DEFAULT_MAX_TOTAL = 4096
#: the syntax nodes all unrolled copies may add (the paper scenes add under 3,000; node analysis
#: runs at roughly 10-30k expression nodes per second, see docs/bench_frontend.md)
DEFAULT_MAX_SIZE = 60_000
_INDEX_TYPES = frozenset({"int", "uint", "float"})


def unroll_loops(shader, max_iterations: int = DEFAULT_MAX_ITERATIONS,
                 max_total: int = DEFAULT_MAX_TOTAL, max_size: int = DEFAULT_MAX_SIZE):
    """Return a copy of ``shader`` with its constant-trip-count ``for`` loops unrolled (see the
    module docstring). The input is not modified; the result is type-checked again.

    >>> from rrcache.glsl.frontend import parse_shader
    >>> s = parse_shader("void main() { float a = 0.0; for (int i = 0; i < 99; i++) a += 1.0;"
    ...                  " gl_FragColor = vec4(a); }")
    >>> from rrcache.glsl.printer import print_glsl
    >>> "for" in print_glsl(unroll_loops(s, max_iterations=10).unit)
    True
    """
    unit = unroll_unit(clone(shader.unit), shader.info, max_iterations, max_total, max_size)
    info = check(unit, shader.path or "<string>")
    return dataclasses.replace(shader, unit=unit, info=info)


def unroll_unit(unit: A.TranslationUnit, info, max_iterations: int = DEFAULT_MAX_ITERATIONS,
                max_total: int = DEFAULT_MAX_TOTAL,
                max_size: int = DEFAULT_MAX_SIZE) -> A.TranslationUnit:
    """The unrolling pass, in place on ``unit`` (a copy the caller owns). ``info`` is the
    :class:`SemanticInfo` of the input (for the values of ``const`` globals)."""
    u = _Unroller(unit, global_scalars(info), max_iterations, max_total, max_size)
    for d in unit.decls:
        if isinstance(d, A.FunctionDecl) and d.body is not None:
            u.scopes = [{}]
            for p in d.params:
                if p.name:
                    u.scopes[-1][p.name] = None
            d.body.stmts = u.block(d.body.stmts)
    return unit


def fold_copy(body: A.Compound, unit: A.TranslationUnit) -> list:
    """Fold what one copy of a loop body made constant once its index is a literal (an ``if`` or
    ``?:`` on the index keeps the branch taken, inner constant loops unroll), as this pass does to
    each iteration's copy; returns the copy's statements. Used by
    :mod:`rrcache.compiler.amortize` for the subsets it unrolls."""
    u = _Unroller(unit, {}, DEFAULT_MAX_ITERATIONS, DEFAULT_MAX_TOTAL)
    while A.substitute(body, u.constant_choice, u.chosen_arm):
        pass
    return u.visit(body)


class _Unroller(NodeVisitor):
    """Visiting a statement returns the statements that replace it."""

    def __init__(self, unit, consts, max_iterations, max_total, max_size=DEFAULT_MAX_SIZE):
        self.consts = consts
        self.max_iterations = max_iterations
        self.budget = max_total
        self.size_budget = max_size
        self.names = NameAllocator(unit)
        self.scopes: list[dict[str, Optional[tuple[str, object]]]] = [{}]
        self.const = Constants(self.lookup)

    # ------------------------------------------------------------------ constants
    def lookup(self, name: str):
        for scope in reversed(self.scopes):
            if name in scope:
                return scope[name]
        return self.consts.get(name)

    def invalidate(self, name: str) -> None:
        for scope in reversed(self.scopes):
            if name in scope:
                scope[name] = None
                return

    # ------------------------------------------------------------------ statements
    def block(self, stmts: list) -> list:
        out: list = []
        for s in stmts:
            out.extend(self.visit(s))
        return out

    def sub(self, s):
        if s is None:
            return None
        self.scopes.append({})
        got = self.visit(s)
        self.scopes.pop()
        return got[0] if len(got) == 1 else A.Compound(got, loc=s.loc)

    def writes(self, node) -> None:
        for root in written_roots(node):
            self.invalidate(root.name)

    def declare(self, decl) -> None:
        if not isinstance(decl, A.VariableDecl):
            return
        for d in decl.declarators:
            if d.init is not None:
                self.writes(d.init)
            value = None
            if d.init is not None and not d.array_dims and not decl.type.spec.array_dims:
                v = self.const(d.init)
                base = decl.type.spec.name
                if v is not None and base in _INDEX_TYPES and v[0] in _INDEX_TYPES:
                    value = scalar(base, v[1])
                elif v is not None and base == v[0]:
                    value = v
            self.scopes[-1][d.name] = value

    def generic_visit(self, s) -> list:
        return [s]

    def visit_Compound(self, s: A.Compound) -> list:
        self.scopes.append({})
        s.stmts = self.block(s.stmts)
        self.scopes.pop()
        return [s]

    def visit_DeclStmt(self, s: A.DeclStmt) -> list:
        self.declare(s.decl)
        return [s]

    def visit_ExprStmt(self, s: A.ExprStmt) -> list:
        if s.expr is not None:
            self.writes(s.expr)
        return [s]

    def visit_Return(self, s: A.Return) -> list:
        if s.expr is not None:
            self.writes(s.expr)
        return [s]

    def visit_If(self, s: A.If) -> list:
        cond = self.const(s.cond)
        if cond is not None and cond[0] == "bool":
            # a condition made constant by unrolling (``if (i > 0)`` with i = 0): keep the
            # branch taken only; the other may index out of range (``a[i - 1]``)
            taken = s.then if cond[1] else s.else_
            if taken is None:
                return []
            got = self.sub(taken)
            return [got if isinstance(got, A.Compound) else A.Compound([got], loc=got.loc)]
        self.writes(s.cond)
        s.then = self.sub(s.then)
        s.else_ = self.sub(s.else_)
        return [s]

    def visit_Switch(self, s: A.Switch) -> list:
        self.writes(s.expr)
        self.scopes.append({})
        s.body.stmts = self.block(s.body.stmts)
        self.scopes.pop()
        return [s]

    def visit_For(self, s: A.For) -> list:
        got = self.try_unroll(s)
        if got is not None:
            return got
        return [self.keep_loop(s)]

    def visit_While(self, s) -> list:
        return [self.keep_loop(s)]

    visit_DoWhile = visit_While

    def keep_loop(self, s):
        """A loop left in place: what it writes is unknown from its start."""
        self.writes(s)
        self.scopes.append({})
        if isinstance(s, A.For) and s.init is not None:
            self.visit(s.init)
        if isinstance(s.cond, A.VariableDecl) and not isinstance(s, A.DoWhile):
            self.declare(s.cond)
        s.body = self.sub(s.body)
        self.scopes.pop()
        self.writes(s)
        return s

    # ------------------------------------------------------------------ unrolling
    def try_unroll(self, s: A.For) -> Optional[list]:
        head, _why = counted_loop(s, self.const)
        if head is None:
            return None
        name, base = head.index, head.base
        if any(r.name == name for r in written_roots(s.body)) or body_exits(s.body):
            return None
        values, exit_value = head.run(min(self.max_iterations, self.budget))
        if values is None:
            return None
        budget = self.budget
        size = sum(1 for _ in walk(s.body)) * len(values)
        if size > self.size_budget:
            return None       # over the total-size budget: left rolled (its nodes are dynamic)
        self.budget -= len(values)
        self.size_budget -= size
        loc = s.loc
        copies: list = []
        for value in values:
            body = clone(s.body, _iteration_loc(f"for {_display(name)}={value}", loc))
            body = body if isinstance(body, A.Compound) else A.Compound([body], loc=body.loc)
            rewrite_scoped(body, {name: _literal(base, value)}, self.names.fresh)
            while A.substitute(body, self.constant_choice, self.chosen_arm):
                pass
            copies.extend(self.visit(body))
        if any(self.out_of_range(n) for c in copies for n in walk(c, decl_types=False)):
            # a constant index out of range left in a copy (``a[i - 1]`` under a guard this
            # pass does not decide): the unrolled program would not compile; keep the loop
            self.budget = budget
            self.size_budget += size
            return None
        if not head.declared:
            exit_lit = _literal(base, exit_value)(A.Ident(name, loc=loc))
            copies.append(A.ExprStmt(A.Assign("=", A.Ident(name, loc=loc), exit_lit, loc=loc),
                                     loc=loc))
            self.invalidate(name)
        return [A.Compound(copies, loc=loc)] if head.declared else copies

    def constant_choice(self, n) -> bool:
        """``c ? a : b`` with ``c`` constant (after the loop variable became a literal)."""
        if not isinstance(n, A.Ternary):
            return False
        c = self.const(n.cond)
        return c is not None and c[0] == "bool"

    def chosen_arm(self, n: A.Ternary) -> A.Expr:
        return n.then if self.const(n.cond)[1] else n.else_

    def out_of_range(self, n) -> bool:
        """An index this pass knows to be constant and outside its array, vector or matrix."""
        if not isinstance(n, A.Index):
            return False
        t = getattr(n.obj, "type", None)
        if t is None:
            return False
        bound = t.dims[0] if t.dims else t.cols if t.is_matrix else t.size if t.is_vector else None
        v = self.const(n.index)
        if v is None or v[0] not in ("int", "uint") or bound is None:
            return False
        return v[1] < 0 or v[1] >= bound


def _literal(base: str, value):
    def make(ident: A.Ident) -> A.Expr:
        loc = ident.loc
        if base == "float":
            lit = A.FloatLit(abs(float(value)), loc=loc)
        else:
            lit = A.IntLit(abs(int(value)), base == "uint", loc=loc)
        return A.Unary("-", lit, loc=loc) if value < 0 else lit
    return make


def _display(name: str) -> str:
    """The source name of a (possibly renamed) variable: ``_rr_i_156`` -> ``i``."""
    m = re.match(r"^_rr_(.+)_\d+$", name)
    return m.group(1) if m else name


def _iteration_loc(step: str, loop_loc):
    """Insert the iteration into a body location's chain, right after the loop's own chain."""
    where = f"{step} ({loop_loc.line}:{loop_loc.col})" if loop_loc else step
    k = len(chain_of(loop_loc))

    def fix(loc):
        c = chain_of(loc)
        return InlinedLoc(loc.file, loc.line, loc.col, c[:k] + (where,) + c[k:])
    return fix
