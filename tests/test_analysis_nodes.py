"""Cacheable-node enumeration: reasons, costs, ids, and the Marble shader."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from rrcache.analysis import CACHE_LOOKUP_COST, CHEAP_BELOW, REASONS, cacheable_nodes, find_node
from rrcache.analysis.cost import EARLY_EXIT
from rrcache.analysis.cost import subtree_cost
from rrcache.errors import RRCacheError
from rrcache.glsl.frontend import load_shader, parse_shader
from rrcache.glsl.printer import print_expr

MARBLE = Path(__file__).resolve().parents[1] / "shaders" / "marble.glsl"
HEAD = "#version 330\nin vec3 v_n;\nin vec2 v_uv;\nout vec4 fragColor;\nuniform float u_k;\n"


def table_of(body: str, **kw):
    return cacheable_nodes(parse_shader(HEAD + body, "t.frag"), **kw)


def reason_of(table, text: str) -> str:
    listed = [n for n in table.nodes if n.text == text]
    excluded = [x.reason for x in table.excluded if x.text == text]
    assert listed or excluded, f"no node {text!r}"
    return "listed" if listed else excluded[0]


def test_each_reason_on_a_small_shader():
    t = table_of("""void main() {
        int k = int(v_uv.x * 4.0);
        vec3 a = sin(v_n) * cos(v_n) + exp(v_n);
        vec3 b = sin(v_n) * cos(v_n) + exp(v_n);
        float w = sin(u_k) * 2.0;
        float d = fwidth(v_uv.x * 3.0) + pow(v_uv.y, 3.0);
        float s = 0.0;
        for (int i = 0; i < int(u_k); i++) s += exp(v_uv.x * float(i));
        if (v_uv.y > 0.5) s += log(v_uv.y + 2.0) * exp(v_uv.x);
        fragColor = vec4(a + b * w + vec3(d + s + float(k)), 1.0);
    }""")
    assert reason_of(t, "sin(v_n) * cos(v_n) + exp(v_n)") == "listed"      # the first copy
    dup = [x for x in t.excluded if x.text == "sin(v_n) * cos(v_n) + exp(v_n)"]
    assert [x.reason for x in dup] == ["duplicate"]
    assert reason_of(t, "int(v_uv.x * 4.0)") == "type"
    assert reason_of(t, "v_uv.y > 0.5") == "type"
    assert reason_of(t, "sin(u_k) * 2.0") == "uniform"
    # a value computed with fwidth() is not excluded: only one-pass cannot cache it
    assert reason_of(t, "fwidth(v_uv.x * 3.0) + pow(v_uv.y, 3.0)") == "cheap"
    assert reason_of(t, "v_uv.x * 3.0") == "derivative"                  # inside fwidth()
    assert reason_of(t, "exp(v_uv.x * float(i))") == "dynamic"           # run-time loop
    assert reason_of(t, "log(v_uv.y + 2.0) * exp(v_uv.x)") == "dynamic"  # per-pixel branch
    assert reason_of(t, "v_uv.x") == "cheap"
    assert reason_of(t, "a") == "duplicate"            # a read of a single definition
    # the colour reads d, computed with fwidth(): through a local variable, it needs
    # derivatives, so it is listed for three-pass and two-pass only, with the reason
    final = [n for n in t.nodes if n.final]
    assert [n.text for n in final] == ["vec4(a + b * w + vec3(d + s + float(k)), 1.0)"]
    assert final[0].algorithms == ["three-pass", "two-pass"]
    assert final[0].invalid["one-pass"].startswith("derivative")
    assert reason_of(t, "a + b * w") == "listed"
    assert [n.algorithms for n in t.nodes if n.text == "a + b * w"] == [
        ["three-pass", "two-pass", "one-pass"]]
    assert set(x.reason for x in t.excluded) <= set(REASONS)


def test_costs_count_through_local_variables():
    t = table_of("""void main() {
        vec3 a = sin(v_n);
        vec3 b = a * 2.0;
        fragColor = vec4(b, 1.0);
    }""", cheap_below=0)
    by_text = {n.text: n for n in t.nodes}
    assert by_text["sin(v_n)"].cost == 24              # 3 components × TRANSCENDENTAL 8
    assert by_text["a * 2.0"].cost == 24 + 3
    assert by_text["vec4(b, 1.0)"].cost == 27 and by_text["vec4(b, 1.0)"].final
    expr = find_node(t.shader, by_text["a * 2.0"].id)
    assert subtree_cost(expr) == 3


def test_cheap_threshold_is_the_listing_threshold():
    t = table_of("void main() { fragColor = vec4(v_n * 2.0 + sin(v_n) + exp(v_n), 1.0); }")
    cheap = {x.text: x.cost for x in t.excluded if x.reason == "cheap"}
    assert cheap and all(c < CHEAP_BELOW for c in cheap.values())
    assert all(n.cost >= CHEAP_BELOW for n in t.nodes)


def test_code_after_discard_and_early_return_is_not_dynamic():
    t = table_of("""float f(vec2 p) { if (p.x < 0.2) return 0.0; return exp(p.y) * sin(p.x); }
        void main() {
            if (v_uv.y < 0.1) discard;
            fragColor = vec4(f(v_uv) + exp(v_uv.x) * sin(v_uv.y), 0.0, 0.0, 1.0);
        }""", cheap_below=0)
    # the node table shows the expression as written in f(), not the inliner's names
    after_return = [n for n in t.nodes if re.fullmatch(r"exp\(p\.y\) \* sin.*", n.text)]
    assert len(after_return) == 1 and after_return[0].call_chain == ["f (9:30)"]
    assert reason_of(t, "exp(v_uv.x) * sin(v_uv.y)") == "listed"
    assert reason_of(t, "0.0") in ("dynamic", "uniform")   # the early return's value


def test_side_effects_are_not_values():
    t = table_of("""void main() { float x = v_uv.x; float y = exp(x++ + v_uv.y);
        fragColor = vec4(y, x, 0.0, 1.0); }""")
    assert reason_of(t, "exp(x++ + v_uv.y)") == "dynamic"


def test_ids_are_stable_and_resolve():
    src = HEAD + "void main() { fragColor = vec4(exp(v_n) * sin(v_n.x), 1.0); }"
    a = cacheable_nodes(parse_shader(src, "t.frag"))
    b = cacheable_nodes(parse_shader(src, "t.frag"))
    assert [(n.id, n.text) for n in a.nodes] == [(n.id, n.text) for n in b.nodes]
    for n in a.nodes + a.excluded:
        assert re.fullmatch(r"n\d+", n.id)
        assert print_expr(find_node(a.shader, n.id)) == n.text
    with pytest.raises(RRCacheError, match="no node 'n999'"):
        find_node(a, "n999")


@pytest.fixture(scope="module")
def marble():
    # (how long this takes is measured by `rrcache bench-frontend`, not asserted here)
    return cacheable_nodes(load_shader(MARBLE))


def test_marble_has_at_least_100_candidates(marble):
    table = marble
    candidates = len(table.nodes) + table.counts()["cheap"]
    assert candidates >= 100
    assert len(table.nodes) >= 20
    assert [n for n in table.nodes if n.final]


def test_marble_has_a_node_per_noise_octave(marble):
    table = marble
    octaves = {}
    for n in table.nodes:
        chain = n.call_chain
        it = [c for c in chain if c.startswith("for i=")]
        # the noise value: the last expression of noise() itself (its return), one per octave
        if chain and chain[-1].startswith("noise") and it and n.text.startswith("mix(") \
                and ".z)" in n.text:
            octaves.setdefault(it[0].split()[1], []).append(n)
    assert sorted(octaves) == [f"i={k}" for k in range(5)]
    assert all(len(v) == 1 for v in octaves.values())
    costs = [octaves[f"i={k}"][0].cost for k in range(5)]
    assert min(costs) > CACHE_LOOKUP_COST


def test_marble_nodes_inside_the_octave_loop_are_listed(marble):
    table = marble
    sums = [n for n in table.nodes if n.text.startswith("sum + amplitude * abs(noise(")]
    assert len(sums) == 5                     # the partial sums of the turbulence
    assert sorted(n.cost for n in sums) == [n.cost for n in sums]


MARCH = """#version 330
in vec3 v_position;
uniform vec3 u_light;
uniform int u_steps;
out vec4 color;
const int STEPS = %s;
float scene(vec3 p) { return length(p) - 1.0; }
void main() {
    float result = 1.0;
    float t = 0.02;
    for (int i = 0; i < %s; i++) {
        float h = scene(v_position + u_light * t);
        result = min(result, 8.0 * h / t);
        t += clamp(h, 0.02, 0.2);
        if (result < 0.001) break;
    }
    color = vec4(vec3(result), 1.0);
}
"""


def _march_cost(bound: str) -> int:
    table = cacheable_nodes(parse_shader(MARCH % ("64", bound), "march.frag"))
    return [n for n in table.nodes if n.final][0].cost


def test_a_rolled_loop_costs_its_trip_bound():
    # the loop has a break, so the unroller leaves it rolled; what it computes costs one
    # iteration per trip of its constant bound, not one in all, and as it may stop early, the
    # share EARLY_EXIT of those trips (1 of 1, 4 of 8, 35 of 64)
    one, eight, sixty_four = _march_cost("1"), _march_cost("8"), _march_cost("STEPS")
    assert one < eight < sixty_four
    extra = (round(64 * EARLY_EXIT) - 1) / (round(8 * EARLY_EXIT) - 1)
    assert 0.8 * extra < (sixty_four - one) / (eight - one) < 1.2 * extra
    # a bound read from a uniform is unknown: one iteration, as before
    assert _march_cost("u_steps") == one
