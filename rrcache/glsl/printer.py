"""GLSL printer: the AST of :mod:`rrcache.glsl.ast` back to source text.

:func:`print_glsl` writes readable GLSL (4-space indentation, one statement a line) with the
fewest parentheses that make a re-parse give the same tree: each expression is printed with the
precedence its context needs and wrapped in ``(...)`` only when its own precedence is lower.
Literals are re-printed from their ``text`` when it still matches their value; generated floats
are always valid float literals (``1.0``, ``2.5e-07``). :func:`print_with_map` also returns, for
each printed line, the :class:`~rrcache.errors.SourceLoc` of the statement or declaration printed
there, so that driver error logs can be mapped back to the original file.
"""
from __future__ import annotations

import math
from typing import Optional

from rrcache.errors import SourceLoc
from rrcache.glsl import ast as A
from rrcache.glsl.parser import BINARY_PRECEDENCE
from rrcache.glsl.visitor import NodeVisitor

INDENT = "    "

# Precedence levels used for parenthesisation (higher binds tighter).
P_SEQUENCE, P_ASSIGN, P_TERNARY, P_UNARY, P_POSTFIX, P_PRIMARY = 0, 1, 2, 14, 15, 16


def _float_text(value: float, double: bool) -> str:
    if math.isnan(value):
        text = "(0.0 / 0.0)"
    elif math.isinf(value):
        text = "(1.0 / 0.0)" if value > 0 else "(-1.0 / 0.0)"
    else:
        text = repr(float(value))
        if "." not in text and "e" not in text and "E" not in text:
            text += ".0"
    return text + "lf" if double and text[-1] != ")" else text


def _literal_ok(text: Optional[str], value, is_float: bool) -> bool:
    """Whether a kept spelling still denotes ``value`` (a pass may have changed the value)."""
    if not text:
        return False
    try:
        if is_float:
            stripped = text.rstrip("fFlLhH")
            return float(stripped) == value
        stripped = text.rstrip("uUlL")
        if stripped[:2].lower() == "0x":
            return int(stripped, 16) == value
        if len(stripped) > 1 and stripped[0] == "0":
            return int(stripped, 8) == value
        return int(stripped) == value
    except ValueError:
        return False


class _Precedence(NodeVisitor):
    """The precedence level of an expression node."""

    def visit_Sequence(self, e) -> int:
        return P_SEQUENCE

    def visit_Assign(self, e) -> int:
        return P_ASSIGN

    def visit_Ternary(self, e) -> int:
        return P_TERNARY

    def visit_Binary(self, e: A.Binary) -> int:
        return BINARY_PRECEDENCE[e.op]

    def visit_Unary(self, e: A.Unary) -> int:
        return P_POSTFIX if e.postfix else P_UNARY

    def visit_Index(self, e) -> int:
        return P_POSTFIX

    visit_Field = visit_Length = visit_Call = visit_Index

    def visit_IntLit(self, e) -> int:
        return P_UNARY if e.value < 0 else P_PRIMARY

    visit_FloatLit = visit_IntLit

    def generic_visit(self, e) -> int:
        return P_PRIMARY


def expr_precedence(e: A.Expr) -> int:
    """The precedence level of an expression node (see the ``P_*`` constants).

    >>> expr_precedence(A.Binary("+", A.Ident("a"), A.Ident("b"))) < expr_precedence(A.Ident("a"))
    True
    """
    return _PRECEDENCE.visit(e)


def print_expr(e: A.Expr, need: int = P_SEQUENCE) -> str:
    """Print an expression, parenthesised when its precedence is below ``need``.

    >>> print_expr(A.Binary("*", A.Binary("+", A.Ident("a"), A.Ident("b")), A.Ident("c")))
    '(a + b) * c'
    """
    text = _expr(e)
    return f"({text})" if _PRECEDENCE.visit(e) < need else text


def _dims(dims, pe=None) -> str:
    pe = pe or print_expr
    if not dims:
        return ""
    return "".join("[]" if d is None else f"[{pe(d)}]" for d in dims)


class _ExprText(NodeVisitor):
    """The text of an expression unparenthesised; ``pe`` prints its operands, ``spine`` says
    whether a ``Binary`` left operand may be printed down the spine (see :func:`_expr`)."""

    def visit_Ident(self, e: A.Ident, pe, spine) -> str:
        return e.name

    def visit_IntLit(self, e: A.IntLit, pe, spine) -> str:
        if _literal_ok(e.text, e.value, False) and ("u" in e.text[-2:].lower()) == e.unsigned:
            return e.text
        return f"{e.value}{'u' if e.unsigned else ''}"

    def visit_FloatLit(self, e: A.FloatLit, pe, spine) -> str:
        if _literal_ok(e.text, e.value, True) and e.text.lower().endswith("lf") == e.double:
            return e.text
        return _float_text(e.value, e.double)

    def visit_BoolLit(self, e: A.BoolLit, pe, spine) -> str:
        return "true" if e.value else "false"

    def visit_Binary(self, e: A.Binary, pe, spine) -> str:
        # down the left spine without recursion: `a + 1.0 + 1.0 + ...` (100,000 terms) prints
        tails = []
        binary = A.Binary
        while True:
            p = BINARY_PRECEDENCE[e.op]
            tails.append(f" {e.op} {pe(e.right, p + 1)}")
            left = e.left
            if spine and left.__class__ is binary and BINARY_PRECEDENCE[left.op] >= p:
                e = left
                continue
            tails.append(pe(left, p))
            break
        tails.reverse()
        return "".join(tails)

    def visit_Unary(self, e: A.Unary, pe, spine) -> str:
        if e.postfix:
            return pe(e.operand, P_POSTFIX) + e.op
        inner = pe(e.operand, P_UNARY)
        if e.op in ("+", "-", "++", "--") and inner[:1] in ("+", "-"):
            inner = f"({inner})"
        return e.op + inner

    def visit_Assign(self, e: A.Assign, pe, spine) -> str:
        return f"{pe(e.target, P_TERNARY + 1)} {e.op} {pe(e.value, P_ASSIGN)}"

    def visit_Ternary(self, e: A.Ternary, pe, spine) -> str:
        return (f"{pe(e.cond, P_TERNARY + 1)} ? {pe(e.then, P_SEQUENCE)} : "
                f"{pe(e.else_, P_ASSIGN)}")

    def visit_Sequence(self, e: A.Sequence, pe, spine) -> str:
        return ", ".join(pe(x, P_ASSIGN) for x in e.exprs)

    def visit_Call(self, e: A.Call, pe, spine) -> str:
        args = ", ".join(pe(a, P_ASSIGN) for a in e.args)
        return f"{e.name}{_dims(e.array_dims, pe)}({args})"

    def _obj(self, e, pe) -> str:
        obj = pe(e.obj, P_POSTFIX)
        if isinstance(e.obj, (A.IntLit, A.FloatLit)) and not obj.startswith("("):
            obj = f"({obj})"
        return obj

    def visit_Field(self, e: A.Field, pe, spine) -> str:
        return f"{self._obj(e, pe)}.{e.name}"

    def visit_Length(self, e: A.Length, pe, spine) -> str:
        return f"{self._obj(e, pe)}.length()"

    def visit_Index(self, e: A.Index, pe, spine) -> str:
        return f"{self._obj(e, pe)}[{pe(e.index)}]"

    def visit_InitList(self, e: A.InitList, pe, spine) -> str:
        return "{" + ", ".join(pe(x, P_ASSIGN) for x in e.items) + "}"

    def generic_visit(self, e, pe, spine) -> str:
        raise TypeError(f"cannot print {type(e).__name__} as an expression")


_PRECEDENCE = _Precedence()
_EXPR_TEXT = _ExprText()


def _expr(e: A.Expr, pe=None) -> str:
    """The text of ``e`` unparenthesised; its operands are printed by ``pe`` (default
    :func:`print_expr`; :func:`memo_printer` passes its own, and then a ``Binary`` operand is
    printed by ``pe`` instead of down the left spine, which gives the same text)."""
    return _EXPR_TEXT.visit(e, pe or print_expr, pe is None)


def memo_printer(ident_text=None):
    """A :func:`print_expr` that remembers the text of every expression it prints (by ``id``),
    so that printing every node of a tree, each with its operands, costs each node's own text
    once. Only for a tree that stays alive and unchanged while the printer is used; recursive,
    so for expressions of bounded depth (the node table's texts of at most a few hundred nodes).
    ``ident_text(ident, need)``, when given, may print an identifier otherwise (a text, or None
    to print its name).

    >>> pe = memo_printer()
    >>> e = A.Binary("*", A.Binary("+", A.Ident("a"), A.Ident("b")), A.Ident("c"))
    >>> pe(e), pe(e.left), pe(e.left, P_POSTFIX)
    ('(a + b) * c', 'a + b', '(a + b)')
    >>> memo_printer(lambda i, need: "x" if i.name == "b" else None)(e)
    '(a + x) * c'
    """
    cache: dict[int, str] = {}
    get = cache.get
    precedence = _PRECEDENCE.visit
    ident = A.Ident

    def pe(e: A.Expr, need: int = P_SEQUENCE) -> str:
        if ident_text is not None and e.__class__ is ident:
            text = ident_text(e, need)
            if text is not None:
                return text
        text = get(id(e))
        if text is None:
            text = cache[id(e)] = _expr(e, pe)
        return f"({text})" if precedence(e) < need else text

    return pe


def _qualifiers(quals) -> str:
    words = []
    for q in quals:
        if isinstance(q, A.Layout):
            items = ", ".join(n if v is None else f"{n} = {print_expr(v, P_TERNARY)}"
                              for n, v in q.items)
            words.append(f"layout({items})")
        else:
            words.append(q)
    return " ".join(words)


def _join(*parts: str) -> str:
    return " ".join(p for p in parts if p)


def _declarators(decls: list[A.Declarator]) -> str:
    out = []
    for d in decls:
        text = d.name + _dims(d.array_dims)
        if d.init is not None:
            text += " = " + print_expr(d.init, P_ASSIGN)
        out.append(text)
    return ", ".join(out)


class _InlineDecl(NodeVisitor):
    """A declaration on one line, without the final ';' (for-loop initialisers)."""

    def __init__(self, printer: "_Printer"):
        self.p = printer

    def visit_VariableDecl(self, d: A.VariableDecl) -> str:
        return _join(self.p.type_inline(d.type), _declarators(d.declarators))

    def visit_PrecisionDecl(self, d: A.PrecisionDecl) -> str:
        return f"precision {d.precision} {self.p.spec_inline(d.spec)}"

    def visit_QualifierDecl(self, d: A.QualifierDecl) -> str:
        return _join(_qualifiers(d.qualifiers), ", ".join(d.names))

    def generic_visit(self, d) -> str:
        raise TypeError(f"cannot print {type(d).__name__} on one line")


class _Printer(NodeVisitor):
    """Visiting a declaration or a statement emits its lines."""

    def __init__(self) -> None:
        self.lines: list[tuple[str, Optional[SourceLoc]]] = []
        self.level = 0
        self.decl_inline = _InlineDecl(self).visit

    def emit(self, text: str, loc: Optional[SourceLoc]) -> None:
        self.lines.append((INDENT * self.level + text if text else "", loc))

    # ------------------------------------------------------------------ types
    def struct_inline(self, s: A.StructSpecifier) -> str:
        members = " ".join(f"{self.type_inline(m.type)} {_declarators(m.declarators)};"
                           for m in s.members)
        return _join("struct", s.name or "", "{ " + members + " }")

    def spec_inline(self, spec: A.TypeSpecifier) -> str:
        base = self.struct_inline(spec.struct) if spec.struct else spec.name
        return base + _dims(spec.array_dims)

    def type_inline(self, t: A.FullType) -> str:
        return _join(_qualifiers(t.qualifiers), self.spec_inline(t.spec))

    def members(self, members: list[A.StructMember]) -> None:
        self.level += 1
        for m in members:
            if m.type.spec.struct is not None:
                self.block_decl(_qualifiers(m.type.qualifiers), m.type.spec.struct,
                                m.type.spec.array_dims, _declarators(m.declarators), m.loc)
            else:
                self.emit(f"{self.type_inline(m.type)} {_declarators(m.declarators)};", m.loc)
        self.level -= 1

    def block_decl(self, quals: str, s: A.StructSpecifier, spec_dims, tail: str, loc) -> None:
        self.emit(_join(quals, "struct", s.name or "", "{"), loc)
        self.members(s.members)
        self.emit(_join("}" + _dims(spec_dims), tail) + ";", None)

    # ------------------------------------------------------------------ declarations
    def visit_FunctionDecl(self, d: A.FunctionDecl) -> None:
        params = ", ".join(
            _join(self.type_inline(p.type), (p.name or "") + _dims(p.array_dims))
            for p in d.params)
        head = f"{self.type_inline(d.return_type)} {d.name}({params})"
        if d.body is None:
            self.emit(head + ";", d.loc)
        else:
            self.emit(head, d.loc)
            self.visit_Compound(d.body)

    def visit_InterfaceBlock(self, d: A.InterfaceBlock) -> None:
        self.emit(_join(_qualifiers(d.qualifiers), d.block_name, "{"), d.loc)
        self.members(d.members)
        tail = (d.instance_name or "") + _dims(d.array_dims)
        self.emit(_join("}", tail) + ";", None)

    def visit_VariableDecl(self, d: A.VariableDecl) -> None:
        if d.type.spec.struct is not None:
            self.block_decl(_qualifiers(d.type.qualifiers), d.type.spec.struct,
                            d.type.spec.array_dims, _declarators(d.declarators), d.loc)
        else:
            self.emit(self.decl_inline(d) + ";", d.loc)

    def visit_PrecisionDecl(self, d) -> None:
        self.emit(self.decl_inline(d) + ";", d.loc)

    visit_QualifierDecl = visit_PrecisionDecl

    # ------------------------------------------------------------------ statements
    def visit_Compound(self, c: A.Compound, switch: bool = False) -> None:
        self.emit("{", c.loc)
        self.level += 1
        in_case = False
        for s in c.stmts:
            if switch and isinstance(s, A.Case):
                if in_case:
                    self.level -= 1
                self.visit(s)
                self.level += 1
                in_case = True
            else:
                self.visit(s)
        if in_case:
            self.level -= 1
        self.level -= 1
        self.emit("}", None)

    def sub(self, s: A.Stmt) -> None:
        if isinstance(s, A.Compound):
            self.visit_Compound(s)
        else:
            self.level += 1
            self.visit(s)
            self.level -= 1

    def visit_DeclStmt(self, s: A.DeclStmt) -> None:
        self.visit(s.decl)

    def visit_ExprStmt(self, s: A.ExprStmt) -> None:
        self.emit(";" if s.expr is None else print_expr(s.expr) + ";", s.loc)

    def visit_If(self, s: A.If) -> None:
        self.emit(f"if ({print_expr(s.cond)})", s.loc)
        then = s.then
        if s.else_ is not None and _DANGLES.visit(then):
            then = A.Compound([then], loc=then.loc)
        self.sub(then)
        if s.else_ is not None:
            self.emit("else", None)
            self.sub(s.else_)

    def visit_For(self, s: A.For) -> None:
        if s.init is None:
            init = ""
        elif isinstance(s.init, A.DeclStmt):
            init = self.decl_inline(s.init.decl)
        else:
            init = "" if s.init.expr is None else print_expr(s.init.expr)
        step = "" if s.step is None else " " + print_expr(s.step)
        self.emit(f"for ({init}; {self.condition(s.cond)};{step})".replace("; ;", ";;"), s.loc)
        self.sub(s.body)

    def visit_While(self, s: A.While) -> None:
        self.emit(f"while ({self.condition(s.cond)})", s.loc)
        self.sub(s.body)

    def visit_DoWhile(self, s: A.DoWhile) -> None:
        self.emit("do", s.loc)
        self.sub(s.body)
        self.emit(f"while ({print_expr(s.cond)});", None)

    def visit_Switch(self, s: A.Switch) -> None:
        self.emit(f"switch ({print_expr(s.expr)})", s.loc)
        self.visit_Compound(s.body, switch=True)

    def visit_Case(self, s: A.Case) -> None:
        self.emit("default:" if s.expr is None else f"case {print_expr(s.expr, P_TERNARY)}:", s.loc)

    def visit_Return(self, s: A.Return) -> None:
        self.emit("return;" if s.expr is None else f"return {print_expr(s.expr)};", s.loc)

    def visit_Break(self, s: A.Break) -> None:
        self.emit("break;", s.loc)

    def visit_Continue(self, s: A.Continue) -> None:
        self.emit("continue;", s.loc)

    def visit_Discard(self, s: A.Discard) -> None:
        self.emit("discard;", s.loc)

    def generic_visit(self, s) -> None:
        raise TypeError(f"cannot print {type(s).__name__} as a statement")

    def condition(self, c) -> str:
        if c is None:
            return ""
        if isinstance(c, A.VariableDecl):
            return self.decl_inline(c)
        return print_expr(c)


class _Dangles(NodeVisitor):
    """Whether an ``else`` printed after a statement would attach to an ``if`` inside it."""

    def visit_If(self, s: A.If) -> bool:
        return s.else_ is None or self.visit(s.else_)

    def visit_For(self, s) -> bool:
        return self.visit(s.body)

    visit_While = visit_For

    def generic_visit(self, s) -> bool:
        return False


_DANGLES = _Dangles()


def _header(unit: A.TranslationUnit) -> list[tuple[str, Optional[SourceLoc]]]:
    lines = []
    if unit.version is not None:
        profile = unit.profile
        if profile == "es" and unit.version < 300:
            profile = None
        if profile in ("core", "compatibility") and unit.version < 150:
            profile = None
        lines.append((_join(f"#version {unit.version}", profile or ""), unit.version_loc))
    locs = list(unit.extension_locs) + [None] * (len(unit.extensions) - len(unit.extension_locs))
    for (name, behavior), loc in zip(unit.extensions, locs):
        lines.append((f"#extension {name} : {behavior}", loc))
    return lines


def print_with_map(unit: A.TranslationUnit) -> tuple[str, list[Optional[SourceLoc]]]:
    """Print a unit and map each printed line to the place it came from.

    ``line_map[i]`` is the SourceLoc of the statement or declaration on printed line ``i + 1``,
    or None (blank lines, closing braces, lines rrcache generated); the ``#version`` and
    ``#extension`` lines map to their directives.

    >>> from rrcache.glsl.parser import parse_source
    >>> text, line_map = print_with_map(parse_source("void main()\\n{ gl_FragColor = vec4(1.0); }", "a.frag"))
    >>> text.splitlines()[2], str(line_map[2])
    ('    gl_FragColor = vec4(1.0);', 'a.frag:2:3')
    """
    p = _Printer()
    for line, loc in _header(unit):
        p.emit(line, loc)
    prev = None
    for d in unit.decls:
        spacious = isinstance(d, (A.FunctionDecl, A.InterfaceBlock)) or (
            isinstance(d, A.VariableDecl) and d.type.spec.struct is not None)
        if p.lines and (spacious or prev) and p.lines[-1][0]:
            p.emit("", None)
        p.visit(d)
        prev = spacious
    text = "\n".join(line for line, _ in p.lines) + "\n"
    return text, [loc for _, loc in p.lines]


def print_glsl(unit: A.TranslationUnit) -> str:
    """Print a unit as GLSL source.

    >>> from rrcache.glsl.parser import parse_source
    >>> print(print_glsl(parse_source("float f(float x){return (x*(x+1.0));}")), end="")
    float f(float x)
    {
        return x * (x + 1.0);
    }
    """
    return print_with_map(unit)[0]
