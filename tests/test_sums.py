"""Sums in any order and their static parts (rrcache.analysis.sums), on shaders of tests/corpus.

- ``weighted_kernel.glsl``: a 3×3 kernel weighted by a const table: the terms are ordered by
  their folded weight, the centre last, so "all but the centre" is a node;
- ``many_lights_loop.glsl``: eight lights in a loop, the third following the session's moving
  light: the static lights first, their sum a node (the static part);
- ``moving_occluders.glsl``: seven occluding spheres, the fourth moved by a keyframed uniform:
  the static spheres' occlusion is a node.

Reordering changes only the rounding: for ``n`` terms two float32 orders differ by at most
``2 (n − 1) u Σ|t_k|`` (:func:`rrcache.analysis.sums.reassociation_bound`). Every variant of a
reordered partial sum is rendered at Δn = 1 (every pixel recomputed every frame) in the three
algorithms and compared with the original within that bound carried through the rest of each
shader (its gain after the sum: see ``BOUNDS``), plus the few units in the last place by which
two separately compiled programs differ after the sum (``COMPILED``).
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from rrcache.analysis.sums import reassociation_bound, sum_chains
from rrcache.compiler import ALGORITHMS
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.renderer import Renderer
from rrcache.pipeline import load_for_session, variant_for
from rrcache.session import load_session

CORPUS = Path(__file__).parent / "corpus"
SIZE = (64, 64)

#: per shader: (terms n, an upper bound of Σ|t_k| over a pixel, the largest factor by which an
#: error of the sum can reach the colour). weighted_kernel: 9 taps in [0, 1] weighted by 16 in
#: all, the colour is sum / 16 × shade (≤ 1); many_lights_loop: 8 lights each ≤ 1.3 (diffuse +
#: 0.3 specular, colours ≤ 1, attenuation ≤ 1), the colour lit / (1 + lit) (slope ≤ 1);
#: moving_occluders: 7 terms each ≤ 1 (r² / l², the receiver outside every sphere), the colour
#: 0.8 × (1 − clamp(occlusion)) × (≤ 1)
BOUNDS = {"weighted_kernel": (9, 16.0, 1.0 / 16.0), "many_lights_loop": (8, 8 * 1.3, 1.0),
          "moving_occluders": (7, 7.0, 0.8)}


def _load(name, session=None):
    session = session or load_session(CORPUS / f"{name}.json")
    return session, load_for_session(CORPUS / f"{name}.glsl", session)


def _partial_sums(work):
    """The listed nodes that are partial sums of a reordered run, in program order."""
    return [n for n in work.table.nodes if re.match(r"^\w+: (\d+ of \d+|all \d+) terms", n.text)]


#: what separately compiled programs may differ by after the sum, whatever its order (a few
#: roundings of colours ≤ 1 evaluated with other instruction choices, fused multiply-adds):
#: 16 units in the last place of 1.0
COMPILED = 16 * 2.0 ** -23


def _colour_bound(name) -> float:
    n, magnitude, gain = BOUNDS[name]
    # the sum's bound for terms summing to ``magnitude`` in magnitude, through the shader's gain
    return reassociation_bound([magnitude / n] * n) * gain + COMPILED


def test_a_weighted_kernel_is_ordered_by_its_folded_weights():
    _session, work = _load("weighted_kernel")
    chain, = sum_chains(work.table.shader.unit, ())
    assert chain.key == ("weight",)
    weights = [t.weight for t in chain.terms]
    assert weights == sorted(weights) and weights[-1] == 4.0 and weights[0] == 1.0
    assert chain.terms[-1].label == "(y=1, x=1)"        # the centre, heaviest, last
    texts = [n.text for n in _partial_sums(work)]
    assert "sum: 8 of 9 terms, all but (y=1, x=1)" in texts
    assert "sum: 1 of 9 terms, (y=0, x=0)" in texts and "sum: all 9 terms" in texts


def test_the_terms_that_read_a_moving_input_go_last():
    _session, work = _load("moving_occluders")
    chain, = sum_chains(work.table.shader.unit, ("u_moverOffset",))
    assert chain.key == ("static",)
    assert [t.label for t in chain.terms][-1] == "(i=3)" and chain.static_count() == 6
    assert chain.terms[-1].moving_reads == {"u_moverOffset"}
    static = [n for n in work.table.nodes if "the static part" in n.text]
    assert [n.text for n in static] == ["occlusion: 6 of 7 terms, all but (i=3), the static part (without u_moverOffset)"]

    _session, lights = _load("many_lights_loop")
    chain, = sum_chains(lights.table.shader.unit, sorted(_moving(lights)))
    assert [t.label for t in chain.terms][-1] == "(i=2)" and chain.static_count() == 7
    assert chain.terms[-1].moving_reads == {"u_light"}   # the session's light colour does not change


def _moving(work):
    from rrcache.session.changes import per_frame_uniforms

    return per_frame_uniforms(load_session(CORPUS / "many_lights_loop.json"))


def test_without_a_session_nothing_moves_and_source_order_stays():
    from rrcache.glsl.frontend import load_shader
    from rrcache.analysis import cacheable_nodes

    table = cacheable_nodes(load_shader(CORPUS / "moving_occluders.glsl"))
    chain, = sum_chains(table.shader.unit, ())
    assert chain.key == ("source",) and [t.source for t in chain.terms] == list(range(7))
    assert not any(" terms" in n.text for n in table.nodes)


@pytest.mark.parametrize("name", sorted(BOUNDS))
def test_reordered_partial_sums_reproduce_the_original_at_period_one(gl_ctx, name):
    """Every algorithm, the first partial sum, the one before the heaviest or moving term, and
    the whole sum: Δn = 1 equals the original within the reassociation bound."""
    session, work = _load(name)
    sums = _partial_sums(work)
    assert len(sums) == BOUNDS[name][0]
    picked = [sums[0], sums[-2], sums[-1]]
    bound = _colour_bound(name)
    frames = range(2)
    with Renderer(work.prepared, session, SIZE) as original:
        reference = [original.render_frame(i) for i in frames]
    worst = 0.0
    for node in picked:
        for algorithm in ALGORITHMS:
            variant = variant_for(work, node.id, algorithm)
            with CachedRenderer(variant, session, work.prepared, SIZE, period=1) as cached:
                for ref in reference:
                    got = cached.render_frame(ref.index)
                    err = float(np.abs(got.image - ref.image)[ref.mask].max())
                    worst = max(worst, err)
                    assert err <= bound, (name, node.id, node.text, algorithm, ref.index, err, bound)
    assert bound < 1e-4   # tighter than the corpus test's tolerance for a variant of any node


def test_the_static_part_cached_for_ever_stays_exact_while_the_whole_sum_goes_stale(gl_ctx, tmp_path):
    """A still camera and the moving sphere: the static part's cache never needs a refresh (it
    reprojects to itself and does not change), the whole occlusion's does."""
    doc = json.loads((CORPUS / "moving_occluders.json").read_text())
    doc["camera"] = {"fov": 45, "near": 0.1, "far": 50,
                     "keyframes": [{"frame": 0, "eye": [0.4, 1.0, 3.2], "target": [0, 0, 0], "up": [0, 1, 0]}]}
    doc["objects"][0]["keyframes"] = [{"frame": 0, "translate": [0, 0, 0], "rotate": [30, 1, 0, 0], "scale": 1}]
    path = tmp_path / "still.json"
    path.write_text(json.dumps(doc))
    session, work = _load("moving_occluders", load_session(path))
    static, = [n for n in work.table.nodes if "the static part" in n.text]
    whole, = [n for n in work.table.nodes if n.text.startswith("occlusion: all 7 terms")]
    never = 2 ** 30
    with Renderer(work.prepared, session, SIZE) as original:
        reference = [original.render_frame(i) for i in range(4)]
    errors = {}
    for node in (static, whole):
        with CachedRenderer(variant_for(work, node.id), session, work.prepared, SIZE, period=never) as cached:
            errors[node.id] = [float(np.abs(cached.render_frame(r.index).image - r.image)[r.mask].max())
                               for r in reference]
    assert max(errors[static.id]) <= _colour_bound("moving_occluders")
    assert max(errors[whole.id][1:]) > 1e-3


def test_a_sum_without_weights_is_ordered_by_measured_scores(gl_ctx):
    """The short training pass (rrcache.profiler.terms): each of the eight lights cached alone
    beside the original; the static lights then go by their measured error, the moving one last."""
    from rrcache.profiler.terms import measure_terms
    from rrcache.session.changes import per_frame_uniforms

    session, work = _load("many_lights_loop")
    moving = sorted(per_frame_uniforms(session))
    scores = measure_terms(work, session, frames=range(3), resolution=(48, 48), moving=moving)
    (key, measured), = scores.items()
    assert len(measured) == 8 and all(v >= 0 for v in measured.values()) and len(set(measured.values())) > 4
    reordered = load_for_session(CORPUS / "many_lights_loop.glsl", session, term_scores=scores)
    chain, = sum_chains(reordered.table.shader.unit, moving, scores)
    assert chain.key == ("static", "measured")
    static = [measured[t.label] for t in chain.terms[:7]]
    assert static == sorted(static) and chain.terms[-1].label == "(i=2)"
    texts = [n.text for n in _partial_sums(reordered)]
    assert any("the 4 that measured the least" in t for t in texts)
    assert any(t.endswith("the static part (without u_light)") for t in texts)


def test_a_profile_measures_the_order_when_asked_and_keeps_it(tmp_path):
    """``TrainingSettings(measure_terms=True)``: the scores are measured before training, kept in
    the store (a resumed profile reuses them) and in profile.json, and the profile's node ids are
    those of the ordered program: loading the shader with its scores finds the same texts."""
    from rrcache.profiler import profile
    from rrcache.profiles import TrainingSettings, load_profile
    from rrcache.choice import load_work

    settings = TrainingSettings(periods=(2,), timing_periods=(2,), timing_frames=2, frames=3,
                                resolution=(32, 32), validate=False, budget_s=1e-6, min_gain=0, max_sets=0,
                                filter="bilinear", measure_terms=True)
    prof = profile(CORPUS / "many_lights_loop.glsl", CORPUS / "many_lights_loop.json", tmp_path / "out",
                   settings, plots=False)
    (key, scores), = prof.term_scores.items()
    assert len(scores) == 8
    reread = load_profile(tmp_path / "out")
    assert reread.term_scores == prof.term_scores
    work, _session = load_work(reread)
    texts = {n.id: n.text for n in work.table.nodes}
    assert all(texts.get(n.id) == n.text for n in reread.nodes)
    assert any("measured the least" in t for t in texts.values())
    again = profile(CORPUS / "many_lights_loop.glsl", CORPUS / "many_lights_loop.json", tmp_path / "out",
                    settings, plots=False)
    assert again.term_scores == prof.term_scores


def test_a_static_part_written_in_one_expression_is_named():
    """The chess shader keeps the king's occlusion apart (``aoStatic * aoKing``): the static
    part's node is named as such (rrcache.analysis.static_parts), without a session it is not."""
    from rrcache.glsl.frontend import load_shader
    from rrcache.analysis import cacheable_nodes

    root = Path(__file__).resolve().parents[1]
    session = load_session(root / "sessions" / "chess.json")
    work = load_for_session(root / "shaders" / "ambient_occlusion.glsl", session)
    named = [n.text for n in work.table.nodes if "the static part" in n.text]
    assert named == ["1.0 - clamp(OCCLUSION_GAIN * staticOcclusion(receiver, N), 0.0, 1.0), "
                     "the static part of aoStatic * aoKing (without u_kingOffset)"]
    bare = cacheable_nodes(load_shader(root / "shaders" / "ambient_occlusion.glsl"))
    assert not any("static part" in n.text for n in bare.nodes)


def test_the_static_part_is_trained_second():
    """Rule 3 of rrcache.profiler.order: chess's static part (the paper's ε1) reads no per-frame
    uniform, so it is trained right after the costliest node (round-robin had it fifth, past a
    budget under load); the rest keep their order."""
    from rrcache.profiler.order import diversity_order
    from rrcache.profiler.train import training_order
    from rrcache.profiles import TrainingSettings

    root = Path(__file__).resolve().parents[1]
    session = load_session(root / "sessions" / "chess.json")
    work = load_for_session(root / "shaders" / "ambient_occlusion.glsl", session)
    order = training_order(work, session, TrainingSettings().resolved(session))
    assert "the static part" in order.nodes[1].text, [n.text for n in order.nodes[:3]]
    assert "u_kingOffset" not in order.signatures[order.nodes[1].id]
    plain = diversity_order(order.nodes, order.signatures)
    assert plain.index(order.nodes[1]) > 1
    assert [n.id for n in order.nodes if n is not order.nodes[1]] == [n.id for n in plain if n is not order.nodes[1]]
