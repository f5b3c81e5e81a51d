"""Tests of the legacy-to-core conversion (rrcache.glsl.legacy), compiled by the real driver."""
from __future__ import annotations

import copy
from pathlib import Path

import pytest

from rrcache.errors import UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.legacy import to_core
from rrcache.glsl.parser import parse_source
from rrcache.glsl.printer import print_glsl

CORPUS = sorted((Path(__file__).parent / "glsl" / "corpus").glob("*.frag"))


def core(src: str) -> str:
    return print_glsl(to_core(parse_source(src, "l.frag")))


# ----------------------------------------------------------------------------- rewrites

def test_legacy_shader_is_rewritten():
    out = core("#version 120\nvarying vec3 v_normal;\nuniform sampler2D t;\nuniform samplerCube c;\n"
               "void main() {\n  vec4 a = texture2D(t, v_normal.xy) + texture2DLod(t, vec2(0.0), 1.0);\n"
               "  a += textureCube(c, v_normal) + texture2DProj(t, vec3(1.0));\n"
               "  gl_FragColor = a;\n}\n")
    assert out.startswith("#version 330 core\nout vec4 rr_FragColor;\nin vec3 v_normal;\n")
    for old in ("texture2D", "textureCube", "varying", "gl_FragColor"):
        assert old not in out
    assert "texture(t, v_normal.xy) + textureLod(t, vec2(0.0), 1.0)" in out
    assert "texture(c, v_normal) + textureProj(t, vec3(1.0))" in out
    assert out.count("rr_FragColor") == 2


def test_frag_color_declared_once_and_fragdata_zero():
    out = core("void main() { gl_FragData[0] = vec4(1.0); gl_FragData[0].a = 0.5; }")
    assert out.count("out vec4 rr_FragColor;") == 1
    assert "rr_FragColor.a = 0.5;" in out


@pytest.mark.parametrize("src, message", [
    ("void main() { gl_FragData[1] = vec4(1.0); }", "several colour outputs"),
    ("uniform int i; void main() { gl_FragData[i] = vec4(1.0); }", "non-constant"),
    ("attribute vec3 position; void main() { gl_FragColor = vec4(position, 1.0); }",
     "vertex shader input"),
])
def test_unsupported(src, message):
    with pytest.raises(UnsupportedShaderError, match=message) as info:
        to_core(parse_source(src, "u.frag"))
    assert info.value.loc.file == "u.frag"


def test_precision_dropped_and_es_extension_removed():
    out = core("#version 100\n#extension GL_OES_standard_derivatives : enable\n"
               "precision highp float;\nvarying mediump vec2 uv;\n"
               "highp float f(lowp float x) { precision lowp int; return dFdx(x); }\n"
               "void main() { gl_FragColor = vec4(f(uv.x)); }")
    assert "precision" not in out and "mediump" not in out and "lowp" not in out
    assert "#extension" not in out
    assert "in vec2 uv;" in out and "float f(float x)" in out


def test_es300_becomes_core_and_keeps_outputs():
    out = core("#version 300 es\nprecision mediump float;\nout vec4 color;\n"
               "void main() { color = vec4(1.0); }")
    assert out.startswith("#version 330 core\nout vec4 color;\n")


def test_core_versions_kept_or_raised():
    assert core("#version 450 core\nout vec4 c;\nvoid main() { c = vec4(1); }").startswith(
        "#version 450 core\n")
    assert core("#version 150\nout vec4 c;\nvoid main() { c = vec4(1); }").startswith(
        "#version 330 core\n")
    assert core("out vec4 c;\nvoid main() { c = vec4(1); }").startswith("#version 330 core\n")


def test_user_function_named_like_builtin_left_alone():
    out = core("vec4 texture2D(sampler2D s, vec2 uv) { return vec4(uv, 0.0, 1.0); }\n"
               "uniform sampler2D t;\nvoid main() { gl_FragColor = texture2D(t, vec2(0.5)); }")
    assert "vec4 texture2D(sampler2D s, vec2 uv)" in out
    assert "rr_FragColor = texture2D(t, vec2(0.5));" in out


def test_names_that_became_keywords_or_builtins_are_renamed():
    out = core("#version 120\nuniform sampler2D texture;\nstruct S { float flat; };\n"
               "float round(float x) { return floor(x + 0.5); }\n"
               "void main() { S s; s.flat = round(1.2); float smooth = s.flat;"
               " gl_FragColor = texture2D(texture, vec2(smooth)); }")
    assert "uniform sampler2D rr_texture;" in out and "float rr_flat;" in out
    assert "s.rr_flat = rr_round(1.2);" in out and "float rr_smooth = s.rr_flat;" in out
    assert "texture(rr_texture, vec2(rr_smooth))" in out


def test_shadow_calls_keep_vec4_result():
    out = core("uniform sampler2DShadow s;\nvoid main() { gl_FragColor = shadow2D(s, vec3(0.5)); }")
    assert "rr_FragColor = vec4(texture(s, vec3(0.5)));" in out


def test_input_unit_is_not_modified():
    unit = parse_source("varying vec2 uv;\nvoid main() { gl_FragColor = texture2D(s, uv); }")
    before = copy.deepcopy(unit)
    result = to_core(unit)
    assert unit == before and result is not unit
    assert isinstance(result.decls[0], A.VariableDecl)


def test_to_core_is_idempotent_on_corpus():
    for path in CORPUS:
        once = to_core(parse_source(path.read_text(), str(path)))
        assert to_core(once) == once, path.name


# ----------------------------------------------------------------------------- the driver

# The driver tests use the shared ``gl_ctx`` fixture (tests/conftest.py): the one context of the
# process, made by rrcache.gl.context.get_context(); no EGL is a failure, not a skip.


def vertex_shader_for(unit: A.TranslationUnit) -> str:
    """A vertex shader declaring, as outputs, every input the fragment shader declares."""
    decls: list = []
    for d in unit.decls:
        if isinstance(d, A.VariableDecl) and (not d.declarators or "const" in d.type.qualifiers):
            decls.append(d)  # struct definitions and constants the inputs may use
        elif isinstance(d, (A.VariableDecl, A.InterfaceBlock)):
            quals = d.type.qualifiers if isinstance(d, A.VariableDecl) else d.qualifiers
            if "in" in quals:
                d = copy.deepcopy(d)
                new = ["out" if q == "in" else q for q in quals]
                if isinstance(d, A.VariableDecl):
                    d.type.qualifiers = new
                else:
                    d.qualifiers = new
                decls.append(d)
    main = A.FunctionDecl(A.FullType([], A.TypeSpecifier("void")), "main", [], A.Compound([
        A.ExprStmt(A.Assign("=", A.Ident("gl_Position"), A.Call("vec4", [A.FloatLit(0.0)])))]))
    vs = A.TranslationUnit(decls + [main], version=unit.version, profile=unit.profile)
    return print_glsl(vs)


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.name)
def test_core_output_compiles_with_the_driver(gl_ctx, path):
    unit = to_core(parse_source(path.read_text(), str(path)))
    fragment = print_glsl(unit)
    vertex = vertex_shader_for(unit)
    prog = gl_ctx.program(vertex_shader=vertex, fragment_shader=fragment)
    prog.release()
