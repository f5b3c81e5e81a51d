"""The inliner on shaders people write (issue 30): sampler parameters are substituted, a kept
function keeps a prototype before its first use, node texts never show the passes' temporaries,
and inlining is bounded (a chain of 2,000 functions is refused in one line, in bounded memory;
identical calls share one inlined body)."""
from __future__ import annotations

from pathlib import Path

import pytest

from rrcache.analysis import cacheable_nodes
from rrcache.analysis.inline import inline_calls
from rrcache.compiler import instance
from rrcache.errors import RRCacheError
from rrcache.gl.context import get_context
from rrcache.glsl.frontend import parse_shader
from rrcache.glsl.printer import print_glsl
from safety_cli import one_error_line, rrcache_traced

ROOT = Path(__file__).resolve().parents[1]

TAP2 = """#version 330
in vec2 v_texcoord;
uniform sampler2D u_tex;
uniform sampler2D u_layers[2];
out vec4 fragColor;

vec4 tap2(sampler2D image, vec2 uv) {
    return 0.5 * (texture(image, uv) + texture(image, uv + vec2(0.01, 0.0)));
}

vec4 both(sampler2D a, sampler2D b, vec2 uv) {
    return tap2(a, uv) * 0.75 + tap2(b, uv * 2.0) * 0.25;
}

void main() {
    vec4 c = tap2(u_tex, v_texcoord) + both(u_layers[1], u_tex, v_texcoord.yx);
    fragColor = vec4(sqrt(c.rgb) * exp(-c.a), 1.0);
}
"""


def _compiles_everywhere(table):
    """Every listed node's variant in every valid algorithm, linked by the GL driver."""
    ctx = get_context()
    built = 0
    for node in table.nodes:
        for algorithm in node.algorithms:
            programs = instance(table, node.id, algorithm).build_programs(ctx)
            for p in programs.values():
                p.release()
            built += 1
    return built


def test_a_sampler_argument_is_substituted_never_copied():
    shader = parse_shader(TAP2, "tap2.frag")
    text = print_glsl(inline_calls(shader).unit)
    assert "sampler2D _rr" not in text                     # GLSL has no sampler locals
    assert "texture(u_layers[1], " in text and "texture(u_tex, " in text
    table = cacheable_nodes(shader)
    assert table.nodes and _compiles_everywhere(table) >= 3


def test_a_struct_holding_a_sampler_is_substituted_too():
    src = """#version 330
in vec2 v_texcoord;
struct Material { sampler2D albedo; float gain; };
uniform Material u_mat;
out vec4 fragColor;
vec3 shade(Material m, vec2 uv) { return texture(m.albedo, uv).rgb * m.gain; }
void main() { fragColor = vec4(pow(shade(u_mat, v_texcoord), vec3(2.2)), 1.0); }
"""
    shader = parse_shader(src, "material.frag")
    text = print_glsl(inline_calls(shader).unit)
    assert "Material _rr" not in text and "texture(u_mat.albedo, " in text
    assert _compiles_everywhere(cacheable_nodes(shader)) >= 1


def test_a_sampler_argument_with_a_side_effect_is_refused_at_its_place():
    src = """#version 400
in vec2 v_texcoord;
uniform sampler2D u_layers[4];
out vec4 fragColor;
vec4 tap(sampler2D t, vec2 uv) { return texture(t, uv) + texture(t, uv * 2.0); }
void main() { int i = 0; fragColor = tap(u_layers[i++], v_texcoord); }
"""
    with pytest.raises(RRCacheError, match="argument of 'tap' has a side effect") as err:
        inline_calls(parse_shader(src, "effect.frag"))
    assert "effect.frag:6:" in str(err.value)


SANDBOX = """#version 330
uniform float time;
uniform vec2 resolution;
in vec2 v_texcoord;
out vec4 fragColor;

void mainImage(out vec4 c, in vec2 p);

void main() {
    mainImage(fragColor, v_texcoord * resolution);
}

float march(vec2 p) {
    for (int i = 0; i < 64; i++) {
        float d = length(p) - 0.5 + 0.1 * sin(time + float(i));
        if (d < 0.01) return float(i);
        p *= 1.02;
    }
    return 64.0;
}

void mainImage(out vec4 c, in vec2 p) {
    vec2 uv = (2.0 * p - resolution) / resolution.y;
    float m = march(uv);
    c = vec4(vec3(m / 64.0) * (0.5 + 0.5 * cos(uv.xyx + time)), 1.0);
}
"""


def test_a_kept_function_is_declared_before_its_first_use(tmp_path):
    """GLSL Sandbox: mainImage declared first, main calling it, mainImage calling a helper that
    returns from inside a loop (so kept, and now called from main, above its definition)."""
    path = tmp_path / "sandbox.frag"
    path.write_text(SANDBOX)
    code, out, lines, peak, _ = rrcache_traced(tmp_path, "nodes", "sandbox.frag")
    assert code == 0 and "mainImage" in out and peak < 400, (lines, peak)
    shader = parse_shader(SANDBOX, "sandbox.frag")
    text = print_glsl(inline_calls(shader).unit)
    assert text.index("float march(vec2 p);") < text.index("void main()") < text.index("float march(vec2 p)\n")
    table = cacheable_nodes(shader)
    assert table.nodes and _compiles_everywhere(table) >= 1


SDF = """#version 330
in vec3 v_objectPosition;
uniform vec3 u_light;
out vec4 fragColor;
float g_mat;

vec2 map(vec3 p) {
    float d = length(p) - 1.0 + 0.1 * sin(p.x * 7.0) * sin(p.y * 5.0);
    g_mat = d < 0.0 ? 1.0 : 2.0;
    return vec2(d, g_mat);
}

void main() {
    vec3 p = v_objectPosition;
    vec2 e = vec2(0.01, 0.0);
    vec3 n = normalize(vec3(map(p + e.xyy).x - map(p - e.xyy).x,
                            map(p + e.yxy).x - map(p - e.yxy).x,
                            map(p + e.yyx).x - map(p - e.yyx).x));
    float ok = v_objectPosition.x > 0.0 && map(p * 2.0).x > 0.0 ? 1.0 : 0.5;
    fragColor = vec4(vec3(max(dot(n, normalize(u_light)), 0.0) * ok) * (0.5 + 0.5 * g_mat), 1.0);
}
"""


def test_node_texts_never_show_the_passes_temporaries():
    """``map`` writes a global, so the inliner hoists the operands before each call into
    temporaries (``_rr_t_3``); the table shows what the user wrote."""
    table = cacheable_nodes(parse_shader(SDF, "sdf.frag"))
    texts = [n.text for n in table.nodes + table.excluded]
    assert not [t for t in texts if "_rr_" in t]
    assert "map(p + e.xyy).x - map(p - e.xyy).x" in [n.text for n in table.nodes]


def _chain(n: int) -> str:
    lines = ["#version 330", "in vec2 v_texcoord;", "out vec4 fragColor;",
             "float f0(float x) { return x * 1.01 + 0.1; }"]
    lines += [f"float f{k}(float x) {{ return f{k - 1}(x) * 0.999 + 0.001; }}" for k in range(1, n)]
    lines.append(f"void main() {{ fragColor = vec4(f{n - 1}(v_texcoord.x)); }}")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("n", [1000, 2000])
def test_a_chain_of_thousands_of_functions_is_refused_in_one_line_in_bounded_memory(tmp_path, stability_case, n):
    """A chain of 1,000 took 7.0 GB and 13 minutes; 2,000 exited 70 at 7.7 GB."""
    path = tmp_path / "chain.frag"
    path.write_text(_chain(n))
    code, _, lines, peak, _ = rrcache_traced(tmp_path, "nodes", "chain.frag", timeout=600)
    line = one_error_line(code, lines)
    stability_case(f"a chain of {n:,} functions, each calling the last", "safety: inlining bounded",
                   f"rrcache nodes on {path.stat().st_size:,} bytes of source").observe(
        exit=code, stderr=line, peak_mib=round(peak))
    assert "inlining the function calls would copy" in line and f"{n:,} deep" in line
    assert f"chain.frag:{n + 4}:" in line and "--max-ast-nodes" in line
    assert peak < 400, f"peak {peak:.0f} MiB"


def test_identical_calls_share_one_inlined_body(tmp_path):
    """``f(x) + f(x)`` of a function without effects is one body; doubling chains stay linear."""
    src = ["#version 330", "in vec2 v_texcoord;", "out vec4 fragColor;",
           "float f0(float x) { return sin(x) * 1.5; }"]
    src += [f"float f{k}(float x) {{ return f{k - 1}(x) + f{k - 1}(x) * 0.5; }}" for k in range(1, 40)]
    src.append("void main() { fragColor = vec4(f39(v_texcoord.x)); }")
    shader = parse_shader("\n".join(src), "doubling.frag")
    text = print_glsl(inline_calls(shader).unit)
    assert text.count("sin(") == 1                         # 2^39 calls without sharing
    effect = SDF.replace("map(p - e.xyy).x", "map(p + e.xyy).x")     # map writes g_mat: not shared
    assert print_glsl(inline_calls(parse_shader(effect, "e.frag")).unit).count("length(") == 7
