"""Tests for rrcache.glsl.preprocessor (fixtures in tests/glsl/pp/)."""
from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rrcache.errors import PreprocessorError, SourceLoc
from rrcache.glsl.preprocessor import PPToken, Preprocessed, preprocess, preprocess_file

PP = Path(__file__).parent / "glsl" / "pp"


def texts(source: str, **kw) -> list[str]:
    return [t.text for t in preprocess(source, "t.glsl", **kw).tokens]


def joined(source: str, **kw) -> str:
    return " ".join(texts(source, **kw))


def error_of(source: str, **kw) -> PreprocessorError:
    with pytest.raises(PreprocessorError) as info:
        preprocess(source, "t.glsl", **kw)
    return info.value


# ---------------------------------------------------------------------------------- tokens

@pytest.mark.parametrize("number", ["1", "1.", ".5", "1.0e-5", "1e3", "0x1F", "017", "1u",
                                    "1.0f", "1.0F", "1.0lf", "2.5LF", "3E+2", "0XaBu"])
def test_pp_numbers_are_single_tokens(number):
    toks = preprocess(f"x = {number};", "t.glsl").tokens
    assert [(t.kind, t.text) for t in toks] == [("ident", "x"), ("punct", "="),
                                                ("number", number), ("punct", ";")]


def test_number_followed_by_operator_and_swizzle():
    assert texts("0x1e+5 1.5.x 1e+") == ["0x1e", "+", "5", "1.5", ".", "x", "1e", "+"]


def test_punctuators_longest_match():
    ops = "<<= >>= ++ -- && || ^^ == != <= >= += -= *= /= %= &= ^= |= << >>"
    singles = "( ) [ ] { } . , ; : ? + - * / % < > = ! ~ & | ^"
    toks = preprocess(ops + " " + singles, "t.glsl").tokens
    assert [t.text for t in toks] == (ops + " " + singles).split()
    assert {t.kind for t in toks} == {"punct"}
    assert texts("a<<=b>>c&&&d") == ["a", "<<=", "b", ">>", "c", "&&", "&", "d"]


def test_other_characters_and_stray_hash():
    toks = preprocess('a @ $ "s" b # c ## d', "t.glsl").tokens
    assert [(t.kind, t.text) for t in toks] == [
        ("ident", "a"), ("other", "@"), ("other", "$"), ("other", '"s"'), ("ident", "b"),
        ("other", "#"), ("ident", "c"), ("other", "##"), ("ident", "d")]


def test_tokens_are_pptokens_with_locations():
    toks = preprocess("float  x;\n  y", "f.glsl").tokens
    assert all(isinstance(t, PPToken) for t in toks)
    assert [t.loc for t in toks] == [SourceLoc("f.glsl", 1, 1), SourceLoc("f.glsl", 1, 8),
                                     SourceLoc("f.glsl", 1, 9), SourceLoc("f.glsl", 2, 3)]


# -------------------------------------------------------------------------- comments, lines

def test_comments_removed_and_separate_tokens():
    src = "a/**/b // line comment\nc /* multi\nline\n */ d\n/*x*/e"
    toks = preprocess(src, "t.glsl").tokens
    assert [(t.text, t.loc.line, t.loc.col) for t in toks] == [
        ("a", 1, 1), ("b", 1, 6), ("c", 2, 1), ("d", 4, 5), ("e", 5, 6)]


def test_comment_markers_inside_comments():
    assert texts("a /* // */ b // /* c\nd") == ["a", "b", "d"]


def test_line_continuation_in_text_and_define():
    src = "#define LONG 1 + \\\n  2\nint x = LONG;\nfl\\\noat y;"
    toks = preprocess(src, "t.glsl").tokens
    assert [t.text for t in toks] == ["int", "x", "=", "1", "+", "2", ";", "float", "y", ";"]
    assert toks[-3].loc == SourceLoc("t.glsl", 4, 1)
    assert toks[-2].loc == SourceLoc("t.glsl", 5, 5)


def test_crlf_fixture():
    pp = preprocess_file(PP / "crlf.frag")
    assert [t.text for t in pp.tokens] == ["int", "x", "=", "1", "+", "2", ";", "int", "y", ";"]
    assert pp.tokens[0].loc.line == 3 and pp.tokens[-3].loc == SourceLoc(str(PP / "crlf.frag"),
                                                                          5, 7)


def test_directive_after_multiline_comment_and_spaced_hash():
    src = "/* a\n b */ # define X 2\n  #   if X == 2\nyes\n# endif\n#\nX"
    assert texts(src) == ["yes", "2"]


# ------------------------------------------------------------------- version, extensions

def test_version_recorded_not_emitted():
    pp = preprocess("// header\n/* c */\n#version 450 compatibility\nint a;", "v.glsl")
    assert (pp.version, pp.profile) == (450, "compatibility")
    assert pp.version_loc == SourceLoc("v.glsl", 3, 1)
    assert [t.text for t in pp.tokens] == ["int", "a", ";"]


@pytest.mark.parametrize("header, profile, es, core, version", [
    ("#version 100", "es", 1, 0, 100),
    ("#version 300 es", "es", 1, 0, 300),
    ("#version 320 es", "es", 1, 0, 320),
    ("#version 120", None, 0, 0, 120),
    ("#version 150", "core", 0, 1, 150),
    ("#version 330 core", "core", 0, 1, 330),
    ("#version 460 compatibility", "compatibility", 0, 1, 460),
    # no #version, but the source tests GL_ES: an ES sketch, read as GLSL ES 1.00
    ("", "es", 1, 0, 100),
])
def test_predefined_version_macros(header, profile, es, core, version):
    src = header + """
#if defined(GL_ES)
es
#endif
#ifdef GL_FRAGMENT_PRECISION_HIGH
high
#endif
#if GL_core_profile
core
#endif
v __VERSION__
"""
    pp = preprocess(src, "t.glsl")
    expected = ["es"] * es + ["high"] * es + ["core"] * core + ["v", str(version)]
    assert [t.text for t in pp.tokens] == expected
    assert pp.profile == profile


def test_extension_and_pragma_recorded():
    src = ("#version 330\n#extension GL_ARB_gpu_shader5 : enable\n#extension all : warn\n"
           "#pragma optimize(off)\n#pragma debug (on)\nint a;")
    pp = preprocess(src, "t.glsl")
    assert pp.extensions == [("GL_ARB_gpu_shader5", "enable"), ("all", "warn")]
    assert pp.pragmas == [("optimize(off)", SourceLoc("t.glsl", 4, 1)),
                          ("debug (on)", SourceLoc("t.glsl", 5, 1))]
    assert texts(src) == ["int", "a", ";"]


# ------------------------------------------------------------------------------- macros

def test_object_like_and_nested_expansion():
    src = "#define A B + 1\n#define B (C * 2)\n#define C 3\nint x = A;"
    assert joined(src) == "int x = ( 3 * 2 ) + 1 ;"


def test_function_like_macros():
    src = ("#define SQ(x) ((x)*(x))\n#define MAX2(a, b) max(a, b)\n#define NONE() 7\n"
           "float y = SQ(a+1) + MAX2(f(1, 2), (3, 4)) + NONE();")
    assert joined(src) == ("float y = ( ( a + 1 ) * ( a + 1 ) ) + max ( f ( 1 , 2 ) , "
                           "( 3 , 4 ) ) + 7 ;")


def test_function_like_name_without_call_and_space_before_paren():
    src = "#define F(x) x+1\n#define G (y)\nF; F (2); G"
    assert joined(src) == "F ; 2 + 1 ; ( y )"


def test_call_spanning_lines():
    assert joined("#define F(a, b) a-b\nF(1,\n  2)") == "1 - 2"


def test_stringizing():
    src = '#define S(x) #x\nS(hello   world ( 1,2 ))'
    toks = preprocess(src, "t.glsl").tokens
    assert [(t.kind, t.text) for t in toks] == [("other", '"hello world ( 1,2 )"')]


def test_token_pasting():
    src = ("#define CAT(a, b) a ## b\n#define V 3\n#define XCAT(a, b) CAT(a, b)\n"
           "CAT(vec, 3) CAT(1, 5) CAT(<<, =) CAT(, x) CAT(y, ) CAT(V, V) XCAT(V, V)")
    toks = preprocess(src, "t.glsl").tokens
    assert [(t.kind, t.text) for t in toks] == [
        ("ident", "vec3"), ("number", "15"), ("punct", "<<="), ("ident", "x"),
        ("ident", "y"), ("ident", "VV"), ("number", "33")]


def test_arguments_expanded_before_substitution_except_near_hash():
    src = ("#define N 4\n#define ID(x) x\n#define STR(x) #x\n#define XSTR(x) STR(x)\n"
           "ID(N) STR(N) XSTR(N)")
    assert texts(src) == ["4", '"N"', '"4"']


def test_no_recursive_self_expansion():
    src = ("#define foo foo + 1\n#define a b\n#define b a\n#define f(x) f(x) * 2\n"
           "foo; a; b; f(f(1))")
    assert joined(src) == "foo + 1 ; a ; b ; f ( f ( 1 ) * 2 ) * 2"


def test_c_standard_rescan_examples():
    # ISO C 6.10.3.5 example 3 (the parts without strings).
    src = ("#define x 3\n#define f(a) f(x * (a))\n#undef x\n#define x 2\n#define g f\n"
           "#define z z[0]\n#define h g(~\n#define m(a) a(w)\n#define w 0,1\n"
           "#define t(a) a\n#define p() int\n#define q(x) x\n#define r(x,y) x ## y\n"
           "f(y+1) + f(f(z)) % t(t(g)(0) + t)(1);\n"
           "g(x+(3,4)-w) | h 5) & m\n(f)^m(m);\n"
           "p() i[q()] = { q(1), r(2,3), r(4,), r(,5), r(,) };")
    assert joined(src) == (
        "f ( 2 * ( y + 1 ) ) + f ( 2 * ( f ( 2 * ( z [ 0 ] ) ) ) ) % "
        "f ( 2 * ( 0 ) ) + t ( 1 ) ; "
        "f ( 2 * ( 2 + ( 3 , 4 ) - 0 , 1 ) ) | f ( 2 * ( ~ 5 ) ) & "
        "f ( 2 * ( 0 , 1 ) ) ^ m ( 0 , 1 ) ; "
        "int i [ ] = { 1 , 23 , 4 , 5 , } ;")


def test_undef_and_identical_redefinition():
    src = "#define N 4\n#define N  4\nN\n#undef N\n#undef NEVER_DEFINED\nN"
    assert texts(src) == ["4", "N"]


def test_injected_defines():
    src = "A B C\n#ifdef C\nyes\n#endif"
    assert texts(src, defines={"A": "2 * 3", "B": "", "C": None}) == ["2", "*", "3", "1", "1",
                                                                        "yes"]
    err = error_of("x", defines={"not valid": "1"})
    assert "not a valid macro name" in str(err)


def test_macro_tokens_carry_use_location():
    src = "#define TWO (1 + 1)\n#define F(x) x * TWO\n\n   float v = F(y);"
    toks = preprocess(src, "m.glsl").tokens
    use = SourceLoc("m.glsl", 4, 14)
    assert [t.text for t in toks[3:]] == ["y", "*", "(", "1", "+", "1", ")", ";"]
    assert all(t.loc == use for t in toks[3:-1])
    assert toks[-1].loc == SourceLoc("m.glsl", 4, 18)


def test_line_macro_in_macro_is_use_line():
    src = "#define L __LINE__\n\nint a = L;\nint b = __LINE__;"
    assert texts(src)[3] == "3" and texts(src)[-2] == "4"


# ------------------------------------------------------------------------- conditionals

def test_conditional_chains():
    src = """#define B 2
#if B == 1
one
#elif B == 2
two
#elif B == 3
three
#else
other
#endif
#ifdef B
#ifndef B
no
#else
nested
#endif
#endif
#if 0
#elif 0
#else
last
#endif"""
    assert texts(src) == ["two", "nested", "last"]


def test_skipped_groups_allow_garbage_and_track_nesting():
    src = """#if 0
  ' unbalanced " quotes @ $ 1.2.3.4e+
  #frobnicate whatever
  #if garbage ((( 1/0
  #elif ???
  #else
  #endif
  #error not raised
  #include "missing.glsl"
#else
kept
#endif"""
    assert texts(src) == ["kept"]


@pytest.mark.parametrize("expr, value", [
    ("1 + 2 * 3 == 7", 1), ("(1 + 2) * 3 == 9", 1), ("10 / 3 == 3 && 10 % 3 == 1", 1),
    ("-7 / 2 == -3 && -7 % 2 == -1", 1), ("1 << 4 == 16 && 256 >> 2 == 64", 1),
    ("(6 & 3) == 2 && (6 | 3) == 7 && (6 ^ 3) == 5", 1), ("~0 == -1 && !0 == 1 && !5 == 0", 1),
    ("-(+3) == -3", 1), ("1 < 2 && 2 > 1 && 2 <= 2 && 3 >= 4", 0), ("1 != 1 || 0", 0),
    ("0x10 == 16 && 010 == 8 && 7u == 7", 1), ("UNDEFINED_NAME == 0", 1),
    ("defined X && defined(X) && !defined Y", 1), ("0 && 1 / 0", 0), ("1 || 1 % 0", 1),
    ("1 ? 2 : 1 / 0", 1), ("2147483647 + 1 < 0", 1), ("X + 1 == 6", 1),
    ("(((((1)))))", 1), ("0 ? 1 : 0", 0),
])
def test_if_expression_evaluation(expr, value):
    src = f"#define X 5\n#if {expr}\ntrue\n#else\nfalse\n#endif"
    assert texts(src) == (["true"] if value else ["false"])


def test_defined_operand_not_expanded():
    src = "#define A B\n#if defined A && !defined B\nyes\n#endif"
    assert texts(src) == ["yes"]


# ---------------------------------------------------------------------- #line, __FILE__

def test_line_directive_and_file_numbers():
    path = PP / "line_directive.frag"
    pp = preprocess_file(path)
    toks = {t.text: t for t in pp.tokens}
    main, inc = str(path), os.path.normpath(str(PP / "line_inc.glsl"))
    assert toks["a"].loc == SourceLoc(main, 1, 7)
    assert toks["b"].loc == SourceLoc(main, 100, 7)
    assert [t.text for t in pp.tokens][6:16] == ["int", "f", "=", "3", ";", "int", "l", "=",
                                                 "7", ";"]
    assert toks["inc"].loc == SourceLoc(inc, 1, 36)
    assert toks["inc50"].loc == SourceLoc(inc, 50, 7)
    assert toks["after"].loc == SourceLoc(main, 9, 7)
    assert pp.files == [main, inc]


def test_line_with_string_source_name():
    toks = preprocess('#line 20 "gen/other.glsl"\nx', "t.glsl").tokens
    assert toks[0].loc == SourceLoc("gen/other.glsl", 20, 1)


def test_file_numbers_through_includes():
    pp = preprocess_file(PP / "file_numbers.frag")
    assert [t.text for t in pp.tokens if t.kind == "number"] == ["0", "1", "2", "0"]


# ------------------------------------------------------------------------------ includes

def test_includes_guards_include_dirs_and_locations():
    path = PP / "main_include.frag"
    pp = preprocess_file(path, include_dirs=[PP / "incdir"])
    text = [t.text for t in pp.tokens]
    assert text.count("saturate") == 2  # defined once (guard), called once
    assert "3.14159265" in text and "43758.5453" in text
    common = os.path.normpath(str(PP / "common.glsl"))
    noise = os.path.normpath(str(PP / "incdir" / "lib" / "noise.glsl"))
    hashf = os.path.normpath(str(PP / "incdir" / "lib" / "hash.glsl"))
    assert pp.files == [str(path), common, noise, hashf]
    first = pp.tokens[0]
    assert (first.text, first.loc) == ("float", SourceLoc(common, 5, 1))
    noise_tok = next(t for t in pp.tokens if t.text == "noise")
    assert noise_tok.loc == SourceLoc(noise, 2, 7)
    assert pp.pragmas == [("once_guard_not_supported", SourceLoc(hashf, 1, 1))]
    # HASH expands at its use in noise.glsl, not in hash.glsl
    assert next(t for t in pp.tokens if t.text == "fract").loc == SourceLoc(noise, 2, 30)


def test_include_prefers_including_directory(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "dirs").mkdir()
    (tmp_path / "sub" / "x.glsl").write_text("near")
    (tmp_path / "dirs" / "x.glsl").write_text("far")
    (tmp_path / "dirs" / "y.glsl").write_text("only_far")
    (tmp_path / "sub" / "main.glsl").write_text(
        '#include "x.glsl"\n#include <y.glsl>\n#define WHICH "x.glsl"\n#include WHICH')
    pp = preprocess_file(tmp_path / "sub" / "main.glsl", include_dirs=[tmp_path / "dirs"])
    assert [t.text for t in pp.tokens] == ["near", "only_far", "near"]


def test_include_from_string_source_uses_include_dirs(tmp_path):
    (tmp_path / "lib.glsl").write_text("\ufefflib_token")
    pp = preprocess('#include "lib.glsl"', "<string>", include_dirs=[str(tmp_path)])
    assert [(t.text, t.loc.line, t.loc.col) for t in pp.tokens] == [("lib_token", 1, 1)]


def test_guarded_self_include():
    pp = preprocess_file(PP / "self_include.glsl")
    assert [t.text for t in pp.tokens] == ["float", "once", ";"]


def test_include_cycle_is_named():
    with pytest.raises(PreprocessorError) as info:
        preprocess_file(PP / "cycle_a.glsl")
    msg = str(info.value)
    assert "#include cycle" in msg
    assert re.search(r"cycle_a\.glsl -> .*cycle_b\.glsl -> .*cycle_a\.glsl", msg)
    assert info.value.loc.file.endswith("cycle_b.glsl") and info.value.loc.line == 2


def test_missing_include_names_place_and_paths():
    with pytest.raises(PreprocessorError) as info:
        preprocess('\n  #include "lost.glsl"', str(PP / "m.frag"), include_dirs=["/nowhere"])
    err = info.value
    assert err.loc == SourceLoc(str(PP / "m.frag"), 2, 12)
    assert os.path.normpath(str(PP / "lost.glsl")) in str(err)
    assert os.path.normpath("/nowhere/lost.glsl") in str(err)


# -------------------------------------------------------------------------------- errors

BAD = sorted((PP / "bad").glob("*.frag"))


def test_enough_malformed_fixtures():
    assert len(BAD) >= 8


@pytest.mark.parametrize("path", BAD, ids=[p.stem for p in BAD])
def test_malformed_fixture_reports_exact_place(path):
    header = path.read_text().splitlines()[0]
    m = re.fullmatch(r"// ERROR (?:(\S+):)?(\d+):(\d+) (.+)", header)
    assert m, f"bad fixture header in {path}"
    file = os.path.normpath(os.path.join(path.parent, m.group(1))) if m.group(1) else str(path)
    with pytest.raises(PreprocessorError) as info:
        preprocess_file(path)
    err = info.value
    assert os.path.normpath(err.loc.file) == os.path.normpath(file)
    assert (err.loc.line, err.loc.col) == (int(m.group(2)), int(m.group(3)))
    assert m.group(4) in err.message
    assert str(err).startswith(f"{err.loc.file}:{m.group(2)}:{m.group(3)}: ")


@pytest.mark.parametrize("source, line, col, words", [
    ("#define F(a, b", 1, 14, "unterminated macro parameter list"),
    ("#define F(a, a) a", 1, 14, "duplicate macro parameter"),
    ("#define F(a, 1) a", 1, 14, "expected a parameter name"),
    ("#define C(a) ## a", 1, 14, "cannot begin"),
    ("#define", 1, 2, "needs a macro name"),
    ("#define defined 1", 1, 9, "reserved"),
    ("#define __LINE__ 1", 1, 9, "reserved"),
    ("#if\n#endif", 1, 2, "has no expression"),
    ("#if 1.5\n#endif", 1, 5, "not an integer constant"),
    ("#if 1 << 40\n#endif", 1, 7, "shift count"),
    ("#if defined(X\n#endif", 1, 13, "missing ')'"),
    ("#ifdef\n#endif", 1, 2, "needs a macro name"),
    ("#ifdef A B\n#endif", 1, 10, "unexpected 'B'"),
    ("#if 1\n#else junk\n#endif", 2, 7, "unexpected 'junk'"),
    ("#extension GL_foo enable", 1, 19, "malformed #extension"),
    ("#extension GL_foo : maybe", 1, 21, "unknown extension behavior"),
    ("#extension all : require", 1, 18, "not allowed"),
    ("#line x", 1, 7, "decimal line number"),
    ("#version 330\n#version 330", 2, 2, "duplicate #version"),
    ("#version 999", 1, 10, "unsupported GLSL version"),
    ("#version 330 es", 1, 14, "not an ES version"),
    ("#version 330 fancy", 1, 14, "unknown profile"),
    ("#include", 1, 2, "needs a file name"),
    ('#include "a.glsl" x', 1, 19, "unexpected 'x'"),
    ("#include <a.glsl", 1, 10, "missing '>'"),
    ("#define P(a) a##a\nP(/)", 2, 1, "pasting '/' and '/'"),
    ("#error", 1, 1, "#error"),
    ("#if 1\n#elif 1\n#else\n#elif 1\n#endif", 4, 1, "#elif after #else"),
    ("x\n  #123", 2, 4, "unknown preprocessor directive"),
])
def test_malformed_sources(source, line, col, words):
    err = error_of(source)
    assert (err.loc.file, err.loc.line, err.loc.col) == ("t.glsl", line, col)
    assert words in err.message


def test_error_directive_message():
    err = error_of("#version 330\n#define N 3\n#error need N lights")
    assert err.message == "#error need N lights" and err.loc == SourceLoc("t.glsl", 3, 1)


def test_version_in_included_file_rejected(tmp_path):
    (tmp_path / "v.glsl").write_text("#version 330\n")
    with pytest.raises(PreprocessorError) as info:
        preprocess('#include "v.glsl"', str(tmp_path / "main.frag"))
    assert info.value.loc == SourceLoc(os.path.normpath(str(tmp_path / "v.glsl")), 1, 2)


def test_missing_and_undecodable_files(tmp_path):
    with pytest.raises(PreprocessorError, match="cannot read"):
        preprocess_file(tmp_path / "none.frag")
    bad = tmp_path / "latin.frag"
    bad.write_bytes(b"float a;\nfloat \xe9;\n")
    with pytest.raises(PreprocessorError) as info:
        preprocess_file(bad)
    assert (info.value.loc.line, info.value.loc.col) == (2, 7)


def test_exponential_macros_are_stopped():
    src = "#define D(x) x x\n" + "D(" * 24 + "a" + ")" * 24
    assert "too large" in str(error_of(src))


# ------------------------------------------------------------------- robustness, speed

_PIECES = ["#define ", "#undef ", "#if ", "#ifdef ", "#ifndef ", "#elif ", "#else", "#endif",
           "#line ", "#include ", "#error ", "#pragma ", "#extension ", "#version ", "#",
           "##", " defined", "(", ")", ",", "A", "F", "F(x)", "x", "1", "0", "0x1", "/", "/*",
           "*/", "//", "\\", "\n", "\r\n", " ", "+", "-", "<<", "&&", "||", "?", ":", '"',
           "<", ">", "__LINE__", "__FILE__", "GL_ES", "1.5", "@", "\t", "\x00", "é"]


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(
    st.text(max_size=200),
    st.lists(st.sampled_from(_PIECES), max_size=60).map("".join),
))
def test_random_input_only_raises_preprocessor_error(source):
    try:
        result = preprocess(source, "fuzz.glsl")
    except PreprocessorError as err:
        assert err.loc is None or err.loc.line >= 0
    else:
        assert isinstance(result, Preprocessed)
        assert all(t.kind in ("ident", "number", "punct", "other") for t in result.tokens)


_DIRECTIVE_LINES = ["#define F(a, b) a ## b + #a", "#define G(x) F(x, x) G", "#undef F",
                    "#if F(1, 2) > 3 || defined(G)", "#ifdef G", "#elif 1 / 0", "#else",
                    "#endif", "#line 5 2", "#pragma p", "#extension e : enable",
                    "G(F(1, 2))", "F(G(3),)", "#include \"nope\""]


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.sampled_from(_DIRECTIVE_LINES), st.integers(0, 40),
                          st.sampled_from(["", " ", "(", ")", ",", "#", "x", "\\"])),
                max_size=12))
def test_mutated_directives_only_raise_preprocessor_error(lines):
    mutated = []
    for text, pos, insert in lines:
        pos = min(pos, len(text))
        mutated.append(text[:pos] + insert + text[pos:])
    try:
        preprocess("\n".join(mutated), "mut.glsl")
    except PreprocessorError as err:
        assert err.loc is not None and err.loc.file == "mut.glsl"


def test_large_shader_is_expanded_exactly():
    # (how fast this runs is measured by `rrcache bench-frontend`, not asserted here)
    lines = ["#version 330 core", "#define SQ(x) ((x)*(x))", "#define K 3.0",
             "#ifndef QUALITY", "#define QUALITY 2", "#endif", "uniform vec3 lightPos;"]
    for i in range(3000):
        if i % 50 == 0:
            lines.append(f"#if QUALITY > {i % 3}")
            lines.append("/* block")
            lines.append("   comment */")
            lines.append("#endif")
        lines.append(f"float v{i} = SQ(K + float({i})) * dot(lightPos, vec3(1.0, 0.5e-3, "
                     f"{i}.0)); // c")
    src = "\n".join(lines)
    out = preprocess(src, "big.glsl")
    texts = [t.text for t in out.tokens]
    # every macro expanded, every block comment and directive gone, nothing else lost
    assert not {"SQ", "K", "QUALITY", "block", "comment", "#", "c"} & set(texts)
    one = ["float", "v7", "=", "(", "(", "3.0", "+", "float", "(", "7", ")", ")", "*", "(",
           "3.0", "+", "float", "(", "7", ")", ")", ")", "*", "dot", "(", "lightPos", ",",
           "vec3", "(", "1.0", ",", "0.5e-3", ",", "7.0", ")", ")", ";"]
    assert len(texts) == 4 + 3000 * len(one)
    start = texts.index("v7") - 1
    assert texts[start:start + len(one)] == one
    # locations stay those of the source: the last declaration is on the last line
    last = [t for t in out.tokens if t.text == "v2999"][0]
    assert last.loc.line == len(lines) and last.loc.file == "big.glsl"


@pytest.mark.parametrize("expr", ["(" * 300 + "1" + ")" * 300, "1||(" * 300 + "1" + ")" * 300,
                                  "1?(" * 300 + "1" + ":0)" * 300, "- " * 500 + "1",
                                  "1*(2<<(" * 150 + "1" + "))" * 150])
def test_deep_if_expressions_are_errors_not_crashes(expr):
    assert "nested too deeply" in error_of(f"#if {expr}\n#endif").message


def test_deep_macro_calls_are_errors_not_crashes():
    src = "#define F(x) x\n" + "F(" * 300 + "1" + ")" * 300
    assert "nested too deeply" in error_of(src).message


# --- shaders without #version: ES sketches (issue 14, item 7) -----------------------------------

SKETCH = """// a glslsandbox / Book of Shaders sketch
#ifdef GL_ES
precision mediump float;
#endif
uniform vec2 u_resolution;
#ifdef GL_ES
es_branch
#else
desktop_branch
#endif
v __VERSION__
"""


def test_versionless_sketch_with_precision_is_es_100():
    pp = preprocess(SKETCH, "sketch.frag")
    texts = [t.text for t in pp.tokens]
    assert "es_branch" in texts and "desktop_branch" not in texts
    assert pp.profile == "es" and pp.version is None and texts[-1] == "100"
    assert pp.assumed.startswith("GLSL ES 1.00") and "precision" in pp.assumed


@pytest.mark.parametrize("src,es", [
    ("precision highp float;\nvoid main(){}\n", True),           # precision alone
    ("#if defined(GL_ES)\n#endif\nvoid main(){}\n", True),        # a GL_ES test alone
    ("  #  ifndef GL_ES\n#define lowp\n#endif\n", True),
    ("void main(){}\n", False),                                  # neither: desktop 1.10
    ("// precision mediump float;\n/* #ifdef GL_ES */\nvoid main(){}\n", False),  # comments
    ("float precision_x;\nvoid main(){}\n", False),
])
def test_versionless_es_rule(src, es):
    pp = preprocess(src, "s.frag")
    assert (pp.profile == "es") is es
    assert pp.assumed.startswith("GLSL ES 1.00" if es else "desktop GLSL 1.10")


def test_versioned_shaders_assume_nothing():
    for header in ("#version 100\n", "#version 120\n", "#version 300 es\n", "#version 330\n"):
        pp = preprocess(header + "precision mediump float;\n", "v.frag")
        assert pp.assumed is None
    assert preprocess("#version 120\n#ifdef GL_ES\nx\n#endif\n", "v.frag").profile is None


def test_precision_in_an_include_does_not_decide(tmp_path):
    (tmp_path / "lib.glsl").write_text("precision mediump float;\n")
    pp = preprocess('#include "lib.glsl"\nvoid main(){}\n', str(tmp_path / "m.frag"))
    assert pp.profile is None  # the main file decides, before any include is read


@pytest.mark.parametrize("header,defined,undefined", [
    ("#version 330\n", ["GL_ARB_texture_query_lod", "GL_ARB_texture_gather", "GL_ARB_gpu_shader5"],
     ["GL_OES_standard_derivatives", "GL_EXT_shader_texture_lod"]),
    ("#version 100\n", ["GL_OES_standard_derivatives", "GL_EXT_shader_texture_lod"],
     ["GL_ARB_texture_query_lod"]),
    ("", ["GL_ARB_texture_query_lod"], ["GL_OES_standard_derivatives"]),
    ("precision mediump float;\n", ["GL_OES_standard_derivatives", "GL_EXT_frag_depth"],
     ["GL_ARB_gpu_shader5"]),
])
def test_extension_macros_predefined(header, defined, undefined):
    body = "".join(f"#ifdef {n}\nyes_{n}\n#else\nno_{n}\n#endif\n" for n in defined + undefined)
    texts = [t.text for t in preprocess(header + body, "e.frag").tokens if t.text.startswith(("yes_", "no_"))]
    assert texts == [f"yes_{n}" for n in defined] + [f"no_{n}" for n in undefined]
    # and they have the value 1
    assert [t.text for t in preprocess(header + f"x {defined[0]}\n", "e.frag").tokens][-2:] == ["x", "1"]


def test_extension_macros_cover_the_front_ends_functions():
    """Each predefined extension's functions are known to the front-end (no macro for an
    extension whose built-ins the checker would then reject)."""
    from rrcache.glsl.builtins import BUILTIN_FUNCTIONS
    from rrcache.glsl.extensions import DESKTOP, ES

    for name in ("textureQueryLod", "textureQueryLevels", "textureGather", "fma", "dFdxFine",
                 "floatBitsToInt", "packHalf2x16", "imageLoad", "texture2DLodEXT",
                 "texture2DGradEXT", "textureCubeLodEXT", "texture3D"):
        assert name in BUILTIN_FUNCTIONS, name
    assert "GL_ARB_texture_query_lod" in DESKTOP and "GL_OES_standard_derivatives" in ES
