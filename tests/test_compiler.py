"""Text-level tests of the instancing compiler (no GL): the single transforms on tiny shaders
(golden texts), the pass assembly, pruning of globals, errors, manifest and files."""
from __future__ import annotations

import json

import pytest

from rrcache.analysis import cacheable_nodes
from rrcache.compiler import instance
from rrcache.compiler.hoist import hoist, side_effect_before
from rrcache.compiler.locate import PLACEHOLDER, find_site, prepare
from rrcache.compiler.passes import build_pass
from rrcache.compiler.prune import prune
from rrcache.errors import RRCacheError, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.frontend import parse_shader
from rrcache.glsl.parser import parse_source
from rrcache.glsl.printer import print_glsl
from rrcache.glsl.semantic import check


def _pruned(src: str) -> str:
    unit = parse_source(src)
    check(unit)
    return print_glsl(prune(unit))


def _main_text(unit_text: str) -> str:
    return unit_text.split("void main()\n", 1)[1]


def _node(shader, text):
    """The node table of ``shader`` and its node (cacheable or excluded: the compiler takes
    any float/vector node) whose printed text is ``text``."""
    table = cacheable_nodes(shader)
    found = [n for n in list(table.nodes) + list(table.excluded) if n.text == text]
    assert found, [n.text for n in table.nodes]
    return table, found[0]


# ----------------------------------------------------------------------------- prune


def test_prune_removes_exactly_the_dead_code():
    src = """#version 330
uniform float a; uniform float b; uniform float unusedU; uniform sampler2D unusedTex;
in vec2 v_texcoord; in vec3 v_normal;
out vec4 c;
struct S { float q; };
struct Unused { float w; };
float helper(float x) { return x * b; }
float deadHelper(float x) { return x; }
void main() {
    float x = a;
    float y = v_normal.x, z = 1.0;
    S s = S(2.0);
    if (x > 0.5) discard;
    float w; w = 3.0; w = 4.0;
    for (int i = 0; i < 3; i++) { y += deadHelper(1.0); if (y > 2.0) break; }
    for (int i = 0; i < 3; i++) { z += 1.0; }
    c = vec4(x + s.q + helper(w) + z);
    y = 5.0;
}"""
    assert _pruned(src) == """#version 330 core
uniform float a;
uniform float b;
out vec4 c;

struct S {
    float q;
};

float helper(float x)
{
    return x * b;
}

void main()
{
    float x = a;
    float z = 1.0;
    S s = S(2.0);
    if (x > 0.5)
        discard;
    float w;
    w = 4.0;
    for (int i = 0; i < 3; i++)
    {
        z += 1.0;
    }
    c = vec4(x + s.q + helper(w) + z);
}
"""


def test_prune_keeps_control_dependencies_of_discard_and_return():
    src = """#version 330
uniform float u; out vec4 c;
void main() {
    float t = u * 2.0;
    float k = u * 3.0;
    if (t > 1.0) { k = 0.0; discard; }
    if (u < 0.0) return;
    c = vec4(1.0);
}"""
    assert _main_text(_pruned(src)) == """{
    float t = u * 2.0;
    if (t > 1.0)
    {
        discard;
    }
    if (u < 0.0)
        return;
    c = vec4(1.0);
}
"""


def test_prune_loop_and_switch_fixed_point():
    src = """#version 330
uniform int n; uniform float u; out vec4 c;
void main() {
    float acc = 0.0;
    float prev = u;
    int i = 0;
    while (i < n) { acc += prev; prev = prev * 0.5; i++; }
    float dead = 0.0;
    int j = 0;
    while (j < n) { dead += 1.0; j++; }
    switch (n) { case 0: acc = 1.0; break; default: break; }
    c = vec4(acc);
}"""
    text = _main_text(_pruned(src))
    assert "prev = prev * 0.5" in text and "i++" in text and "switch (n)" in text
    assert "dead" not in text and "j" not in text


# ----------------------------------------------------------------------------- replace, hoist


def _prepared(src, text):
    shader = parse_shader(src)
    node = [n for n in shader.unit.walk() if isinstance(n, A.Expr) and n.type is not None
            and n.type.glsl_name() in ("float", "vec2", "vec3", "vec4")
            and __import__("rrcache.glsl.printer", fromlist=["print_expr"]).print_expr(n) == text]
    assert node, text
    return prepare(shader, node[0])


def test_prepare_puts_placeholder_and_converts_legacy():
    loc = _prepared("varying vec2 v_texcoord; uniform sampler2D t;\n"
                    "void main() { gl_FragColor = texture2D(t, v_texcoord) * 0.5; }",
                    "texture2D(t, v_texcoord)")
    assert loc.type_name == "vec4" and loc.components == 4
    assert PLACEHOLDER in print_glsl(loc.unit)
    assert "rr_FragColor" in print_glsl(loc.unit)
    assert loc.expr.name == "texture"  # converted like the rest of the unit


def test_hoist_golden_and_inline_form_with_earlier_side_effect():
    unit = parse_source(f"void main() {{ float a = 1.0; float y = 2.0 * {PLACEHOLDER}; }}")
    site = find_site(unit)
    assert not side_effect_before(site.stmt)
    assert hoist(site, "float", A.Call("sin", [A.Ident("a")])) == "hoist"
    assert _main_text(print_glsl(unit)) == """{
    float a = 1.0;
    float rr_node = sin(a);
    float y = 2.0 * rr_node;
}
"""
    unit = parse_source(f"void main() {{ float a = 1.0; float y = (a = 3.0) + {PLACEHOLDER}; }}")
    site = find_site(unit)
    assert side_effect_before(site.stmt)
    assert hoist(site, "float", A.Call("sin", [A.Ident("a")]), then=[]) == "inline"
    assert _main_text(print_glsl(unit)) == """{
    float a = 1.0;
    float rr_node;
    float y = (a = 3.0) + (rr_node = sin(a));
}
"""


def test_site_inside_bare_if_branch_is_wrapped():
    unit = parse_source(f"uniform bool b; void main() {{ float y; if (b) y = {PLACEHOLDER}; }}")
    site = find_site(unit)
    assert isinstance(site.block, A.Compound) and site.block.stmts == [site.stmt]


SHADE_SRC = """#version 330
in vec3 v_normal; in vec2 v_texcoord;
uniform vec3 u_light; uniform float u_scale; uniform float u_unused;
out vec4 fragColor;
float unusedFunction(float x) { return x * u_unused; }
void main() {
    float n = sin(v_texcoord.x * u_scale) * cos(v_texcoord.y * u_scale);
    float d = max(dot(normalize(v_normal), normalize(u_light)), 0.0);
    fragColor = vec4(vec3(n * d), 1.0);
}
"""


def test_passes_golden_three_pass():
    shader = parse_shader(SHADE_SRC)
    table, node = _node(shader, "sin(v_texcoord.x * u_scale) * cos(v_texcoord.y * u_scale)")
    loc = prepare(table, node.id)
    shade = print_glsl(build_pass(loc, "shade").unit)
    assert _main_text(shade) == """{
    float n = rr_current().x;
    float d = max(dot(normalize(v_normal), normalize(u_light)), 0.0);
    fragColor = vec4(vec3(n * d), 1.0);
}
"""
    assert "u_scale" not in shade and "v_texcoord" not in shade
    payload = print_glsl(build_pass(loc, "payload").unit)
    # the initial rr_out writes are dead here (no early return): pruned
    assert _main_text(payload) == """{
    float rr_node = sin(v_texcoord.x * u_scale) * cos(v_texcoord.y * u_scale);
    rr_outPayload = vec4(rr_node, 0.0, 0.0, 0.0);
    rr_outInvDepth = gl_FragCoord.w;
}
"""
    assert "fragColor" not in payload and "u_light" not in payload and "v_normal" not in payload
    reproject = print_glsl(build_pass(loc, "reproject").unit)
    assert _main_text(reproject) == """{
    if (!rr_hit() || rr_refreshNow())
        discard;
    rr_outPayload = rr_previous();
    rr_outInvDepth = gl_FragCoord.w;
}
"""
    # only the runtime's declarations remain, and the emitter prints those verbatim
    assert reproject.startswith("#version 330 core\n\nvoid main()")


def test_early_return_keeps_the_invalid_cache_initialisation():
    src = SHADE_SRC.replace("void main() {", "void main() {\n    if (v_normal.z < -0.5) return;")
    table, node = _node(parse_shader(src), "n * d")
    loc = prepare(table, node.id)
    for name in ("reproject", "payload", "single"):
        body = _main_text(print_glsl(build_pass(loc, name).unit))
        assert body.startswith("{\n    rr_outInvDepth = 0.0;\n    rr_outPayload = vec4(0.0);\n"
                               "    if (v_normal.z < -0.5)\n        return;\n"), (name, body)
    assert "rr_outInvDepth" not in print_glsl(build_pass(loc, "shade").unit)


def test_one_pass_moves_feeders_into_the_miss_branch():
    shader = parse_shader(SHADE_SRC)
    table, node = _node(shader, "n * d")
    single = print_glsl(build_pass(prepare(table, node.id), "single").unit)
    body = _main_text(single)
    branch = body.index("if (rr_hit() && !rr_refreshNow())")
    # n and d only feed E: computed in the else branch, after the hit test
    assert body.index("float n = ") > branch and body.index("float d = ") > branch
    assert "rr_outPayload = vec4(rr_node, 0.0, 0.0, 0.0);" in body
    assert "layout(location = 0) out vec4 fragColor;" in single


def test_emitted_shaders_contain_only_what_each_pass_needs():
    shader = parse_shader(SHADE_SRC)
    table, node = _node(shader, "sin(v_texcoord.x * u_scale) * cos(v_texcoord.y * u_scale)")
    for algorithm in ("three-pass", "two-pass", "one-pass"):
        v = instance(table, node.id, algorithm)
        for name, src in v.passes.items():
            assert "u_unused" not in src.fragment and "unusedFunction" not in src.fragment
            assert src.fragment.startswith("#version 330 core\n")
            assert "invariant gl_Position;" in src.vertex
            assert ("rr_prevClip" in src.vertex) == ("rr_hit()" in src.fragment)
            for uniform in v.uniforms[name] + v.samplers[name]:
                assert uniform in src.fragment or uniform in src.vertex
    v = instance(table, node.id, "three-pass")
    assert "u_light" not in v.passes["payload"].fragment
    assert "v_normal" not in v.passes["payload"].vertex
    assert "u_scale" not in v.uniforms["shade"] and "u_light" in v.uniforms["shade"]
    assert "rr_curPayload" in v.runtime_uniforms["shade"]
    assert "rr_period" in v.runtime_uniforms["reproject"]


def test_line_map_points_into_the_original_file():
    shader = parse_shader(SHADE_SRC, "shade.frag")
    table, node = _node(shader, "sin(v_texcoord.x * u_scale) * cos(v_texcoord.y * u_scale)")
    v = instance(table, node.id, "three-pass")
    src = v.passes["shade"]
    lines = src.fragment.split("\n")
    i = next(k for k, line in enumerate(lines) if "float d = " in line)
    assert src.fragment_line_map[i].file == "shade.frag" and src.fragment_line_map[i].line == 8


def test_manifest_and_write(tmp_path):
    shader = parse_shader(SHADE_SRC)
    table, node = _node(shader, "n * d")
    v = instance(table, node.id, "two-pass", filter="catmull-rom", payload_dtype="f2")
    paths = v.write(tmp_path / "variant")
    names = sorted(p.rsplit("/", 1)[1] for p in paths)
    assert names == ["hit.frag", "hit.vert", "manifest.json", "miss.frag", "miss.vert"]
    m = json.loads((tmp_path / "variant" / "manifest.json").read_text())
    assert m["node"]["id"] == node.id and m["node"]["type"] == "float"
    assert m["algorithm"] == "two-pass" and m["filter"] == "catmull-rom"
    assert m["payload_dtype"] == "f2" and m["default_period"] >= 1
    assert set(m["passes"]) == {"hit", "miss"} and "u_light" in m["uniforms"]
    assert "rr_prevPayload" in m["passes"]["hit"]["runtime_uniforms"]
    assert (tmp_path / "variant" / "hit.frag").read_text().rstrip("\n") == v.passes["hit"].fragment.rstrip("\n")


def test_errors():
    shader = parse_shader(SHADE_SRC)
    with pytest.raises(RRCacheError):
        instance(shader, "n999999")
    int_node = parse_shader("#version 330\nuniform int k; out vec4 c;\n"
                            "void main() { c = vec4(float(k * 2)); }")
    mul = [n for n in int_node.unit.walk() if isinstance(n, A.Binary)][0]
    with pytest.raises(UnsupportedShaderError) as err:
        instance(int_node, mul)
    assert "only float and vec2-4" in str(err.value) and ":3:" in str(err.value)
    with pytest.raises(ValueError):
        instance(shader, "n1", algorithm="four-pass")
    clash = (parse_shader("#version 330\nuniform float rr_period; in vec2 v_texcoord;\n"
                                 "out vec4 c;\nvoid main() { c = vec4(sin(v_texcoord.x) + rr_period); }"))
    table, node = _node(clash, "sin(v_texcoord.x)")
    with pytest.raises(UnsupportedShaderError) as err:
        instance(table, node.id)
    assert "reserved" in str(err.value)


# ----------------------------------------------------------------------------- tidy output


TIDY = """#version 330
in vec3 v_objectPosition;
out vec4 fragColor;
float hash(vec3 p) { p = fract(p * 0.3183 + 0.1); p *= 17.0; return fract(p.x * p.y * p.z * (p.x + p.y + p.z)); }
float fbm(vec3 p) {
    float s = 0.0;
    float a = 0.5;
    for (int i = 0; i < 3; i++) { float h = hash(p); s += a * h; p = p * 2.0 + 0.1; a *= 0.5; }
    return s;
}
void main() {
    float w = fbm(v_objectPosition);
    fragColor = vec4(vec3(w), 1.0);
}
"""


def _blocks_are_tidy(text: str) -> list[str]:
    """The runs of nested braces in ``text``: empty blocks in a statement list and blocks
    whose only statement is a block."""
    bad = []
    for n in A.walk(parse_source(text)):
        if isinstance(n, A.Compound):
            bad += [f"empty block at {x.loc}" for x in n.stmts if isinstance(x, A.Compound) and not x.stmts]
            if len(n.stmts) == 1 and isinstance(n.stmts[0], A.Compound):
                bad.append(f"block holding only a block at {n.loc}")
    return bad


def test_pruned_passes_have_no_runs_of_nested_braces():
    # a node deep in nested blocks (fbm inlined, then the second unrolled iteration)
    table = cacheable_nodes(parse_shader(TIDY, "tidy.frag"))
    node = [n for n in table.nodes if n.call_chain[-1:] == ["for i=1 (8:5)"]][0]
    variant = instance(table, node.id, "three-pass")
    for name, p in variant.passes.items():
        assert not _blocks_are_tidy(p.fragment), (name, p.fragment)
    # golden: the reprojection pass keeps nothing of the shader's code, and says so plainly
    assert _main_text(variant.passes["reproject"].fragment) == """{
    if (!rr_hit() || rr_refreshNow())
        discard;
    rr_outPayload = rr_previous();
    rr_outInvDepth = gl_FragCoord.w;
}
"""


def test_tidy_keeps_a_block_a_loop_header_needs():
    src = """#version 330
uniform int n; out vec4 c;
void main() { float s = 0.0; for (int i = 0; i < n; i++) { { int i = 2; s += float(i); } } c = vec4(s); }
"""
    text = _pruned(src)
    assert "for (int i = 0; i < n; i++)\n    {\n        {\n            int i = 2;" in text
    check(parse_source(text))


def test_prune_drops_case_labels_left_at_the_end_of_a_switch():
    src = """#version 330
uniform int k; uniform float a; out vec4 c;
void main() { float x = 0.0; float dead = 0.0;
    switch (k) { case 0: x = a; break; case 1: dead = 2.0; break; default: dead = 3.0; }
    c = vec4(x); }
"""
    text = _pruned(src)
    body = text.split("switch (k)", 1)[1]
    # the driver refuses a label followed by '}' (GLSL: a label precedes a statement)
    assert "case 0:" in body and "default:" not in body
    assert not body.split("}")[0].rstrip().endswith(":")
