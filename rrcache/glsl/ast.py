"""The GLSL abstract syntax tree.

Plain dataclasses, one per construct. Every node carries ``loc`` (a :class:`SourceLoc` in the
*original* file, after preprocessing and includes), which is excluded from equality so that
``parse(print(parse(src))) == parse(src)`` compares structure only. Expression nodes also carry
``type``, filled in by semantic analysis (:mod:`rrcache.glsl.semantic`), likewise excluded from
equality.

Qualifiers are kept as an ordered list of words (``"const"``, ``"uniform"``, ``"highp"``,
``"flat"``, ``"centroid"``, ...) and :class:`Layout` objects, exactly as written, so the printer
reproduces them in their source order.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, Iterator, Optional, Union

from rrcache.errors import SourceLoc


@dataclass
class Node:
    loc: Optional[SourceLoc] = field(default=None, compare=False, repr=False, kw_only=True)

    def children(self) -> Iterator["Node"]:
        """Direct child nodes, in source order."""
        skip = ("loc", "type") if isinstance(self, Expr) else ("loc",)
        for f in fields(self):
            if f.name in skip or not f.compare:
                continue
            value = getattr(self, f.name)
            if isinstance(value, Node):
                yield value
            elif isinstance(value, list):
                for item in value:
                    if isinstance(item, Node):
                        yield item
                    elif isinstance(item, tuple):
                        for sub in item:
                            if isinstance(sub, Node):
                                yield sub

    def walk(self) -> Iterator["Node"]:
        """This node and all its descendants, pre-order (iterative: a chain of 100,000 binary
        operators walks without recursion)."""
        stack = [self]
        pop, extend = stack.pop, stack.extend
        while stack:
            node = pop()
            yield node
            kids = list(node.children())
            kids.reverse()
            extend(kids)


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
    type: FullType
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

    type: FullType
    declarators: list[Declarator]


@dataclass
class Param(Node):
    type: FullType
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
