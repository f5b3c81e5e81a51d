"""The source text of a listed node as the user wrote it (not a pass: it reads the table).

The analysis numbers the nodes of the *analysed* program (calls inlined, loops unrolled), where
an expression that came from a function body reads the inliner's temporaries
(``_rr_sum_3 + _rr_amp_3 * _rr_snoise_5``). The node table shows what the user wrote instead:
:func:`attach_source_text` finds, for each node, the expression of the original program at the
same place (file, line, column) with the same shape (the inliner and the unroller only replace
sub-expressions by temporaries or constants), and takes its printed text
(``sum + amp * snoise(p)``); the call chain stays beside it in the table. It also records the
file of a node that comes from an included file, so the table can say
``lygia/generative/fbm.glsl:31``.

>>> from rrcache.glsl.frontend import parse_shader
>>> from rrcache.analysis.cacheable import cacheable_nodes
>>> s = parse_shader("varying vec2 v;\\nfloat f(float x) { return sin(x) * cos(x * 3.0) + x; }\\n"
...                  "void main() { gl_FragColor = vec4(f(v.x) * f(v.y)); }", "a.frag")
>>> table = cacheable_nodes(s)
>>> texts = [n.text for n in table.nodes + table.excluded]
>>> "sin(x) * cos(x * 3.0) + x" in texts and not any("_rr_" in t for t in texts)
True
"""
from __future__ import annotations

import os
import re
from dataclasses import fields
from typing import Optional

from rrcache.glsl import ast as A
from rrcache.glsl.ast import children, iter_exprs
from rrcache.glsl.printer import memo_printer

__all__ = ["attach_source_text", "display_file"]

_GENERATED = re.compile(r"^_rr_(.+)_(\d+)$")  # the names the passes make (glsl/rewrite.NameAllocator)
_MATCH_DEPTH = 6  # enough to tell apart the left-nested chains that share a start


def _key(loc) -> Optional[tuple]:
    return (loc.file, loc.line, loc.col) if loc is not None else None


class _Compared(dict):
    """``class -> which of op, name, value its nodes have`` (the attributes a match compares),
    filled on first use; absent ones compare equal (both None)."""

    def __missing__(self, cls: type) -> tuple[str, ...]:
        names = {f.name for f in fields(cls)}
        found = self[cls] = tuple(a for a in ("op", "name", "value")
                                  if a in names or hasattr(cls, a))
        return found


_COMPARED = _Compared()
_LITERALS = (A.IntLit, A.FloatLit, A.BoolLit)
#: the passes' own temporaries: a hoisted operand (``t``), a ``?:`` (``sel``) or a ``&&``/``||``
#: (``cond``) turned into statements, an early-return flag (``live``), an unnamed parameter
_PASS_TEMPORARIES = {"t", "cond", "sel", "live", "arg"}


class _Sources:
    """What the analysed program's generated names stand for in the original program."""

    def __init__(self, table, original_unit: A.TranslationUnit):
        self.functions = {d.name for d in original_unit.decls if isinstance(d, A.FunctionDecl)}
        self.index: dict[tuple, list] = {}
        for e in iter_exprs(original_unit):
            k = _key(e.loc)
            if k is not None:
                self.index.setdefault(k, []).append(e)
        # a hoisted operand's temporary: its initialiser (the operand, in the analysed program)
        self.inits: dict[str, A.Expr] = {}
        shader = getattr(table, "shader", None)
        if shader is not None:
            for n in A.walk(shader.unit, decl_types=False):
                if n.__class__ is A.Declarator and n.init is not None and n.name.startswith("_rr_t_"):
                    self.inits[n.name] = n.init
        self.resolved: dict[int, Optional[A.Expr]] = {}
        self.printed = memo_printer()  # the original unit stays alive and unchanged meanwhile
        self.display = memo_printer(self.ident_text)

    def original(self, ident: A.Ident) -> Optional[A.Expr]:
        """The original expression a generated name holds the value of (a call's result, a
        hoisted operand, a ``?:`` or ``&&``/``||`` made statements), or None (a renamed
        variable, or not found)."""
        key = id(ident)
        if key in self.resolved:
            return self.resolved[key]
        m = _GENERATED.match(ident.name)
        base = m.group(1) if m else None
        found = None
        for c in self.index.get(_key(ident.loc), ()) if base else ():
            cls = c.__class__
            if base == "t":
                init = self.inits.get(ident.name)
                if init is not None and self.same_shape(init, c):
                    found = c
            elif base == "sel":
                found = c if cls is A.Ternary else None
            elif base == "cond":
                found = c if cls is A.Binary and c.op in ("&&", "||") else None
            elif base in self.functions:
                found = c if cls is A.Call and c.name == base else None
            if found is not None:
                break
        self.resolved[key] = found
        return found

    def same_shape(self, analysed, original, depth: int = 0) -> bool:
        """Whether ``analysed`` is ``original`` with names replaced by the inliner's (renamed
        locals and parameters, hoisted call results and operands) or the unroller's constants
        (compared to a bounded depth)."""
        cls = analysed.__class__
        if cls is A.Ident and analysed.name.startswith("_rr_") and _GENERATED.match(analysed.name):
            held = self.original(analysed)
            if held is not None:
                return held is original
            # a renamed local or parameter, or a call's hoisted result
            return isinstance(original, (A.Ident, A.Call))
        if isinstance(analysed, _LITERALS) and isinstance(original, A.Ident):
            return True  # an unrolled loop index or a constant argument
        if cls is not original.__class__:
            return False
        for attr in _COMPARED[cls]:
            if getattr(analysed, attr) != getattr(original, attr):
                return False
        if depth >= _MATCH_DEPTH:
            return True
        a, o = children(analysed), children(original)  # an expression's children are expressions
        if len(a) != len(o):
            return False
        depth += 1
        for x, y in zip(a, o):
            if not self.same_shape(x, y, depth):
                return False
        return True

    def ident_text(self, ident: A.Ident, need: int) -> Optional[str]:
        """How a node's text shows a generated name: the original expression it holds, or the
        variable's own name; never the pass's temporary."""
        if not ident.name.startswith("_rr_"):
            return None
        held = self.original(ident)
        if held is not None:
            return self.printed(held, need)
        m = _GENERATED.match(ident.name)
        if m is None:
            return None
        base = m.group(1)
        if base in self.functions:
            return f"{base}(…)"
        return "(…)" if base in _PASS_TEMPORARIES else base


def attach_source_text(table, original_unit: A.TranslationUnit) -> None:
    """Set each node's ``text`` (listed and excluded) to the original expression's text where
    the node came from inlined or unrolled code, and its ``file`` to the file it was written in
    (None for the main file's own lines)."""
    main_file = None
    shader = getattr(table, "shader", None)
    if shader is not None:
        main_file = getattr(shader, "path", None)
    main_file = str(main_file) if main_file else None
    sources = None
    for entry in list(table.nodes) + list(table.excluded):
        e = entry.node
        loc = getattr(e, "loc", None)
        if loc is None:
            continue
        file = str(loc.file) if loc.file else None
        if file and file != main_file and not file.startswith("<"):
            entry.file = file
        if not entry.call_chain and "_rr_" not in entry.text:
            continue
        if sources is None:
            sources = _Sources(table, original_unit)
        for candidate in sources.index.get(_key(loc), ()):
            if sources.same_shape(e, candidate):
                # the copies of one inlined or unrolled expression share its text, and a text
                # is made of its operands' texts: each original expression is printed once
                entry.text = sources.printed(candidate)
                break
        else:
            if "_rr_" in entry.text:  # made by a pass (``p *= 2.0`` → ``p * 2.0``): as written
                abbreviated = entry.text.startswith("(") and " nodes" in entry.text
                entry.text = (_TEMP.sub(lambda m: _written_name(m, sources.functions), entry.text)
                              if abbreviated else sources.display(e))


_TEMP = re.compile(r"\b_rr_(\w+?)_(\d+)\b")


def _written_name(m: "re.Match", functions: set) -> str:
    """The user's name behind a generated one in an abbreviated text: a renamed variable's own
    name, ``f(…)`` for the result of an inlined call of ``f``, ``(…)`` for a temporary."""
    base = m.group(1)
    if base in functions:
        return f"{base}(…)"
    if base in _PASS_TEMPORARIES:
        return "(…)"
    return base


def display_file(file: Optional[str], main_path: Optional[str]) -> Optional[str]:
    """How a table names an included file: relative to the main shader's folder when below it
    (``lygia/generative/fbm.glsl``), else as it was found.

    >>> display_file("/p/shaders/lygia/fbm.glsl", "/p/shaders/main.frag")
    'lygia/fbm.glsl'
    """
    if not file:
        return None
    if main_path:
        base = os.path.dirname(os.path.abspath(main_path))
        rel = os.path.relpath(os.path.abspath(file), base)
        if not rel.startswith(".."):
            return rel
    return file
