"""Semantic analysis (rrcache.glsl.semantic) and the front-end entry point (frontend)."""
import dataclasses
import glob
import os
import re

import pytest

from rrcache.errors import GLSLError, SemanticError, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.builtins import BuiltinFunction
from rrcache.glsl.frontend import load_shader, parse_shader
from rrcache.glsl.parser import parse_source
from rrcache.glsl.semantic import check
from rrcache.glsl.types import BOOL, FLOAT, INT, VEC2, VEC3, VEC4, Type

HERE = os.path.dirname(__file__)
ROOT = os.path.dirname(HERE)


def nodes(node):
    """Every node below ``node``, not following the links semantic analysis adds
    (``Call.target`` points at a FunctionDecl elsewhere in the tree)."""
    yield node
    for f in dataclasses.fields(node):
        if f.name in ("loc", "type", "symbol", "kind") or (
                f.name == "target" and isinstance(node, A.Call)):
            continue
        value = getattr(node, f.name)
        items = value if isinstance(value, list) else [value]
        for item in items:
            subs = item if isinstance(item, tuple) else (item,)
            for sub in subs:
                if isinstance(sub, A.Node):
                    yield from nodes(sub)


def checked(src, name="test.frag"):
    unit = parse_source(src, name)
    info = check(unit)
    untyped = [n for n in nodes(unit) if isinstance(n, A.Expr) and n.type is None]
    assert not untyped, f"expressions without a type: {untyped[:3]}"
    return unit, info


def init_of(unit, name):
    """The initializer of the (first) declarator called ``name``."""
    for n in nodes(unit):
        if isinstance(n, A.Declarator) and n.name == name:
            return n.init
    raise KeyError(name)


def ty(unit, name):
    return init_of(unit, name).type


def calls(unit, name):
    return [n for n in nodes(unit) if isinstance(n, A.Call) and n.name == name]


T = Type.from_name

SHADER_330 = """#version 330
uniform float u_time;
uniform vec3 u_light;
uniform mat4 u_mvp;
uniform mat3 u_normalMatrix;
uniform sampler2D u_tex;
uniform samplerCube u_env;
in vec4 v_position;
in vec3 v_normal;
in vec2 v_texcoord;
out vec4 fragColor;

struct Material { vec3 albedo; float shininess; float weights[3]; };
const int N = 2 * 3 + 1;
const float SCALE = 0.5;

float lum(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }
vec3 shade(Material m, vec3 n, vec3 l);

void main() {
    vec3 n = normalize(u_normalMatrix * v_normal);
    vec4 clip = u_mvp * v_position;
    vec2 uv = v_texcoord.yx * 2.0 - 1.0;
    vec4 texel = texture(u_tex, uv);
    vec3 env = texture(u_env, reflect(-n, n)).rgb;
    float arr[N];
    int len = arr.length();
    Material mat = Material(texel.rgb, 16.0, float[3](0.1, 0.2, 0.3));
    float w = mat.weights[1] + mat.albedo.g;
    bool front = gl_FrontFacing && u_time > 1.0;
    ivec2 size = textureSize(u_tex, 0);
    float mixed = mix(0.0, 1.0, 0.5);
    vec3 mixv = mix(env, vec3(1.0), 0.25);
    float sel = front ? 1.0 : 0.0;
    mat3 m3 = mat3(u_mvp);
    vec3 row = vec3(1.0) * m3;
    float fw = fwidth(uv.x);
    float conv = u_time + 1;
    for (int i = 0; i < N; ++i) { arr[i] = float(i) * SCALE; }
    vec3 c = shade(mat, n, normalize(u_light - v_position.xyz)) * lum(env);
    fragColor = vec4(c + env * w * sel + texel.rgb * fw, clip.w);
}

vec3 shade(Material m, vec3 n, vec3 l) {
    float d = max(dot(n, l), 0.0);
    return m.albedo * d + pow(d, m.shininess);
}
"""


# ----------------------------------------------------------------------------- typing

def test_expression_types_in_a_core_shader():
    unit, info = checked(SHADER_330)
    assert ty(unit, "n") == VEC3
    assert ty(unit, "clip") == VEC4
    assert ty(unit, "uv") == VEC2
    assert ty(unit, "texel") == VEC4
    assert ty(unit, "env") == VEC3
    assert ty(unit, "len") == INT
    assert ty(unit, "mat").glsl_name() == "Material"
    assert ty(unit, "w") == FLOAT
    assert ty(unit, "front") == BOOL
    assert ty(unit, "size") == T("ivec2")
    assert ty(unit, "mixed") == FLOAT
    assert ty(unit, "mixv") == VEC3
    assert ty(unit, "sel") == FLOAT
    assert ty(unit, "m3") == T("mat3")
    assert ty(unit, "row") == VEC3
    assert ty(unit, "fw") == FLOAT
    assert ty(unit, "conv") == FLOAT  # int -> float implicitly in 3.30
    arr_uses = [n for n in nodes(unit) if isinstance(n, A.Ident) and n.name == "arr"]
    assert arr_uses and all(n.symbol.type == FLOAT.array_of(7) for n in arr_uses)
    assert all(n.type == FLOAT.array_of(7) for n in arr_uses)
    assert init_of(unit, "N").type == INT


def test_symbols_calls_and_info():
    unit, info = checked(SHADER_330)
    assert list(info.uniforms) == ["u_time", "u_light", "u_mvp", "u_normalMatrix", "u_tex",
                                   "u_env"]
    assert info.uniforms["u_tex"].type == T("sampler2D")
    assert list(info.inputs) == ["v_position", "v_normal", "v_texcoord"]
    assert list(info.outputs) == ["fragColor"]
    assert info.globals["N"].const_value == 7 and info.globals["N"].kind == "const"
    assert info.structs["Material"].field_type("weights") == FLOAT.array_of(3)
    idents = {n.name: n.symbol for n in nodes(unit) if isinstance(n, A.Ident)}
    assert idents["u_time"].kind == "uniform" and idents["u_time"].read_only
    assert idents["v_normal"].kind == "in" and idents["v_normal"].read_only
    assert idents["fragColor"].kind == "out" and not idents["fragColor"].read_only
    assert idents["gl_FrontFacing"].kind == "builtin" and idents["gl_FrontFacing"].read_only
    assert idents["m"].kind == "param" and idents["i"].kind == "local"
    assert idents["SCALE"].kind == "const"
    (norm,) = [c for c in calls(unit, "normalize") if c.args[0].type == VEC3][:1]
    assert norm.kind == "builtin" and isinstance(norm.target, BuiltinFunction)
    assert str(norm.target) == "vec3 normalize(vec3)"
    (shade,) = calls(unit, "shade")
    assert shade.kind == "function" and isinstance(shade.target, A.FunctionDecl)
    assert shade.target.body is not None  # the definition after main, not the prototype
    (ctor,) = calls(unit, "Material")
    assert ctor.kind == "constructor" and ctor.target == info.structs["Material"]
    assert calls(unit, "float")[0].kind == "constructor"
    assert info.call_graph["main()"] == {"lum(vec3)", "shade(Material, vec3, vec3)"}
    assert "fwidth" in info.builtins_used and "texture" in info.builtins_used
    assert {"u_time", "v_normal", "gl_FrontFacing", "fragColor"} <= info.used_globals
    assert info.main is not None and info.main.name == "main"
    assert set(info.functions) == {"lum(vec3)", "shade(Material, vec3, vec3)", "main()"}


def test_legacy_es_shader():
    src = """#version 100
precision mediump float;
uniform sampler2D tex;
uniform samplerCube cube;
varying vec2 v_uv;
void main() {
    vec4 a = texture2D(tex, v_uv);
    vec4 b = textureCube(cube, vec3(v_uv, 1.0));
    vec4 c = texture2DLodEXT(tex, v_uv, 0.0);
    gl_FragColor = a + b * c;
}
"""
    unit, info = checked(src)
    assert info.es and info.version == 100
    assert ty(unit, "a") == VEC4 and ty(unit, "b") == VEC4
    assert info.inputs["v_uv"].kind == "in"
    assert "gl_FragColor" in info.used_globals


def test_implicit_conversions_depend_on_version():
    body = "void main() { float x = 1; gl_FragColor = vec4(x); }"
    checked("#version 120\n" + body)
    with pytest.raises(SemanticError, match="cannot initialize 'x'"):
        checked(body)  # 1.10: no conversions
    with pytest.raises(SemanticError):
        checked("#version 300 es\nprecision highp float;\nout vec4 c;\n"
                "void main() { float x = 1; c = vec4(x); }")
    # 4.00: int -> uint and float -> double
    unit, _ = checked("#version 400\nout vec4 c;\nvoid main() { uint u = 1; double d = 1.0;"
                      " float m = max(1, 2.0); c = vec4(float(d) + float(u) + m); }")
    assert ty(unit, "m") == FLOAT
    with pytest.raises(SemanticError):
        checked("#version 330\nout vec4 c;\nvoid main() { uint u = 1; c = vec4(1.0); }")


def test_overload_resolution_prefers_exact_and_reports_ambiguity():
    src = """#version 400
out vec4 c;
float f(float a, double b) { return a; }
float f(double a, float b) { return b; }
float g(float a) { return a; }
float g(double a) { return 2.0; }
void main() { float x = g(1); float y = g(1.0); c = vec4(x + y); }
"""
    unit, info = checked(src)
    gcalls = calls(unit, "g")
    assert gcalls[0].target.params[0].type.spec.name == "float"  # int->float beats int->double
    assert gcalls[1].target.params[0].type.spec.name == "float"  # exact
    with pytest.raises(SemanticError, match="ambiguous call to 'f\\(float, float\\)'"):
        checked(src.replace("float x = g(1);", "float x = f(1.0, 1.0);"))


def test_constructors():
    unit, _ = checked("""#version 330
out vec4 c;
struct S { vec2 a; int b; };
void main() {
    vec4 v1 = vec4(vec3(1.0), 1);
    vec4 v2 = vec4(vec2(0.0), vec2(1.0));
    vec3 v3 = vec3(vec4(1.0));
    mat2 m1 = mat2(1, 2, 3, 4);
    mat3 m2 = mat3(mat4(1.0));
    mat2 m3 = mat2(vec4(1.0));
    ivec3 iv = ivec3(v3);
    bool b = bool(1.0);
    float fs[] = float[](1.0, 2.0, 3.0);
    S s = S(vec2(1.0), 2);
    S ss[2] = S[2](s, s);
    c = v1 + v2 + vec4(v3, fs.length()) + vec4(m1[0], m2[1].xy) + vec4(iv, 1) + vec4(m3[1], 1.0, 0.0);
}
""")
    assert ty(unit, "fs") == FLOAT.array_of(3)
    assert ty(unit, "ss") == Type.struct("S", (("a", VEC2), ("b", INT))).array_of(2)
    assert ty(unit, "iv") == T("ivec3") and ty(unit, "b") == BOOL
    bad = {
        "vec3 x = vec3(vec2(1.0));": "not enough data",
        "vec2 x = vec2(1.0, 2.0, 3.0);": "too many arguments",
        "mat2 x = mat2(mat2(1.0), 1.0);": "matrix argument",
        "float x[2] = float[2](1.0, 2.0, 3.0);": "array constructor",
        "vec3 x = vec3(float[2](1.0, 2.0));": "constructor has type 'float[2]'",
        "vec3 x = vec3();": "needs arguments",
    }
    for decl, msg in bad.items():
        with pytest.raises(SemanticError, match=re.escape(msg)):
            checked(f"#version 330\nout vec4 c;\nvoid main() {{ {decl} c = vec4(1.0); }}")


def test_operators():
    unit, _ = checked("""#version 330
out vec4 c;
uniform mat2x3 m23;
uniform mat3x2 m32;
void main() {
    mat3 p = m23 * m32;
    mat2 q = m32 * m23;
    vec3 mv = m23 * vec2(1.0);
    vec2 vm = vec3(1.0) * m23;
    ivec2 sh = ivec2(1) << 2;
    uvec3 bits = uvec3(1u) & 3u;
    int md = 7 % 3;
    bvec2 eqv = equal(vec2(1.0), vec2(1.0));
    bool eq = vec3(1.0) == vec3(2.0);
    float neg = -1.0;
    int inv = ~5;
    vec2 bc = 2.0 / vec2(1.0);
    c = vec4(p[0], q[1][0]) + vec4(mv, vm.x) + vec4(sh, bits.xy) + vec4(md, neg, inv, bc.x)
        + vec4(eq ? 1.0 : 0.0) + vec4(eqv.x ? 1.0 : 0.0);
}
""")
    assert ty(unit, "p") == T("mat3") and ty(unit, "q") == T("mat2")
    assert ty(unit, "mv") == VEC3 and ty(unit, "vm") == VEC2
    assert ty(unit, "sh") == T("ivec2") and ty(unit, "bits") == T("uvec3")
    assert ty(unit, "eq") == BOOL and ty(unit, "bc") == VEC2
    bad = {
        "float x = 1.0 % 2.0;": "'%' needs integer operands",
        "vec3 x = vec3(1.0) + vec2(1.0);": "cannot be applied to 'vec3' and 'vec2'",
        "bool x = vec2(1.0) < vec2(2.0);": "lessThan",
        "bool x = 1.0 && true;": "'&&' needs scalar bool operands",
        "float x = -true;": "unary '-'",
        "bool x = !1;": "'!' needs a scalar bool",
        "vec3 x = vec3(1.0); x *= mat2(1.0);": "cannot multiply",
        "float x = 1.0; x += vec2(1.0);": "cannot be stored in 'float'",
        "float x = 1.0; (x + 1.0) = 2.0;": "not an l-value",
        "vec2 x = vec2(1.0); x.zz;": "out of range",
        "int i = 0; float x = vec3(1.0)[1.0];": "index must be a scalar integer",
        "float x = 1.0; float y = x[0];": "cannot index",
        "float x = 1.0; x++; x.length();": "length() cannot be applied",
    }
    for stmt, msg in bad.items():
        with pytest.raises(SemanticError, match=re.escape(msg)):
            checked(f"#version 330\nout vec4 c;\nvoid main() {{ {stmt} c = vec4(1.0); }}")


def test_constant_folding_for_array_sizes():
    unit, info = checked("""#version 330
out vec4 c;
const int N = 4;
const int M = N * 2 - 1;
const uint U = 3u;
float a[N];
float b[M > 6 ? 2 : 1][N / 3];
float d[int(2.9)];
float e[a.length() + int(U)];
void main() { c = vec4(a[3] + b[1][0] + d[1] + e[6]); }
""")
    g = info.globals
    assert g["M"].const_value == 7
    assert g["a"].type == FLOAT.array_of(4)
    assert g["b"].type == FLOAT.array_of(2, 1)
    assert g["d"].type == FLOAT.array_of(2)
    assert g["e"].type == FLOAT.array_of(7)
    with pytest.raises(SemanticError, match="greater than zero"):
        checked("#version 330\nout vec4 c;\nconst int K = 1 - 1;\nfloat z[K];\n"
                "void main() { c = vec4(1.0); }")


def test_scopes():
    checked("""#version 330
out vec4 c;
float x = 1.0;
void main() {
    float x = 2.0;
    { float x = 3.0; c = vec4(x); }
    for (int i = 0; i < 3; i++) { float x = float(i); c += vec4(x); }
    int i = 5;
    if (x > 1.0) { int i = 2; c *= float(i); }
}
""")
    with pytest.raises(SemanticError, match="undeclared identifier 'i'"):
        checked("#version 330\nout vec4 c;\nvoid main() { for (int i = 0; i < 3; i++) {} "
                "c = vec4(i); }")
    with pytest.raises(SemanticError, match="redefinition of 'a'"):
        checked("#version 330\nout vec4 c;\nvoid f(float a) { float a = 1.0; }\n"
                "void main() { c = vec4(1.0); }")
    with pytest.raises(SemanticError, match="undeclared identifier 'y'"):
        checked("#version 330\nout vec4 c;\nvoid main() { { float y = 1.0; } c = vec4(y); }")


def test_statements():
    checked("""#version 330
out vec4 c;
uniform int mode;
void main() {
    c = vec4(0.0);
    switch (mode) { case 0: c.r = 1.0; break; case 1: case 2: c.g = 1.0; break; default: break; }
    int k = 0;
    while (k < 4) { k++; if (k == 2) continue; }
    do { k--; } while (k > 0);
    if (c.r > 0.5) discard;
}
""")
    bad = {
        "switch (mode) { case 1: break; case 1: break; }": "duplicate case label",
        "switch (1.0) { default: break; }": "switch expression",
        "continue;": "'continue' outside a loop",
        "while (1) {}": "while-loop condition",
        "return 1.0;": "void function 'main' cannot return a value",
        "uniform float q;": "not allowed on a local variable",
        "const float q;": "must be initialized",
    }
    for stmt, msg in bad.items():
        with pytest.raises(SemanticError, match=re.escape(msg)):
            checked(f"#version 330\nout vec4 c;\nuniform int mode;\nvoid main() {{ {stmt} }}")


def test_out_params_interface_blocks_and_builtin_redeclaration():
    unit, info = checked("""#version 330
layout(origin_upper_left) in vec4 gl_FragCoord;
layout(std140) uniform Lights { vec3 lightPos; vec3 lightColor; };
uniform Camera { mat4 view; } cam;
out vec4 c;
void split(in float v, out float whole, inout float acc) { whole = floor(v); acc += v; }
void main() {
    float w; float acc = 0.0;
    split(gl_FragCoord.x, w, acc);
    float ip;
    float fr = modf(acc, ip);
    c = vec4(lightPos * lightColor, w + fr + ip) * cam.view;
}
""")
    assert info.uniforms["lightPos"].type == VEC3
    assert info.uniforms["cam"].type.field_type("view") == T("mat4")
    assert ty(unit, "fr") == FLOAT
    with pytest.raises(SemanticError, match="argument 2 of 'split'"):
        checked("#version 330\nout vec4 c;\nvoid split(float v, out float w) { w = v; }\n"
                "uniform float u;\nvoid main() { split(1.0, u); c = vec4(1.0); }")


def test_declaration_errors():
    bad = {
        "float f() { return 1.0; }\nint f() { return 1; }": "redeclared with return type",
        "float gl_Custom;": "reserved",
        "void f(); ": "declared but never defined",
        "struct S { float a; float a; };": "duplicate member",
        "uniform vec3 main;": "already",
        "float v; float v;": "redefinition of 'v'",
        "void main2(void x);": "cannot be void",
        "in float k = 1.0;": "cannot have an initializer",
    }
    for decl, msg in bad.items():
        main = "void main() { f(); }" if "void f()" in decl else "void main() {}"
        with pytest.raises(SemanticError, match=re.escape(msg)):
            checked(f"#version 330\n{decl}\n{main}")


def test_recursion_direct_and_indirect():
    with pytest.raises(SemanticError, match="recursion is not allowed: f -> f"):
        checked("#version 330\nfloat f(float x) { return x < 1.0 ? x : f(x - 1.0); }\n"
                "void main() { f(2.0); }")
    with pytest.raises(SemanticError, match="a -> b -> c -> a"):
        checked("#version 330\nvoid c();\nvoid a() { }\nvoid b() { c(); }\n"
                "void c() { a(); }\nvoid a2() {}\nvoid main() { b(); }".replace(
                    "void a() { }", "void b();\nvoid a() { b(); }"))


# ----------------------------------------------------------------------------- error corpus

ERROR_FILES = sorted(glob.glob(os.path.join(HERE, "glsl", "semantic_errors", "*.frag")))


def test_there_are_enough_error_inputs():
    assert len(ERROR_FILES) >= 15


@pytest.mark.parametrize("path", ERROR_FILES, ids=os.path.basename)
def test_semantic_error_file(path):
    src = open(path).read()
    m = re.match(r"// expect: (\d+):(\d+) (.+)", src)
    assert m, "missing '// expect: line:col message' header"
    with pytest.raises(SemanticError) as err:
        check(parse_source(src, path))
    e = err.value
    assert (e.loc.line, e.loc.col) == (int(m.group(1)), int(m.group(2))), str(e)
    assert e.loc.file == path
    assert m.group(3).strip() in e.message
    assert str(e).startswith(f"{path}:{m.group(1)}:{m.group(2)}: ")


# ----------------------------------------------------------------------------- real shaders

REAL_SHADERS = sorted(
    glob.glob(os.path.join(HERE, "glsl", "corpus", "*.frag"))
    + glob.glob(os.path.join(HERE, "glsl", "corpus", "*.glsl"))
    + glob.glob(os.path.join(ROOT, "shaders", "*.glsl")))


@pytest.mark.parametrize("path", REAL_SHADERS, ids=os.path.basename)
def test_real_shaders_check(path):
    unit = parse_source(open(path).read(), path)
    info = check(unit)
    assert info.main is not None
    untyped = [n for n in nodes(unit) if isinstance(n, A.Expr) and n.type is None]
    assert not untyped
    for n in nodes(unit):
        if isinstance(n, A.Ident):
            assert n.symbol is not None
        if isinstance(n, A.Call):
            assert n.kind in ("function", "builtin", "constructor") and n.target is not None


def _big_shader(functions=100):
    parts = ["#version 330", "uniform float u_time;", "uniform vec3 u_light;",
             "in vec3 v_normal;", "in vec4 v_position;", "out vec4 fragColor;",
             "const int STEPS = 4;"]
    for k in range(functions):
        prev = f"f{k - 1}(p * 1.01, s)" if k else "vec3(s)"
        parts += [
            f"vec3 f{k}(vec3 p, float s) {{",
            f"    vec3 acc = {prev};",
            "    for (int i = 0; i < STEPS; ++i) {",
            "        float t = float(i) * 0.25 + s;",
            "        vec3 q = fract(p * t) - 0.5;",
            "        acc += normalize(q + vec3(0.001)) * smoothstep(0.0, 1.0, length(q));",
            "        acc.xy = mix(acc.xy, acc.yx, 0.5) * mat2(cos(t), sin(t), -sin(t), cos(t));",
            "    }",
            "    if (dot(acc, u_light) > 0.0) { acc = max(acc, vec3(0.0)); } else { acc *= 0.5; }",
            "    float w = clamp(abs(acc.x) + abs(acc.y) * 2.0, 0.0, 1.0);",
            "    vec4 tmp = vec4(acc, w) * (u_time + float(STEPS));",
            "    tmp.xyz = reflect(tmp.xyz, normalize(v_normal));",
            "    acc = tmp.xyz / max(tmp.w, 1e-3) + pow(abs(p), vec3(1.5));",
            "    acc += cross(acc, p) * dot(p, p) + floor(p * 3.0) * exp(-abs(s));",
            "    int j = int(w * 10.0) % 3;",
            "    acc += (j == 1) ? vec3(0.1) : vec3(0.2);",
            "    acc = clamp(acc, -1.0, 1.0) + sqrt(abs(acc)) * 0.01;",
            "    float m = min(min(acc.x, acc.y), acc.z);",
            "    acc -= vec3(m) * step(0.5, w);",
            "    acc = acc * inversesqrt(dot(acc, acc) + 1.0);",
            "    acc += sin(p.zxy * 4.0 + u_time) * 0.05 + v_position.xyz * 0.001;",
            "    acc.z += atan(acc.y, acc.x + 2.0);",
            "    vec2 uv = acc.xy * 0.5 + 0.5;",
            "    acc.xy = uv * 2.0 - 1.0;",
            "    acc = faceforward(acc, -u_light, v_normal);",
            "    acc *= (s > 0.5 || w < 0.1) ? 1.0 : 0.9;",
            "    return acc;",
            "}",
        ]
    parts += ["void main() {",
              f"    vec3 c = f{functions - 1}(v_position.xyz, u_time);",
              "    fragColor = vec4(c, 1.0);", "}"]
    return "\n".join(parts) + "\n"


def test_check_of_a_3000_line_shader():
    # (its speed is measured by `rrcache bench-frontend`, not asserted here)
    src = _big_shader(108)
    assert src.count("\n") >= 3000
    unit = parse_source(src, "big.frag")
    info = check(unit)
    assert [f for f in info.functions if f != "main()"] == [f"f{k}(vec3, float)" for k in range(108)]
    assert info.call_graph["f107(vec3, float)"] == {"f106(vec3, float)"} or \
        list(info.call_graph["f107(vec3, float)"]) == ["f106(vec3, float)"]
    calls = [n for n in unit.walk() if isinstance(n, A.Call) and n.name[1:].isdigit()]
    assert len(calls) == 108 and all(c.kind == "function" and c.type is not None for c in calls)


# ----------------------------------------------------------------------------- front-end

def test_parse_shader_fields():
    s = parse_shader(SHADER_330, "mem.frag")
    assert s.version == 330 and s.profile in (None, "core")
    assert list(s.uniforms) == ["u_time", "u_light", "u_mvp", "u_normalMatrix"]
    assert list(s.samplers) == ["u_tex", "u_env"]
    assert s.samplers["u_env"][0] == T("samplerCube")
    assert s.uniforms["u_time"][0] == FLOAT and s.uniforms["u_time"][1].line == 2
    assert list(s.inputs) == ["v_position", "v_normal", "v_texcoord"] == list(s.varyings)
    assert list(s.outputs) == ["fragColor"]
    assert s.unit.decls and s.info.main is not None
    assert len(s.hash) == 64
    # inputs lists only the varyings the shader reads
    s2 = parse_shader("#version 330\nin vec3 unused;\nin vec2 uv;\nout vec4 c;\n"
                      "void main() { c = vec4(uv, 0.0, 1.0); }")
    assert list(s2.inputs) == ["uv"]


def test_hash_covers_source_defines_and_includes(tmp_path):
    inc = tmp_path / "lib.glsl"
    inc.write_text("float helper(float x) { return x * 2.0; }\n")
    main = tmp_path / "main.frag"
    main.write_text('#version 330\n#include "lib.glsl"\nout vec4 c;\n'
                    "void main() { c = vec4(helper(SCALE)); }\n")
    a = load_shader(main, defines={"SCALE": "1.0"})
    b = load_shader(str(main), defines={"SCALE": "1.0"})
    c = load_shader(main, defines={"SCALE": "2.0"})
    assert a.hash == b.hash != c.hash
    assert a.path == str(main) and "SCALE" in a.defines
    inc.write_text("float helper(float x) { return x * 3.0; }\n")
    assert load_shader(main, defines={"SCALE": "1.0"}).hash != a.hash


def test_load_shader_errors(tmp_path):
    missing = tmp_path / "nope.frag"
    with pytest.raises(GLSLError, match="nope.frag"):
        load_shader(missing)
    bad = tmp_path / "bad.frag"
    bad.write_text("#version 330\nout vec4 c;\nvoid main() { c = vec4(zzz); }\n")
    with pytest.raises(SemanticError) as err:
        load_shader(bad)
    assert err.value.loc.file == str(bad) and err.value.loc.line == 3


@pytest.mark.parametrize("src, msg", [
    ("attribute vec3 pos;\nvoid main() { gl_Position = vec4(pos, 1.0); }", "vertex shader"),
    ("#version 330\nin vec3 p;\nvoid main() { gl_Position = vec4(p, 1.0); }", "gl_Position"),
    ("#version 430\nlayout(local_size_x = 8) in;\nvoid main() { }", "compute shader"),
    ("#version 330\nlayout(triangles) in;\nlayout(max_vertices = 3) out;\n"
     "void main() { EmitVertex(); }", "geometry shader"),
    ("#version 330\nout vec4 a;\nout vec4 b;\nvoid main() { a = vec4(1.0); b = a; }",
     "several colour outputs"),
    ("#version 330\nout vec4 a[2];\nvoid main() { a[0] = vec4(1.0); a[1] = a[0]; }",
     "several colour outputs"),
    ("void main() { gl_FragData[0] = vec4(1.0); gl_FragData[1] = vec4(0.0); }", "gl_FragData"),
])
def test_unsupported_shaders(src, msg):
    with pytest.raises(UnsupportedShaderError, match=msg) as err:
        parse_shader(src, "stage.glsl")
    assert err.value.loc is not None and err.value.loc.file == "stage.glsl"


def test_single_gl_fragdata_and_fragdepth_are_fine():
    s = parse_shader("void main() { gl_FragData[0] = vec4(1.0); gl_FragDepth = 0.5; }")
    assert s.version == 110 and "gl_FragData" in s.info.used_globals
    s = parse_shader("#version 330\nout vec4 c;\nvoid main() { c = vec4(1.0); "
                     "gl_FragDepth = gl_FragCoord.z; }")
    assert list(s.outputs) == ["c"]


def test_read_only_builtins_and_hints():
    with pytest.raises(SemanticError, match="cannot assign to read-only built-in variable "
                                            "'gl_FragCoord'"):
        checked("void main() { gl_FragCoord = vec4(0.0); }")
    with pytest.raises(SemanticError, match="'gl_FrontFacing'"):
        checked("void main() { gl_FrontFacing = true; }")
    with pytest.raises(SemanticError) as err:
        checked("#version 330\nuniform float u_time;\nout vec4 c;\n"
                "void main() { c = vec4(u_tmie); }")
    assert err.value.hint == "did you mean 'u_time'?"
    with pytest.raises(SemanticError, match="'sin' is a function, not a variable"):
        checked("void main() { float x = sin; }")
    with pytest.raises(SemanticError, match="'x' is a variable, not a function"):
        checked("void main() { float x = 1.0; x(2.0); }")
    # writable built-ins
    checked("void main() { gl_FragColor = vec4(gl_FragCoord.xy, 0.0, 1.0); gl_FragDepth = 0.5; }")


def test_swizzle_lvalues_and_types():
    unit, _ = checked("""#version 330
out vec4 c;
void main() {
    vec4 v = vec4(1.0);
    v.zyx = vec3(0.0);
    v.rg += vec2(1.0);
    float s = 2.0;
    vec3 sv = s.xxx;
    vec2 back = v.wz;
    c = v + vec4(sv, back.y);
}
""")
    assert ty(unit, "sv") == VEC3 and ty(unit, "back") == VEC2


# ---------------------------------------------------------------- glslang-suite regressions
def test_unsized_local_array_redeclared_with_size():
    # GLSL allows 'float u[][7]; ... float u[5][7];' in one scope (found via glslang's tests).
    unit, _ = checked("#version 430\nout vec4 c;\nvoid main() {\n float u[][7];\n"
                      " u[2][2] = 3.0;\n float u[5][7];\n c = vec4(u[2][2]);\n}\n")
    decls = [n for n in nodes(unit) if isinstance(n, A.Ident) and n.name == "u"]
    assert all(d.symbol.type.dims == (5, 7) for d in decls)
    with pytest.raises(SemanticError, match="redefinition of 'u'"):
        checked("#version 430\nvoid main() { float u[3]; float u[5]; }\n")
    with pytest.raises(SemanticError, match="redefinition of 'u'"):
        checked("#version 430\nvoid main() { float u[][7]; int u[5][7]; }\n")


def test_compatibility_input_redeclared_twice():
    # 'in vec4 gl_Color; flat in vec4 gl_Color;' is accepted (glslang's spv.130.frag).
    checked("#version 130\nin vec4 gl_Color;\nflat in vec4 gl_Color;\n"
            "void main() { gl_FragColor = gl_Color; }\n")
    with pytest.raises(SemanticError, match="redefinition of 'gl_FragCoord'"):
        checked("#version 150\nin vec4 gl_FragCoord;\n"
                "layout(origin_upper_left) in vec4 gl_FragCoord;\nout vec4 c;\n"
                "void main() { c = gl_FragCoord; }\n")
