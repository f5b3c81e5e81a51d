"""The analysis passes (inline, unroll, compound expansion) keep programs equivalent.

Each shader is rendered on a 32×32 full-screen quad as written and as analysed (printed from the
transformed AST); the pixels must agree to 1e-5.
"""
from __future__ import annotations

import os

import numpy as np
import pytest

from rrcache.analysis import analyse, expand_compound_assignments, inline_calls, unroll_loops
from rrcache.glsl.ast import walk
from rrcache.errors import UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.frontend import parse_shader
from rrcache.glsl.printer import print_glsl

os.environ.setdefault("LP_NUM_THREADS", "1")

SIZE = 32
VERTEX = """#version 330 core
in vec2 in_pos;
out vec2 uv;
void main() { uv = in_pos * 0.5 + 0.5; gl_Position = vec4(in_pos, 0.0, 1.0); }
"""
HEAD = "#version 330\nin vec2 uv;\nout vec4 fragColor;\nuniform float u_k;\n"


_TARGET: dict = {}


def _target(ctx):
    """One framebuffer and quad for the whole run (releasing a bound framebuffer leaves a GL
    error in the next draw, and a standalone context has no default framebuffer to go back to)."""
    if "fbo" not in _TARGET:
        quad = np.array([-1, -1, 1, -1, -1, 1, 1, 1], dtype="f4")
        _TARGET["vbo"] = ctx.buffer(quad.tobytes())
        _TARGET["tex"] = ctx.texture((SIZE, SIZE), 4, dtype="f4")
        _TARGET["fbo"] = ctx.framebuffer([_TARGET["tex"]])
    return _TARGET["fbo"], _TARGET["vbo"]


def render(ctx, fragment: str) -> np.ndarray:
    fbo, vbo = _target(ctx)
    prog = ctx.program(vertex_shader=VERTEX, fragment_shader=fragment)
    if "u_k" in prog:
        prog["u_k"].value = 3.0
    vao = ctx.vertex_array(prog, [(vbo, "2f", "in_pos")])
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0)
    vao.render(mode=5)   # TRIANGLE_STRIP
    img = np.frombuffer(fbo.read(components=4, dtype="f4"), dtype="f4").reshape(SIZE, SIZE, 4)
    vao.release()
    prog.release()
    return img.copy()


def assert_equivalent(ctx, body: str) -> str:
    source = HEAD + body
    shader = parse_shader(source, "t.frag")
    before = print_glsl(shader.unit)
    analysed = analyse(shader)
    assert print_glsl(shader.unit) == before, "the pass modified its input"
    text = print_glsl(analysed.unit)
    a, b = render(ctx, source), render(ctx, text)
    assert np.isfinite(a).all()
    assert np.abs(a).max() > 0, "test shader renders black: the comparison would be vacuous"
    np.testing.assert_allclose(b, a, atol=1e-5, rtol=0)
    return text


CASES = {
    "out_inout_params": """
        void split(in vec2 p, out float a, inout float b) { a = p.x * 2.0; b += p.y; }
        void main() { float x; float y = 0.25; split(uv, x, y); split(uv.yx, x, y);
                      fragColor = vec4(x, y, 0.0, 1.0); }""",
    "early_returns": """
        float shape(vec2 p) {
            if (p.x < 0.3) return 0.1;
            float d = length(p - 0.5);
            if (d > 0.4) { if (p.y > 0.5) return 0.2; d *= 0.5; }
            return d;
        }
        void main() { fragColor = vec4(shape(uv), shape(uv.yx), 0.0, 1.0); }""",
    "conditional_calls": """
        float f(float x) { return x * x + 0.1; }
        void main() {
            float a = uv.x > 0.5 ? f(uv.y) : f(uv.x) * 2.0;
            bool b = uv.y > 0.3 && f(uv.x) > 0.4;
            fragColor = vec4(a, b ? 1.0 : 0.0, f(f(uv.x)), 1.0); }""",
    "global_side_effects": """
        float g = 0.0;
        float bump(float x) { g += x; return g; }
        void main() { float a = bump(uv.x); float b = bump(uv.y) * a;
                      fragColor = vec4(a, b, g, 1.0); }""",
    "nested_constant_loops": """
        float tri(float x) { return abs(fract(x) - 0.5); }
        void main() {
            float s = 0.0;
            for (int i = 0; i < 3; i++)
                for (int j = i; j <= 3; j += 2) s += tri(uv.x * float(i + 1) + float(j) * uv.y);
            for (float t = 0.0; t < 1.0; t += 0.25) s += t * uv.x;
            int k; for (k = 4; k > 0; k--) s -= 0.01 * float(k);
            fragColor = vec4(s * 0.2, float(k), 0.0, 1.0); }""",
    "runtime_loop_kept": """
        float f(float x) { return sin(x) * 0.5 + 0.5; }
        void main() {
            float s = 0.0;
            for (int i = 0; i < int(u_k); i++) { s += f(uv.x * float(i)); if (s > 2.0) break; }
            int n = 0;
            while (f(float(n) + uv.y) > 0.2 && n < 6) n++;
            fragColor = vec4(s * 0.3, float(n) * 0.1, 0.0, 1.0); }""",
    "loop_with_return_not_inlined": """
        float firstAbove(float x) {
            for (int i = 0; i < 8; i++) { if (float(i) * 0.1 > x) return float(i) * 0.1; }
            return 1.0;
        }
        void main() { fragColor = vec4(firstAbove(uv.x), 0.5, 0.0, 1.0); }""",
    "discard_and_compound": """
        void main() {
            vec4 c = vec4(uv, 0.5, 1.0);
            if (uv.x < 0.1) discard;
            c.rg *= 2.0; c.b /= 4.0; c += vec4(0.1);
            fragColor = c; }""",
    # the analysis once rejected its own rewrite of each of these (issue 14, item 4)
    "shadowed_globals": """
        vec3 pos = vec3(0.25, 0.5, 0.75);
        vec2 st = vec2(0.3, 0.6);
        float height() { return pos.y * 2.0 + uv.x; }
        vec3 tint(float h) { return vec3(st, h); }
        void main() { float pos = uv.y; vec3 st = vec3(uv, 0.5);
                      fragColor = vec4(tint(height()) * 0.5 + st * 0.25 + pos * 0.1, 1.0); }""",
    "local_named_like_a_builtin": """
        float edge(float x) { return step(0.5, x) * 0.5 + smoothstep(0.2, 0.8, x) * 0.5; }
        void main() { float step = 0.25; float smoothstep = uv.y;
                      fragColor = vec4(edge(uv.x) + step, smoothstep, 0.5, 1.0); }""",
    "globals_after_main": """
        float wave(float x);
        void main() { fragColor = vec4(wave(uv.x), wave(uv.y), 0.5, 1.0); }
        const float FREQ = 7.0;
        float g_bias = 0.25;
        float wave(float x) { return g_bias + 0.5 * sin(x * FREQ); }""",
    "struct_after_main": """
        float lit(vec2 p);
        void main() { fragColor = vec4(lit(uv), lit(uv.yx), 0.5, 1.0); }
        struct Light { vec2 dir; float k; };
        const Light SUN = Light(vec2(0.6, 0.8), 0.75);
        float lit(vec2 p) { Light l = SUN; l.k *= 0.5; return max(dot(p, l.dir), 0.0) * l.k + 0.1; }""",
    "void_ternary": """
        vec3 g;
        void a(float k) { g = vec3(k, 0.2, 0.1); }
        void b(float k) { g = vec3(0.1, k, 0.2); }
        void none() { }
        void main() { g = vec3(0.0); none(); uv.x > 0.5 ? a(uv.y) : b(uv.x);
                      fragColor = vec4(g, 1.0); }""",
    "unsigned_wrap": """
        const uint ALL = -1u;
        void main() {
            uint m = -1u; uint h = uint(uv.x * 255.0) + 7u;
            for (uint i = 0u; i < 3u; i++) { h = h * 747796405u + m; h ^= h >> 13u; }
            uint n = 0u; for (uint k = 3u; k != ALL; k--) n += k;
            fragColor = vec4(float(h & 255u) / 255.0, float(n) / 6.0, float(ALL >> 31u), 1.0); }""",
    "offset_indices": """
        void main() {
            vec2 a[5];
            for (int i = 0; i < 5; i++) a[i] = uv * float(i + 1);
            vec2 s = vec2(0.0);
            for (int i = 0; i < 5; i++) {
                s += a[i - 1 + 1];
                if (i > 0) s += a[i - 1] * 0.5;
                if (i < 4) s -= a[i + 1] * 0.25; else s += a[0];
                s += i > 0 ? a[i - 1] * 0.1 : a[0];
            }
            fragColor = vec4(s * 0.1, 0.5, 1.0); }""",
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_analysed_program_renders_the_same(gl_ctx, name):
    assert_equivalent(gl_ctx, CASES[name])


def test_inlining_removes_calls_and_renames_locals():
    s = parse_shader(HEAD + CASES["early_returns"], "t.frag")
    out = inline_calls(s)
    text = print_glsl(out.unit)
    assert "shape(" not in text
    assert [d.name for d in out.unit.decls if isinstance(d, A.FunctionDecl)] == ["main"]
    assert "_rr_live_" in text and "_rr_shape_" in text


def test_operands_before_a_side_effecting_call_are_evaluated_first():
    # GLSL leaves the order unspecified (Mesa reads g late); the inliner fixes left to right
    src = HEAD + """float g = 0.0;
        float bump(float x) { g += x; return g; }
        float pure(float x) { return x * 2.0; }
        void main() { float t = g + bump(uv.x); float u = g + pure(uv.y);
                      fragColor = vec4(t, u, 0.0, 1.0); }"""
    text = print_glsl(inline_calls(parse_shader(src, "t.frag")).unit)
    body = text[text.index("void main"):]
    assert "float t = _rr_t_" in body
    assert body.index("= g;") < body.index("g += ")
    assert "float u = g + _rr_pure_" in body       # a pure call does not hoist its left operand


def test_function_with_return_in_loop_is_kept():
    s = parse_shader(HEAD + CASES["loop_with_return_not_inlined"], "t.frag")
    names = [d.name for d in inline_calls(s).unit.decls if isinstance(d, A.FunctionDecl)]
    assert names == ["firstAbove", "main"]


def test_reserved_names_are_rejected():
    s = parse_shader(HEAD + "void main() { float _rr_x = 1.0; fragColor = vec4(_rr_x); }",
                     "t.frag")
    with pytest.raises(UnsupportedShaderError, match=r"t\.frag:5:\d+: .*_rr_x.*hint: rename"):
        inline_calls(s)


def _loops(unit) -> int:
    return sum(isinstance(n, (A.For, A.While, A.DoWhile)) for n in walk(unit))


def test_unroll_respects_bound_and_loop_shape():
    src = HEAD + """void main() { float s = 0.0;
        for (int i = 0; i < 10; i++) s += 1.0;
        for (int i = 0; i < 4; i++) { s += 1.0; if (s > u_k) break; }
        for (int i = 0; i < 4; i++) { i += 0; s += 1.0; }
        const int N = 3; int m = 2;
        for (int i = 0; i < N * m; i++) s += 2.0;
        fragColor = vec4(s); }"""
    s = parse_shader(src, "t.frag")
    assert _loops(unroll_loops(s).unit) == 2          # break, and a body writing i
    assert _loops(unroll_loops(s, max_iterations=9).unit) == 3   # 10 > 9 iterations
    assert _loops(s.unit) == 4                        # the input is untouched


def test_unroll_float_loop_counts_in_single_precision():
    # 0.1 accumulated in float32 reaches 1.0000001 after 10 steps: 11 iterations, not 10 or 12
    src = HEAD + """void main() { float s = 0.0;
        for (float t = 0.0; t < 1.0; t += 0.1) s += 1.0; fragColor = vec4(s); }"""
    text = print_glsl(unroll_loops(parse_shader(src, "t.frag")).unit)
    t, n = np.float32(0), 0
    while t < np.float32(1.0):
        n, t = n + 1, np.float32(t + np.float32(0.1))
    assert text.count("s = s + 1.0") + text.count("s += 1.0") == n


def test_expand_compound_assignments():
    src = HEAD + """void main() { vec4 c = vec4(uv, 0.0, 1.0); int i = 0;
        c.xy *= 2.0; c[i++] += 1.0; fragColor = c; }"""
    text = print_glsl(expand_compound_assignments(parse_shader(src, "t.frag")).unit)
    assert "c.xy = c.xy * 2.0;" in text
    assert "c[i++] += 1.0;" in text      # the target has a side effect: left alone


def test_unroll_drops_branches_the_loop_index_decides():
    shader = parse_shader(HEAD + CASES["offset_indices"], "t.frag")
    text = print_glsl(analyse(shader).unit)
    assert "for (" not in text and "if (" not in text and "?" not in text
    assert "0 - 1]" not in text


def test_unroll_keeps_a_loop_whose_copy_would_index_out_of_range():
    # the guard is not an if this pass decides: a copy would hold a[0 - 1], which does not compile
    shader = parse_shader(HEAD + """void main() { float a[3] = float[3](uv.x, uv.y, 0.5); float s = 0.0;
        for (int i = 0; i < 3; i++) { if (i > 0 && a[i - 1] > 0.2) s += a[i]; }
        fragColor = vec4(s); }""", "t.frag")
    assert _loops(analyse(shader).unit) == 1


def test_inlined_body_keeps_reading_the_global_a_local_shadows():
    text = print_glsl(analyse(parse_shader(HEAD + CASES["shadowed_globals"], "t.frag")).unit)
    assert "float pos = " not in text and "= pos.y * 2.0" in text and "vec3(st, " in text


def test_void_ternary_becomes_an_if():
    text = print_glsl(analyse(parse_shader(HEAD + CASES["void_ternary"], "t.frag")).unit)
    assert "_rr_sel" not in text and "if (uv.x > 0.5)" in text
