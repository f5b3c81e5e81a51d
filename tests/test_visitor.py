"""The one visitor of the GLSL tree (rrcache/glsl/visitor.py), the one recogniser of counted
loops (rrcache/analysis/loops.py) and the one def-use account (rrcache/glsl/defuse.py)."""
from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from pathlib import Path

import pytest

from rrcache.analysis.cost import MAX_LOOP_TRIPS, loop_trips
from rrcache.analysis.estimators import find_estimators, loop_header
from rrcache.analysis.loops import Constants, body_exits, counted_loop, global_scalars
from rrcache.analysis.unroll import unroll_loops
from rrcache.glsl import ast as A
from rrcache.glsl.defuse import definitions, uses, var_key
from rrcache.glsl.frontend import parse_shader
from rrcache.glsl.parser import parse_source
from rrcache.glsl.printer import print_glsl
from rrcache.glsl.visitor import NodeTransformer, NodeVisitor

ROOT = Path(__file__).resolve().parents[1]
CORPUS = sorted((ROOT / "tests" / "glsl" / "corpus").glob("*.frag"))


class _Order(NodeVisitor):
    def __init__(self):
        self.seen = []

    def generic_visit(self, node):
        self.seen.append(node)
        super().generic_visit(node)


@pytest.mark.parametrize("path", CORPUS[::6], ids=lambda p: p.stem)
def test_generic_descent_is_the_trees_one_walk(path):
    unit = parse_shader(path.read_text(), path.name).unit
    v = _Order()
    v.visit(unit)
    assert [id(n) for n in v.seen] == [id(n) for n in A.walk(unit)]


def test_dispatch_follows_the_class_bases_and_passes_arguments_on():
    class Kinds(NodeVisitor):
        def __init__(self):
            self.out = []

        def visit_Expr(self, e, depth):
            self.out.append(("expr", type(e).__name__, depth))
            self.generic_visit(e, depth + 1)

        def visit_Binary(self, e, depth):
            self.out.append(("binary", e.op, depth))
            self.generic_visit(e, depth + 1)

        def visit_Stmt(self, s, depth):
            self.out.append(("stmt", type(s).__name__, depth))
            self.generic_visit(s, depth + 1)

    stmt = parse_source("void main() { x = a + f(b); }").decls[0].body
    v = Kinds()
    v.visit(stmt, 0)
    assert v.out == [("stmt", "Compound", 0), ("stmt", "ExprStmt", 1), ("expr", "Assign", 2),
                     ("expr", "Ident", 3), ("binary", "+", 3), ("expr", "Ident", 4),
                     ("expr", "Call", 4), ("expr", "Ident", 5)]


def test_a_new_node_class_needs_no_change_to_a_pass():
    @dataclass
    class Swizzle4(A.Expr):      # a node class the passes were not written for
        obj: A.Expr
        lanes: str

    class Names(NodeVisitor):
        def __init__(self):
            self.names = []

        def visit_Ident(self, e):
            self.names.append(e.name)

    e = A.Binary("+", Swizzle4(A.Call("f", [A.Ident("a")]), "xyzw"), A.Ident("b"))
    v = Names()
    v.visit(e)
    assert v.names == ["a", "b"]


def test_the_transformer_replaces_drops_and_splices():
    unit = parse_source("void main() { a = 1.0; b = 2.0; c = 3.0; }")

    class Edit(NodeTransformer):
        def visit_ExprStmt(self, s):
            name = s.expr.target.name
            if name == "a":
                return None                                   # dropped from the block
            if name == "b":
                return [s, A.ExprStmt(A.Assign("=", A.Ident("d"), A.FloatLit(4.0)))]  # spliced
            return self.generic_visit(s)

        def visit_FloatLit(self, e):
            return A.FloatLit(e.value * 10)                   # a field replaced

    out = Edit().visit(unit)
    assert out is unit
    assert print_glsl(unit).split() == ["void", "main()", "{", "b", "=", "2.0;", "d", "=", "4.0;",
                                        "c", "=", "30.0;", "}"]


# ----------------------------------------------------------------------------- counted loops

def _loop(body: str, decls: str = ""):
    s = parse_shader(f"#version 330\n{decls}\nout vec4 o;\nvoid main() {{ float acc = 0.0; {body}"
                     " o = vec4(acc); }")
    loop = next(n for n in A.walk(s.unit) if isinstance(n, A.For))
    return s, loop


@pytest.mark.parametrize("header,decls,values", [
    ("int i = 0; i < 4; i++", "", [0, 1, 2, 3]),
    ("int i = 10; 2 <= i; i -= 3", "", [10, 7, 4]),
    ("int i = 1; i < N * 2; i = i + 3", "const int N = 4;", [1, 4, 7]),
    ("int i = 0; i != 6; i += 2", "", [0, 2, 4]),
    ("int i = N / 2; i < 5; ++i", "const int N = 7;", [3, 4]),
    ("uint k = 2u; k < 10u; k--", "", [2, 1, 0]),        # wraps through zero to 4294967295
    ("float t = 0.0; t < 1.0; t += 0.25", "", [0.0, 0.25, 0.5, 0.75]),
])
def test_counted_loop_headers(header, decls, values):
    s, loop = _loop(f"for ({header}) acc += 1.0;", decls)
    head, why = counted_loop(loop, Constants(global_scalars(s.info).get))
    assert why == "" and head.values(100) == values
    assert loop_trips(loop, Constants(global_scalars(s.info).get)) == len(values)


@pytest.mark.parametrize("header,reason", [
    ("; i < 4; i++", "the loop does not declare its index in its header"),
    ("vec2 v = vec2(0.0); v.x < 4.0; v.x++", "the loop index is not an int, uint or float"),
    ("int i = int(u); i < 4; i++", "the loop index does not start at a constant"),
    ("int i = 0; true; i++", "the loop condition is not a comparison of the index with a constant"),
    ("int i = 0; j < 4; i++", "the loop condition does not compare the index"),
    ("int i = 0; i < int(u); i++", "the loop bound is not constant"),
    ("int i = 0; i < 4; i *= 2", "the loop step is not a constant increment of the index"),
])
def test_counted_loop_refusals_say_why(header, reason):
    s, loop = _loop(f"int i = 0; int j = 0; for ({header}) acc += 1.0;", "uniform float u;")
    head, why = counted_loop(loop, Constants(global_scalars(s.info).get))
    assert head is None and why == reason
    assert loop_trips(loop, Constants(global_scalars(s.info).get)) == 1


def test_the_three_users_agree_on_one_loop():
    """The unroller copies the body as often as the cost model counts and the estimator search
    samples."""
    s, loop = _loop("for (int i = 1; i < N * 2; i = i + 3) acc += sin(float(i));", "const int N = 4;")
    consts = global_scalars(s.info)
    assert loop_trips(loop, Constants(consts.get)) == 3
    assert loop_header(loop, consts)[0] == ("i", 1, 3, 3)
    est = find_estimators(s).estimators[0]
    assert (est.samples, est.start, est.step) == (3, 1, 3)
    text = print_glsl(unroll_loops(s).unit)
    assert "for" not in text and text.count("sin(") == 3


def test_an_early_exit_is_a_property_of_the_body():
    s, loop = _loop("for (int i = 0; i < 8; i++) { acc += 1.0; if (acc > 3.0) break; }")
    assert body_exits(loop.body)
    assert "for" in print_glsl(unroll_loops(s).unit)              # left rolled
    assert "break" in find_estimators(s).rejected[0].reason
    s, loop = _loop("for (int i = 0; i < 8; i++) { for (int j = 0; j < 2; j++) break; acc += 1.0; }")
    assert not body_exits(loop.body)


def test_the_cost_model_counts_a_loop_past_its_limit_as_the_limit():
    s, loop = _loop("for (int i = 0; i < 100000; i++) { acc += 1.0; if (acc > 3.0) break; }")
    assert loop_trips(loop, Constants(global_scalars(s.info).get)) == MAX_LOOP_TRIPS


# ----------------------------------------------------------------------------- def-use

def test_definitions_whole_and_partial():
    s = parse_shader("#version 330\nout vec4 o;\nvoid f(out float a, inout float b) { a = b; }\n"
                     "void main() { vec4 c; float a[2]; float x, y, z;\n"
                     "  c = vec4(0.0); c.rg = vec2(1.0); a[1] = 2.0; x += 1.0; y++;\n"
                     "  f(z, x); float w = modf(x, y); o = c; }")
    main = s.unit.decls[-1]
    got = [(d.root.name, type(d.node).__name__, d.whole) for d in definitions(main.body)]
    assert got == [("c", "Assign", True), ("c", "Assign", False), ("a", "Assign", False),
                   ("x", "Assign", False), ("y", "Unary", False), ("z", "Call", True),
                   ("x", "Call", False), ("y", "Call", True), ("o", "Assign", True)]
    read = [u.name for u in uses(main.body)]
    assert "o" not in read and read.count("c") == 2      # c.rg = ... reads c; o = c reads c
    keys = {var_key(u) for u in uses(main.body) if u.name == "x"}
    assert len(keys) == 1 and next(iter(keys))[1] == "x"


# ----------------------------------------------------------------------------- no ladders

def test_no_pass_switches_on_three_node_classes_by_hand():
    spec = importlib.util.spec_from_file_location("ast_ladders", ROOT / "tools" / "ast_ladders.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    assert tool.count(ROOT, min_classes=3) == {}, "write the pass as a rrcache.glsl.visitor.NodeVisitor"
