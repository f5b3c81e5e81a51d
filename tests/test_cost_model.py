"""Static costs that follow what a fetch costs on llvmpipe (issue 30): texture fetches by kind,
early-exit loops below their full trip count, and the training order they give an IBL shader."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from rrcache.analysis import cacheable_nodes
from rrcache.analysis.cost import CACHE_LOOKUP_COST, EARLY_EXIT, TEXTURE_COSTS, subtree_cost
from rrcache.glsl import ast as A
from rrcache.glsl.frontend import parse_shader
from rrcache.pipeline import load_for_session
from rrcache.profiler.train import training_order
from rrcache.profiles import TrainingSettings
from rrcache.session import load_session

ROOT = Path(__file__).resolve().parents[1]


def _fetch_costs(src: str) -> dict:
    """The cost of the fetches of each built-in, summed over its calls."""
    out: dict = {}
    for c in A.walk(parse_shader(src, "fetch.frag").unit):
        if isinstance(c, A.Call) and c.name.startswith(("texture", "texelFetch")):
            out[c.name] = out.get(c.name, 0) + subtree_cost(c)
    return out


def test_each_kind_of_fetch_costs_what_the_table_says():
    costs = _fetch_costs("""#version 400
uniform sampler2D t; uniform samplerCube c; in vec2 uv; in vec3 d; out vec4 o;
void main() { o = texture(t, uv) + textureLod(t, uv, 1.0) + textureGather(t, uv)
                + texelFetch(t, ivec2(3, 4), 0) + texture(c, d) + textureLod(c, d, 2.0)
                + vec4(textureSize(t, 0), 0.0, 0.0); }""")
    assert costs["texture"] == TEXTURE_COSTS[("2d", "implicit")] + TEXTURE_COSTS[("cube", "implicit")]
    assert costs["textureLod"] == TEXTURE_COSTS[("2d", "lod")] + TEXTURE_COSTS[("cube", "lod")]
    assert costs["textureGather"] == TEXTURE_COSTS[("2d", "gather")]
    assert costs["texelFetch"] == TEXTURE_COSTS[("2d", "fetch")]
    assert costs["textureSize"] == 1
    # legacy names price the same
    legacy = _fetch_costs("uniform samplerCube c; varying vec3 d;\n"
                          "void main() { gl_FragColor = textureCube(c, d) + textureCubeLod(c, d, 1.0); }")
    assert legacy == {"textureCube": TEXTURE_COSTS[("cube", "implicit")],
                      "textureCubeLod": TEXTURE_COSTS[("cube", "lod")]}
    assert TEXTURE_COSTS[("2d", "flat")] < CACHE_LOOKUP_COST < 2 * TEXTURE_COSTS[("2d", "implicit")]


MARCH = """#version 330
in vec3 v_objectPosition;
out vec4 fragColor;
void main() {{
    float t = 0.0;
    for (int i = 0; i < 64; i++) {{
        vec3 p = v_objectPosition + vec3(0.0, 0.0, t);
        float d = length(p) - 0.5 + 0.1 * sin(p.x * 9.0) * sin(p.y * 7.0) * sin(p.z * 5.0);
        {exit}
        t += d * 0.5;
    }}
    fragColor = vec4(vec3(t * 0.1), 1.0);
}}
"""


def test_a_loop_that_exits_early_is_not_costed_at_its_full_trip_count():
    def final_cost(src):
        table = cacheable_nodes(parse_shader(src, "march.frag"), cheap_below=0)
        return next(n.cost for n in table.nodes if n.final)

    full = final_cost(MARCH.format(exit=""))
    early = final_cost(MARCH.format(exit="if (d < 0.001) break;"))
    # without the break the loop unrolls (64 copies, all counted); with it, it stays rolled and
    # its body counts EARLY_EXIT of the 64 trips
    assert early < full
    per_step = (full - 3) / 64
    assert abs(early - round(64 * EARLY_EXIT) * per_step) <= 0.1 * early


def test_an_ibl_shader_trains_the_final_colour_and_the_fetches_first_not_the_tone_map_chain():
    """glTF-style image-based lighting: two cube-map fetches and two 2D fetches, then a long
    chain of cheap tone-mapping steps. With fetches priced at a few units, the tone-map links
    came first and the final colour 57th; priced as measured, the final colour comes first and
    the environment fetches right after."""
    session = load_session(ROOT / "sessions" / "ibl.json")
    work = load_for_session(ROOT / "shaders" / "ibl_gltf.glsl", session)
    order = training_order(work, session, TrainingSettings())
    first = [n.text for n in order.nodes[:6]]
    assert order.nodes[0].final
    assert any("u_LambertianEnvSampler" in t for t in first[:3])
    tone_map_steps = ("0.0245786", "0.983729", "a / b", "ACESInput", "ACESOutput", "pow(color")
    assert not [t for t in first if any(k in t for k in tone_map_steps)], first


def test_the_calibration_tool_measures_every_kind(tmp_path):
    out = tmp_path / "costs.json"
    p = subprocess.run([sys.executable, str(ROOT / "tools" / "calibrate_costs.py"), "--repeats", "1",
                        "--size", "32", "--short", "2", "--long", "4", "--json", str(out)],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    table = json.loads(out.read_text())
    assert set(table["costs"]) >= {"texture 2D", "texture cube", "textureGather 2D", "texelFetch 2D",
                                   "texture 2D, explicit LOD", "texture cube, explicit LOD"}
    assert set(table["early_exit"]) == {"spread (a gradient)", "hashed per pixel"}
    assert "units" in p.stdout
