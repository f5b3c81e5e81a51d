"""Fuzz tests of the GLSL front-end: parse_source either succeeds or raises GLSLError.

Two hypothesis tests, 200 examples each (about a second or two in all):

* random token streams drawn from GLSL keywords, names, numbers, punctuators, directives and
  junk characters;
* corpus shaders mutated by deleting, duplicating and swapping tokens.

Nothing but :class:`rrcache.errors.GLSLError` may escape, and whatever parses must also survive
print → parse unchanged. (No example's duration is asserted: the parser's speed is measured by
``rrcache bench-frontend``.)
"""
from __future__ import annotations

import re
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rrcache.errors import GLSLError
from rrcache.glsl.parser import parse_source
from rrcache.glsl.printer import print_glsl

CORPUS = sorted((Path(__file__).parent / "glsl" / "corpus").glob("*.frag"))
SOURCES = [p.read_text() for p in CORPUS]

_VOCABULARY = (
    "void float int uint bool vec2 vec3 vec4 mat3 sampler2D struct S uniform in out inout const "
    "flat layout location precision highp mediump if else for while do switch case default "
    "break continue return discard true false main a b c x length texture2D gl_FragColor "
    "0 1 0x1F 017 3u 1.0 .5 2e3 1.0f 1.0lf 08 1e 99999999999 "
    "( ) [ ] { } . , : ; + - * / % < > <= >= == != && || ^^ & | ^ ! ~ ? = += -= <<= >>= ++ -- "
    "<< >> # @ $ \" \\ ` goto class"
).split()
_DIRECTIVES = ["#version 330 core", "#version 100", "#define N 3", "#ifdef N", "#endif",
               "#extension GL_OES_standard_derivatives : enable", "#if 1 +", "#line 7"]

_TOKEN_RE = re.compile(r"[A-Za-z_][A-Za-z_0-9]*|[0-9.][0-9A-Za-z_.]*|\S")


def _check(source: str) -> None:
    try:
        unit = parse_source(source, "fuzz.frag")
    except GLSLError as err:
        assert err.loc is None or err.loc.line >= 1
        unit = None
    if unit is not None:
        text = print_glsl(unit)
        assert parse_source(text, "printed.frag") == unit, text


_lines = st.lists(
    st.one_of(
        st.lists(st.sampled_from(_VOCABULARY), max_size=25).map(" ".join),
        st.sampled_from(_DIRECTIVES),
    ),
    max_size=8,
)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_lines)
def test_random_token_streams(lines):
    """200 random token streams."""
    _check("\n".join(lines))


def _split(source: str) -> list[tuple[str, str]]:
    """(token, whitespace after it) pairs, so mutated sources keep their line structure."""
    out = []
    for m in _TOKEN_RE.finditer(source):
        end = m.end()
        nxt = _TOKEN_RE.search(source, end)
        out.append((m.group(), source[end:nxt.start() if nxt else len(source)]))
    return out


@st.composite
def _mutated(draw):
    tokens = _split(draw(st.sampled_from(SOURCES)))
    for _ in range(draw(st.integers(1, 4))):
        if not tokens:
            break
        i = draw(st.integers(0, len(tokens) - 1))
        op = draw(st.sampled_from(["delete", "duplicate", "swap"]))
        if op == "delete":
            del tokens[i]
        elif op == "duplicate":
            tokens.insert(i, tokens[i])
        else:
            j = draw(st.integers(0, len(tokens) - 1))
            tokens[i], tokens[j] = tokens[j], tokens[i]
    return "".join(tok + (ws or " ") for tok, ws in tokens)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_mutated())
def test_mutated_corpus_shaders(source):
    """200 corpus shaders with 1-4 tokens deleted, duplicated or swapped."""
    _check(source)


def test_unmutated_corpus_passes_the_check():
    for source in SOURCES:
        _check(source)
