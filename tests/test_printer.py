"""Tests of the GLSL printer (rrcache.glsl.printer): round trips, parentheses, line maps."""
from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rrcache.glsl import ast as A
from rrcache.glsl.parser import parse_source
from rrcache.glsl.printer import print_expr, print_glsl, print_with_map

CORPUS = sorted((Path(__file__).parent / "glsl" / "corpus").glob("*.frag"))


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.name)
def test_corpus_round_trip_and_fixed_point(path):
    unit = parse_source(path.read_text(), str(path))
    text = print_glsl(unit)
    again = parse_source(text, "printed.frag")
    assert again == unit
    assert print_glsl(again) == text


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.name)
def test_line_map_points_at_the_source_of_each_line(path):
    src_lines = path.read_text().splitlines()
    unit = parse_source(path.read_text(), str(path))
    text, line_map = print_with_map(unit)
    printed = text.splitlines()
    assert len(line_map) == len(printed)
    for line, loc in zip(printed, line_map):
        if loc is None:
            continue
        assert loc.file == str(path)
        # The mapped source line holds, at the mapped column, the first word printed here.
        first = line.split()[0].rstrip(";").split("(")[0].split("[")[0].split(".")[0]
        if first.isidentifier():
            assert src_lines[loc.line - 1][loc.col - 1:].startswith(first), (line, loc)


def test_print_with_map_example():
    unit = parse_source("#version 330\nout vec4 c;\nvoid main()\n{\n    if (true)\n"
                        "        c = vec4(1.0);\n}\n", "m.frag")
    text, line_map = print_with_map(unit)
    lines = text.splitlines()
    assert lines[0] == "#version 330 core" and (line_map[0].file, line_map[0].line) == ("m.frag", 1)
    idx = lines.index("        c = vec4(1.0);")
    assert (line_map[idx].line, line_map[idx].col) == (6, 9)
    idx = lines.index("    if (true)")
    assert line_map[idx].line == 5


def test_header_lines():
    unit = parse_source("#version 100\n#extension GL_OES_standard_derivatives : enable\n"
                        "precision mediump float;", "h.frag")
    assert print_glsl(unit).splitlines()[:3] == [
        "#version 100", "#extension GL_OES_standard_derivatives : enable",
        "precision mediump float;"]
    assert print_glsl(parse_source("#version 300 es\nint a;")).startswith("#version 300 es\n")
    assert print_glsl(parse_source("int a;")) == "int a;\n"


def test_minimal_parentheses():
    cases = {
        "x = (a + b) * c": "x = (a + b) * c",
        "x = a + (b * c)": "x = a + b * c",
        "x = a - (b - c)": "x = a - (b - c)",
        "x = (a - b) - c": "x = a - b - c",
        "x = (a = b)": "x = a = b",
        "x = (p ? a : b) ? c : d": "x = (p ? a : b) ? c : d",
        "x = p ? a : (q ? b : c)": "x = p ? a : q ? b : c",
        "x = -(-a)": "x = -(-a)",
        "x = -(a.y)": "x = -a.y",
        "x = (-a).y": "x = (-a).y",
        "x = f((a, b))": "x = f((a, b))",
        "x = ((a)) << (1 + 2)": "x = a << 1 + 2",
    }
    for src, want in cases.items():
        stmt = parse_source("void main() {" + src + ";}").decls[0].body.stmts[0]
        assert print_expr(stmt.expr) == want


def test_generated_literals_are_valid():
    assert print_expr(A.FloatLit(1.0)) == "1.0"
    assert print_expr(A.FloatLit(1e-7)) == "1e-07"
    assert print_expr(A.FloatLit(3.0, double=True)) == "3.0lf"
    assert print_expr(A.IntLit(7, unsigned=True)) == "7u"
    # A changed value wins over a stale spelling.
    assert print_expr(A.FloatLit(2.5, text="1.0")) == "2.5"
    assert print_expr(A.Binary("-", A.Ident("a"), A.FloatLit(-2.0))) == "a - -2.0"
    assert print_expr(A.Field(A.FloatLit(-2.0), "x")) == "(-2.0).x"
    for v in (0.1, 1e20, 123456789.0, 5e-324, float("inf")):
        text = print_expr(A.FloatLit(v))
        unit = parse_source(f"float a = {text};")
        assert unit.decls[0].declarators[0].init is not None


def test_dangling_else_in_generated_tree_gets_braces():
    inner = A.If(A.Ident("b"), A.ExprStmt(A.Ident("x")))
    tree = A.If(A.Ident("a"), inner, A.ExprStmt(A.Ident("y")))
    unit = A.TranslationUnit([A.FunctionDecl(
        A.FullType([], A.TypeSpecifier("void")), "main", [], A.Compound([tree]))])
    again = parse_source(print_glsl(unit))
    outer = again.decls[0].body.stmts[0]
    assert outer.else_ == A.ExprStmt(A.Ident("y"))
    assert outer.then == A.Compound([inner])


# ----------------------------------------------------------------------------- random trees

_names = st.sampled_from(["a", "b", "c", "v"])
_leaves = st.one_of(
    _names.map(A.Ident),
    st.integers(0, 1000).map(lambda v: A.IntLit(v)),
    st.floats(0, 1e6, allow_nan=False).map(lambda v: A.FloatLit(v)),
    st.booleans().map(A.BoolLit),
)


def _extend(children):
    binops = st.sampled_from(["*", "/", "%", "+", "-", "<<", ">>", "<", ">", "<=", ">=", "==",
                              "!=", "&", "^", "|", "&&", "^^", "||"])
    return st.one_of(
        st.builds(A.Binary, binops, children, children),
        st.builds(A.Unary, st.sampled_from(["+", "-", "!", "~", "++", "--"]), children),
        st.builds(lambda o, e: A.Unary(o, e, postfix=True), st.sampled_from(["++", "--"]),
                  children),
        st.builds(A.Assign, st.sampled_from(["=", "+=", "<<=", "|="]), children, children),
        st.builds(A.Ternary, children, children, children),
        st.builds(A.Sequence, st.lists(children, min_size=2, max_size=3)),
        st.builds(A.Call, st.sampled_from(["f", "vec3"]), st.lists(children, max_size=3)),
        st.builds(A.Field, children, st.sampled_from(["x", "yz"])),
        st.builds(A.Index, children, children),
        st.builds(A.Length, children),
    )


_exprs = st.recursive(_leaves, _extend, max_leaves=12)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_exprs)
def test_random_expression_trees_round_trip(e):
    """300 random expression trees: print → parse gives the same tree."""
    text = print_expr(e)
    stmt = parse_source("void main() {" + text + ";}").decls[0].body.stmts[0]
    assert stmt.expr == e, text
