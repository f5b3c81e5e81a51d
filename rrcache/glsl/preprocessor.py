"""The GLSL preprocessor (GLSL 4.60 §3.3, GLSL ES 3.00 §3.4: C preprocessor semantics).

:func:`preprocess` turns shader source into a list of :class:`PPToken` for the lexer:

* line continuations (backslash-newline) and comments are removed, CRLF and CR are newlines;
* the text is split into pp-tokens (identifiers, pp-numbers, punctuators, anything else is
  ``other`` and left to the parser to report);
* directives are executed: ``#version`` ``#extension`` ``#pragma`` (recorded, not emitted),
  ``#define``/``#undef`` (object-like and function-like macros with ``#`` and ``##``),
  ``#if``/``#ifdef``/``#ifndef``/``#elif``/``#else``/``#endif``, ``#line``, ``#error``,
  ``#include "file"``/``#include <file>`` and the null directive ``#``;
* macros are expanded with hide sets (Prosser's algorithm), so a macro never re-expands itself.

Every token carries the *original* ``file:line:col`` of its first character (honouring
``#line``); tokens produced by a macro expansion carry the place of the macro use. ``__FILE__``
is the GLSL source string number: 0 for the main file, then the index of each included file in
:attr:`Preprocessed.files`. ``#if`` arithmetic is 32-bit two's complement; undefined
identifiers are 0. Every problem raises :class:`rrcache.errors.PreprocessorError` at its place.
"""
from __future__ import annotations

import gc
import hashlib
import os
import re
from bisect import bisect_right
from dataclasses import dataclass, field
from typing import Iterator, Mapping, Sequence

from rrcache.errors import PreprocessorError, SourceLoc, printable as _printable
from rrcache.files import Refused, open_file, read_file
from rrcache.glsl.extensions import predefined as predefined_extensions

__all__ = ["PPToken", "Preprocessed", "preprocess", "preprocess_file"]


@dataclass(slots=True)
class PPToken:
    """One preprocessed token: ``kind`` is ``ident``, ``number``, ``punct`` or ``other``."""

    kind: str
    text: str
    loc: SourceLoc


@dataclass
class Preprocessed:
    """The result of :func:`preprocess`.

    ``version`` is the ``#version`` number (None when absent); ``profile`` the effective
    profile: ``es`` for ES versions, the written one or ``core`` for desktop 150 and later,
    None below 150. ``files`` lists every file read, the main file first. ``assumed`` says,
    for a shader without ``#version``, which language it was read as and why (see
    :func:`_es_sketch_reason`).
    """

    tokens: list[PPToken]
    version: int | None = None
    profile: str | None = None
    version_loc: SourceLoc | None = None
    extensions: list[tuple[str, str]] = field(default_factory=list)
    extension_locs: list[SourceLoc] = field(default_factory=list)  # where each #extension stands
    pragmas: list[tuple[str, SourceLoc]] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    #: the sha256 of the bytes read of each included file (by its path in ``files``): what the
    #: shader's hash is made of, never a second read of the path
    file_hashes: dict[str, str] = field(default_factory=dict)
    #: without ``#version``: the language the shader was read as, and why (None with one)
    assumed: str | None = None


# --------------------------------------------------------------------------------------------
# Scanning

_PUNCT = (r"<<=|>>=|\+\+|--|&&|\|\||\^\^|==|!=|<=|>=|\+=|-=|\*=|/=|%=|&=|\^=|\|=|<<|>>|##"
          r"|[-()\[\]{}.,;:?+*/%<>=!~&|^#]")
_TOKEN_RE = re.compile(
    r"(?P<ws>[ \t\f\v]+)"
    r"|(?P<nl>\n)"
    r"|(?P<lc>//[^\n]*)"
    r"|(?P<bc>/\*.*?\*/)"
    r"|(?P<bcu>/\*)"
    r"|(?P<number>(?:0[xX][0-9A-Fa-f]*|(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)"
    r"[A-Za-z0-9_]*)"
    r"|(?P<ident>[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<str>\"[^\"\n]*\")"
    r"|(?P<punct>" + _PUNCT + r")"
    r"|(?P<other>.)",
    re.S,
)
_INT_RE = re.compile(r"(0[xX][0-9A-Fa-f]+|0[0-7]*|[1-9][0-9]*)[uU]?")
_IDENT_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_NOHIDE: frozenset = frozenset()


class _Tok:
    """An internal pp-token: ``space`` says whitespace preceded it, ``hide`` is its hide set."""

    __slots__ = ("kind", "text", "loc", "space", "hide")

    def __init__(self, kind: str, text: str, loc: SourceLoc | None, space: bool = False,
                 hide: frozenset = _NOHIDE):
        self.kind = kind
        self.text = text
        self.loc = loc
        self.space = space
        self.hide = hide

    def is_punct(self, text: str) -> bool:
        return self.kind == "punct" and self.text == text


def _err(message: str, loc: SourceLoc | None, hint: str | None = None) -> PreprocessorError:
    return PreprocessorError(message, loc, hint)


class _Source:
    """One file's text, split into logical lines of pp-tokens with original locations.

    ``label`` (the file name in locations), ``delta`` (added to physical line numbers) and
    ``number`` (``__FILE__``) are changed by ``#line`` while :meth:`lines` is being consumed.
    """

    def __init__(self, text: str, label: str, number: int):
        text = text.replace("\r\n", "\n").replace("\r", "\n")
        if text.startswith("\ufeff"):
            text = text[1:]
        self.label = label
        self.number = number
        self.delta = 0
        self.line_starts = [0] + [m.end() for m in re.finditer("\n", text)]
        self.splices: list[int] = []
        if "\\\n" in text:
            for k, m in enumerate(re.finditer(r"\\\n", text)):
                self.splices.append(m.start() - 2 * k)
            text = text.replace("\\\n", "")
        self.text = text

    def _orig(self, pos: int) -> int:
        if self.splices:
            return pos + 2 * bisect_right(self.splices, pos)
        return pos

    def physical(self, pos: int) -> tuple[int, int]:
        """(line, col) in the original text of spliced position ``pos``, both 1-based."""
        orig = self._orig(pos)
        line = bisect_right(self.line_starts, orig)
        return line, orig - self.line_starts[line - 1] + 1

    def loc(self, pos: int) -> SourceLoc:
        line, col = self.physical(pos)
        return SourceLoc(self.label, line + self.delta, col)

    def lines(self) -> Iterator[tuple[list[_Tok], int]]:
        """Yield (tokens of one logical line, physical number of the line after it)."""
        toks: list[_Tok] = []
        space = False
        fast = not self.splices
        line, start = 1, 0  # physical line and its start offset, tracked when ``fast``
        for m in _TOKEN_RE.finditer(self.text):
            kind = m.lastgroup
            if kind == "ws" or kind == "lc":
                space = True
            elif kind == "nl":
                if fast:
                    line, start = line + 1, m.end()
                    yield toks, line
                else:
                    yield toks, self.physical(m.start())[0] + 1
                toks = []
                space = False
            elif kind == "bc":
                space = True
                if fast:
                    text = m.group()
                    nls = text.count("\n")
                    if nls:
                        line += nls
                        start = m.start() + text.rindex("\n") + 1
            elif kind == "bcu":
                raise _err("unterminated /* comment", self.loc(m.start()),
                           "close the comment with */")
            else:
                pos = m.start()
                loc = (SourceLoc(self.label, line + self.delta, pos - start + 1) if fast
                       else self.loc(pos))
                toks.append(_Tok(kind, m.group(), loc, space))
                space = False
        if toks:
            yield toks, self.physical(len(self.text))[0] + 1


# --------------------------------------------------------------------------------------------
# Macros

class _Macro:
    __slots__ = ("name", "params", "body", "loc", "pindex", "builtin", "key")

    def __init__(self, name: str, params: list[str] | None, body: list[_Tok],
                 loc: SourceLoc | None, builtin: bool = False):
        self.name = name
        self.params = params
        self.body = body
        self.loc = loc
        self.builtin = builtin
        self.pindex = {p: i for i, p in enumerate(params)} if params is not None else None
        self.key = (tuple(params) if params is not None else None,
                    tuple((t.text, bool(i and t.space)) for i, t in enumerate(body)))


_DYNAMIC = frozenset({"__LINE__", "__FILE__", "__VERSION__"})
_VERSIONS = (100, 110, 120, 130, 140, 150, 300, 310, 320, 330, 400, 410, 420, 430, 440, 450, 460)
_ES_VERSIONS = (100, 300, 310, 320)
_BEHAVIORS = ("require", "enable", "warn", "disable")
#: the tokens macro expansion may produce: at least :data:`_MIN_EXPANSION`, else
#: :data:`_EXPANSION_PER_BYTE` per byte of source read, and never more than twice the analysis
#: budget's syntax nodes (more tokens than that would be refused by it after parsing anyway). A
#: macro bomb (``#define D(x) x x`` nested 24 deep: 2^25 tokens) from a few hundred bytes is refused
#: after 200,000 tokens, not after two million (seconds and half a gigabyte)
_MIN_EXPANSION = 200_000
_EXPANSION_PER_BYTE = 5
_MAX_NESTING = 120
_MAX_INCLUDE_DEPTH = 64


def _join(toks: Sequence[_Tok]) -> str:
    parts = []
    for i, t in enumerate(toks):
        if i and t.space:
            parts.append(" ")
        parts.append(t.text)
    return "".join(parts)


def _wrap32(v: int) -> int:
    return ((v + 0x80000000) & 0xFFFFFFFF) - 0x80000000


# --------------------------------------------------------------------------------------------
# #if expressions

_BINARY_PREC = {"||": 1, "&&": 2, "|": 3, "^": 4, "&": 5, "==": 6, "!=": 6, "<": 7, ">": 7,
                "<=": 7, ">=": 7, "<<": 8, ">>": 8, "+": 9, "-": 9, "*": 10, "/": 10, "%": 10}


class _ExprParser:
    """Evaluates a macro-expanded ``#if`` expression by precedence climbing.

    ``live`` is False inside the unevaluated operand of ``&&``, ``||`` and ``?:``, where
    division by zero and bad shifts are not errors (as in C).
    """

    def __init__(self, toks: list[_Tok], is_defined, directive: _Tok):
        self.toks = toks
        self.pos = 0
        self.is_defined = is_defined
        self.directive = directive
        self.depth = 0

    def _peek(self) -> _Tok | None:
        return self.toks[self.pos] if self.pos < len(self.toks) else None

    def _end_loc(self) -> SourceLoc:
        return self.toks[-1].loc if self.toks else self.directive.loc

    def _next(self, what: str) -> _Tok:
        t = self._peek()
        if t is None:
            raise _err(f"expected {what} at the end of the #{self.directive.text} expression",
                       self._end_loc())
        self.pos += 1
        return t

    def evaluate(self) -> int:
        value = self._cond(True)
        t = self._peek()
        if t is not None:
            raise _err(f"unexpected '{t.text}' in #{self.directive.text} expression", t.loc,
                       "a binary operator is missing, or a parenthesis is unbalanced")
        return value

    def _cond(self, live: bool) -> int:
        c = self._binary(1, live)
        t = self._peek()
        if t is not None and t.is_punct("?"):
            self.pos += 1
            a = self._cond(live and c != 0)
            colon = self._next("':'")
            if not colon.is_punct(":"):
                raise _err(f"expected ':' in ?: but found '{colon.text}'", colon.loc)
            b = self._cond(live and c == 0)
            return a if c else b
        return c

    def _binary(self, min_prec: int, live: bool) -> int:
        lhs = self._unary(live)
        while True:
            t = self._peek()
            prec = _BINARY_PREC.get(t.text) if t is not None and t.kind == "punct" else None
            if prec is None or prec < min_prec:
                return lhs
            self.pos += 1
            op = t.text
            if op == "&&":
                rhs = self._binary(prec + 1, live and lhs != 0)
                lhs = int(lhs != 0 and rhs != 0)
            elif op == "||":
                rhs = self._binary(prec + 1, live and lhs == 0)
                lhs = int(lhs != 0 or rhs != 0)
            else:
                rhs = self._binary(prec + 1, live)
                lhs = self._apply(op, lhs, rhs, t, live)

    @staticmethod
    def _apply(op: str, a: int, b: int, t: _Tok, live: bool) -> int:
        if op in ("/", "%"):
            if b == 0:
                if live:
                    raise _err("division by zero in #if expression", t.loc)
                return 0
            q = abs(a) // abs(b)
            if (a < 0) != (b < 0):
                q = -q
            return _wrap32(q if op == "/" else a - b * q)
        if op in ("<<", ">>"):
            if not 0 <= b < 32:
                if live:
                    raise _err(f"shift count {b} out of range 0..31 in #if expression", t.loc)
                return 0
            return _wrap32(a << b) if op == "<<" else a >> b
        if op == "+":
            return _wrap32(a + b)
        if op == "-":
            return _wrap32(a - b)
        if op == "*":
            return _wrap32(a * b)
        if op == "&":
            return a & b
        if op == "|":
            return a | b
        if op == "^":
            return a ^ b
        return int({"==": a == b, "!=": a != b, "<": a < b, ">": a > b,
                    "<=": a <= b, ">=": a >= b}[op])

    def _unary(self, live: bool) -> int:
        t = self._next("a value")
        self.depth += 1
        if self.depth > _MAX_NESTING:
            raise _err("#if expression nested too deeply", t.loc)
        try:
            if t.kind == "punct" and t.text in ("+", "-", "!", "~"):
                v = self._unary(live)
                return {"+": v, "-": _wrap32(-v), "!": int(v == 0), "~": ~v}[t.text]
            if t.is_punct("("):
                v = self._cond(live)
                close = self._peek()
                if close is None or not close.is_punct(")"):
                    raise _err("missing ')' in #if expression", t.loc,
                               "this parenthesis is never closed")
                self.pos += 1
                return v
            if t.kind == "number":
                m = _INT_RE.fullmatch(t.text)
                if m is None:
                    raise _err(f"'{t.text}' is not an integer constant", t.loc,
                               "#if expressions use integers only")
                digits = m.group(1)
                base = 16 if digits[1:2] in ("x", "X") else 8 if digits[0] == "0" else 10
                return _wrap32(int(digits, base))
            if t.kind == "ident":
                if t.text == "defined":
                    return self._defined(t)
                return 0
            raise _err(f"unexpected '{t.text}' in #{self.directive.text} expression", t.loc)
        finally:
            self.depth -= 1

    def _defined(self, t: _Tok) -> int:
        paren = self._peek() is not None and self._peek().is_punct("(")
        if paren:
            self.pos += 1
        name = self._next("a macro name after 'defined'")
        if name.kind != "ident":
            raise _err(f"'defined' needs a macro name, not '{name.text}'", name.loc)
        if paren:
            close = self._next("')'")
            if not close.is_punct(")"):
                raise _err("missing ')' after defined(", close.loc)
        return int(self.is_defined(name.text))


# --------------------------------------------------------------------------------------------
# The preprocessor proper

class _Cond:
    __slots__ = ("active", "taken", "parent_active", "seen_else", "loc", "name")

    def __init__(self, active: bool, taken: bool, parent_active: bool, loc: SourceLoc, name: str):
        self.active = active
        self.taken = taken
        self.parent_active = parent_active
        self.seen_else = False
        self.loc = loc
        self.name = name


class _Preprocessor:
    def __init__(self, defines: Mapping[str, object] | None, include_dirs: Sequence[str]):
        self.macros: dict[str, _Macro] = {}
        self.out: list[PPToken] = []
        self.result = Preprocessed(tokens=self.out)
        self.include_dirs = [os.fspath(d) for d in include_dirs]
        #: the folders includes may come from: the main file's folder tree (added by preprocess)
        #: and the include directories' trees, as real paths
        self.roots = [os.path.realpath(d) for d in self.include_dirs]
        self.source_bytes = 0
        self.cond: list[_Cond] = []
        self.includes: list[tuple[str, str, frozenset]] = []
        self.version_done = False
        self.main_source = ""  # the main file's text: without #version it decides ES or not
        self.produced = 0
        self.cur: _Source | None = None
        for name, value in (defines or {}).items():
            self._inject(name, value)

    # -- setup --------------------------------------------------------------------------------
    def _inject(self, name: object, value: object) -> None:
        where = SourceLoc("<defines>", 1, 1)
        if not isinstance(name, str) or not _IDENT_RE.fullmatch(name) or name in _DYNAMIC \
                or name == "defined":
            raise _err(f"cannot define {name!r}: not a valid macro name", where,
                       "pass identifiers such as {'USE_FOG': '1'}")
        text = "1" if value is None or value == "" else str(value)
        body = [t for toks, _ in _Source(text, f"<define {name}>", 0).lines() for t in toks]
        self.macros[name] = _Macro(name, None, body, None)

    def _builtin(self, name: str, value: str) -> None:
        if name not in self.macros:
            self.macros[name] = _Macro(name, None, [_Tok("number", value, None)], None, True)

    def _finish_version(self, version: int | None, profile: str | None,
                        loc: SourceLoc | None) -> None:
        r = self.result
        self.version_done = True
        r.version, r.version_loc = version, loc
        es_sketch = _es_sketch_reason(self.main_source) if version is None else None
        if es_sketch:
            # no #version, but written for GLSL ES 1.00 (see _es_sketch_reason)
            profile = "es"
            r.assumed = f"GLSL ES 1.00 (no #version; {es_sketch})"
        elif version is None:
            r.assumed = "desktop GLSL 1.10 (no #version, no precision statement, no GL_ES test)"
        if version in _ES_VERSIONS or profile == "es":
            r.profile = "es"
            self._builtin("GL_ES", "1")
            self._builtin("GL_FRAGMENT_PRECISION_HIGH", "1")
        elif version is not None and version >= 150:
            r.profile = profile or "core"
            self._builtin("GL_core_profile", "1")
            if r.profile == "compatibility":
                self._builtin("GL_compatibility_profile", "1")
        else:
            r.profile = None
        for ext in predefined_extensions(r.profile == "es"):
            self._builtin(ext, "1")

    def _mark_content(self) -> None:
        if not self.version_done:
            self._finish_version(None, None, None)

    # -- files --------------------------------------------------------------------------------
    def _file_number(self, label: str) -> int:
        files = self.result.files
        if label not in files:
            files.append(label)
        return files.index(label)

    def run_file(self, text: str, label: str, key: str, include_loc: SourceLoc | None) -> None:
        # the user's macros only: the built-in ones appear when the version is settled, which
        # must not make a file's second entry look like a different state
        state = frozenset((n, m.key) for n, m in self.macros.items() if not m.builtin)
        for i, (k, _, s) in enumerate(self.includes):
            if k == key and s == state:
                chain = " -> ".join([lab for _, lab, _ in self.includes[i:]] + [label])
                raise _err(f"#include cycle: {chain}", include_loc,
                           "guard the file with #ifndef NAME / #define NAME / #endif")
        if len(self.includes) >= _MAX_INCLUDE_DEPTH:
            chain = " -> ".join([lab for _, lab, _ in self.includes] + [label])
            raise _err(f"#include nested more than {_MAX_INCLUDE_DEPTH} deep: {chain}",
                       include_loc, "look for an #include cycle")
        self.includes.append((key, label, state))
        outer = self.cur
        src = self.cur = _Source(text, label, self._file_number(label))
        base = len(self.cond)
        pending: list[_Tok] = []
        for toks, next_line in src.lines():
            if not toks:
                continue
            if toks[0].is_punct("#"):
                if pending:
                    self._emit(self._expand(pending))
                    pending = []
                self._directive(toks, src, next_line, base, include_loc is None)
            elif not self.cond or self.cond[-1].active:
                if not self.version_done:
                    self._mark_content()
                pending.extend(toks)
        if pending:
            self._emit(self._expand(pending))
        if len(self.cond) > base:
            c = self.cond[-1]
            raise _err(f"unterminated #{c.name}: no matching #endif", c.loc,
                       "add #endif at the end of the group")
        self.includes.pop()
        self.cur = outer

    def _emit(self, toks: list[_Tok]) -> None:
        append = self.out.append
        for t in toks:
            kind = t.kind
            if kind == "str" or (kind == "punct" and (t.text == "#" or t.text == "##")):
                kind = "other"
            append(PPToken(kind, t.text, t.loc))

    # -- directives -----------------------------------------------------------------------------
    def _directive(self, toks: list[_Tok], src: _Source, next_line: int, base: int,
                   main: bool) -> None:
        hash_tok = toks[0]
        active = not self.cond or self.cond[-1].active
        if len(toks) == 1:
            if active:
                self._mark_content()
            return
        name_tok = toks[1]
        rest = toks[2:]
        name = name_tok.text if name_tok.kind == "ident" else ""
        if name in ("if", "ifdef", "ifndef", "elif", "else", "endif"):
            self._mark_content()
            self._conditional(name, hash_tok, name_tok, rest, base, active)
            return
        if not active:
            return
        if name == "version":
            self._version(hash_tok, name_tok, rest, main)
            return
        self._mark_content()
        handler = getattr(self, "_d_" + name, None) if name else None
        if handler is None:
            raise _err(f"unknown preprocessor directive '#{name_tok.text}'", name_tok.loc,
                       "directives are #define #undef #if #ifdef #ifndef #elif #else #endif "
                       "#include #line #error #pragma #extension #version")
        handler(hash_tok, name_tok, rest, src, next_line)

    def _version(self, hash_tok: _Tok, name_tok: _Tok, rest: list[_Tok], main: bool) -> None:
        if not main:
            raise _err("#version is not allowed in an included file", name_tok.loc,
                       "put #version in the main shader only")
        if self.version_done:
            if self.result.version_loc is not None:
                raise _err(f"duplicate #version (the first is at {self.result.version_loc})",
                           name_tok.loc)
            raise _err("#version must come before anything else except comments and whitespace",
                       name_tok.loc, "move #version to the first line")
        if not rest or rest[0].kind != "number" or not rest[0].text.isdigit():
            where = rest[0].loc if rest else name_tok.loc
            raise _err("#version needs a version number", where, "e.g. #version 330 core")
        version = int(rest[0].text)
        if version not in _VERSIONS:
            raise _err(f"unsupported GLSL version {rest[0].text}", rest[0].loc,
                       "use one of " + " ".join(map(str, _VERSIONS)))
        profile = None
        if len(rest) > 1:
            p = rest[1]
            if p.kind != "ident" or p.text not in ("core", "compatibility", "es"):
                raise _err(f"unknown profile '{p.text}' in #version", p.loc,
                           "the profile is core, compatibility or es")
            profile = p.text
            if profile == "es" and version not in _ES_VERSIONS:
                raise _err(f"version {version} is not an ES version", p.loc,
                           "ES versions are 100, 300, 310 and 320")
            if profile != "es" and (version in _ES_VERSIONS or version < 150):
                raise _err(f"version {version} takes no '{profile}' profile", p.loc)
            if version == 100:
                raise _err("#version 100 takes no profile", p.loc)
        if len(rest) > 2:
            raise _err(f"unexpected '{rest[2].text}' after #version", rest[2].loc)
        if version in (300, 310, 320) and profile != "es":
            raise _err(f"#version {version} needs the es profile", rest[0].loc,
                       f"write #version {version} es")
        self._finish_version(version, profile, hash_tok.loc)

    def _conditional(self, name: str, hash_tok: _Tok, name_tok: _Tok, rest: list[_Tok],
                     base: int, active: bool) -> None:
        if name in ("if", "ifdef", "ifndef"):
            if not active:
                self.cond.append(_Cond(False, True, False, hash_tok.loc, name))
                return
            if name == "if":
                value = self._eval_if(rest, name_tok)
            else:
                if not rest or rest[0].kind != "ident":
                    raise _err(f"#{name} needs a macro name", rest[0].loc if rest else name_tok.loc)
                if len(rest) > 1:
                    raise _err(f"unexpected '{rest[1].text}' after #{name} {rest[0].text}",
                               rest[1].loc)
                value = self._is_defined(rest[0].text) == (name == "ifdef")
            self.cond.append(_Cond(value, value, True, hash_tok.loc, name))
            return
        if len(self.cond) <= base:
            raise _err(f"#{name} without #if", hash_tok.loc,
                       "remove it, or add the #if it belongs to (in the same file)")
        c = self.cond[-1]
        if name == "elif":
            if c.seen_else:
                raise _err("#elif after #else", hash_tok.loc)
            if c.parent_active and not c.taken:
                c.active = self._eval_if(rest, name_tok)
                c.taken = c.active
            else:
                c.active = False
            return
        if rest and c.parent_active:
            raise _err(f"unexpected '{rest[0].text}' after #{name}", rest[0].loc,
                       "use a comment for the text")
        if name == "else":
            if c.seen_else:
                raise _err("#else after #else", hash_tok.loc)
            c.seen_else = True
            c.active = c.parent_active and not c.taken
            c.taken = True
        else:
            self.cond.pop()

    def _is_defined(self, name: str) -> bool:
        return name in self.macros or name in _DYNAMIC

    def _eval_if(self, rest: list[_Tok], name_tok: _Tok) -> bool:
        items: list[_Tok] = []
        i, n = 0, len(rest)
        while i < n:
            t = rest[i]
            if t.kind == "ident" and t.text == "defined":
                j = i + 1
                paren = j < n and rest[j].is_punct("(")
                if paren:
                    j += 1
                if j >= n or rest[j].kind != "ident":
                    raise _err("'defined' needs a macro name", rest[j].loc if j < n else t.loc)
                value = self._is_defined(rest[j].text)
                j += 1
                if paren:
                    if j >= n or not rest[j].is_punct(")"):
                        raise _err("missing ')' after defined(", rest[j].loc if j < n else
                                   rest[j - 1].loc)
                    j += 1
                items.append(_Tok("number", "1" if value else "0", t.loc, t.space))
                i = j
            else:
                items.append(t)
                i += 1
        expanded = self._expand(items)
        if not expanded:
            raise _err(f"#{name_tok.text} has no expression", name_tok.loc)
        return _ExprParser(expanded, self._is_defined, name_tok).evaluate() != 0

    def _check_name(self, tok: _Tok, what: str) -> None:
        if tok.kind != "ident":
            raise _err(f"#{what} needs a macro name, not '{tok.text}'", tok.loc)
        name = tok.text
        if name == "defined" or name in _DYNAMIC or name.startswith("GL_"):
            raise _err(f"cannot #{what} the reserved name '{name}'", tok.loc,
                       "names starting with GL_, 'defined' and the predefined macros are reserved")
        m = self.macros.get(name)
        if m is not None and m.builtin:
            raise _err(f"cannot #{what} the predefined macro '{name}'", tok.loc)

    def _d_define(self, hash_tok, name_tok, rest, src, next_line) -> None:
        if not rest:
            raise _err("#define needs a macro name", name_tok.loc)
        mtok = rest[0]
        self._check_name(mtok, "define")
        i = 1
        params: list[str] | None = None
        if len(rest) > 1 and rest[1].is_punct("(") and not rest[1].space:
            params = []
            i = 2
            if i < len(rest) and rest[i].is_punct(")"):
                i += 1
            else:
                while True:
                    if i >= len(rest):
                        raise _err("unterminated macro parameter list", rest[-1].loc,
                                   "close the parameter list with ')'")
                    p = rest[i]
                    if p.kind != "ident":
                        raise _err(f"expected a parameter name, not '{p.text}'", p.loc,
                                   "variadic macros are not supported in GLSL")
                    if p.text in params:
                        raise _err(f"duplicate macro parameter '{p.text}'", p.loc)
                    params.append(p.text)
                    i += 1
                    if i >= len(rest):
                        raise _err("unterminated macro parameter list", p.loc,
                                   "close the parameter list with ')'")
                    sep = rest[i]
                    i += 1
                    if sep.is_punct(")"):
                        break
                    if not sep.is_punct(","):
                        raise _err(f"expected ',' or ')' in the parameter list, not '{sep.text}'",
                                   sep.loc)
        body = rest[i:]
        if body and body[0].is_punct("##"):
            raise _err("'##' cannot begin a macro body", body[0].loc)
        if body and body[-1].is_punct("##"):
            raise _err("'##' cannot end a macro body", body[-1].loc)
        if params is not None:
            for k, t in enumerate(body):
                if t.is_punct("#") and (k + 1 >= len(body) or body[k + 1].kind != "ident"
                                        or body[k + 1].text not in params):
                    raise _err("'#' must be followed by a macro parameter", t.loc)
        macro = _Macro(mtok.text, params, body, mtok.loc)
        old = self.macros.get(mtok.text)
        if old is not None and old.key != macro.key:
            where = f" (first defined at {old.loc})" if old.loc else ""
            raise _err(f"macro '{mtok.text}' redefined differently{where}", mtok.loc,
                       "#undef it first")
        self.macros[mtok.text] = macro

    def _d_undef(self, hash_tok, name_tok, rest, src, next_line) -> None:
        if not rest:
            raise _err("#undef needs a macro name", name_tok.loc)
        self._check_name(rest[0], "undef")
        if len(rest) > 1:
            raise _err(f"unexpected '{rest[1].text}' after #undef {rest[0].text}", rest[1].loc)
        self.macros.pop(rest[0].text, None)

    def _d_line(self, hash_tok, name_tok, rest, src, next_line) -> None:
        toks = self._expand(rest)
        if not toks or toks[0].kind != "number" or not toks[0].text.isdigit():
            raise _err("#line needs a decimal line number", toks[0].loc if toks else name_tok.loc,
                       "e.g. #line 10 or #line 10 2")
        line = int(toks[0].text)
        if line > 0x7FFFFFFF:
            raise _err(f"line number {toks[0].text} is too large", toks[0].loc)
        if len(toks) > 1:
            s = toks[1]
            if s.kind == "number" and s.text.isdigit():
                src.number = int(s.text)
            elif s.kind == "str":
                src.label = s.text[1:-1]
            else:
                raise _err(f"#line source must be a number, not '{s.text}'", s.loc)
        if len(toks) > 2:
            raise _err(f"unexpected '{toks[2].text}' after #line", toks[2].loc)
        src.delta = line - next_line

    def _d_error(self, hash_tok, name_tok, rest, src, next_line) -> None:
        text = _join(rest)
        raise _err(f"#error {text}".rstrip(), hash_tok.loc)

    def _d_pragma(self, hash_tok, name_tok, rest, src, next_line) -> None:
        self.result.pragmas.append((_join(rest), hash_tok.loc))

    def _d_extension(self, hash_tok, name_tok, rest, src, next_line) -> None:
        if len(rest) < 3 or rest[0].kind != "ident" or not rest[1].is_punct(":") \
                or rest[2].kind != "ident":
            bad = next((t for k, t in enumerate(rest)
                        if (k == 1 and not t.is_punct(":")) or (k != 1 and t.kind != "ident")),
                       None)
            raise _err("malformed #extension", bad.loc if bad else (rest[-1].loc if rest
                                                                  else name_tok.loc),
                       "write #extension name : require|enable|warn|disable")
        if len(rest) > 3:
            raise _err(f"unexpected '{rest[3].text}' after #extension", rest[3].loc)
        ext, behavior = rest[0].text, rest[2].text
        if behavior not in _BEHAVIORS:
            raise _err(f"unknown extension behavior '{behavior}'", rest[2].loc,
                       "use require, enable, warn or disable")
        if ext == "all" and behavior in ("require", "enable"):
            raise _err(f"#extension all : {behavior} is not allowed", rest[2].loc,
                       "'all' takes only warn or disable")
        self.result.extensions.append((ext, behavior))
        self.result.extension_locs.append(hash_tok.loc)

    def _d_include(self, hash_tok, name_tok, rest, src, next_line) -> None:
        toks = rest
        if toks and not (toks[0].kind == "str" or toks[0].is_punct("<")):
            toks = self._expand(toks)
        if not toks:
            raise _err("#include needs a file name", name_tok.loc, 'write #include "file.glsl"')
        first = toks[0]
        if first.kind == "str":
            path, end = first.text[1:-1], 1
        elif first.is_punct("<"):
            end = next((k for k in range(1, len(toks)) if toks[k].is_punct(">")), None)
            if end is None:
                raise _err("missing '>' in #include", first.loc)
            path, end = _join(toks[1:end]), end + 1
        else:
            raise _err(f"expected \"file\" or <file> after #include, not '{first.text}'",
                       first.loc)
        if end < len(toks):
            raise _err(f"unexpected '{toks[end].text}' after the #include file name",
                       toks[end].loc)
        if not path:
            raise _err("empty #include file name", first.loc)
        tried = []
        including = self.includes[-1][1]
        dirs = ([os.path.dirname(including)] if not including.startswith("<") else [])
        dirs += self.include_dirs
        for d in dirs:
            cand = os.path.normpath(os.path.join(d, path)) if d else os.path.normpath(path)
            tried.append(cand)
            # by rrcache.files' rule: opened once, the opened file checked (kind, folder, size),
            # read from that descriptor; a link flipped after a check cannot redirect the read
            opened = self._open_include(path, cand, first.loc)
            if opened is not None:
                break
        else:
            raise _err(f"cannot find include file '{_printable(path)}' (tried: "
                       f"{', '.join(map(_printable, tried)) or 'none'})",
                       first.loc, "add its directory to the include directories (-I DIR, or the "
                       "session's \"include_dirs\")")
        with opened:
            text = _decode(self._take(opened, path, first.loc), opened.path, self)
        self.run_file(text, cand, opened.real, first.loc)

    def _open_include(self, path: str, cand: str, loc: SourceLoc):
        """The include file ``cand`` opened by the rule, or None when there is none (or only a
        folder) there: it must be a shader file inside the main file's folder tree or an include
        directory's; anything else is refused without reading it (a shader from the web must not
        read, nor leak, the machine's other files)."""
        from rrcache.budgets import budget

        try:
            opened = open_file(cand, budget.source_bytes - self.source_bytes, self.roots)
        except Refused as err:
            if err.kind == "missing" or (err.kind == "type" and os.path.isdir(cand)):
                return None
            if err.kind == "outside":
                where = " and ".join(_printable(r) for r in self.roots) or "no folder (no include directory given)"
                raise _err(f"#include '{_printable(path)}' resolves to {_printable(err.real)}, outside the folders "
                           f"includes are read from ({where})", loc,
                           "includes come from the shader's own folder tree and the include directories; "
                           "add a folder with -I DIR (or the session's \"include_dirs\") if you trust it") from None
            if err.kind == "size":
                size = f" ({err.size:,} bytes)" if err.size is not None else ""
                raise _err(f"'{_printable(cand)}'{size} takes the shader's sources past {budget.source_bytes:,} bytes, "
                           "the analysis budget; nothing of it was read", loc,
                           "raise it with 'rrcache --max-source-bytes N ...'") from None
            raise _err(f"cannot read #include '{_printable(path)}' ({_printable(cand)}): {_printable(err.reason)}",
                       loc, err.hint) from None
        ext = os.path.splitext(opened.real)[1].lower()
        if ext not in SHADER_EXTENSIONS:
            opened.close()
            raise _err(f"#include '{_printable(path)}' is not a shader file (its name ends in "
                       f"'{_printable(ext) or 'no extension'}')", loc,
                       f"includes must be shader sources: {' '.join(sorted(SHADER_EXTENSIONS))}")
        return opened

    def _take(self, opened, path: str, loc: SourceLoc) -> bytes:
        """The bytes of an opened include, within what is left of the source budget; their
        sha256 is recorded for the shader's hash (:attr:`Preprocessed.file_hashes`)."""
        from rrcache.budgets import budget

        try:
            data = opened.read(budget.source_bytes - self.source_bytes)
        except Refused:
            raise _err(f"'{_printable(opened.path)}' takes the shader's sources past {budget.source_bytes:,} bytes, "
                       "the analysis budget", loc, "raise it with 'rrcache --max-source-bytes N ...'") from None
        self.source_bytes += len(data)
        self.result.file_hashes[os.path.normpath(opened.path)] = hashlib.sha256(data).hexdigest()
        return data

    # -- macro expansion -----------------------------------------------------------------------
    def _expand(self, toks: list[_Tok], depth: int = 0) -> list[_Tok]:
        macros = self.macros
        out: list[_Tok] = []
        stack = toks[::-1]
        while stack:
            t = stack.pop()
            if t.kind != "ident":
                out.append(t)
                continue
            name = t.text
            m = macros.get(name)
            if m is None:
                if name in _DYNAMIC:
                    out.append(self._dynamic(t))
                else:
                    out.append(t)
                continue
            if name in t.hide:
                out.append(t)
                continue
            if m.params is None:
                if self.produced + len(m.body) > self._expansion_limit():
                    self._too_large(t)
                body = self._subst(m, None, t.hide | {name}, t, depth)
            else:
                if not stack or not stack[-1].is_punct("("):
                    out.append(t)
                    continue
                args, rparen = self._collect_args(stack, t, m)
                body = self._subst(m, args, (t.hide & rparen.hide) | {name}, t, depth)
            self.produced += len(body) + 1
            if self.produced > self._expansion_limit():
                self._too_large(t)
            body.reverse()
            stack.extend(body)
        return out

    def _expansion_limit(self) -> int:
        from rrcache.budgets import budget

        return min(2 * budget.analysis_nodes, max(_MIN_EXPANSION, _EXPANSION_PER_BYTE * self.source_bytes))

    def _too_large(self, use: _Tok):
        raise _err(f"macro expansion too large: more than {self._expansion_limit():,} tokens from "
                   f"{self.source_bytes:,} bytes of source", use.loc,
                   "look for macros that multiply their arguments (a larger analysis budget, "
                   "'rrcache --max-ast-nodes N', allows more for a large shader)")

    def _dynamic(self, t: _Tok) -> _Tok:
        if t.text == "__LINE__":
            value = t.loc.line
        elif t.text == "__FILE__":
            value = self.cur.number if self.cur is not None else 0
        else:
            value = self.result.version or (100 if self.result.profile == "es" else 110)
        return _Tok("number", str(value), t.loc, t.space, t.hide)

    @staticmethod
    def _collect_args(stack: list[_Tok], use: _Tok, m: _Macro) -> tuple[list[list[_Tok]], _Tok]:
        stack.pop()  # the '('
        args: list[list[_Tok]] = [[]]
        level = 0
        while stack:
            a = stack.pop()
            if a.kind == "punct":
                if a.text == "(":
                    level += 1
                elif a.text == ")":
                    if level == 0:
                        n = len(m.params)
                        if n == 0 and len(args) == 1 and not args[0]:
                            args = []
                        if len(args) != n:
                            raise _err(f"macro '{m.name}' takes {n} argument"
                                       f"{'' if n == 1 else 's'}, but {len(args)} given",
                                       use.loc)
                        return args, a
                    level -= 1
                elif a.text == "," and level == 0:
                    args.append([])
                    continue
            args[-1].append(a)
        raise _err(f"unterminated call of macro '{m.name}'", use.loc,
                   "close the argument list with ')' before the next directive or file end")

    def _subst(self, m: _Macro, args: list[list[_Tok]] | None, hide: frozenset, use: _Tok,
               depth: int) -> list[_Tok]:
        body = m.body
        pindex = m.pindex or {}
        expanded: dict[int, list[_Tok]] = {}
        res: list[_Tok] = []
        pm = _Tok("pm", "", use.loc)
        i, n = 0, len(body)
        while i < n:
            t = body[i]
            if t.kind == "punct" and args is not None and t.text == "#":
                res.append(self._stringize(args[pindex[body[i + 1].text]], use))
                i += 2
                continue
            if t.kind == "punct" and t.text == "##":
                r = body[i + 1]
                i += 2
                if r.kind == "ident" and r.text in pindex:
                    rhs = args[pindex[r.text]]
                else:
                    rhs = [r]
                lhs = res.pop() if res else pm
                if not rhs:
                    res.append(lhs)
                elif lhs.kind == "pm":
                    res.extend(rhs)
                else:
                    res.append(self._paste(lhs, rhs[0], use))
                    res.extend(rhs[1:])
                continue
            if t.kind == "ident" and t.text in pindex:
                k = pindex[t.text]
                if i + 1 < n and body[i + 1].is_punct("##"):
                    res.extend(args[k] or [pm])
                else:
                    if k not in expanded:
                        if depth >= _MAX_NESTING:
                            raise _err("macro calls nested too deeply", use.loc)
                        expanded[k] = self._expand(args[k], depth + 1)
                    if self.produced + len(res) + len(expanded[k]) > self._expansion_limit():
                        self._too_large(use)  # before a body that large is made
                    res.extend(expanded[k])
                i += 1
                continue
            res.append(t)
            i += 1
        loc = use.loc
        final = [_Tok(t.kind, t.text, loc, t.space, t.hide | hide if t.hide else hide)
                 for t in res if t.kind != "pm"]
        if final:
            final[0].space = use.space
        return final

    @staticmethod
    def _stringize(arg: list[_Tok], use: _Tok) -> _Tok:
        text = _join(arg).replace("\\", "\\\\").replace('"', '\\"')
        return _Tok("str", f'"{text}"', use.loc)

    @staticmethod
    def _paste(a: _Tok, b: _Tok, use: _Tok) -> _Tok:
        text = a.text + b.text
        m = _TOKEN_RE.fullmatch(text)
        kind = m.lastgroup if m else None
        if kind not in ("number", "ident", "punct"):
            raise _err(f"pasting '{a.text}' and '{b.text}' does not give a valid token", use.loc,
                       "'##' must join two pieces into one identifier, number or operator")
        return _Tok(kind, text, use.loc, a.space)


#: the file name endings an ``#include`` may read (GLSL sources and their usual headers)
SHADER_EXTENSIONS = frozenset({".glsl", ".frag", ".vert", ".fs", ".vs", ".fsh", ".vsh", ".fp", ".vp",
                               ".h", ".inc", ".glslinc", ".hlsl", ".comp", ".geom", ".tesc", ".tese",
                               ".shader", ".fx", ".cginc"})

def read_source(path: str, what: str = "shader file") -> tuple[str, str]:
    """The text of the shader file ``path`` and the sha256 of its bytes, read by
    :mod:`rrcache.files`' rule within the source budget (``rrcache --max-source-bytes``): a FIFO
    or a device is refused as what it is, a file larger than the budget before a byte is read.
    Problems raise :class:`PreprocessorError` naming the file (and the line and column of a NUL
    byte or invalid UTF-8)."""
    from rrcache.budgets import budget

    try:
        got = read_file(path, budget.source_bytes)
    except Refused as err:
        if err.kind == "size":
            size = f"{err.size:,} bytes, " if err.size is not None else ""
            raise _err(f"the {what} is {size}larger than {budget.source_bytes:,} bytes, the analysis budget",
                       SourceLoc(path, 1, 1), "raise it with 'rrcache --max-source-bytes N ...'") from None
        raise _err(f"cannot read {what} '{_printable(path)}': " + (
            "not found" if err.kind == "missing" and "NUL" not in err.reason else f"it {_printable(err.reason)}"), None,
                   "check the path" if err.kind == "missing" else err.hint) from None
    return _decode(got.data, path, None), got.sha256


def _decode(data: bytes, path: str, pp: "_Preprocessor | None") -> str:
    nul = data.find(b"\0")
    if nul >= 0:
        line = data.count(b"\n", 0, nul) + 1
        col = nul - (data.rfind(b"\n", 0, nul) + 1) + 1
        raise _err("the file contains a NUL byte: it is not GLSL source text", SourceLoc(path, line, col),
                   "pass a shader source file")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        col = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        raise _err("the file is not valid UTF-8", SourceLoc(path, line, col),
                   "save the shader as UTF-8") from None


_COMMENT_RE = re.compile(r"//[^\n]*|/\*.*?(?:\*/|\Z)", re.S)
_PRECISION_RE = re.compile(r"(?m)^[ \t]*precision[ \t]+(?:lowp|mediump|highp)[ \t]+\w+[ \t]*;")
_GL_ES_TEST_RE = re.compile(r"(?m)^[ \t]*#[ \t]*(?:(?:ifdef|ifndef)[ \t]+GL_ES\b|(?:el)?if\b[^\n]*\bGL_ES\b)")


def _es_sketch_reason(source: str) -> str | None:
    """Why a main file without ``#version`` is GLSL ES 1.00, or None for desktop GLSL 1.10.

    The ES sketch tools (glslViewer, GLSL Sandbox, The Book of Shaders' editor; all WebGL 1 or
    GLES 2 underneath) run a versionless fragment shader as GLSL ES 1.00, and such sketches
    say so: a ``precision`` statement (mandatory for floats in an ES 1.00 fragment shader), or a
    test of ``GL_ES`` (``#ifdef GL_ES precision mediump float; #endif``). A versionless shader
    with either, in its main file, active or not, is read as ES 1.00 (``GL_ES`` defined, so it
    takes the branches its author ran); one with neither is desktop GLSL 1.10, as the GLSL
    specification says. Comments are ignored.

    >>> _es_sketch_reason("#ifdef GL_ES\\nprecision mediump float;\\n#endif\\nvoid main(){}")
    'it has a precision statement and tests GL_ES, as ES sketches do'
    >>> _es_sketch_reason("// precision highp float;\\nvoid main(){}") is None
    True
    """
    text = _COMMENT_RE.sub(" ", source)
    found = [what for what, pattern in (("has a precision statement", _PRECISION_RE),
                                         ("tests GL_ES", _GL_ES_TEST_RE)) if pattern.search(text)]
    if not found:
        return None
    return f"it {' and '.join(found)}, as ES sketches do"


def preprocess(source: str, filename: str | os.PathLike = "<string>",
               defines: Mapping[str, object] | None = None,
               include_dirs: Sequence[str] = ()) -> Preprocessed:
    """Preprocess GLSL ``source`` read from ``filename`` into tokens for the lexer.

    ``defines`` maps macro names to their values (``""`` or None means ``1``); includes are
    looked up next to the including file, then in ``include_dirs``.

    >>> pp = preprocess("#version 330 core\\n#define N 4\\nfloat a[N];\\n", "a.glsl")
    >>> [t.text for t in pp.tokens], pp.version, pp.profile
    (['float', 'a', '[', '4', ']', ';'], 330, 'core')
    """
    filename = os.fspath(filename)
    pp = _Preprocessor(defines, include_dirs)
    pp.main_source = source
    if not filename.startswith("<"):
        pp.roots.insert(0, os.path.dirname(os.path.realpath(filename)))
    pp.source_bytes = len(source.encode("utf-8", "surrogatepass"))
    key = os.path.realpath(filename) if not filename.startswith("<") else filename
    # Tokens are many small acyclic objects: pausing the cyclic GC halves the run time.
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        pp.run_file(source, filename, key, None)
    finally:
        if gc_was_enabled:
            gc.enable()
    if not pp.version_done:
        pp._finish_version(None, None, None)
    return pp.result


def preprocess_file(path: str | os.PathLike, defines: Mapping[str, object] | None = None,
                    include_dirs: Sequence[str] = ()) -> Preprocessed:
    """Read and preprocess the shader file ``path`` (see :func:`preprocess`).

    >>> pp = preprocess_file("shaders/glslviewer_basic.glsl", defines={"MODEL_VERTEX_NORMAL": None})
    >>> pp.files[0], "v_normal" in [t.text for t in pp.tokens]
    ('shaders/glslviewer_basic.glsl', True)
    """
    path = os.fspath(path)
    text, _ = read_source(path)
    return preprocess(text, path, defines, include_dirs)
