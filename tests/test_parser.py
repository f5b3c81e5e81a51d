"""Tests of the GLSL lexer and parser (rrcache.glsl.lexer, rrcache.glsl.parser)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from rrcache.errors import GLSLError, ParseError
from rrcache.glsl import ast as A
from rrcache.glsl.lexer import lex
from rrcache.glsl.parser import parse, parse_source
from rrcache.glsl.printer import print_glsl
from rrcache.glsl.preprocessor import preprocess

HERE = Path(__file__).parent
CORPUS = sorted((HERE / "glsl" / "corpus").glob("*.frag"))
MALFORMED = sorted((HERE / "glsl" / "malformed").glob("*.frag"))


def body(src: str, header: str = "") -> list[A.Stmt]:
    """The statements of ``void main() { src }``."""
    unit = parse_source(header + "void main() {" + src + "}", "t.frag")
    return unit.decls[-1].body.stmts


def expr(src: str) -> A.Expr:
    return body(src + ";")[0].expr


def tokens(src: str):
    return lex(preprocess(src, "t.frag").tokens)


# ----------------------------------------------------------------------------- lexer

def test_lexer_kinds_and_values():
    toks = tokens("vec3 a = 0x1F + 017 + 3u + 1.5f + 2.0lf + 1e3 + .5; bool b = true;")
    kinds = [(t.kind, t.value) for t in toks if t.kind not in ("punct",)]
    assert kinds == [
        ("keyword", None), ("ident", None), ("int", 31), ("int", 15), ("uint", 3),
        ("float", 1.5), ("double", 2.0), ("float", 1000.0), ("float", 0.5),
        ("keyword", None), ("ident", None), ("bool", True), ("eof", None)]


def test_lexer_keywords_cover_samplers_images_and_dmat():
    for word in ("sampler2DArrayShadow", "usamplerCubeArray", "iimage2DMS", "dmat4x3",
                 "atomic_uint", "noperspective", "writeonly", "precise"):
        assert tokens(f"{word}")[0].kind == "keyword", word


def test_lexer_late_keywords_depend_on_version():
    pp = preprocess("float sample;", "t.frag")
    assert lex(pp.tokens, 120)[1].kind == "ident"
    assert lex(pp.tokens, 450)[1].kind == "keyword"


@pytest.mark.parametrize("src, message", [
    ("int a = 0x;", "invalid number"), ("float a = 1f;", "invalid number"),
    ("int a = 4294967296;", "does not fit"), ("int input;", "reserved word"),
    ("float a = $;", "unexpected character"), ("int a = 08;", "invalid octal"),
])
def test_lexer_errors(src, message):
    with pytest.raises(ParseError, match=message) as info:
        tokens(src)
    assert info.value.loc.file == "t.frag"


def test_lexer_eof_location_is_after_last_token():
    toks = tokens("float  abc")
    assert toks[-1].kind == "eof" and (toks[-1].loc.line, toks[-1].loc.col) == (1, 11)


# ----------------------------------------------------------------------------- expressions

def test_precedence_and_associativity():
    e = expr("a = b = c + d * e - f")
    assert isinstance(e, A.Assign) and isinstance(e.value, A.Assign)
    add = e.value.value
    assert add.op == "-" and add.left.op == "+" and add.left.right.op == "*"
    t = expr("x = p ? a : q ? b : c").value
    assert isinstance(t, A.Ternary) and isinstance(t.else_, A.Ternary)
    e = expr("x = a || b ^^ c && d | e ^ f & g == h < i << j + k * l")
    ops = []
    while isinstance(e, (A.Binary, A.Assign)):
        if isinstance(e, A.Assign):
            e = e.value
            continue
        ops.append(e.op)
        e = e.right
    assert ops == ["||", "^^", "&&", "|", "^", "&", "==", "<", "<<", "+", "*"]


def test_unary_postfix_and_sequence():
    e = expr("x = -a++ + ~b - !c, ++d, e--")
    assert isinstance(e, A.Sequence) and len(e.exprs) == 3
    plus = e.exprs[0].value.left
    assert plus.left == A.Unary("-", A.Unary("++", A.Ident("a"), postfix=True))
    assert plus.right == A.Unary("~", A.Ident("b"))
    assert e.exprs[2] == A.Unary("--", A.Ident("e"), postfix=True)


def test_postfix_chain_calls_and_length():
    e = expr("x = s.lights[i + 1].color.rgb * f(a, b)[2] + arr.length() + vec3(1.0).x")
    add = e.value
    assert isinstance(add.right, A.Field) and add.right.obj.name == "vec3"
    assert isinstance(add.left.right, A.Length)
    mul = add.left.left
    assert mul.left == A.Field(A.Field(A.Index(A.Field(A.Ident("s"), "lights"), A.Binary(
        "+", A.Ident("i"), A.IntLit(1))), "color"), "rgb")
    assert mul.right == A.Index(A.Call("f", [A.Ident("a"), A.Ident("b")]), A.IntLit(2))


def test_array_constructors():
    e = expr("x = float[3](1.0, 2.0, 3.0)")
    assert e.value.name == "float" and e.value.array_dims == [A.IntLit(3)]
    e = expr("x = vec2[](vec2(0.0), vec2(1.0))")
    assert e.value.array_dims == [None] and len(e.value.args) == 2


def test_locations_are_first_token():
    e = expr("x = a + b * c")
    assert (e.loc.line, e.loc.col) == (1, 14)
    assert (e.value.loc.col, e.value.right.loc.col) == (18, 22)
    unit = parse_source("uniform float u;\nvoid main() {\n  float v = u;\n}", "t.frag")
    for node in unit.walk():
        assert node.loc is not None, node


# ----------------------------------------------------------------------------- declarations

def test_declaration_versus_expression_statements():
    stmts = parse_source(
        "struct S { float a; };\nvoid main() { S s; S(1.0); vec3 v; vec3(1.0); float[2] f; "
        "float[2](1.0, 2.0); s.a = 1.0; }", "t.frag").decls[1].body.stmts
    kinds = [type(s).__name__ for s in stmts]
    assert kinds == ["DeclStmt", "ExprStmt", "DeclStmt", "ExprStmt", "DeclStmt", "ExprStmt",
                     "ExprStmt"]
    assert stmts[4].decl.type.spec.array_dims == [A.IntLit(2)]


def test_struct_names_are_scoped():
    src = "void f() { struct L { int i; }; L l; }\nvoid main() { L l; }"
    with pytest.raises(ParseError, match="unknown type name 'L'") as info:
        parse_source(src, "t.frag")
    assert (info.value.loc.line, info.value.loc.col) == (2, 15)


def test_qualifiers_and_layouts_kept_in_order():
    unit = parse_source("#version 450\nlayout(location = 1 + 1, index = 0) flat centroid in "
                        "highp ivec2 a[2], b;", "t.frag")
    d = unit.decls[0]
    lay, *words = d.type.qualifiers
    assert words == ["flat", "centroid", "in", "highp"]
    assert lay.items[0][0] == "location" and isinstance(lay.items[0][1], A.Binary)
    assert [x.name for x in d.declarators] == ["a", "b"]
    assert d.declarators[0].array_dims == [A.IntLit(2)]


def test_qualifier_only_declarations():
    unit = parse_source("#version 450\ninvariant gl_FragColor, x;\nlayout(early_fragment_tests) in;",
                        "t.frag")
    assert unit.decls[0] == A.QualifierDecl(["invariant"], ["gl_FragColor", "x"])
    assert unit.decls[1] == A.QualifierDecl([A.Layout([("early_fragment_tests", None)]), "in"])


def test_interface_blocks():
    unit = parse_source("#version 330\nlayout(std140) uniform B { mat4 m; vec4 v[2]; } inst[3];\n"
                        "uniform C { float x; };", "t.frag")
    b, c = unit.decls
    assert isinstance(b, A.InterfaceBlock) and b.block_name == "B"
    assert b.instance_name == "inst" and b.array_dims == [A.IntLit(3)]
    assert [m.declarators[0].name for m in b.members] == ["m", "v"]
    assert c.instance_name is None


def test_functions_params_prototypes():
    unit = parse_source("float f(const in float a, out vec2 b[2], inout int);\n"
                        "void g(void) {}\nfloat[2] h() { return float[2](0.0, 1.0); }", "t.frag")
    f, g, h = unit.decls
    assert f.body is None and [p.name for p in f.params] == ["a", "b", None]
    assert f.params[0].type.qualifiers == ["const", "in"] and f.params[1].array_dims == [A.IntLit(2)]
    assert g.params == [] and g.body == A.Compound([])
    assert h.return_type.spec.array_dims == [A.IntLit(2)]


def test_structs_anonymous_nested_with_variables():
    unit = parse_source("struct A { vec3 p; } a1, a2[2];\nstruct { A inner; float w; } anon;\n"
                        "struct B { struct C { int i; } c; };", "t.frag")
    a, anon, b = unit.decls
    assert a.type.spec.struct.name == "A" and [d.name for d in a.declarators] == ["a1", "a2"]
    assert anon.type.spec.struct.name is None
    assert anon.type.spec.struct.members[0].type.spec.name == "A"
    assert b.declarators == [] and b.type.spec.struct.members[0].type.spec.struct.name == "C"


def test_initializer_lists_and_precision():
    unit = parse_source("#version 450\nprecision mediump float;\nconst vec2 v[2] = { {1.0, 2.0}, "
                        "vec2(3.0), };", "t.frag")
    assert unit.decls[0] == A.PrecisionDecl("mediump", A.TypeSpecifier("float"))
    init = unit.decls[1].declarators[0].init
    assert isinstance(init, A.InitList) and len(init.items) == 2
    assert isinstance(init.items[0], A.InitList)


def test_statements():
    stmts = body("if (a) b = 1; else if (c) ; else { discard; }"
                 "for (int i = 0, j; i < 3; i++, j--) continue;"
                 "for (;;) break;"
                 "while (bool k = a < b) {}"
                 "do x++; while (x < 3);"
                 "switch (m) { case 1: case 2 + 1: x = 0; break; default: return; }"
                 "return x;", header="#version 330\n")
    i, f, f2, w, d, s, r = stmts
    assert isinstance(i.else_, A.If) and isinstance(i.else_.then, A.ExprStmt)
    assert isinstance(i.else_.else_.stmts[0], A.Discard)
    assert isinstance(f.init, A.DeclStmt) and isinstance(f.step, A.Sequence)
    assert f2.init is None and f2.cond is None and f2.step is None
    assert isinstance(w.cond, A.VariableDecl) and w.cond.declarators[0].name == "k"
    assert isinstance(d, A.DoWhile)
    assert [type(x).__name__ for x in s.body.stmts] == ["Case", "Case", "ExprStmt", "Break",
                                                          "Case", "Return"]
    assert s.body.stmts[4].expr is None
    assert r == A.Return(A.Ident("x"))


def test_dangling_else_binds_to_nearest_if():
    (stmt,) = body("if (a) if (b) x = 1; else x = 2;")
    assert stmt.else_ is None and stmt.then.else_ is not None


def test_version_profile_extensions():
    unit = parse_source("#version 300 es\n#extension GL_EXT_foo : enable\nvoid main() {}", "t.frag")
    assert (unit.version, unit.profile, unit.extensions) == (300, "es", [("GL_EXT_foo", "enable")])
    assert parse(lex(preprocess("void main(){}", "t").tokens)).version is None


def test_defines_are_applied():
    unit = parse_source("float a = N;", "t.frag", defines={"N": "2.0"})
    assert unit.decls[0].declarators[0].init.value == 2.0


# ----------------------------------------------------------------------------- corpus and errors

def test_corpus_is_large_enough():
    assert len(CORPUS) >= 40 and len(MALFORMED) >= 30


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.name)
def test_corpus_parses(path):
    unit = parse_source(path.read_text(), str(path))
    assert any(isinstance(d, A.FunctionDecl) and d.name == "main" for d in unit.decls)


@pytest.mark.parametrize("path", MALFORMED, ids=lambda p: p.name)
def test_malformed_gives_one_error_at_the_place(path):
    src = path.read_text()
    m = re.match(r"// expect: (\d+):(\d+) (.*)", src)
    assert m, "malformed shaders start with '// expect: line:col message'"
    with pytest.raises(GLSLError) as info:
        parse_source(src, str(path))
    err = info.value
    assert (err.loc.line, err.loc.col) == (int(m[1]), int(m[2])), str(err)
    assert m[3] in err.message
    assert str(err).startswith(f"{path}:{m[1]}:{m[2]}: ")


def test_deep_nesting_is_a_parse_error_not_recursion_error():
    with pytest.raises(ParseError, match="nesting too deep"):
        expr("x = " + "(" * 5000 + "1" + ")" * 5000)
    with pytest.raises(ParseError, match="nesting too deep"):
        body("{" * 3000 + "}" * 3000)
    with pytest.raises(ParseError, match="nesting too deep"):
        expr("x = " + "-" * 5000 + "1")


def test_large_shader_parses_completely():
    # (its speed is measured by `rrcache bench-frontend`, not asserted here)
    fn = (HERE / "glsl" / "corpus" / "37_raymarch_scene.frag").read_text().split("void main()")[0]
    parts = ["#version 330 core\nuniform vec3 u_camera;\nuniform float u_time;\n"
             "uniform vec2 u_resolution;\nout vec4 fragColor;\n"]
    body_ = fn.split("out vec4 fragColor;")[1]
    i = 0
    while sum(p.count("\n") for p in parts) < 3000:
        parts.append(re.sub(r"\b(sdTorus|opSmoothUnion|scene|normalAt)\b", rf"\1_{i}", body_))
        i += 1
    src = "".join(parts) + "void main() { fragColor = vec4(1.0); }\n"
    assert src.count("\n") >= 3000
    unit = parse_source(src, "big.frag")
    names = [d.name for d in unit.decls if isinstance(d, A.FunctionDecl)]
    assert len(names) == 4 * i + 1 and names[-1] == "main"
    assert {f"scene_{k}" for k in range(i)} <= set(names)
    assert parse_source(print_glsl(unit), "printed.frag") == unit


def test_layout_keyword_before_140_with_extension():
    # GL_ARB_shading_language_420pack (and the other layout extensions) make 'layout' a keyword
    # in #version 130 shaders (glslang's spv.130.frag); without one it stays an identifier.
    src = ("#version 130\n#extension GL_ARB_shading_language_420pack : enable\n"
           "uniform layout(binding=0) sampler2D bounds;\nvoid main() {}\n")
    unit = parse_source(src)
    assert isinstance(unit.decls[0], A.VariableDecl)
    assert any(isinstance(q, A.Layout) for q in unit.decls[0].type.qualifiers)
    kinds = [t.kind for t in lex(preprocess("#version 130\nfloat layout;\n", "a.frag").tokens,
                                 130)]
    assert kinds[1] == "ident"
