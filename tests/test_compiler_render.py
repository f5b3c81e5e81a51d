"""Rendering tests of compiled variants through CacheRuntime on a tiny orbiting-icosphere scene:
at Δn = 1 every variant reproduces the original image; the three algorithms agree; discards
before and after the node are kept; the driver's refusal names node and pass."""
from __future__ import annotations

import random

import numpy as np
import pytest

from compiler_scene import Scene, original_program, render_original, render_variant
from rrcache.analysis import cacheable_nodes
from rrcache.compiler import PassSource, Variant, instance
from rrcache.errors import GLError
from rrcache.glsl.frontend import load_shader, parse_shader

NOISE = """#version 330
in vec3 v_objectPosition;
in vec3 v_normal;
in vec4 v_position;
uniform vec3 u_light;
uniform vec3 u_camera;
out vec4 fragColor;

vec3 hash33(vec3 p) {
    p = fract(p * vec3(0.1031, 0.1030, 0.0973));
    p += dot(p, p.yxz + 33.33);
    return fract((p.xxy + p.yxx) * p.zyx);
}

float valueNoise(vec3 p) {
    vec3 c = floor(p);
    vec3 f = fract(p);
    vec3 w = f * f * (3.0 - 2.0 * f);
    float a = mix(hash33(c).x, hash33(c + vec3(1.0, 0.0, 0.0)).x, w.x);
    float b = mix(hash33(c + vec3(0.0, 1.0, 0.0)).x, hash33(c + vec3(1.0, 1.0, 0.0)).x, w.x);
    return mix(a, b, w.y);
}

void main() {
    vec3 p = v_objectPosition * 3.0;
    float t = valueNoise(p) + 0.5 * valueNoise(p * 2.0);
    vec3 albedo = mix(vec3(0.8, 0.5, 0.3), vec3(0.2, 0.3, 0.7), t / 1.5);
    vec3 N = normalize(v_normal);
    vec3 L = normalize(u_light - v_position.xyz);
    float diffuse = max(dot(N, L), 0.0);
    fragColor = vec4(albedo * (0.2 + 0.8 * diffuse), 1.0);
}
"""
UNIFORMS = {"u_light": (3.0, 3.0, 3.0), "u_camera": (0.0, 0.6, 2.7)}
ALGORITHMS = ("three-pass", "two-pass", "one-pass")


@pytest.fixture(scope="module")
def noise(gl_ctx):
    table = cacheable_nodes(parse_shader(NOISE, "noise.frag"))
    scene = Scene(gl_ctx, (48, 48), UNIFORMS)
    prog = original_program(gl_ctx, table.shader)
    ref = render_original(scene, prog, 3)
    scene.forget(prog)
    prog.release()
    yield table, scene, ref
    scene.release()


def _pick(table, texts):
    # excluded ("cheap") nodes are fine too: the compiler takes any float/vector node
    by_text = {n.text: n for n in list(table.excluded) + list(table.nodes)}
    missing = [t for t in texts if t not in by_text]
    assert not missing, (missing, sorted(by_text))
    return [by_text[t] for t in texts]


NOISE_NODES = ["albedo * (0.2 + 0.8 * diffuse)", "mix(vec3(0.8, 0.5, 0.3), vec3(0.2, 0.3, 0.7), t / 1.5)",
               "max(dot(N, L), 0.0)"]


def test_reference_covers_the_sphere(noise):
    _, _, ref = noise
    covered = (ref[0][..., 3] > 0).sum()
    assert 300 < covered < 48 * 48 and ref[0][..., :3].max() > 0.1


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_period_one_reproduces_the_original(noise, algorithm):
    table, scene, ref = noise
    nodes = _pick(table, NOISE_NODES) + [max(table.nodes, key=lambda n: n.cost)]
    nodes += [n for n in table.nodes if "hash33" in n.text or "_rr_" in n.text][:2]
    for node in nodes:
        variant = instance(table, node.id, algorithm)
        images, _ = render_variant(scene, variant, 3, period=1)
        for frame, (img, want) in enumerate(zip(images, ref)):
            err = np.abs(img - want).max()
            assert err <= 1e-5, (node.id, node.text, algorithm, frame, err)


def test_half_float_payload(noise):
    table, scene, ref = noise
    node = _pick(table, [NOISE_NODES[1]])[0]
    for algorithm in ALGORITHMS:
        variant = instance(table, node.id, algorithm, payload_dtype="f2")
        images, _ = render_variant(scene, variant, 2, period=1)
        assert max(np.abs(a - b).max() for a, b in zip(images, ref)) <= 2e-3


def test_algorithms_agree_when_reusing(noise):
    table, scene, ref = noise
    for node in _pick(table, NOISE_NODES[:2]):
        results = {}
        for algorithm in ALGORITHMS:
            variant = instance(table, node.id, algorithm, filter="nearest")
            results[algorithm], stats = render_variant(scene, variant, 4, period=3)
            if algorithm == "three-pass":
                assert stats[0].hits == 0 and any(s.hits > 50 for s in stats[1:])
        for algorithm in ALGORITHMS[1:]:
            for a, b in zip(results["three-pass"], results[algorithm]):
                assert np.abs(a - b).max() <= 1e-5, (node.text, algorithm)


DISCARD = NOISE.replace(
    "    float t = valueNoise(p) + 0.5 * valueNoise(p * 2.0);\n",
    "    if (v_objectPosition.x > 0.55) discard;\n"
    "    float t = valueNoise(p) + 0.5 * valueNoise(p * 2.0);\n"
    "    if (t > 1.0) discard;\n"
    "    if (v_objectPosition.y < -0.6) { fragColor = vec4(0.0, 1.0, 0.0, 1.0); return; }\n")


def test_discard_before_and_after_the_node(gl_ctx):
    table = cacheable_nodes(parse_shader(DISCARD, "discard.frag"))
    scene = Scene(gl_ctx, (48, 48), UNIFORMS)
    try:
        prog = original_program(gl_ctx, table.shader)
        ref = render_original(scene, prog, 3)
        scene.forget(prog)
        prog.release()
        holes = ((ref[0][..., 3] == 0)).sum()
        assert holes > 48 * 48 // 2
        t_node = [n for n in table.nodes if n.text.startswith("valueNoise(") and "0.5 *" in n.text]
        assert t_node, [n.text for n in table.nodes]
        for algorithm in ALGORITHMS:
            variant = instance(table, t_node[0].id, algorithm)
            assert "discard" in variant.passes[variant.pass_names[0]].fragment
            # pass 2 discards where the value says so; the final pass's == depth test then
            # shades the surface behind, not this fragment from an empty payload
            images, _ = render_variant(scene, variant, 3, period=1)
            for img, want in zip(images, ref):
                assert np.abs(img - want).max() <= 1e-5, algorithm
    finally:
        scene.release()


def test_driver_refusal_names_node_and_pass(gl_ctx):
    table = cacheable_nodes(parse_shader(NOISE, "noise.frag"))
    variant = instance(table, _pick(table, NOISE_NODES[2:])[0].id, "three-pass")
    broken = variant.passes["shade"]
    variant.passes["shade"] = PassSource(broken.vertex, broken.fragment.replace(
        "fragColor = ", "fragColor = undefinedThing + "), broken.fragment_line_map)
    with pytest.raises(GLError) as err:
        variant.build_programs(gl_ctx)
    text = str(err.value)
    assert "shade pass" in text and variant.node_id in text and "max(dot(N, L), 0.0)" in text
    assert "noise.frag:" in text  # mapped back to the original file


MARBLE_UNIFORMS = {"u_camera": (0.0, 0.6, 2.7), "u_light": (3.0, 3.0, 3.0),
                   "u_lightColor": (1.0, 1.0, 1.0), "u_veinColor": (0.2, 0.2, 0.3),
                   "u_baseColor": (0.9, 0.9, 0.85), "u_noiseScale": 2.0, "u_shininess": 16.0}


def _marble_sweep(gl_ctx, nodes_of, frames=2):
    table = cacheable_nodes(load_shader("shaders/marble.glsl"))
    scene = Scene(gl_ctx, (32, 32), MARBLE_UNIFORMS)
    try:
        prog = original_program(gl_ctx, table.shader)
        ref = render_original(scene, prog, frames)
        scene.forget(prog)
        prog.release()
        assert (ref[0][..., 3] > 0).sum() > 100
        nodes = nodes_of(table)
        for node in nodes:
            variant = instance(table, node.id, "three-pass")
            images, _ = render_variant(scene, variant, frames, period=1)
            err = max(np.abs(a - b).max() for a, b in zip(images, ref))
            assert err <= 1e-5, (node.id, node.text, err)
        return len(nodes)
    finally:
        scene.release()


def test_marble_sample_of_nodes(gl_ctx):
    def sample(table):
        costly = sorted(table.nodes, key=lambda n: -n.cost)[:4]
        rest = [n for n in table.nodes if n not in costly]
        return costly + random.Random(7).sample(rest, 18)
    assert _marble_sweep(gl_ctx, sample) >= 20


@pytest.mark.slow
def test_marble_every_node(gl_ctx):
    assert _marble_sweep(gl_ctx, lambda table: list(table.nodes)) > 100
