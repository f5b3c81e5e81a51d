"""Node tables on the code people write (issue 14): partial writes of every kind, values after
implicit-LOD lookups (valid per algorithm), screen-space values, exact costs over shared
definitions, and the unrolling size budget."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from rrcache.analysis import REASONS, analyse, cacheable_nodes
from rrcache.analysis.cacheable import ALGORITHMS
from rrcache.analysis.unroll import unroll_loops
from rrcache.errors import UnsupportedShaderError
from rrcache.glsl.frontend import parse_shader
from rrcache.glsl.printer import print_glsl

HEAD = ("#version 330\nin vec3 v_normal;\nin vec2 v_texcoord;\nout vec4 fragColor;\nuniform float u_k;\n"
        "uniform vec2 u_resolution;\nuniform sampler2D u_tex;\nuniform samplerCube u_env;\n")
CORPUS = Path(__file__).parent / "corpus"


def table_of(body: str, **kw):
    return cacheable_nodes(parse_shader(HEAD + body, "t.frag"), **kw)


def entry(table, text: str):
    """The first entry (listed or excluded) with this text, and its reason ('listed')."""
    for n in sorted(list(table.nodes) + list(table.excluded), key=lambda x: int(x.id[1:])):
        if n.text == text:
            return n, getattr(n, "reason", "listed")
    raise AssertionError(f"no node {text!r}")


def final(table):
    got = [n for n in table.nodes if n.final]
    assert len(got) == 1, "the final colour is not listed"
    return got[0]


# ----------------------------------------------------------------------------- partial writes


def test_component_write_the_issue_example():
    t = table_of("void main() { vec4 c = vec4(0.0, 0.0, 0.0, 1.0);"
                 " c.rgb += sin(v_normal) * cos(v_normal); fragColor = c; }")
    work, why = entry(t, "sin(v_normal) * cos(v_normal)")
    assert why == "listed" and work.cost == 51             # two vec3 transcendentals + multiply
    f = final(t)
    assert f.text == "c"                                   # the final colour is offered ...
    assert f.cost == work.cost + 3                         # ... with everything that flowed in
    # the initial value alone is uniform, the value after the write is not
    assert entry(t, "vec4(0.0, 0.0, 0.0, 1.0)")[1] == "uniform"


def test_member_write_by_component():
    t = table_of("struct M { vec3 albedo; float r; };\nvoid main() { M m;"
                 " m.albedo = vec3(0.5); m.r = 1.0;"
                 " m.albedo.rgb = m.albedo.rgb * exp(v_normal) * sin(v_normal);"
                 " fragColor = vec4(m.albedo, m.r); }")
    written, why = entry(t, "m.albedo.rgb * exp(v_normal) * sin(v_normal)")
    assert why == "listed"
    f = final(t)
    assert f.text == "vec4(m.albedo, m.r)" and f.cost == written.cost
    reads = [n for n in t.nodes + t.excluded if n.text == "m.albedo"]
    reads.sort(key=lambda n: int(n.id[1:]))
    assert reads[0].reason == "uniform"              # read before the write: vec3(0.5)
    assert reads[-1].cost == written.cost            # read after it: costs the write


def test_element_writes_constant_and_per_pixel_index():
    t = table_of("void main() { vec3 a[3]; a[0] = vec3(0.0); a[1] = cos(v_normal) * sin(v_normal);"
                 " int j = int(v_texcoord.x * 2.0); a[j] = a[j] + exp(v_normal) * 2.0;"
                 " fragColor = vec4(a[0] + a[1], 1.0); }")
    one = entry(t, "cos(v_normal) * sin(v_normal)")[0]
    more = entry(t, "a[j] + exp(v_normal) * 2.0")[0]
    assert entry(t, "a[j] + exp(v_normal) * 2.0")[1] == "listed"
    read = [n for n in t.nodes if n.text == "a[0] + a[1]"]
    # the per-pixel write reads the array (so the constant-index one too), and the reads
    # after it cost both: each write counted once
    assert more.cost > one.cost and read and read[0].cost == more.cost + 3


def test_inout_and_out_parameters_written_by_component():
    t = table_of("void shade(inout vec4 c, vec3 k) { c.rgb += sin(k) * cos(k); }\n"
                 "void split(vec3 x, out vec3 lo) { lo.xy = exp(x.xy) * sin(x.z); lo.z = 1.0; }\n"
                 "void main() { vec4 c = vec4(0.0, 0.0, 0.0, 1.0); shade(c, v_normal);"
                 " vec3 lo; split(v_normal, lo); fragColor = c * vec4(lo, 1.0); }")
    # the inliner turns the calls into component assignments of the parameters' copies
    text = print_glsl(t.shader.unit)
    assert ".rgb = _rr_c_" in text and ".xy = exp(" in text
    shaded = entry(t, "sin(k) * cos(k)")[0]
    split = [n for n in t.excluded + t.nodes if n.text.startswith("exp(") and "* sin(" in n.text][0]
    f = final(t)
    assert f.text == "c * vec4(lo, 1.0)"
    assert f.cost >= shaded.cost + split.cost


def test_builtin_out_argument_and_increment():
    t = table_of("void main() { vec3 ip; vec3 fr = modf(v_normal * exp(v_normal), ip);"
                 " float k = 0.0; k++; fragColor = vec4(ip * fr, k); }")
    ip_read = entry(t, "ip")[0]
    assert entry(t, "ip")[1] != "uniform" and ip_read.cost > 0   # written by the call
    assert entry(t, "k")[1] == "uniform"             # 0.0 then ++: the same for every pixel


def test_costs_count_shared_definitions_once():
    t = table_of("void main() { vec3 a = sin(v_normal); vec3 b = a * 2.0; vec3 c = a * 3.0;"
                 " vec3 d = b + c; fragColor = vec4(d, 1.0); }")
    # sin (24) + two vec3 multiplies (3 + 3) + the add (3): a counted once
    assert entry(t, "b + c")[0].cost == 33


def test_long_chains_cost_the_sum_of_their_steps():
    steps = 400
    body = "float x0 = v_texcoord.x;\n" + "".join(
        f"float x{k} = x{k - 1} * 1.001 + x{max(0, k - 7)};\n" for k in range(1, steps + 1))
    t = table_of(f"void main() {{\n{body} fragColor = vec4(x{steps}); }}")
    # every step is a multiply and an add, each counted once however often it is reached
    assert final(t).cost == 2 * steps


# ----------------------------------------------------------------------------- derivatives


LOD_SHADER = """void main() {
    vec2 uv = v_texcoord * 4.0 + sin(v_normal.xy) * 0.1;
    vec4 t = texture(u_tex, uv);
    vec3 e = texture(u_env, v_normal, 0.5).rgb;
    vec3 light = normalize(v_normal) * exp(v_normal.z) * sin(v_normal);
    vec3 c = t.rgb * light * exp(t.a) + e * 0.5;
    float later = sin(v_normal.x) * 0.1;
    fragColor = vec4(c + sin(v_normal.xy).x * later, 1.0);
}"""


def test_values_after_implicit_lod_lookups_are_listed_for_two_and_three_pass():
    t = table_of(LOD_SHADER)
    after, why = entry(t, "t.rgb * light * exp(t.a) + e * 0.5")
    assert why == "listed"
    assert after.algorithms == ["three-pass", "two-pass"]
    assert after.invalid["one-pass"].startswith("derivative")
    lit, why = entry(t, "normalize(v_normal) * exp(v_normal.z) * sin(v_normal)")
    assert why == "listed" and lit.algorithms == list(ALGORITHMS)
    assert final(t).algorithms == ["three-pass", "two-pass"]


def test_values_flowing_into_a_lookup_coordinate_are_excluded():
    t = table_of(LOD_SHADER)
    assert entry(t, "uv")[1] == "derivative"                        # the coordinate itself
    assert entry(t, "v_texcoord * 4.0 + sin(v_normal.xy) * 0.1")[1] == "derivative"   # through uv
    assert entry(t, "sin(v_normal.xy) * 0.1")[1] == "derivative"
    # the same expression elsewhere is not a duplicate of the excluded one
    later = [n for n in t.nodes + t.excluded if n.text == "sin(v_normal.xy)"]
    assert [getattr(n, "reason", "listed") for n in later] == ["derivative", "cheap"]


def test_the_compiler_refuses_one_pass_for_a_derivative_node():
    from rrcache.compiler import instance

    t = table_of(LOD_SHADER)
    after = entry(t, "t.rgb * light * exp(t.a) + e * 0.5")[0]
    with pytest.raises(UnsupportedShaderError, match="cannot be cached with one-pass: derivative"):
        instance(t, after.id, "one-pass")
    assert instance(t, after.id, "two-pass").algorithm == "two-pass"


def run(capsys, *args):
    from rrcache.cli import main

    try:
        main(list(args))
        code = 0
    except SystemExit as e:
        code = e.code
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_nodes_json_and_instance_say_which_algorithms(tmp_path, capsys):
    shader = CORPUS / "implicit_lod.glsl"
    code, out, err = run(capsys, "nodes", str(shader), "--json")
    assert code == 0, err
    doc = json.loads(out)
    restricted = [n for n in doc["nodes"] if n["algorithms"] == ["three-pass", "two-pass"]]
    assert restricted and all(n["not_valid"]["one-pass"].startswith("derivative")
                              for n in restricted)
    assert all(n["not_valid"] == {} for n in doc["nodes"] if len(n["algorithms"]) == 3)
    code, out, err = run(capsys, "instance", str(shader), "--session", str(CORPUS / "implicit_lod.json"),
                         "--node", restricted[0]["id"], "--algorithm", "one-pass",
                         "--out", str(tmp_path / "v"))
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "cannot be cached with one-pass" in err and "three-pass or two-pass" in err
    assert not (tmp_path / "v").exists()


def test_a_one_pass_profile_trains_only_what_one_pass_can_cache():
    from rrcache.pipeline import load_for_session
    from rrcache.profiles.settings import TrainingSettings
    from rrcache.profiler.train import training_order
    from rrcache.session import load_session

    session = load_session(CORPUS / "implicit_lod.json")
    work = load_for_session(CORPUS / "implicit_lod.glsl", session)
    order = training_order(work, session, TrainingSettings(algorithm="one-pass", min_saving=0.0))
    assert order.nodes and all("one-pass" in n.algorithms for n in order.nodes)
    refused = [n.id for n in work.table.nodes if "one-pass" not in n.algorithms]
    assert refused and all("one-pass cannot cache it: derivative" in order.skipped[i] for i in refused)
    auto = training_order(work, session, TrainingSettings(algorithm="auto", min_saving=0.0))
    assert {n.id for n in auto.nodes} == {n.id for n in work.table.nodes}


# ----------------------------------------------------------------------------- screen space


def test_screen_space_values_are_excluded():
    t = table_of("void main() { vec3 surf = sin(v_normal) * cos(v_normal) * exp(v_normal);"
                 " vec2 st = gl_FragCoord.xy / u_resolution;"
                 " float stripes = sin(st.x * 60.0) * cos(st.y * 30.0);"
                 " float still = sin(gl_FragCoord.x * 0.3) * cos(gl_FragCoord.y * 0.2);"
                 " fragColor = vec4(surf * stripes + still, 1.0); }")
    assert entry(t, "gl_FragCoord.xy / u_resolution")[1] == "screen"
    assert entry(t, "sin(st.x * 60.0) * cos(st.y * 30.0)")[1] == "screen"
    # the same at a pixel every frame, but not at a surface point: still screen
    assert entry(t, "sin(gl_FragCoord.x * 0.3) * cos(gl_FragCoord.y * 0.2)")[1] == "screen"
    assert entry(t, "sin(v_normal) * cos(v_normal) * exp(v_normal)")[1] == "listed"
    assert not [n for n in t.nodes if n.final]       # the colour reads the stripes
    assert "screen" in REASONS and t.counts()["screen"] > 0


# ----------------------------------------------------------------------------- unrolling budget


def test_unrolling_stops_at_the_size_budget_and_leaves_loops_rolled():
    from rrcache.glsl import ast as A
    from rrcache.glsl.ast import walk

    src = HEAD + ("void main() { float a = 0.0; float b = 0.0;\n"
                  " for (int i = 0; i < 8; i++) a += sin(v_texcoord.x * float(i)) * exp(v_texcoord.y);\n"
                  " for (int j = 0; j < 8; j++) b += cos(v_texcoord.y * float(j)) * exp(v_texcoord.x);\n"
                  " fragColor = vec4(a, b, 0.0, 1.0); }")
    s = parse_shader(src, "t.frag")
    first = [n for n in walk(s.unit) if isinstance(n, A.For)][0]
    budget = 8 * sum(1 for _ in walk(first.body)) + 4    # the first loop's copies, not both
    text = print_glsl(unroll_loops(s, max_size=budget).unit)
    assert text.count("for (") == 1 and "for (int j" in text     # the second one stays
    table = cacheable_nodes(analyse(s, max_size=budget), analysed=True)
    assert entry(table, "cos(v_texcoord.y * float(j)) * exp(v_texcoord.x)")[1] == "dynamic"
    assert [n for n in table.nodes if any(c.startswith("for i=") for c in n.call_chain)]
    assert "for (" not in print_glsl(analyse(s).unit)          # the default budget unrolls both


# ----------------------------------------------------------------------------- mipmaps


def test_session_textures_are_mipmapped_and_minified_in_the_corpus(gl_ctx):
    """The implicit-LOD corpus shader samples its checker minified: with the default (mipmap)
    filter the image differs from level-0-only sampling, so the Δn = 1 comparison in
    tests/test_corpus.py exercises real level-of-detail selection."""
    import numpy as np

    from rrcache.harness.renderer import Renderer
    from rrcache.pipeline import load_for_session
    from rrcache.session import load_session

    session = load_session(CORPUS / "implicit_lod.json")
    assert session.textures["u_checker"].filter == "mipmap"
    work = load_for_session(CORPUS / "implicit_lod.glsl", session)
    with Renderer(work.prepared, session, (64, 64)) as r:
        mipmapped = r.render_frame(0)
    session.textures["u_checker"].filter = "linear"
    with Renderer(work.prepared, session, (64, 64)) as r:
        level0 = r.render_frame(0)
    diff = np.abs(mipmapped.image - level0.image)[mipmapped.mask]
    assert diff.mean() > 0.01


def test_every_node_after_implicit_lod_lookups_reproduces_the_original_at_period_one(gl_ctx):
    """Issue 14 item 2 on rendered images: every listed node of the implicit-LOD corpus shader
    (a minified mipmapped checker, a biased cube-map lookup, fwidth), in every algorithm its
    table entry allows, reproduces the original at Δn = 1 on a 64×64 frame."""
    import numpy as np

    from rrcache.harness.cached import CachedRenderer
    from rrcache.harness.renderer import Renderer
    from rrcache.pipeline import load_for_session, variant_for
    from rrcache.session import load_session

    session = load_session(CORPUS / "implicit_lod.json")
    work = load_for_session(CORPUS / "implicit_lod.glsl", session)
    frames = range(min(2, session.frames))
    with Renderer(work.prepared, session, (64, 64)) as original:
        reference = [original.render_frame(i) for i in frames]
    restricted = [n for n in work.table.nodes if n.algorithms == ["three-pass", "two-pass"]]
    assert len(restricted) >= 5 and reference[0].covered_pixels > 200
    checked = 0
    for node in work.table.nodes:
        for algorithm in node.algorithms:
            variant = variant_for(work, node.id, algorithm)
            with CachedRenderer(variant, session, work.prepared, (64, 64), period=1) as cached:
                for ref in reference:
                    got = cached.render_frame(ref.index)
                    err = float(np.abs(got.image - ref.image)[ref.mask].max())
                    assert err <= 1e-4, (node.id, node.text, algorithm, ref.index, err)
                    checked += 1
    assert checked >= 2 * (2 * len(restricted))


def test_bench_frontend_probes_generated_shaders_in_fresh_processes():
    from rrcache.bench.frontend import run_generated

    rows = run_generated([150], repeat=1)
    assert [r["shader"] for r in rows] == ["realistic-150", "sketch-150"]
    for r in rows:
        assert 50 < r["lines"] <= 150 and r["exprs"] > 500 and r["counts"]["listed"] > 0
        assert r["rss_peak_mb"] >= r["rss_before_mb"] > 0 and r["analyse_cpu_s"] > 0
