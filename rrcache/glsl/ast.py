"""The GLSL abstract syntax tree.

Plain dataclasses, one per construct. Every node carries ``loc`` (a :class:`SourceLoc` in the
*original* file, after preprocessing and includes), which is excluded from equality so that
``parse(print(parse(src))) == parse(src)`` compares structure only. Expression nodes also carry
``type``, filled in by semantic analysis (:mod:`rrcache.glsl.semantic`), likewise excluded from
equality.

Qualifiers are kept as an ordered list of words (``"const"``, ``"uniform"``, ``"highp"``,
``"flat"``, ``"centroid"``, ...) and :class:`Layout` objects, exactly as written, so the printer
reproduces them in their source order.

The tree's shape is declared once, by these classes: a field is a *syntax child field* when it
takes part in equality (``compare``; the annotations ``loc``, ``Expr.type``, ``Ident.symbol``,
``Call.target``, ``Call.kind`` and literal spellings do not) and its annotation can hold a node.
:func:`children`, :func:`walk`, :func:`post_order`, :func:`substitute` and :func:`clone
<rrcache.glsl.rewrite.clone>` all follow that one spec, so a walk never wanders from a call into
the body of the function it calls. The ``type`` of a declaration (a :class:`FullType`, marked
:data:`DECL_TYPE`: struct names and array sizes live there) is followed unless
``decl_types=False``: the analysis shares it between the copies it makes and does not number the
expressions inside it.

>>> from rrcache.glsl.parser import parse_source
>>> unit = parse_source("float[2] a; void main() { float x = 1.0; x = x + a[1]; }")
>>> child_fields(VariableDecl), child_fields(VariableDecl, decl_types=False)
(('type', 'declarators'), ('declarators',))
>>> [type(e).__name__ for e in iter_exprs(unit.decls[1])]
['FloatLit', 'Assign', 'Ident', 'Binary', 'Ident', 'Index', 'Ident', 'IntLit']
>>> sum(isinstance(n, IntLit) for n in walk(unit)), sum(isinstance(n, IntLit) for n in walk(unit, decl_types=False))
(2, 1)
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, Callable, Iterator, Optional, Union

from rrcache.errors import SourceLoc


#: Metadata of the fields that hold a declaration's type (``VariableDecl.type``, ``Param.type``,
#: ``StructMember.type``): followed by a traversal unless ``decl_types=False``.
DECL_TYPE = {"decl_type": True}


@dataclass
class Node:
    loc: Optional[SourceLoc] = field(default=None, compare=False, repr=False, kw_only=True)

    def children(self) -> list["Node"]:
        """Direct child nodes, in source order (:func:`children`)."""
        return children(self)

    def walk(self) -> Iterator["Node"]:
        """This node and all its descendants, pre-order (:func:`walk`)."""
        return walk(self)


# ----------------------------------------------------------------------------- types, qualifiers


@dataclass
class Layout(Node):
    """``layout(location = 0, std140)``: a list of (name, value-or-None)."""

    items: list[tuple[str, Optional["Expr"]]]


Qualifier = Union[str, Layout]


@dataclass
class StructSpecifier(Node):
    name: Optional[str]
    members: list["StructMember"]


@dataclass
class TypeSpecifier(Node):
    """A type as written: a built-in or struct name (``name``) or an inline struct (``struct``),
    optionally with array dimensions on the type itself (``float[3] a;``; ``None`` in the list
    means an unsized dimension ``[]``)."""

    name: Optional[str]
    struct: Optional[StructSpecifier] = None
    array_dims: Optional[list[Optional["Expr"]]] = None


@dataclass
class FullType(Node):
    qualifiers: list[Qualifier]
    spec: TypeSpecifier


@dataclass
class StructMember(Node):
    type: FullType = field(metadata=DECL_TYPE)
    declarators: list["Declarator"]


# ----------------------------------------------------------------------------- declarations


@dataclass
class Declarator(Node):
    """One name in a declaration: ``a[2][3] = init``."""

    name: str
    array_dims: Optional[list[Optional["Expr"]]] = None
    init: Optional["Expr"] = None


@dataclass
class VariableDecl(Node):
    """``const highp vec3 a = ..., b[2];`` (also a bare struct declaration ``struct S {...};``
    with no declarators)."""

    type: FullType = field(metadata=DECL_TYPE)
    declarators: list[Declarator]


@dataclass
class Param(Node):
    type: FullType = field(metadata=DECL_TYPE)
    name: Optional[str] = None
    array_dims: Optional[list[Optional["Expr"]]] = None


@dataclass
class FunctionDecl(Node):
    """A function definition, or a prototype when ``body`` is ``None``."""

    return_type: FullType
    name: str
    params: list[Param]
    body: Optional["Compound"] = None


@dataclass
class PrecisionDecl(Node):
    """``precision mediump float;``"""

    precision: str
    spec: TypeSpecifier


@dataclass
class InterfaceBlock(Node):
    """``layout(std140) uniform Block { ... } inst[2];``"""

    qualifiers: list[Qualifier]
    block_name: str
    members: list[StructMember]
    instance_name: Optional[str] = None
    array_dims: Optional[list[Optional["Expr"]]] = None


@dataclass
class QualifierDecl(Node):
    """A declaration of qualifiers only: ``invariant gl_FragColor;``,
    ``layout(early_fragment_tests) in;`` (``names`` empty)."""

    qualifiers: list[Qualifier]
    names: list[str] = field(default_factory=list)


Declaration = Union[VariableDecl, FunctionDecl, PrecisionDecl, InterfaceBlock, QualifierDecl]


@dataclass
class TranslationUnit(Node):
    """A whole shader. ``version`` is the ``#version`` number (``None`` when absent: 110, or 100
    for ES), ``profile`` ``"core"``, ``"compatibility"``, ``"es"`` or ``None``; ``extensions`` the
    ``#extension name : behavior`` pairs in order."""

    decls: list[Declaration]
    version: Optional[int] = None
    profile: Optional[str] = None
    extensions: list[tuple[str, str]] = field(default_factory=list)
    # where the #version and each #extension directive stand (for error messages)
    version_loc: Optional[SourceLoc] = field(default=None, compare=False, repr=False)
    extension_locs: list[SourceLoc] = field(default_factory=list, compare=False, repr=False)


# ----------------------------------------------------------------------------- statements


@dataclass
class Stmt(Node):
    pass


@dataclass
class Compound(Stmt):
    stmts: list[Stmt]


@dataclass
class DeclStmt(Stmt):
    decl: Declaration


@dataclass
class ExprStmt(Stmt):
    """An expression statement; ``expr`` is ``None`` for the empty statement ``;``."""

    expr: Optional["Expr"]


@dataclass
class If(Stmt):
    cond: "Expr"
    then: Stmt
    else_: Optional[Stmt] = None


@dataclass
class For(Stmt):
    """``init`` is a DeclStmt or ExprStmt (or None); ``cond`` an expression or, rarely, a
    condition declaration (``VariableDecl`` with one initialised declarator)."""

    init: Optional[Stmt]
    cond: Optional[Union["Expr", VariableDecl]]
    step: Optional["Expr"]
    body: Stmt


@dataclass
class While(Stmt):
    cond: Union["Expr", VariableDecl]
    body: Stmt


@dataclass
class DoWhile(Stmt):
    body: Stmt
    cond: "Expr"


@dataclass
class Switch(Stmt):
    expr: "Expr"
    body: Compound


@dataclass
class Case(Stmt):
    """``case expr:`` label; ``expr`` is ``None`` for ``default:``."""

    expr: Optional["Expr"]


@dataclass
class Break(Stmt):
    pass


@dataclass
class Continue(Stmt):
    pass


@dataclass
class Return(Stmt):
    expr: Optional["Expr"] = None


@dataclass
class Discard(Stmt):
    pass


# ----------------------------------------------------------------------------- expressions


@dataclass
class Expr(Node):
    # The GLSL type, filled in by semantic analysis (a rrcache.glsl.types.Type).
    type: Any = field(default=None, compare=False, repr=False, kw_only=True)


@dataclass
class Ident(Expr):
    name: str
    # What the name refers to (a rrcache.glsl.semantic.Symbol), set by semantic analysis.
    symbol: Any = field(default=None, compare=False, repr=False)


@dataclass
class IntLit(Expr):
    """An integer literal. ``text`` is the spelling (``0x1Fu``) kept for printing."""

    value: int
    unsigned: bool = False
    text: Optional[str] = field(default=None, compare=False)


@dataclass
class FloatLit(Expr):
    """A floating-point literal. ``double`` for the ``lf``/``LF`` suffix. ``text`` is the
    spelling kept for printing."""

    value: float
    double: bool = False
    text: Optional[str] = field(default=None, compare=False)


@dataclass
class BoolLit(Expr):
    value: bool


@dataclass
class Unary(Expr):
    """``op`` in ``+ - ! ~ ++ --``; ``postfix`` for ``a++`` / ``a--``."""

    op: str
    operand: Expr
    postfix: bool = False


@dataclass
class Binary(Expr):
    """``op`` in ``* / % + - << >> < > <= >= == != & ^ | && ^^ ||``."""

    op: str
    left: Expr
    right: Expr


@dataclass
class Assign(Expr):
    """``op`` in ``= += -= *= /= %= <<= >>= &= ^= |=``."""

    op: str
    target: Expr
    value: Expr


@dataclass
class Ternary(Expr):
    cond: Expr
    then: Expr
    else_: Expr


@dataclass
class Sequence(Expr):
    """The comma operator: ``a, b, c``."""

    exprs: list[Expr]


@dataclass
class Call(Expr):
    """A function call or a constructor: ``name(args)``. Array constructors (``float[3](...)``)
    set ``array_dims``. Whether ``name`` is a function, a built-in, a type or a struct is decided
    by semantic analysis (it sets ``kind`` to ``"function"``, ``"builtin"`` or
    ``"constructor"``)."""

    name: str
    args: list[Expr]
    array_dims: Optional[list[Optional[Expr]]] = None
    kind: Optional[str] = field(default=None, compare=False, repr=False)
    # The FunctionDecl (user function) or built-in signature the call resolves to, set by
    # semantic analysis.
    target: Any = field(default=None, compare=False, repr=False)


@dataclass
class Field(Expr):
    """``obj.name``: a struct member or a swizzle."""

    obj: Expr
    name: str


@dataclass
class Index(Expr):
    obj: Expr
    index: Expr


@dataclass
class Length(Expr):
    """``obj.length()``"""

    obj: Expr


@dataclass
class InitList(Expr):
    """``{a, b, c}`` initializer list (GLSL 4.20+)."""

    items: list[Expr]


# ----------------------------------------------------------------------------- traversal

#: Field annotations that can never hold a node (names, operators, literal values, spellings).
_SCALAR_ANNOTATIONS = frozenset({"str", "bool", "int", "float", "Optional[str]", "Optional[int]",
                                 "list[str]", "list[tuple[str, str]]", "list[SourceLoc]"})


class _FieldTable(dict):
    """``class -> names of its syntax child fields``, filled on first use of a class."""

    def __init__(self, decl_types: bool):
        super().__init__()
        self.decl_types = decl_types

    def __missing__(self, cls: type) -> tuple[str, ...]:
        names = tuple(f.name for f in fields(cls)
                      if f.compare and f.type not in _SCALAR_ANNOTATIONS
                      and (self.decl_types or not f.metadata.get("decl_type")))
        self[cls] = names
        return names


_WITH_TYPES = _FieldTable(True)
_WITHOUT_TYPES = _FieldTable(False)


def child_fields(cls: type, decl_types: bool = True) -> tuple[str, ...]:
    """The names of the fields of node class ``cls`` that hold syntax children, in source order
    (declaration types left out with ``decl_types=False``; see the module docstring)."""
    return (_WITH_TYPES if decl_types else _WITHOUT_TYPES)[cls]


def children(node: Node, decl_types: bool = True) -> list[Node]:
    """The direct syntax children of ``node`` in source order (items of list fields, and nodes
    inside the tuples of ``Layout.items``, included)."""
    out = []
    node_cls = Node
    d = node.__dict__
    for name in (_WITH_TYPES if decl_types else _WITHOUT_TYPES)[node.__class__]:
        value = d[name]
        if value is None:
            continue
        if isinstance(value, node_cls):
            out.append(value)
        elif value.__class__ is list:
            for item in value:
                if isinstance(item, node_cls):
                    out.append(item)
                elif item.__class__ is tuple:
                    out.extend(sub for sub in item if isinstance(sub, node_cls))
    return out


def walk(node: Node, decl_types: bool = True) -> Iterator[Node]:
    """``node`` and its syntax descendants, pre-order (iterative: deep trees are fine)."""
    stack = [node]
    pop, extend = stack.pop, stack.extend
    while stack:
        n = pop()
        yield n
        kids = children(n, decl_types)
        if kids:
            kids.reverse()
            extend(kids)


def post_order(node: Node, decl_types: bool = True) -> Iterator[Node]:
    """``node`` and its descendants, children (left to right) before their parent: the order in
    which an expression's operands are evaluated."""
    for child in children(node, decl_types):
        yield from post_order(child, decl_types)
    yield node


def iter_exprs(node: Node) -> Iterator["Expr"]:
    """Every expression under ``node`` in pre-order, declaration types left out: the order that
    numbers the analysis' node ids."""
    expr_cls = Expr
    for n in walk(node, decl_types=False):
        if isinstance(n, expr_cls):
            yield n


def substitute(node: Node, pred: Callable[[Node], bool], make: Callable[[Node], Node]) -> int:
    """Replace, in place, every descendant ``n`` of ``node`` with ``pred(n)`` true by
    ``make(n)`` (the replacement is not searched again). Returns the number replaced."""
    count = 0
    for name in _WITH_TYPES[node.__class__]:
        value = getattr(node, name)
        if isinstance(value, Node):
            if pred(value):
                setattr(node, name, make(value))
                count += 1
            else:
                count += substitute(value, pred, make)
        elif isinstance(value, list):
            for i, item in enumerate(value):
                if isinstance(item, Node):
                    if pred(item):
                        value[i] = make(item)
                        count += 1
                    else:
                        count += substitute(item, pred, make)
                elif isinstance(item, tuple):
                    new = []
                    for sub in item:
                        if isinstance(sub, Node) and pred(sub):
                            new.append(make(sub))
                            count += 1
                        else:
                            if isinstance(sub, Node):
                                count += substitute(sub, pred, make)
                            new.append(sub)
                    value[i] = tuple(new)
    return count


def contains(node: Optional[Node], pred: Callable[[Node], bool]) -> bool:
    """Whether ``node`` or a descendant satisfies ``pred``."""
    return node is not None and any(pred(n) for n in walk(node))


def is_ident(name: str) -> Callable[[Node], bool]:
    """A predicate: the node is the identifier ``name``."""
    return lambda n: isinstance(n, Ident) and n.name == name


def is_literal(e: Node) -> bool:
    """Whether ``e`` is an ``int``/``uint``, float or bool literal."""
    return isinstance(e, (IntLit, FloatLit, BoolLit))


# ----------------------------------------------------------------------------- statements


def own_parts(s: Stmt) -> list[Node]:
    """The parts a statement evaluates itself (not its sub-statements), in evaluation order: an
    expression statement's expression, a declaration, the condition of ``if``/``while``/
    ``do``-``while``, ``switch``'s selector, ``return``'s value, and a ``for``'s init, condition
    and step (the condition and step once per iteration).

    >>> from rrcache.glsl.parser import parse_source
    >>> loop = parse_source("void main() { for (int i = 0; i < 3; i++) {} }").decls[0].body.stmts[0]
    >>> [type(p).__name__ for p in own_parts(loop)]
    ['DeclStmt', 'Binary', 'Unary']
    """
    return [p for p in (getattr(s, f) for f in _OWN_PARTS.get(s.__class__, ())) if p is not None]


#: the fields of each statement class that :func:`own_parts` and :func:`branches` give
_OWN_PARTS = {ExprStmt: ("expr",), DeclStmt: ("decl",), If: ("cond",), For: ("init", "cond", "step"),
              While: ("cond",), DoWhile: ("cond",), Switch: ("expr",), Return: ("expr",),
              Case: ("expr",)}
_BRANCHES = {If: ("then", "else_"), For: ("body",), While: ("body",), DoWhile: ("body",),
             Switch: ("body",)}


def branches(s: Stmt) -> list[tuple[str, Stmt]]:
    """The sub-statements of ``if``, the loops and ``switch`` as ``(field name, statement)``
    (a block's statements are ``s.stmts``)."""
    return [(f, getattr(s, f)) for f in _BRANCHES.get(s.__class__, ()) if getattr(s, f) is not None]


def main_function(unit: TranslationUnit) -> Optional[FunctionDecl]:
    """The definition of ``void main()``, or None."""
    for d in unit.decls:
        if isinstance(d, FunctionDecl) and d.name == "main" and d.body is not None:
            return d
    return None
