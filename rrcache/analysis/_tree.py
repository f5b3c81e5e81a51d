"""Tree utilities shared by the analysis passes (not a pass itself).

- :func:`children` / :func:`walk` / :func:`iter_exprs`: traversal that follows the syntax tree
  only. ``Node.walk`` also follows ``Call.target`` (a ``FunctionDecl`` after semantic analysis)
  and so revisits function bodies; the passes and node ids use these functions instead.
- :func:`clone`: a fast structural copy (``loc``, ``type``, ``symbol``, ``target``, ``kind`` and
  the ``FullType`` of declarations are shared, not copied), optionally rewriting every ``loc``.
- :class:`InlinedLoc`: a :class:`SourceLoc` that also records the inlined call chain (and the
  unrolled loop iterations) that produced a node, outermost first.
- :class:`NameAllocator`: fresh names ``_rr_<base>_<n>`` for generated variables; names starting
  with ``_rr`` are reserved for rrcache (:func:`check_reserved_names`).
- :func:`rewrite_scoped`: a scope-aware rename/substitute of variables in a statement.
- :func:`paused_gc`: the cyclic garbage collector paused while a pass builds trees.

>>> from rrcache.glsl.parser import parse_source
>>> unit = parse_source("void main() { float x = 1.0; x = x + 2.0; }")
>>> [type(e).__name__ for e in iter_exprs(unit)]
['FloatLit', 'Assign', 'Ident', 'Binary', 'Ident', 'FloatLit']
"""
from __future__ import annotations

import contextlib
import gc
import re
from dataclasses import dataclass, fields
from typing import Callable, Iterator, Optional, Union

from rrcache.errors import SourceLoc, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.types import Type

#: Semantic annotations, never tree children (``target`` and ``kind`` only on ``Call``:
#: ``Assign.target`` is a child).
_ANNOTATIONS = frozenset({"loc", "symbol"})
_CALL_ANNOTATIONS = frozenset({"target", "kind"})
#: Field annotations that can never hold a node (names, operators, literal values, spellings):
#: traversal skips such fields without looking at them.
_ATOMIC_FIELDS = frozenset({"str", "bool", "int", "float", "Optional[str]", "Optional[int]"})
_SCALAR_FIELDS = _ATOMIC_FIELDS | {"list[str]", "list[tuple[str, str]]", "list[SourceLoc]"}
_FIELD_CACHE: dict[tuple[type, bool], tuple[str, ...]] = {}
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


def tree_fields(cls: type, decl_types: bool = False) -> tuple[str, ...]:
    """The names of the fields of AST class ``cls`` that can hold syntax children.

    Never the semantic annotations (``loc``, ``Expr.type``, ``Ident.symbol``, ``Call.target``,
    ``Call.kind``). The ``type`` of a declaration (a ``FullType``: struct names and array sizes
    live there) is followed only with ``decl_types``: the analysis passes share it between
    copies and do not number what is inside; the compiler's rewrites follow it.

    >>> from rrcache.glsl.parser import parse_source
    >>> decl = parse_source("float[2] a;").decls[0]
    >>> tree_fields(type(decl)), tree_fields(type(decl), decl_types=True)
    (('declarators',), ('type', 'declarators'))
    """
    key = (cls, decl_types)
    names = _FIELD_CACHE.get(key)
    if names is None:
        skip = set(_ANNOTATIONS)
        if issubclass(cls, A.Call):
            skip |= _CALL_ANNOTATIONS
        if not decl_types or issubclass(cls, A.Expr):
            skip.add("type")
        names = tuple(f.name for f in fields(cls)
                      if f.name not in skip and f.type not in _SCALAR_FIELDS)
        _FIELD_CACHE[key] = names
    return names


def _child_list(node: A.Node, decl_types: bool = False) -> list:
    """The direct syntax children of ``node`` in source order, as a list."""
    out = []
    node_cls = A.Node
    d = node.__dict__
    names = _FIELD_CACHE.get((node.__class__, decl_types)) or tree_fields(node.__class__, decl_types)
    for name in names:
        value = d[name]
        if value is None:
            continue
        if isinstance(value, node_cls):
            out.append(value)
        elif isinstance(value, list):
            for item in value:
                if isinstance(item, node_cls):
                    out.append(item)
                elif item.__class__ is tuple:
                    out.extend(sub for sub in item if isinstance(sub, node_cls))
    return out


def children(node: A.Node, decl_types: bool = False) -> Iterator[A.Node]:
    """The direct syntax children of ``node`` in source order (``Call.target`` never;
    declaration types only with ``decl_types``, see :func:`tree_fields`)."""
    return iter(_child_list(node, decl_types))


def walk(node: A.Node, decl_types: bool = False) -> Iterator[A.Node]:
    """``node`` and its syntax descendants, pre-order (iterative: deep trees are fine)."""
    stack = [node]
    pop, extend = stack.pop, stack.extend
    while stack:
        n = pop()
        yield n
        kids = _child_list(n, decl_types)
        if kids:
            kids.reverse()
            extend(kids)


def iter_exprs(unit: A.Node) -> Iterator[A.Expr]:
    """Every expression node under ``unit`` in pre-order: the order that numbers node ids."""
    expr_cls = A.Expr
    for n in walk(unit):
        if isinstance(n, expr_cls):
            yield n


def clone(node, loc_fn: Optional[Callable[[SourceLoc], SourceLoc]] = None):
    """A structural copy of ``node``; ``loc_fn`` maps every location of the copy."""
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
    if names is None:      # the syntax fields plus lists of names (copied, not shared)
        names = _CLONE_FIELDS[cls] = tuple(
            f.name for f in fields(cls) if f.type not in _ATOMIC_FIELDS
            and f.name not in _ANNOTATIONS and f.name != "type"
            and not (f.name in _CALL_ANNOTATIONS and issubclass(cls, A.Call)))
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


def check_reserved_names(unit: A.TranslationUnit) -> None:
    """Raise :class:`UnsupportedShaderError` when the shader declares a name starting with
    ``_rr`` (reserved for the variables the passes generate)."""
    for n in walk(unit):
        names: list[tuple[str, Optional[SourceLoc]]] = []
        if isinstance(n, A.Declarator):
            names.append((n.name, n.loc))
        elif isinstance(n, A.Param) and n.name:
            names.append((n.name, n.loc))
        elif isinstance(n, A.FunctionDecl):
            names.append((n.name, n.loc))
        for name, loc in names:
            if name.startswith(RESERVED_PREFIX):
                raise UnsupportedShaderError(
                    f"the name '{name}' starts with '{RESERVED_PREFIX}', which rrcache reserves "
                    "for the variables it generates", loc, "rename it")


class NameAllocator:
    """Fresh, unique variable names ``_rr_<base>_<n>`` (``n`` counts up across the unit).

    >>> names = NameAllocator()
    >>> names.fresh("cell"), names.fresh("_rr_cell_0")
    ('_rr_cell_0', '_rr_cell_1')
    """

    def __init__(self, unit: Optional[A.Node] = None):
        self.counter = 0
        if unit is not None:
            for n in walk(unit):
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


# ----------------------------------------------------------------------------- types


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


# ----------------------------------------------------------------------------- predicates


def lvalue_root(e: A.Expr) -> Optional[A.Ident]:
    """The variable an l-value expression writes (``a`` in ``a[i].xy``)."""
    while isinstance(e, (A.Field, A.Index)):
        e = e.obj
    return e if isinstance(e, A.Ident) else None


def written_roots(e: A.Node) -> Iterator[A.Ident]:
    """The variables an expression (or statement) writes: assignment targets, ``++``/``--`` operands, and
    arguments passed to ``out``/``inout`` parameters (of calls with a resolved target)."""
    for n in walk(e):
        target = None
        if isinstance(n, A.Assign):
            target = n.target
        elif isinstance(n, A.Unary) and n.op in ("++", "--"):
            target = n.operand
        elif isinstance(n, A.Call) and n.target is not None:
            for q, arg in zip(out_qualifiers(n), n.args):
                if q != "in":
                    root = lvalue_root(arg)
                    if root is not None:
                        yield root
        if target is not None:
            root = lvalue_root(target)
            if root is not None:
                yield root


def out_qualifiers(call: A.Call) -> tuple[str, ...]:
    """The parameter qualifiers (``in``/``out``/``inout``) of a resolved call."""
    target = call.target
    if target is None:
        return ()
    if isinstance(target, A.FunctionDecl):
        return tuple(param_qualifier(p) for p in target.params)
    return tuple(getattr(target, "qualifiers", ()))


def param_qualifier(p: A.Param) -> str:
    """``in``, ``out`` or ``inout`` for a parameter."""
    quals = [q for q in p.type.qualifiers if isinstance(q, str)]
    if "inout" in quals:
        return "inout"
    if "out" in quals:
        return "out"
    return "in"


def is_literal(e: A.Expr) -> bool:
    return isinstance(e, (A.IntLit, A.FloatLit, A.BoolLit))


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


class _ScopedRewriter:
    def __init__(self, initial, rename_decl):
        self.scopes: list[dict[str, Replacement]] = [dict(initial)]
        self.rename_decl = rename_decl

    def lookup(self, name: str) -> Replacement:
        for scope in reversed(self.scopes):
            if name in scope:
                return scope[name]
        return None

    def expr(self, e):
        if e is None:
            return None
        if isinstance(e, A.Ident):
            rep = self.lookup(e.name)
            if isinstance(rep, str):
                e.name = rep
                return e
            if rep is not None:
                return rep(e)
            return e
        for name in tree_fields(type(e)):
            value = getattr(e, name)
            if isinstance(value, A.Expr):
                setattr(e, name, self.expr(value))
            elif isinstance(value, list):
                setattr(e, name, [self.expr(x) if isinstance(x, A.Expr) else x for x in value])
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

    def stmt(self, s) -> None:
        if s is None:
            return
        if isinstance(s, A.Compound):
            self.scopes.append({})
            for x in s.stmts:
                self.stmt(x)
            self.scopes.pop()
        elif isinstance(s, A.DeclStmt):
            self.var_decl(s.decl)
        elif isinstance(s, A.ExprStmt):
            s.expr = self.expr(s.expr)
        elif isinstance(s, A.If):
            s.cond = self.expr(s.cond)
            self.sub(s.then)
            self.sub(s.else_)
        elif isinstance(s, A.For):
            self.scopes.append({})
            self.stmt(s.init)
            if isinstance(s.cond, A.VariableDecl):
                self.var_decl(s.cond)
            else:
                s.cond = self.expr(s.cond)
            s.step = self.expr(s.step)
            self.sub(s.body)
            self.scopes.pop()
        elif isinstance(s, A.While):
            self.scopes.append({})
            if isinstance(s.cond, A.VariableDecl):
                self.var_decl(s.cond)
            else:
                s.cond = self.expr(s.cond)
            self.sub(s.body)
            self.scopes.pop()
        elif isinstance(s, A.DoWhile):
            self.sub(s.body)
            s.cond = self.expr(s.cond)
        elif isinstance(s, A.Switch):
            s.expr = self.expr(s.expr)
            self.stmt(s.body)
        elif isinstance(s, A.Return):
            s.expr = self.expr(s.expr)
        elif isinstance(s, A.Case):
            s.expr = self.expr(s.expr)

    def sub(self, s) -> None:
        """A sub-statement (if branch, loop body): its own scope."""
        if s is None:
            return
        self.scopes.append({})
        self.stmt(s)
        self.scopes.pop()
