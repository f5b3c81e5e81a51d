"""GLSL parser: tokens to the AST of :mod:`rrcache.glsl.ast`.

A recursive-descent parser for fragment shaders in GLSL 1.10–4.60 and GLSL ES 1.00/3.00, with
precedence climbing for binary operators. Every node gets the location of its first token.
A statement that starts with a built-in type name or a struct name in scope followed by an
identifier (after optional ``[...]``) is a declaration; otherwise it is an expression (a
constructor call such as ``vec3(1.0)`` or ``float[2](a, b)``).

Syntax errors raise exactly one :class:`~rrcache.errors.ParseError` at the offending token, e.g.
``shader.frag:4:12: expected ';' after declaration, found 'x'``. Errors at the end of the input
point just past the last token.
"""
from __future__ import annotations

import sys
from typing import Optional, Sequence as Seq

from rrcache.errors import ParseError, SourceLoc
from rrcache.glsl import ast as A
from rrcache.glsl.preprocessor import preprocess
from rrcache.glsl.lexer import (
    MEMORY_QUALIFIERS, PRECISION_QUALIFIERS, QUALIFIER_WORDS, TYPE_NAMES, Token, lex,
)
from rrcache.glsl.types import SOFT_TYPE_NAMES

#: Binary operator precedence (higher binds tighter); all are left-associative.
BINARY_PRECEDENCE: dict[str, int] = {
    "||": 3, "^^": 4, "&&": 5, "|": 6, "^": 7, "&": 8,
    "==": 9, "!=": 9, "<": 10, ">": 10, "<=": 10, ">=": 10,
    "<<": 11, ">>": 11, "+": 12, "-": 12, "*": 13, "/": 13, "%": 13,
}
ASSIGN_OPS = frozenset({"=", "+=", "-=", "*=", "/=", "%=", "<<=", ">>=", "&=", "^=", "|="})
PREFIX_OPS = frozenset({"+", "-", "!", "~", "++", "--"})
PARAM_QUALIFIERS = frozenset({"const", "in", "out", "inout", "precise", "nonuniformEXT"}) \
    | PRECISION_QUALIFIERS \
    | MEMORY_QUALIFIERS

#: Deepest nesting of expressions/statements accepted before a ParseError.
MAX_DEPTH = 120


#: what to check when an expected punctuator is missing (the error names the token found instead)
_EXPECT_HINTS = {
    ";": "every statement and declaration ends with ';': is one missing just before here?",
    ")": "check that the parentheses are balanced",
    "]": "check that the brackets are balanced",
    "}": "check that the braces are balanced",
}


def _describe(tok: Token) -> str:
    return "end of file" if tok.kind == "eof" else f"'{tok.text}'"


class _Parser:
    def __init__(self, tokens: Seq[Token]):
        toks = list(tokens)
        if not toks or toks[-1].kind != "eof":
            last = toks[-1].loc if toks else SourceLoc("<string>", 1, 1)
            end = SourceLoc(last.file, last.line, last.col + (len(toks[-1].text) if toks else 0))
            toks.append(Token("eof", "", None, end))
        self.toks = toks
        self.pos = 0
        self.scopes: list[set[str]] = [set()]
        self.depth = 0

    # ------------------------------------------------------------------ token helpers
    @property
    def tok(self) -> Token:
        return self.toks[self.pos]

    def peek(self, n: int = 1) -> Token:
        return self.toks[min(self.pos + n, len(self.toks) - 1)]

    def at(self, text: str) -> bool:
        t = self.toks[self.pos]
        return t.text == text and t.kind in ("punct", "keyword")

    def advance(self) -> Token:
        t = self.toks[self.pos]
        if t.kind != "eof":
            self.pos += 1
        return t

    def accept(self, text: str) -> Optional[Token]:
        if self.at(text):
            return self.advance()
        return None

    def error(self, message: str, tok: Optional[Token] = None, hint: Optional[str] = None):
        tok = tok or self.tok
        return ParseError(message, tok.loc, hint)

    def expect(self, text: str, context: str, hint: Optional[str] = None) -> Token:
        if self.at(text):
            return self.advance()
        raise self.error(f"expected '{text}' {context}, found {_describe(self.tok)}",
                         hint=hint or _EXPECT_HINTS.get(text))

    def expect_ident(self, context: str) -> Token:
        t = self.tok
        if t.kind == "ident":
            return self.advance()
        if t.kind == "keyword":
            raise self.error(f"expected a name {context}, found keyword '{t.text}'",
                             hint="keywords cannot be used as names")
        raise self.error(f"expected a name {context}, found {_describe(t)}")

    def enter(self) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.error("nesting too deep", hint=f"at most {MAX_DEPTH} nested levels are supported")

    # ------------------------------------------------------------------ scopes
    def is_struct(self, name: str) -> bool:
        return any(name in s for s in self.scopes)

    def is_soft_type(self, i: int = 0) -> bool:
        """Whether the identifier at ``i`` is a Vulkan type word (``sampler``, ``texture2D``...)
        used as a type: only when a declared name follows it (``uniform sampler s;``), so the
        same word stays a variable or function name elsewhere (``texture(sampler, uv)``)."""
        t = self.peek(i)
        return (t.kind == "ident" and t.text in SOFT_TYPE_NAMES and not self.is_struct(t.text)
                and self.peek(self.skip_dims(i + 1)).kind == "ident")

    def is_named_type(self, i: int = 0) -> bool:
        """A struct name or a Vulkan type word in type position at ``i``."""
        t = self.peek(i)
        return t.kind == "ident" and (self.is_struct(t.text) or self.is_soft_type(i))

    def is_type_start(self, i: int = 0) -> bool:
        t = self.peek(i)
        return (t.kind == "keyword" and (t.text in TYPE_NAMES or t.text == "struct")) or (
            self.is_named_type(i))

    def skip_dims(self, i: int) -> int:
        """Index (relative to pos) after any balanced ``[...]`` groups starting at ``i``."""
        while self.peek(i).text == "[" and self.peek(i).kind == "punct":
            level = 0
            while True:
                t = self.peek(i)
                if t.kind == "eof":
                    return i
                if t.kind == "punct" and t.text == "[":
                    level += 1
                elif t.kind == "punct" and t.text == "]":
                    level -= 1
                    if level == 0:
                        i += 1
                        break
                i += 1
        return i

    def looks_like_declaration(self) -> bool:
        t = self.tok
        if t.kind == "keyword" and t.text == "nonuniformEXT" and self.peek().text == "(":
            return False  # the GL_EXT_nonuniform_qualifier function-like form, an expression
        if t.kind == "keyword" and (t.text in QUALIFIER_WORDS or t.text in (
                "layout", "precision", "struct", "subroutine")):
            return True
        if self.is_type_start():
            return self.peek(self.skip_dims(1)).kind == "ident"
        return False

    # ------------------------------------------------------------------ translation unit
    def unit(self) -> A.TranslationUnit:
        start = self.tok.loc
        decls: list = []
        while self.tok.kind != "eof":
            if self.accept(";"):
                continue
            decls.append(self.external_declaration())
        return A.TranslationUnit(decls, loc=start)

    def external_declaration(self):
        t = self.tok
        if t.kind == "ident" and not self.is_named_type() and self.peek().kind == "ident":
            raise self.error(f"unknown type name '{t.text}'",
                             hint="declare the struct before using it, or check the spelling")
        if t.kind == "ident" and self.peek().text == "(":
            raise self.error(f"expected a declaration, found '{t.text}'",
                             hint="a function definition needs a return type")
        if t.kind not in ("keyword", "ident"):
            raise self.error(f"expected a declaration, found {_describe(t)}")
        return self.declaration(global_scope=True)

    # ------------------------------------------------------------------ declarations
    def declaration(self, global_scope: bool):
        start = self.tok
        if self.at("precision"):
            return self.precision_decl()
        quals = self.qualifiers()
        t = self.tok
        if quals:
            if self.at(";"):
                self.advance()
                return A.QualifierDecl(quals, [], loc=start.loc)
            if t.kind == "ident" and not self.is_named_type():
                nxt = self.peek()
                if nxt.text == "{":
                    return self.interface_block(quals, start)
                if nxt.text in (";", ","):
                    names = [self.advance().text]
                    while self.accept(","):
                        names.append(self.expect_ident("in the qualifier declaration").text)
                    self.expect(";", "after declaration")
                    return A.QualifierDecl(quals, names, loc=start.loc)
                if nxt.kind == "ident":
                    raise self.error(f"unknown type name '{t.text}'",
                                     hint="declare the struct before using it, or check the spelling")
        spec = self.type_specifier("in the declaration")
        ftype = A.FullType(quals, spec, loc=start.loc)
        if self.accept(";"):
            return A.VariableDecl(ftype, [], loc=start.loc)
        name = self.expect_ident("in the declaration")
        if self.at("("):
            if not global_scope:
                raise self.error("functions cannot be declared inside a function", name)
            return self.function(ftype, name, start)
        return self.declarator_list(ftype, name, start)

    def precision_decl(self) -> A.PrecisionDecl:
        start = self.advance()
        t = self.tok
        if not (t.kind == "keyword" and t.text in PRECISION_QUALIFIERS):
            raise self.error(f"expected lowp, mediump or highp after 'precision', found {_describe(t)}")
        self.advance()
        spec = self.type_specifier("in the precision statement")
        self.expect(";", "after precision statement")
        return A.PrecisionDecl(t.text, spec, loc=start.loc)

    def qualifiers(self) -> list:
        quals: list = []
        while True:
            t = self.tok
            if t.kind != "keyword":
                return quals
            if t.text == "layout":
                quals.append(self.layout())
            elif t.text == "subroutine":
                raise self.error("subroutines are not supported",
                                 hint="replace the subroutine with an ordinary function")
            elif t.text in QUALIFIER_WORDS:
                quals.append(self.advance().text)
            else:
                return quals

    def layout(self) -> A.Layout:
        start = self.advance()
        self.expect("(", "after 'layout'")
        items: list = []
        while True:
            t = self.tok
            if t.kind not in ("ident", "keyword"):
                raise self.error(f"expected a layout qualifier name, found {_describe(t)}")
            self.advance()
            value = None
            if self.accept("="):
                value = self.conditional()
            items.append((t.text, value))
            if self.accept(")"):
                return A.Layout(items, loc=start.loc)
            self.expect(",", "or ')' in the layout qualifier")

    def array_dims(self) -> Optional[list]:
        if not self.at("["):
            return None
        dims: list = []
        while self.at("["):
            self.advance()
            if self.accept("]"):
                dims.append(None)
                continue
            dims.append(self.expression())
            self.expect("]", "after array size")
        return dims

    def type_specifier(self, context: str) -> A.TypeSpecifier:
        t = self.tok
        if t.kind == "keyword" and t.text == "struct":
            struct = self.struct_specifier()
            return A.TypeSpecifier(None, struct, self.array_dims(), loc=t.loc)
        if (t.kind == "keyword" and t.text in TYPE_NAMES) or self.is_named_type():
            self.advance()
            return A.TypeSpecifier(t.text, None, self.array_dims(), loc=t.loc)
        if t.kind == "ident":
            raise self.error(f"unknown type name '{t.text}'",
                             hint="declare the struct before using it, or check the spelling")
        raise self.error(f"expected a type {context}, found {_describe(t)}")

    def struct_specifier(self) -> A.StructSpecifier:
        start = self.advance()
        name = None
        if self.tok.kind == "ident":
            name = self.advance().text
        elif self.tok.kind == "keyword" and not self.at("{"):
            raise self.error(f"expected a struct name or '{{', found keyword '{self.tok.text}'")
        self.expect("{", "to start the struct body")
        members = []
        if self.at("}"):
            raise self.error("a struct needs at least one member")
        while not self.accept("}"):
            members.append(self.member("in the struct"))
        if name is not None:
            self.scopes[-1].add(name)
        return A.StructSpecifier(name, members, loc=start.loc)

    def member(self, context: str) -> A.StructMember:
        start = self.tok
        if start.kind == "eof":
            raise self.error(f"expected '}}' to close the {context[3:]}, found end of file")
        quals = self.qualifiers()
        spec = self.type_specifier(f"for a member {context}")
        decls = []
        while True:
            name = self.expect_ident(f"for a member {context}")
            decls.append(A.Declarator(name.text, self.array_dims(), loc=name.loc))
            if self.accept(";"):
                break
            self.expect(",", "or ';' after member declaration")
        return A.StructMember(A.FullType(quals, spec, loc=start.loc), decls, loc=start.loc)

    def interface_block(self, quals: list, start: Token) -> A.InterfaceBlock:
        name = self.advance()
        self.expect("{", "to start the interface block")
        members = []
        while not self.accept("}"):
            members.append(self.member("in the interface block"))
        inst = dims = None
        if self.tok.kind == "ident":
            inst = self.advance().text
            dims = self.array_dims()
        self.expect(";", "after interface block")
        return A.InterfaceBlock(quals, name.text, members, inst, dims, loc=start.loc)

    def declarator_list(self, ftype: A.FullType, name: Token, start: Token) -> A.VariableDecl:
        decls = []
        while True:
            dims = self.array_dims()
            init = None
            if self.accept("="):
                init = self.initializer()
            decls.append(A.Declarator(name.text, dims, init, loc=name.loc))
            if self.accept(";"):
                return A.VariableDecl(ftype, decls, loc=start.loc)
            if not self.at(","):
                raise self.error(f"expected ';' after declaration, found {_describe(self.tok)}",
                                 hint="end the declaration with ';'")
            self.advance()
            name = self.expect_ident("after ',' in the declaration")

    def initializer(self) -> A.Expr:
        if not self.at("{"):
            return self.assignment()
        start = self.advance()
        self.enter()
        items = [self.initializer()]
        while self.accept(","):
            if self.at("}"):
                break
            items.append(self.initializer())
        self.expect("}", "to close the initializer list")
        self.depth -= 1
        return A.InitList(items, loc=start.loc)

    def function(self, ftype: A.FullType, name: Token, start: Token) -> A.FunctionDecl:
        self.advance()  # (
        params: list[A.Param] = []
        if self.at("void") and self.peek().text == ")":
            self.advance()
        if not self.at(")"):
            while True:
                params.append(self.param())
                if self.at(")"):
                    break
                self.expect(",", "or ')' after parameter")
        self.advance()  # )
        if self.accept(";"):
            return A.FunctionDecl(ftype, name.text, params, None, loc=start.loc)
        if not self.at("{"):
            raise self.error(f"expected '{{' or ';' after function header, found {_describe(self.tok)}")
        self.scopes.append(set())
        body = self.compound(new_scope=False)
        self.scopes.pop()
        return A.FunctionDecl(ftype, name.text, params, body, loc=start.loc)

    def param(self) -> A.Param:
        start = self.tok
        quals: list = []
        while self.tok.kind == "keyword" and self.tok.text in PARAM_QUALIFIERS:
            quals.append(self.advance().text)
        spec = self.type_specifier("for the parameter")
        pname = dims = None
        if self.tok.kind == "ident":
            pname = self.advance().text
            dims = self.array_dims()
        return A.Param(A.FullType(quals, spec, loc=start.loc), pname, dims, loc=start.loc)

    # ------------------------------------------------------------------ statements
    def compound(self, new_scope: bool = True) -> A.Compound:
        start = self.expect("{", "to start a block")
        self.enter()
        if new_scope:
            self.scopes.append(set())
        stmts = []
        while not self.accept("}"):
            if self.tok.kind == "eof":
                raise self.error("expected '}' to close the block, found end of file",
                                 hint=f"the block opened at line {start.loc.line} is not closed")
            stmts.append(self.statement())
        if new_scope:
            self.scopes.pop()
        self.depth -= 1
        return A.Compound(stmts, loc=start.loc)

    def scoped_statement(self) -> A.Stmt:
        """A sub-statement (if/loop body): a new scope even when it is not a block."""
        self.scopes.append(set())
        try:
            return self.statement()
        finally:
            self.scopes.pop()

    def statement(self) -> A.Stmt:
        t = self.tok
        if t.kind == "punct":
            if t.text == "{":
                return self.compound()
            if t.text == ";":
                self.advance()
                return A.ExprStmt(None, loc=t.loc)
        elif t.kind == "keyword":
            handler = _STATEMENT_HANDLERS.get(t.text)
            if handler is not None:
                self.enter()
                stmt = handler(self)
                self.depth -= 1
                return stmt
        if self.looks_like_declaration():
            return A.DeclStmt(self.declaration(global_scope=False), loc=t.loc)
        if t.kind == "ident" and self.peek().kind == "ident":
            raise self.error(f"unknown type name '{t.text}'",
                             hint="declare the struct before using it, or check the spelling")
        expr = self.expression()
        self.expect(";", "after expression")
        return A.ExprStmt(expr, loc=t.loc)

    def if_stmt(self) -> A.If:
        start = self.advance()
        self.expect("(", "after 'if'")
        cond = self.expression()
        self.expect(")", "after the if condition")
        then = self.scoped_statement()
        else_ = self.scoped_statement() if self.accept("else") else None
        return A.If(cond, then, else_, loc=start.loc)

    def condition(self):
        t = self.tok
        if self.looks_like_declaration():
            quals = self.qualifiers()
            spec = self.type_specifier("in the condition")
            name = self.expect_ident("in the condition declaration")
            self.expect("=", "in the condition declaration")
            init = self.initializer()
            return A.VariableDecl(A.FullType(quals, spec, loc=t.loc),
                                  [A.Declarator(name.text, None, init, loc=name.loc)], loc=t.loc)
        return self.expression()

    def for_stmt(self) -> A.For:
        start = self.advance()
        self.expect("(", "after 'for'")
        self.scopes.append(set())
        if self.at(";"):
            self.advance()
            init = None
        elif self.looks_like_declaration():
            t = self.tok
            init = A.DeclStmt(self.declaration(global_scope=False), loc=t.loc)
        else:
            t = self.tok
            init = A.ExprStmt(self.expression(), loc=t.loc)
            self.expect(";", "after the for-loop initialiser")
        cond = None if self.at(";") else self.condition()
        self.expect(";", "after the for-loop condition")
        step = None if self.at(")") else self.expression()
        self.expect(")", "after the for-loop header")
        body = self.statement()
        self.scopes.pop()
        return A.For(init, cond, step, body, loc=start.loc)

    def while_stmt(self) -> A.While:
        start = self.advance()
        self.expect("(", "after 'while'")
        self.scopes.append(set())
        cond = self.condition()
        self.expect(")", "after the while condition")
        body = self.statement()
        self.scopes.pop()
        return A.While(cond, body, loc=start.loc)

    def do_stmt(self) -> A.DoWhile:
        start = self.advance()
        body = self.scoped_statement()
        self.expect("while", "after the do-loop body")
        self.expect("(", "after 'while'")
        cond = self.expression()
        self.expect(")", "after the do-while condition")
        self.expect(";", "after do-while")
        return A.DoWhile(body, cond, loc=start.loc)

    def switch_stmt(self) -> A.Switch:
        start = self.advance()
        self.expect("(", "after 'switch'")
        expr = self.expression()
        self.expect(")", "after the switch expression")
        if not self.at("{"):
            raise self.error(f"expected '{{' to start the switch body, found {_describe(self.tok)}")
        return A.Switch(expr, self.compound(), loc=start.loc)

    def case_stmt(self) -> A.Case:
        start = self.advance()
        if start.text == "default":
            self.expect(":", "after 'default'")
            return A.Case(None, loc=start.loc)
        expr = self.conditional()
        self.expect(":", "after the case label")
        return A.Case(expr, loc=start.loc)

    def jump_stmt(self) -> A.Stmt:
        start = self.advance()
        word = start.text
        if word == "return":
            expr = None if self.at(";") else self.expression()
            self.expect(";", "after return")
            return A.Return(expr, loc=start.loc)
        self.expect(";", f"after '{word}'")
        cls = {"break": A.Break, "continue": A.Continue, "discard": A.Discard}[word]
        return cls(loc=start.loc)

    def misplaced(self) -> A.Stmt:
        t = self.tok
        raise self.error(f"'{t.text}' without a matching 'if'" if t.text == "else"
                         else f"unexpected '{t.text}'")

    # ------------------------------------------------------------------ expressions
    def expression(self) -> A.Expr:
        first = self.assignment()
        if not self.at(","):
            return first
        exprs = [first]
        while self.accept(","):
            exprs.append(self.assignment())
        return A.Sequence(exprs, loc=first.loc)

    def assignment(self) -> A.Expr:
        self.enter()
        left = self.conditional()
        t = self.tok
        if t.kind == "punct" and t.text in ASSIGN_OPS:
            self.advance()
            left = A.Assign(t.text, left, self.assignment(), loc=left.loc)
        self.depth -= 1
        return left

    def conditional(self) -> A.Expr:
        cond = self.binary(3)
        if not self.accept("?"):
            return cond
        self.enter()
        then = self.expression()
        self.expect(":", "in the ?: expression")
        else_ = self.assignment()
        self.depth -= 1
        return A.Ternary(cond, then, else_, loc=cond.loc)

    def binary(self, min_prec: int) -> A.Expr:
        left = self.unary()
        while True:
            t = self.tok
            prec = BINARY_PRECEDENCE.get(t.text) if t.kind == "punct" else None
            if prec is None or prec < min_prec:
                return left
            self.advance()
            right = self.binary(prec + 1)
            left = A.Binary(t.text, left, right, loc=left.loc)

    def unary(self) -> A.Expr:
        t = self.tok
        if t.kind == "punct" and t.text in PREFIX_OPS:
            self.advance()
            self.enter()
            operand = self.unary()
            self.depth -= 1
            return A.Unary(t.text, operand, loc=t.loc)
        return self.postfix()

    def postfix(self) -> A.Expr:
        expr = self.primary()
        while True:
            t = self.tok
            if t.kind != "punct":
                return expr
            if t.text == "[":
                self.advance()
                index = self.expression()
                self.expect("]", "after the index")
                expr = A.Index(expr, index, loc=expr.loc)
            elif t.text == ".":
                self.advance()
                name = self.tok
                if name.kind != "ident":
                    raise self.error(f"expected a field name after '.', found {_describe(name)}")
                self.advance()
                if name.text == "length" and self.at("("):
                    self.advance()
                    self.expect(")", "after '.length('", hint="length() takes no arguments")
                    expr = A.Length(expr, loc=expr.loc)
                else:
                    expr = A.Field(expr, name.text, loc=expr.loc)
            elif t.text in ("++", "--"):
                self.advance()
                expr = A.Unary(t.text, expr, postfix=True, loc=expr.loc)
            else:
                return expr

    def call_args(self) -> list[A.Expr]:
        self.advance()  # (
        if self.at("void") and self.peek().text == ")":
            self.advance()
        args: list[A.Expr] = []
        if self.accept(")"):
            return args
        while True:
            args.append(self.assignment())
            if self.accept(")"):
                return args
            if not self.at(","):
                raise self.error(f"expected ',' or ')' in the argument list, found {_describe(self.tok)}")
            self.advance()

    def primary(self) -> A.Expr:
        t = self.tok
        k = t.kind
        if k == "ident":
            self.advance()
            if self.at("("):
                return A.Call(t.text, self.call_args(), loc=t.loc)
            if self.is_struct(t.text) and self.at("["):
                dims = self.array_dims()
                if not self.at("("):
                    raise self.error(f"expected '(' after array type, found {_describe(self.tok)}")
                return A.Call(t.text, self.call_args(), dims, loc=t.loc)
            return A.Ident(t.text, loc=t.loc)
        if k in ("int", "uint"):
            self.advance()
            return A.IntLit(t.value, k == "uint", t.text, loc=t.loc)
        if k in ("float", "double"):
            self.advance()
            return A.FloatLit(t.value, k == "double", t.text, loc=t.loc)
        if k == "bool":
            self.advance()
            return A.BoolLit(t.value, loc=t.loc)
        if k == "punct" and t.text == "(":
            self.advance()
            self.enter()
            expr = self.expression()
            self.expect(")", "to close '('")
            self.depth -= 1
            return expr
        if k == "keyword" and t.text == "nonuniformEXT" and self.peek().text == "(":
            self.advance()  # nonuniformEXT(expr): marks a value non-uniform, a built-in call
            return A.Call(t.text, self.call_args(), loc=t.loc)
        if k == "keyword" and t.text in TYPE_NAMES:
            self.advance()
            dims = self.array_dims()
            if not self.at("("):
                raise self.error(
                    f"expected '(' after type name '{t.text}' in an expression, found "
                    f"{_describe(self.tok)}")
            return A.Call(t.text, self.call_args(), dims, loc=t.loc)
        if k == "eof":
            raise self.error("expected an expression, found end of file")
        raise self.error(f"expected an expression, found {_describe(t)}")


_STATEMENT_HANDLERS = {
    "if": _Parser.if_stmt, "for": _Parser.for_stmt, "while": _Parser.while_stmt,
    "do": _Parser.do_stmt, "switch": _Parser.switch_stmt, "case": _Parser.case_stmt,
    "default": _Parser.case_stmt, "break": _Parser.jump_stmt, "continue": _Parser.jump_stmt,
    "return": _Parser.jump_stmt, "discard": _Parser.jump_stmt, "else": _Parser.misplaced,
}


def parse(tokens: Seq[Token], version: Optional[int] = None,
          profile: Optional[str] = None) -> A.TranslationUnit:
    """Parse lexed tokens (from :func:`rrcache.glsl.lexer.lex`) into a TranslationUnit.

    >>> unit = parse(lex(preprocess("void main() { gl_FragColor = vec4(1.0); }", "a.frag").tokens))
    >>> unit.decls[0].name
    'main'
    """
    old_limit = sys.getrecursionlimit()
    if old_limit < 20 * MAX_DEPTH + 1000:
        sys.setrecursionlimit(20 * MAX_DEPTH + 1000)
    try:
        unit = _Parser(tokens).unit()
    finally:
        sys.setrecursionlimit(old_limit)
    unit.version = version
    unit.profile = profile
    return unit


def parse_source(source: str, filename: str = "<string>",
                 defines: Optional[dict] = None) -> A.TranslationUnit:
    """Preprocess, lex and parse a shader source.

    >>> unit = parse_source("#version 330\\nout vec4 c;\\nvoid main() { c = vec4(1.0); }")
    >>> unit.version, [type(d).__name__ for d in unit.decls]
    (330, ['VariableDecl', 'FunctionDecl'])
    """
    return parse_preprocessed(preprocess(source, filename, defines), filename)


def parse_preprocessed(pp, filename: str = "<string>") -> A.TranslationUnit:
    """Lex and parse a :class:`~rrcache.glsl.preprocessor.Preprocessed` result, carrying its
    ``#version`` and ``#extension`` directives (and where they stand) into the unit."""
    # Without #version the language is GLSL 1.10 (or ES 1.00): late keywords are identifiers.
    lex_version = pp.version if pp.version is not None else 110
    tokens = lex(pp.tokens, lex_version, pp.profile, filename=filename,
                 extensions=pp.extensions)
    unit = parse(tokens, pp.version, pp.profile)
    unit.extensions = list(pp.extensions)
    unit.extension_locs = list(pp.extension_locs)
    unit.version_loc = pp.version_loc
    return unit

