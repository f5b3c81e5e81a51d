"""The equal-time alternatives (main paper §5.4) on a tiny scene (an icosphere, 64×48, the
noise-like shader of test_profile):

- the searches, with injected timing functions (timings themselves are never asserted);
- dynamic resolution renders images of the target size, and at scale 1 the original's image;
- simplification: the shader with no node replaced compiles and renders the original's image;
  a node replaced by its mean changes the image measurably and lowers the static cost; the
  greedy sequence respects its cost floor; bad inputs raise RRCacheError.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from rrcache.alternatives import dynres, simplify
from rrcache.alternatives.measure import compare_renderers
from rrcache.alternatives.search import first_reaching, match_scale
from rrcache.errors import RRCacheError
from rrcache.harness.metrics import mean_l2
from rrcache.harness.renderer import Renderer
from rrcache.pipeline import load_for_session
from rrcache.session import load_session

from scene_files import write_scene


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    shader, session_path = write_scene(tmp_path_factory.mktemp("alternatives"))
    session = load_session(session_path)
    return load_for_session(shader, session), session


# ---------------------------------------------------------------- searches (injected timings)
def test_match_scale_converges_within_tolerance():
    calls = []

    def model(s):  # a fixed cost plus shading proportional to the pixels
        return 1.0 / (0.15 + 0.85 * s * s)

    def speedup(s):
        calls.append(s)
        return model(s)

    for target in (1.3, 2.0, 3.5):
        calls.clear()
        r = match_scale(speedup, target, lo=0.1, rel_tol=0.02, max_steps=12)
        assert r.matched and abs(r.speedup / target - 1) <= 0.02
        assert r.steps == [(s, model(s)) for s in calls]
        assert 0.1 <= r.value <= 1.0


def test_match_scale_unreachable_target_reports_closest():
    r = match_scale(lambda s: 1.0 / (0.5 + 0.5 * s * s), 5.0, lo=0.1, rel_tol=0.02, max_steps=6)
    assert not r.matched and len(r.steps) == 6
    assert r.speedup == max(sp for _, sp in r.steps)  # the smallest scale tried comes closest
    with pytest.raises(RRCacheError, match="not a speed-up"):
        match_scale(lambda s: 1.0, float("nan"))
    with pytest.raises(RRCacheError):
        match_scale(lambda s: 1.0, 2.0, lo=0.5, hi=0.2)


def test_first_reaching_finds_smallest_k_in_log_steps():
    values = [1.0, 1.1, 1.3, 1.6, 2.2, 2.9, 3.1, 4.0, 6.0, 9.0, 12.0, 20.0]
    r = first_reaching(lambda k: values[k - 1], 3.0, len(values), rel_tol=0.0)
    assert r.matched and r.value == 7 and r.speedup == 3.1
    assert len(r.steps) <= math.ceil(math.log2(len(values))) + 1
    r = first_reaching(lambda k: values[k - 1], 3.0, len(values), rel_tol=0.05)
    assert r.value == 6  # 2.9 is within 5 % of 3.0
    r = first_reaching(lambda k: values[k - 1], 50.0, len(values))
    assert not r.matched and r.value == len(values)
    with pytest.raises(RRCacheError, match="no candidate"):
        first_reaching(lambda k: 1.0, 2.0, 0)


# ---------------------------------------------------------------- dynamic resolution
def test_dynres_images_have_the_target_size(scene):
    work, session = scene
    with dynres.DynresRenderer(work.prepared, session, (64, 48), 0.5) as r:
        assert r.low_size == (32, 24)
        frame = r.render_frame(3)
    assert frame.image.shape == (48, 64, 4) and frame.mask.shape == (48, 64)
    assert frame.ms > 0 and 0 < frame.covered_pixels < 64 * 48
    with pytest.raises(RRCacheError, match="resolution scale"):
        dynres.low_size((64, 48), 0.0)


def test_dynres_at_scale_one_is_the_original_and_lower_scales_blur(scene):
    work, session = scene
    with Renderer(work.prepared, session) as original:
        with dynres.DynresRenderer(work.prepared, session, None, 1.0) as same:
            c = compare_renderers(original, same, [2, 3])
        with dynres.DynresRenderer(work.prepared, session, None, 0.25) as small:
            low = compare_renderers(original, small, [2, 3])
    assert c.mean_error < 1e-5 and c.psnr >= 90
    assert low.mean_error > 1e-3 and low.psnr < c.psnr
    assert len(low.frames) == 2 and low.ms_per_frame > 0


# ---------------------------------------------------------------- simplification
def test_no_replacement_renders_the_original(scene):
    work, session = scene
    plain = simplify.simplified_shader(work, {})
    assert plain.replaced == [] and plain.cost > 0
    final = next(n for n in work.table.nodes if n.final)
    assert plain.cost == final.cost  # every contributing expression once: the final colour's cost
    with Renderer(work.prepared, session) as a, Renderer(plain.prepared, session) as b:
        for index in (0, 5):
            x, y = a.render_frame(index), b.render_frame(index)
            assert np.array_equal(x.mask, y.mask)
            assert np.abs(x.image - y.image).max() < 1e-5


def test_node_replaced_by_its_mean_changes_the_image(scene):
    work, session = scene
    node = max((n for n in work.table.nodes if not n.final and n.type == "float"), key=lambda n: n.cost)
    means = simplify.node_means(work, session, [node.id], [0, 6], (32, 24))
    (value,) = means[node.id]
    assert math.isfinite(value)
    simple = simplify.simplified_shader(work, {node.id: (value,)})
    assert simple.replaced == [node.id]
    from rrcache.glsl.printer import print_expr

    assert "float(" not in work.prepared.source
    assert print_expr(simplify.constant("float", (value,))) in simple.prepared.source
    assert simple.cost < simplify.simplified_shader(work, {}).cost
    with Renderer(work.prepared, session) as a, Renderer(simple.prepared, session) as b:
        ref, got = a.render_frame(4), b.render_frame(4)
    err, _ = mean_l2(got.image, ref.image, ref.mask)
    assert err > 1e-3


def test_mean_is_the_mean_of_the_node_over_covered_pixels(scene):
    work, session = scene
    # the final colour's alpha is 1.0 everywhere: its mean must be exactly that
    final = next(n for n in work.table.nodes if n.final)
    (r, g, b, a) = simplify.node_means(work, session, [final.id], [1], (32, 24))[final.id]
    assert a == pytest.approx(1.0, abs=1e-6)
    assert 0 < r < 1 and 0 < g < 1 and 0 < b < 1


WIDTH = {"float": 1, "vec2": 2, "vec3": 3, "vec4": 4}


def test_a_node_inside_a_replaced_node_is_subsumed(scene):
    from rrcache.glsl.ast import walk

    work, _ = scene
    nodes = [n for n in work.table.nodes if not n.final]
    pairs = [(o, i) for o in nodes for i in nodes
             if i is not o and any(x is i.node for x in walk(o.node))]
    assert pairs, "the noise sum holds its octaves"
    outer, inner = pairs[0]
    both = simplify.simplified_shader(work, {outer.id: (0.5,) * WIDTH[outer.type],
                                             inner.id: (0.1,) * WIDTH[inner.type]})
    alone = simplify.simplified_shader(work, {outer.id: (0.5,) * WIDTH[outer.type]})
    assert both.replaced == [outer.id] and both.subsumed == [inner.id]
    assert both.prepared.source == alone.prepared.source


def test_greedy_sequence_respects_its_cost_floor(scene):
    work, _ = scene
    nodes = sorted((n for n in work.table.nodes if not n.final), key=lambda n: -n.cost)
    base = simplify.simplified_shader(work, {}).cost
    ranking = [simplify.Candidate(n.id, n.text, (0.3,) * WIDTH[n.type], 0.01, n.cost) for n in nodes]
    floor = 0.6 * base
    seq = simplify.greedy_sequence(work, ranking, floor)
    assert seq, "some node alone keeps the cost above 60 %"
    assert len(seq) < len(ranking)  # the costliest (the whole noise) would go below the floor
    costs = [simplify.prefix_shader(work, seq, k).cost for k in range(1, len(seq) + 1)]
    assert all(c >= floor for c in costs)
    assert costs == sorted(costs, reverse=True) and len(set(costs)) == len(costs)


def test_constant_rejects_bad_values():
    with pytest.raises(Exception, match="cannot be replaced"):
        simplify.constant("mat3", (1.0,))
    with pytest.raises(RRCacheError, match="values for a vec3"):
        simplify.constant("vec3", (1.0, 2.0))
    assert simplify.constant("float", (float("nan"),)).args[0].value == 0.0


def test_means_of_nodes_one_pass_cannot_cache():
    """A value after an implicit-LOD lookup is not valid for one-pass; its mean comes from a
    multi-pass variant instead of an error (the temple's PCF shader stopped the bench here)."""
    session = load_session("tests/corpus/implicit_lod.json")
    work = load_for_session("tests/corpus/implicit_lod.glsl", session)
    nodes = [n for n in work.table.nodes if "one-pass" not in n.algorithms][:2]
    assert nodes, "the corpus shader lists values after implicit-LOD lookups"
    means = simplify.node_means(work, session, [n.id for n in nodes], [0, 1], (32, 32))
    for node in nodes:
        values = means[node.id]
        assert len(values) >= 1 and all(math.isfinite(v) for v in values)
        assert any(v != 0.0 for v in values), (node.id, values)
