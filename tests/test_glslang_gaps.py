"""Front-end gaps found by running glslang's own test suite (tools/glsl_conformance.py).

Each test is a minimal reproduction written for rrcache, not a copy of a glslang test file: it
shows the construct glslang accepts and rrcache rejected, and that the fixed front-end accepts,
types and prints it (print → parse gives the same tree). Invalid neighbours stay rejected.
"""
from __future__ import annotations

import pytest

from rrcache.errors import GLSLError, SemanticError
from rrcache.glsl import ast as A
from rrcache.glsl.parser import parse_source
from rrcache.glsl.printer import print_glsl
from rrcache.glsl.semantic import check
from rrcache.glsl.types import Type


def accepted(src: str) -> A.TranslationUnit:
    """Parse and check ``src``; the printed text parses back to the same tree."""
    unit = parse_source(src, "gap.frag")
    check(unit, "gap.frag")
    printed = print_glsl(unit)
    assert parse_source(printed, "printed.frag") == unit
    return unit


def calls(unit: A.TranslationUnit, name: str) -> list[A.Call]:
    out: list[A.Call] = []

    def walk(node):
        if isinstance(node, A.Call) and node.name == name:
            out.append(node)
        if isinstance(node, A.Node):
            for value in vars(node).values():
                for item in value if isinstance(value, (list, tuple)) else [value]:
                    if isinstance(item, A.Node) and item is not node and not (
                            isinstance(node, A.Call) and item is node.target):
                        walk(item)
    walk(unit)
    return out


# ----------------------------------------------------------------- 'sampler' in OpenGL GLSL

def test_sampler_is_an_ordinary_name_in_opengl_glsl():
    unit = accepted("""
        #version 330
        uniform sampler2D sampler;
        out vec4 color;
        void main() { color = texture(sampler, vec2(0.5)); }
    """)
    assert calls(unit, "texture")[0].args[0].type == Type("sampler2D")


def test_legacy_texture2D_call_next_to_a_variable_named_sampler():
    accepted("""
        precision mediump float;
        uniform sampler2D sampler;
        void main() { gl_FragColor = texture2D(sampler, gl_PointCoord); }
    """)


# ----------------------------------------------------------------- Vulkan separate samplers

VULKAN = """
    #version 450
    layout(set = 0, binding = 0) uniform texture2D tex;
    layout(set = 0, binding = 1) uniform sampler smp;
    layout(set = 0, binding = 2) uniform samplerShadow cmp;
    layout(set = 0, binding = 3) uniform texture3D vols[3];
    layout(input_attachment_index = 0, set = 0, binding = 4) uniform subpassInput gbuf;
    layout(location = 0) out vec4 color;
    float lit(texture2D t, sampler s, vec2 uv) { return texture(sampler2D(t, s), uv).r; }
    void main() {
        sampler3D each[3] = sampler3D[3](vols, smp);
        color = texture(sampler2D(tex, smp), vec2(0.5)) + subpassLoad(gbuf)
              + texture(each[1], vec3(0.5))
              + vec4(texture(sampler2DShadow(tex, cmp), vec3(0.5, 0.5, 0.25)))
              + vec4(lit(tex, smp, vec2(0.25)));
    }
"""


def test_vulkan_textures_samplers_and_subpass_inputs():
    unit = accepted(VULKAN)
    made = {c.args[0].type.base: c.type for c in calls(unit, "sampler2D")}
    assert made == {"texture2D": Type("sampler2D")}
    arrays = [c for c in calls(unit, "sampler3D") if c.array_dims is not None]
    assert arrays[0].type == Type("sampler3D").array_of(3)
    assert calls(unit, "subpassLoad")[0].type == Type("float", 4)


@pytest.mark.parametrize("bad, message", [
    ("sampler2D(tex)", "cannot construct"),                 # a texture alone is not a sampler
    ("sampler2D(smp, smp)", "cannot construct"),            # two samplers
    ("sampler3D(tex, smp)", "cannot construct"),            # shape mismatch
    ("sampler2D(vols[0], smp)", "cannot construct"),        # texture3D into a sampler2D
])
def test_wrong_combined_sampler_constructors_are_rejected(bad, message):
    src = VULKAN.replace("texture(sampler2D(tex, smp), vec2(0.5))", f"texture({bad}, vec2(0.5))")
    with pytest.raises(GLSLError, match=message) as err:
        accepted(src)
    assert "hint: a combined sampler is built as" in str(err.value)


# ----------------------------------------------------------------- small extensions

def test_nonuniform_qualifier_and_function_form():
    unit = accepted("""
        #version 450
        #extension GL_EXT_nonuniform_qualifier : enable
        layout(binding = 0) uniform sampler2D texs[];
        layout(location = 0) flat in int index;
        layout(location = 0) out vec4 color;
        nonuniformEXT int pick(nonuniformEXT int i) { return i; }
        void main() {
            nonuniformEXT int j = pick(index);
            color = texture(texs[nonuniformEXT(j + 1)], vec2(0.5));
        }
    """)
    assert calls(unit, "nonuniformEXT")[0].type == Type("int")


def test_device_and_view_index_builtins():
    accepted("""
        #version 450
        #extension GL_EXT_device_group : enable
        #extension GL_EXT_multiview : enable
        layout(location = 0) out vec4 color;
        void main() { color = vec4(gl_DeviceIndex, gl_ViewIndex, 0, 1); }
    """)


BINDLESS = """
    #version 450
    #extension GL_ARB_bindless_texture : require
    uniform uvec2 handle;
    uniform sampler2D tex;
    out vec4 color;
    void main() {
        sampler2D s = tex;
        s = sampler2D(handle);
        uvec2 back = uvec2(tex);
        color = texture(s, vec2(back));
    }
"""


def test_bindless_handles_and_sampler_assignment():
    accepted(BINDLESS)


def test_sampler_assignment_needs_the_bindless_extension():
    with pytest.raises(SemanticError, match="cannot assign to a variable of type 'sampler2D'"):
        accepted(BINDLESS.replace("#extension GL_ARB_bindless_texture : require", ""))


# ----------------------------------------------------------------- constant expressions

@pytest.mark.parametrize("decls, size_expr, size", [
    ("const ivec4 v = ivec4(1, 2, 3, 4);", "v.y", 2),                      # swizzle
    ("const ivec4 v = ivec4(1, 2, 3, 4);", "v[2] + v.w", 7),               # index, vector
    ("const ivec4 v = ivec4(1, 2, 3, 4); const ivec4 u = ~v;", "u.x + 3", 1),
    ("", "int(max(2.0, 3.5))", 3),                                         # pure built-in
    ("", "int(sin(3.2)) + 1", 1),
    ("const struct S { ivec2 iv; } s = S(ivec2(3, 4));", "s.iv.y", 4),     # struct member
    ("const mat2 m2 = mat2(2, 3, 4, 5); const mat3 m3 = mat3(m2);", "int(m3[2][2])", 1),
    ("const mat2 m2 = mat2(2, 3, 4, 5); const mat3 m3 = mat3(m2);", "int(m3[1][0])", 4),
    ("const vec2 a = vec2(1, 2); const vec3 b = vec3(3, 4, 5);",
     "uint(mat3(a, b, a, a)[2][2])", 2),                                   # matrix constructor
    ("const int k[3] = int[3](4, 5, 6);", "k[1] - ivec2(1, 2).y", 3),       # const array
    ("const ivec3 w = ivec3(2) * ivec3(1, 2, 3) + 1;", "w.z", 7),          # broadcast scalars
    ("const vec2 p = vec2(3.0, 4.0);", "int(length(p) + dot(p, p))", 30),  # geometric
])
def test_constant_array_sizes(decls, size_expr, size):
    unit = accepted(f"""
        #version 430
        {decls}
        out vec4 color;
        void main() {{ float sized[{size_expr}]; color = vec4(sized.length()); }}
    """)
    sizes = []

    def walk(node):
        if isinstance(node, A.VariableDecl):
            for d in node.declarators:
                if d.name == "sized":
                    sizes.append(d.array_dims)
        if isinstance(node, A.Node):
            for value in vars(node).values():
                for item in value if isinstance(value, list) else [value]:
                    if isinstance(item, A.Node):
                        walk(item)
    walk(unit)
    assert len(sizes) == 1
    from rrcache.glsl.constfold import const_value
    assert const_value(sizes[0][0]) == size


@pytest.mark.parametrize("size_expr", ["v.y", "int(max(u, 2.0))"])
def test_non_constant_array_sizes_stay_rejected(size_expr):
    with pytest.raises(SemanticError, match="array size must be a constant integer expression"):
        accepted(f"""
            #version 430
            uniform float u;
            void main() {{ ivec4 v = ivec4(1); float a[{size_expr}]; }}
        """)


# ----------------------------------------------------------------- invalid neighbours

def test_embedded_struct_definition_is_rejected():
    with pytest.raises(SemanticError, match="struct 'Inner' is defined inside struct 'Outer'"):
        accepted("""
            struct Outer { float x; struct Inner { int a; } inner; };
            uniform Outer o;
            void main() { gl_FragColor = vec4(o.x); }
        """)


def test_opaque_block_member_is_rejected_without_bindless():
    src = """
        #version 450
        {ext}
        layout(std140) uniform Material {{ vec4 tint; sampler2D albedo; }};
        out vec4 color;
        void main() {{ color = tint * texture(albedo, vec2(0.5)); }}
    """
    with pytest.raises(SemanticError, match="block member of type 'sampler2D' is not allowed"):
        accepted(src.format(ext=""))
    accepted(src.format(ext="#extension GL_ARB_bindless_texture : require"))


# ----------------------------------------------------------------- sparse texture lookups

def test_sparse_texture_and_lod_clamp_builtins():
    unit = accepted("""
        #version 450
        #extension GL_ARB_sparse_texture2 : enable
        #extension GL_ARB_sparse_texture_clamp : enable
        uniform sampler2D tex;
        uniform sampler2DShadow depth;
        uniform isampler2DArray layers;
        in vec2 uv;
        out vec4 color;
        void main() {
            vec4 texel = vec4(0.0);
            ivec4 itexel = ivec4(0);
            float d = 0.0;
            int code = sparseTextureARB(tex, uv, texel, 1.0);
            code |= sparseTextureGatherARB(layers, vec3(uv, 1.0), itexel, 2);
            code |= sparseTextureLodARB(depth, vec3(uv, 0.5), 0.0, d);
            code |= sparseTextureClampARB(tex, uv, 2.0, texel);
            texel += textureGradOffsetClampARB(tex, uv, uv, uv, ivec2(1), 3.0);
            color = sparseTexelsResidentARB(code) ? texel + vec4(itexel) + d : vec4(0.0);
        }
    """)
    sparse = calls(unit, "sparseTextureARB")[0]
    assert sparse.type == Type("int") and sparse.target.out_params == (2,)
    assert sparse.target.derivative  # an implicit-LOD lookup, like texture()


def test_sparse_lookup_needs_its_out_texel():
    with pytest.raises(SemanticError, match="no matching overload for 'sparseTextureARB"):
        accepted("""
            #version 450
            uniform sampler2D tex;
            out vec4 color;
            void main() { color = vec4(sparseTextureARB(tex, vec2(0.5))); }
        """)


# ----------------------------------------------------------------- explicit arithmetic types

def test_int64_types_literals_conversions_and_builtins():
    unit = accepted("""
        #version 450
        #extension GL_ARB_gpu_shader_int64 : enable
        uniform ivec2 iv;
        out vec4 color;
        void main() {
            int64_t big = 0x7FFFFFFFFFFFFFFFl - 1l;
            uint64_t ubig = 18446744073709551615ul;
            i64vec2 v = iv;                        // int -> int64 implicitly
            u64vec2 u = v;                         // int64 -> uint64 implicitly
            v = max(v, i64vec2(-1)) + abs(v);
            bool less = lessThan(u, u64vec2(ubig)).x;
            double d = int64BitsToDouble(big) + double(u.y);
            ivec2 halves = unpackInt2x32(packInt2x32(iv));
            color = vec4(float(d), less ? 1.0 : 0.0, vec2(halves));
        }
    """)
    assert calls(unit, "packInt2x32")[0].type == Type("int64_t")
    assert calls(unit, "max")[0].type == Type("int64_t", 2)


def test_float16_types_literals_and_builtins():
    unit = accepted("""
        #version 450
        #extension GL_AMD_gpu_shader_half_float : enable
        in f16vec3 n;
        out vec4 color;
        void main() {
            const float16_t h = 0.5hf;
            f16vec3 m = normalize(n) * h + f16vec3(0.25HF);
            f16mat3 r = f16mat3(1.0hf);
            float l = length(r * m) + dFdx(m.x);   // float16_t -> float implicitly
            color = vec4(l, vec3(m));
        }
    """)
    assert calls(unit, "normalize")[0].type == Type("float16_t", 3)
    assert calls(unit, "dFdx")[0].target.derivative


@pytest.mark.parametrize("src, message", [
    ("int a = 4294967296;", "does not fit in 32 bits"),
    ("int64_t a = 18446744073709551616l;", "does not fit in 64 bits"),
    ("int a = 1l;", "cannot initialize 'a' of type 'int' with a value of type 'int64_t'"),
    ("float16_t h = 1.0;", "cannot initialize 'h' of type 'float16_t'"),
])
def test_explicit_types_are_not_narrowed_implicitly(src, message):
    with pytest.raises(GLSLError, match=message):
        accepted(f"#version 450\nvoid main() {{ {src} }}")


# ----------------------------------------------------------------- version-dependent type words

def test_uint_is_an_ordinary_name_before_it_became_a_type():
    accepted("""
        #version 100
        precision mediump float;
        int uint;
        void main() { uint = 2; gl_FragColor = vec4(float(uint)); }
    """)
    with pytest.raises(GLSLError, match="keyword"):
        accepted("#version 300 es\nprecision mediump float;\nint uint;\nvoid main() {}")


# ----------------------------------------------------------------- found on the whole OpenGL set

def test_arb_texture_query_lod_spelling():
    """GL_ARB_texture_query_lod names its function textureQueryLOD (glslang's textureQueryLOD.frag);
    GLSL 4.00 renamed it textureQueryLod. Both take derivatives like an implicit-LOD lookup."""
    from rrcache.glsl.builtins import DERIVATIVE_FUNCTIONS
    unit = accepted("""
        #version 150
        #extension GL_ARB_texture_query_lod : enable
        uniform sampler2DShadow s;
        uniform sampler2D t;
        in vec2 uv;
        out vec4 color;
        void main() {
            vec2 a = textureQueryLOD(s, uv);
            vec2 b = textureQueryLod(t, uv);
            color = vec4(a, b);
        }
    """)
    assert [str(c.type) for c in calls(unit, "textureQueryLOD")] == ["vec2"]
    assert "textureQueryLOD" in DERIVATIVE_FUNCTIONS
    with pytest.raises(SemanticError, match="textureQueryLOD"):
        accepted("#version 150\nuniform sampler2D t;\nout vec4 c;\n"
                 "void main() { c = vec4(textureQueryLOD(t, 1.0), 0.0, 0.0); }")


def test_gl_fragcoord_redeclared_again_with_the_same_qualifiers():
    """glslang's gl_FragCoord.frag redeclares gl_FragCoord twice, identically, with a use between
    (GLSL 4.60 §7.1.2: every redeclaration must have the same qualifiers)."""
    unit = accepted("""
        #version 150 core
        layout(origin_upper_left, pixel_center_integer) in vec4 gl_FragCoord;
        float x = gl_FragCoord.x;
        layout(origin_upper_left, pixel_center_integer) in vec4 gl_FragCoord;
        out vec4 c;
        void main() { c = vec4(x, gl_FragCoord.y, 0.0, 1.0); }
    """)
    assert len([d for d in unit.decls if isinstance(d, A.VariableDecl)
                and d.declarators and d.declarators[0].name == "gl_FragCoord"]) == 2
    with pytest.raises(SemanticError, match="redefinition of 'gl_FragCoord'"):
        accepted("#version 150\nlayout(origin_upper_left) in vec4 gl_FragCoord;\n"
                 "layout(pixel_center_integer) in vec4 gl_FragCoord;\nout vec4 c;\n"
                 "void main() { c = gl_FragCoord; }\n")
    with pytest.raises(SemanticError, match="redefinition of 'gl_FragDepth'"):
        accepted("#version 420\nlayout(depth_greater) out float gl_FragDepth;\n"
                 "layout(depth_less) out float gl_FragDepth;\nout vec4 c;\n"
                 "void main() { c = vec4(1.0); gl_FragDepth = 0.5; }\n")


# ----------------------------------------------------------------- the measuring tool

def _stages() -> tuple:
    """The tool's stage names, read from the module (loaded, not run)."""
    import importlib.util
    from pathlib import Path
    tool = Path(__file__).resolve().parent.parent / "tools" / "glsl_conformance.py"
    spec = importlib.util.spec_from_file_location("glsl_conformance", tool)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return tuple(mod.STAGES)


def _tool(argv) -> tuple:
    """Run tools/glsl_conformance.py in a process of its own: (exit status, stdout). Its worker
    pool forks, and a fork of this test process (GL driver threads running) can deadlock in the
    child on a lock another thread held at the fork; a fresh interpreter forks single-threaded."""
    import os
    import subprocess
    import sys
    from pathlib import Path
    root = Path(__file__).resolve().parent.parent
    env = dict(os.environ, PYTHONPATH=str(root))
    p = subprocess.run([sys.executable, str(root / "tools" / "glsl_conformance.py"), *argv], cwd=root, env=env,
                       capture_output=True, text=True, timeout=300)
    return p.returncode, p.stdout


def test_conformance_tool_verdicts_exclude_and_categories(tmp_path):
    import json
    shaders = {
        "plain.frag": "void main() { gl_FragColor = vec4(1.0); }",
        "spv.sep.frag": VULKAN,
        "ext.frag": BINDLESS,
        "bad.frag": "void main() { undeclared = 1.0; }",
        "hlsl.skip.frag": "float4 main() : SV_Target { return 1; }",
    }
    for name, text in shaders.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "verdicts.tsv").write_text(
        "plain.frag\tvalid\tsuite\nspv.sep.frag\tvalid\tsuite\next.frag\tvalid\tsuite\n"
        "bad.frag\tinvalid\tcomment\n")
    report = tmp_path / "report.json"
    rc, out = _tool([str(tmp_path), "--frontend-only", "--exclude", "hlsl.*",
                     "--verdicts", str(tmp_path / "verdicts.tsv"), "--json", str(report)])
    assert rc == 0
    assert "valid shaders accepted: 3/3" in out and "invalid shaders also rejected: 1/1" in out
    rows = {r["file"]: r for r in json.loads(report.read_text())["results"]}
    assert set(rows) == {"plain.frag", "spv.sep.frag", "ext.frag", "bad.frag"}
    assert {n: r["category"] for n, r in rows.items() if n != "bad.frag"} == {
        "plain.frag": "core", "spv.sep.frag": "vulkan", "ext.frag": "extension"}
    assert rows["bad.frag"]["outcome"] == "rejected"
    assert (rows["bad.frag"]["parse"], rows["bad.frag"]["check"]) == ("ok", "rejected")


def test_conformance_tool_stages_opengl_rule_and_time_limit(tmp_path):
    """Each stage is counted, the OpenGL rule drops Vulkan/HLSL names, a slow shader is cut off
    by the per-shader limit without stopping the others."""
    import json
    stages = _stages()
    many_defines = "".join(f"#define M{i}(x) M{i - 1}(x)+M{i - 1}(x)\n" for i in range(1, 40))
    shaders = {
        "lit.frag": "varying vec3 n;\nvoid main() { gl_FragColor = vec4(sin(n) * cos(n), 1.0); }",
        "two.frag": "#version 330\nout vec4 a;\nout vec4 b;\n"
                    "void main() { a = vec4(1.0); b = vec4(0.0); }",
        "badtype.frag": "void main() { gl_FragColor = vec3(1.0); }",
        "syntax.frag": "void main() { gl_FragColor = ; }",
        # macro expansion doubling 39 times: far beyond any time limit
        "slow.frag": "#define M0(x) x\n" + many_defines + "void main() { float f = M39(1.0); }",
        "spv.vk.frag": "void main() {}", "vk.relaxed.frag": "void main() {}",
        "enhanced.0.frag": "void main() {}", "web.array.frag": "void main() {}",
    }
    for name, text in shaders.items():
        (tmp_path / name).write_text(text)
    report = tmp_path / "report.json"
    rc, out = _tool([str(tmp_path), "--opengl", "--timeout", "3", "--json", str(report)])
    rows = {r["file"]: r for r in json.loads(report.read_text())["results"]}
    assert set(rows) == {"lit.frag", "two.frag", "badtype.frag", "syntax.frag", "slow.frag"}
    assert [rows["lit.frag"][s] for s in stages] == ["ok"] * 4 and rows["lit.frag"]["listed"] >= 1
    assert [rows["two.frag"][s] for s in stages] == ["ok", "ok", "unsupported", "skipped"]
    assert [rows["badtype.frag"][s] for s in stages] == ["ok", "rejected", "skipped", "skipped"]
    assert rows["syntax.frag"]["parse"] == "rejected" and rows["syntax.frag"]["stage"] == "parse"
    assert rows["slow.frag"]["parse"] in ("timeout", "rejected"), rows["slow.frag"]
    assert rc == 0 and "crashes (non-rrcache exceptions, bugs): 0" in out
    assert "unknown" in out and "parse" in out
