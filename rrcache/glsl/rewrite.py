"""Building and rewriting syntax trees: what the analysis passes and the compiler make new code
with (none of it is a pass itself).

- :func:`clone`: a fast structural copy (semantic annotations and declaration types shared),
  optionally rewriting every ``loc``; it follows the tree's one spec
  (:func:`rrcache.glsl.ast.child_fields`).
- :class:`InlinedLoc`: a :class:`SourceLoc` that also records the inlined call chain (and the
  unrolled loop iterations) that produced a node, outermost first.
- :class:`NameAllocator`: fresh names ``_rr_<base>_<n>`` for generated variables; names starting
  with ``_rr`` are reserved for rrcache (:func:`check_reserved_names`).
- :func:`rewrite_scoped`: a scope-aware rename/substitute of variables in a statement.
- :func:`declare`, :func:`declare_typed`, :func:`assign`: generated statements.
- :func:`paused_gc`: the cyclic garbage collector paused while a pass builds trees.

>>> from rrcache.glsl.parser import parse_source
>>> from rrcache.glsl.printer import print_glsl
>>> unit = parse_source("void main() { float x = 1.0; x = x + y; }")
>>> copy = clone(unit)
>>> _ = rewrite_scoped(copy.decls[0].body, {"y": "z"}, NameAllocator().fresh)
>>> print(print_glsl(copy).strip())
void main()
{
    float _rr_x_0 = 1.0;
    _rr_x_0 = _rr_x_0 + z;
}
>>> print(print_glsl(unit).strip().splitlines()[2])
    float x = 1.0;
"""
from __future__ import annotations

import contextlib
import gc
import re
from dataclasses import dataclass, fields
from typing import Callable, Optional, Union

from rrcache.errors import SourceLoc, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.types import Type
from rrcache.glsl.visitor import NodeTransformer, NodeVisitor

_CLONE_FIELDS: dict[type, tuple[str, ...]] = {}

RESERVED_PREFIX = "_rr"
_GENERATED = re.compile(r"^_rr_(.+)_(\d+)$")


@dataclass(frozen=True)
class InlinedLoc(SourceLoc):
    """A source location inside inlined or unrolled code. ``chain`` lists, outermost first, the
    call sites (``"noise (95:33)"``) and loop iterations (``"for i=2 (93:5)"``) it came through."""

    chain: tuple[str, ...] = ()


def chain_of(loc: Optional[SourceLoc]) -> tuple[str, ...]:
    """The inlined call chain of a location (empty for code written in ``main``)."""
    return loc.chain if isinstance(loc, InlinedLoc) else ()


def with_chain(loc: Optional[SourceLoc], step: str) -> Optional[SourceLoc]:
    """``loc`` with ``step`` prepended to its chain."""
    if loc is None:
        return None
    return InlinedLoc(loc.file, loc.line, loc.col, (step,) + chain_of(loc))



def _clone_fields(cls: type) -> tuple[str, ...]:
    """The fields :func:`clone` copies: the syntax child fields without declaration types
    (:func:`rrcache.glsl.ast.child_fields`), plus the lists of names and places (copied so that
    a copy's list can change alone)."""
    syntax = set(A.child_fields(cls, decl_types=False))
    return tuple(f.name for f in fields(cls)
                 if f.name in syntax or f.type.startswith("list["))


def clone(node, loc_fn: Optional[Callable[[SourceLoc], SourceLoc]] = None):
    """A structural copy of ``node``; ``loc_fn`` maps every location of the copy.

    The semantic annotations (``loc``, ``Expr.type``, ``Ident.symbol``, ``Call.target``,
    ``Call.kind``) and the ``FullType`` of declarations are shared with the original, not
    copied.

    >>> from rrcache.glsl.parser import parse_source
    >>> decl = parse_source("float a = 1.0;").decls[0]
    >>> copy = clone(decl)
    >>> copy == decl, copy.declarators[0] is decl.declarators[0], copy.type is decl.type
    (True, False, True)
    """
    cls = node.__class__
    if cls is list:
        return [clone(x, loc_fn) for x in node]
    if cls is tuple:
        return tuple(clone(x, loc_fn) for x in node)
    if not isinstance(node, A.Node):
        return node
    new = cls.__new__(cls)
    d = node.__dict__.copy()
    node_cls = A.Node
    names = _CLONE_FIELDS.get(cls)
    if names is None:
        names = _CLONE_FIELDS[cls] = _clone_fields(cls)
    for name in names:
        value = d[name]
        if value is not None and (isinstance(value, node_cls) or value.__class__ is list):
            d[name] = clone(value, loc_fn)
    if loc_fn is not None and d.get("loc") is not None:
        d["loc"] = loc_fn(d["loc"])
    new.__dict__ = d
    return new


@contextlib.contextmanager
def paused_gc():
    """Pause the cyclic garbage collector inside the block; on leaving it, move the objects
    made there to the oldest generation and restore the collector's previous state.

    The passes allocate hundreds of thousands of AST nodes that stay alive (they make no
    reference cycles). Every collection of the oldest generation walks all of them, which took
    60% of the analysis of a 3,000-line shader; and without the move, the first collections
    after the block would walk them again, once per younger generation, as they are promoted.
    ``gc.freeze()`` followed by ``gc.unfreeze()`` puts every tracked object in the oldest
    generation (documented behaviour): they are then examined at the next full collection like
    any other long-lived data.
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.freeze()
            gc.unfreeze()
            gc.enable()


# ----------------------------------------------------------------------------- names


class _ReservedNames(NodeVisitor):
    """Refuses a declared name (variable, parameter, function) starting with ``_rr``."""

    decl_types = False

    def visit_Declarator(self, n) -> None:
        if n.name and n.name.startswith(RESERVED_PREFIX):
            raise UnsupportedShaderError(
                f"the name '{n.name}' starts with '{RESERVED_PREFIX}', which rrcache reserves "
                "for the variables it generates", n.loc, "rename it")
        self.generic_visit(n)

    visit_Param = visit_FunctionDecl = visit_Declarator


def check_reserved_names(unit: A.TranslationUnit) -> None:
    """Raise :class:`UnsupportedShaderError` when the shader declares a name starting with
    ``_rr`` (reserved for the variables the passes generate)."""
    _ReservedNames().visit(unit)


class NameAllocator:
    """Fresh, unique variable names ``_rr_<base>_<n>`` (``n`` counts up across the unit).

    >>> names = NameAllocator()
    >>> names.fresh("cell"), names.fresh("_rr_cell_0")
    ('_rr_cell_0', '_rr_cell_1')
    """

    def __init__(self, unit: Optional[A.Node] = None):
        self.counter = 0
        if unit is not None:
            for n in A.walk(unit, decl_types=False):
                name = getattr(n, "name", None)
                if isinstance(name, str):
                    m = _GENERATED.match(name)
                    if m:
                        self.counter = max(self.counter, int(m.group(2)) + 1)

    def fresh(self, base: str) -> str:
        m = _GENERATED.match(base)
        if m:
            base = m.group(1)
        name = f"_rr_{base}_{self.counter}"
        self.counter += 1
        return name


def is_live_flag(name: str) -> bool:
    """Whether ``name`` is an early-return flag made by the inliner (``_rr_live_<n>``)."""
    return bool(re.match(r"^_rr_live_\d+$", name))


# ----------------------------------------------------------------------------- generated statements


def type_spec(t: Type) -> tuple[A.FullType, Optional[list]]:
    """A ``FullType`` and declarator array dims spelling the GLSL type ``t``."""
    if t.base == "struct":
        name = t.struct_name
    else:
        name = t.without_array().glsl_name()
    dims = [A.IntLit(d) if d is not None else None for d in t.dims] if t.dims else None
    return A.FullType([], A.TypeSpecifier(name)), dims


def declare(name: str, full_type: A.FullType, init: Optional[A.Expr] = None,
            dims: Optional[list] = None, loc: Optional[SourceLoc] = None) -> A.DeclStmt:
    """``T name[dims] = init;`` as a statement."""
    decl = A.VariableDecl(full_type, [A.Declarator(name, dims, init, loc=loc)], loc=loc)
    return A.DeclStmt(decl, loc=loc)


def declare_typed(name: str, t: Type, init: Optional[A.Expr] = None,
                  loc: Optional[SourceLoc] = None) -> A.DeclStmt:
    """``T name = init;`` for a semantic :class:`Type`."""
    full, dims = type_spec(t)
    return declare(name, full, init, dims, loc)


def assign(name: str, value: A.Expr, loc: Optional[SourceLoc] = None) -> A.ExprStmt:
    """``name = value;``"""
    return A.ExprStmt(A.Assign("=", A.Ident(name, loc=loc), value, loc=loc), loc=loc)


# ----------------------------------------------------------------------------- scoped rewriting

Replacement = Union[str, Callable[[A.Ident], A.Expr], None]


def rewrite_scoped(stmt: A.Stmt, initial: dict[str, Replacement],
                   rename_decl: Optional[Callable[[str], Optional[str]]] = None) -> A.Stmt:
    """Rename or substitute variables in ``stmt`` (in place), respecting scopes.

    ``initial`` maps names visible at ``stmt`` to a new name (``str``) or to a function building
    the replacement expression. Declarations inside ``stmt`` are renamed to
    ``rename_decl(name)`` (when it returns a name) and shadow outer entries. Returns ``stmt``.
    """
    _ScopedRewriter(initial, rename_decl).stmt(stmt)
    return stmt


class _ScopedRewriter(NodeTransformer):
    """Visiting a statement rewrites it in place; visiting an expression returns its rewrite."""

    decl_types = False

    def __init__(self, initial, rename_decl):
        self.scopes: list[dict[str, Replacement]] = [dict(initial)]
        self.rename_decl = rename_decl

    def lookup(self, name: str) -> Replacement:
        for scope in reversed(self.scopes):
            if name in scope:
                return scope[name]
        return None

    def expr(self, e):
        return None if e is None else self.visit(e)

    def visit_Ident(self, e: A.Ident):
        rep = self.lookup(e.name)
        if isinstance(rep, str):
            e.name = rep
            return e
        if rep is not None:
            return rep(e)
        return e

    def declare(self, d: A.Declarator) -> None:
        if d.array_dims:
            d.array_dims = [self.expr(x) for x in d.array_dims]
        d.init = self.expr(d.init)
        new = self.rename_decl(d.name) if self.rename_decl else None
        self.scopes[-1][d.name] = new
        if new:
            d.name = new

    def var_decl(self, decl) -> None:
        if isinstance(decl, A.VariableDecl):
            for d in decl.declarators:
                self.declare(d)

    def condition(self, s) -> None:
        """A loop's condition: a declaration (``while (bool b = ...)``) or an expression."""
        if isinstance(s.cond, A.VariableDecl):
            self.var_decl(s.cond)
        else:
            s.cond = self.expr(s.cond)

    def stmt(self, s) -> None:
        if s is not None:
            self.visit(s)

    def visit_Stmt(self, s):
        return s     # break, continue, discard

    def visit_Compound(self, s: A.Compound):
        self.scopes.append({})
        for x in s.stmts:
            self.visit(x)
        self.scopes.pop()
        return s

    def visit_DeclStmt(self, s: A.DeclStmt):
        self.var_decl(s.decl)
        return s

    def visit_ExprStmt(self, s: A.ExprStmt):
        s.expr = self.expr(s.expr)
        return s

    visit_Return = visit_Case = visit_ExprStmt

    def visit_If(self, s: A.If):
        s.cond = self.expr(s.cond)
        self.sub(s.then)
        self.sub(s.else_)
        return s

    def visit_For(self, s: A.For):
        self.scopes.append({})
        self.stmt(s.init)
        self.condition(s)
        s.step = self.expr(s.step)
        self.sub(s.body)
        self.scopes.pop()
        return s

    def visit_While(self, s: A.While):
        self.scopes.append({})
        self.condition(s)
        self.sub(s.body)
        self.scopes.pop()
        return s

    def visit_DoWhile(self, s: A.DoWhile):
        self.sub(s.body)
        s.cond = self.expr(s.cond)
        return s

    def visit_Switch(self, s: A.Switch):
        s.expr = self.expr(s.expr)
        self.visit(s.body)
        return s

    def sub(self, s) -> None:
        """A sub-statement (if branch, loop body): its own scope."""
        if s is None:
            return
        self.scopes.append({})
        self.visit(s)
        self.scopes.pop()
