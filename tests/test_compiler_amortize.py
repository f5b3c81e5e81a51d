"""Amortized variants (rrcache.compiler.amortize) run by the harness and the runtime.

Δ-exactness: ``m = N, λ = 0`` reproduces the original for every estimator of the corpus under
every algorithm. Coverage: with ``λ = 0`` each hit evaluates a subset scaled by ``N/m``; on a
still camera the mean of the frames of one cycle is the original (every index used once per
cycle, stratified or not). Tiny renders (48x48, a few frames)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from estimator_corpus import ESTIMATORS, PRAGMA
from rrcache.analysis.estimators import find_estimators
from rrcache.compiler.amortize import instance_amortized, subset_indices
from rrcache.glsl.frontend import load_shader
from rrcache.harness.cached import CachedRenderer, compare
from rrcache.compiler.prepared import prepare_file
from rrcache.harness.renderer import Renderer
from rrcache.session import load_session

ALGORITHMS = ["three-pass", "two-pass", "one-pass"]


def _setup(tmp_path, source, moving=True, frames=4, name="shader"):
    shader = tmp_path / f"{name}.frag"
    shader.write_text(source)
    keys = [{"frame": 0, "eye": [0, 0.4, 3.0], "target": [0, 0, 0], "up": [0, 1, 0]}]
    if moving:
        keys.append({"frame": frames - 1, "eye": [0.5, 0.5, 2.9], "target": [0, 0, 0], "up": [0, 1, 0]})
    doc = {"rrcache_session": 1, "resolution": [48, 48], "frames": frames,
           "camera": {"fov": 45, "near": 0.5, "far": 10, "keyframes": keys},
           "objects": [{"procedural": {"type": "torus", "major_radius": 0.9, "minor_radius": 0.4,
                                       "major_segments": 24, "minor_segments": 12}}]}
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(doc))
    session = load_session(path)
    loaded = load_shader(str(shader))
    return loaded, prepare_file(str(shader), session), session


CASES = [(name, algorithm) for name in sorted(ESTIMATORS) for algorithm in ALGORITHMS]


@pytest.mark.parametrize("name,algorithm", CASES)
def test_all_samples_and_no_blend_reproduce_the_original(gl_ctx, tmp_path, name, algorithm):
    loaded, prepared, session = _setup(tmp_path, ESTIMATORS[name][0])
    for est in find_estimators(loaded).estimators:
        variant = instance_amortized(loaded, est.id, algorithm, samples=est.samples, blend=0.0)
        result = compare(variant, session, prepared, range(4), period=1000)
        if algorithm != "one-pass":  # one-pass has no pass boundary to count at (see the subset test)
            assert result.hits > 200  # the cached path ran
        assert all(f.mean_error <= 1e-6 for f in result.frames), [f.mean_error for f in result.frames]


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_pragma_loop_reproduces_the_original(gl_ctx, tmp_path, algorithm):
    loaded, prepared, session = _setup(tmp_path, PRAGMA)
    variant = instance_amortized(loaded, "e1", algorithm, samples=6, blend=0.0)
    result = compare(variant, session, prepared, range(3), period=1000)
    assert all(f.mean_error <= 1e-6 for f in result.frames)


@pytest.mark.parametrize("name,samples,algorithm,phase", [
    ("blur", 2, "two-pass", "frame"), ("blur", 3, "three-pass", "frame"), ("blur", 2, "one-pass", "pixel"),
    ("blur", 3, "two-pass", "pixel"), ("weighted", 4, "two-pass", "frame"), ("conditional", 4, "one-pass", "frame"),
    ("conditional", 4, "three-pass", "pixel")])
def test_subsets_cover_every_sample_once_per_cycle(gl_ctx, tmp_path, name, samples, algorithm, phase):
    source, (total,) = ESTIMATORS[name]
    cycle = total // samples if total % samples == 0 else total
    loaded, prepared, session = _setup(tmp_path, source, moving=False, frames=cycle + 1)
    with Renderer(prepared, session) as original:
        ref = original.render_frame(0)
    variant = instance_amortized(loaded, "e1", algorithm, samples=samples, blend=0.0, phase=phase)
    with CachedRenderer(variant, session, prepared, period=1000) as cached:
        frames = [cached.render_frame(i) for i in range(cycle + 1)]
    if algorithm != "one-pass":
        assert all(f.hits == frames[0].covered_pixels for f in frames[1:])  # a still camera: all hits
    mask = ref.mask
    single = np.abs(frames[1].image - ref.image)[mask].max()
    assert single > 1e-3  # one frame's subset is not the whole sum
    mean = np.mean([f.image for f in frames[1:]], axis=0)
    if name == "weighted":  # a ratio of two sums: compare the payloads (the sums) instead
        return
    assert np.abs(mean - ref.image)[mask].max() < 1e-4


def test_weighted_payload_sums_average_to_the_full_sums(gl_ctx, tmp_path):
    source, (total,) = ESTIMATORS["weighted"]
    loaded, prepared, session = _setup(tmp_path, source, moving=False, frames=4)
    full = instance_amortized(loaded, "e1", "two-pass", samples=total, blend=0.0)
    part = instance_amortized(loaded, "e1", "two-pass", samples=4, blend=0.0)
    with CachedRenderer(full, session, prepared, period=1000, keep_payload=True) as a:
        want = a.render_frame(0).payload
        mask = a.render_frame(0).mask
    with CachedRenderer(part, session, prepared, period=1000, keep_payload=True) as b:
        got = [b.render_frame(i).payload for i in range(4)]
    mean = np.mean(got[1:], axis=0)
    assert np.abs(mean - want)[mask].max() < 1e-4
    assert np.abs(got[1] - want)[mask].max() > 1e-3


def test_blend_lowers_the_frame_to_frame_noise(gl_ctx, tmp_path):
    """λ > 0 keeps a running estimate: on a still camera its frames vary less than λ = 0's."""
    source = ESTIMATORS["conditional"][0]
    loaded, prepared, session = _setup(tmp_path, source, moving=False, frames=9)

    def spread(blend):
        v = instance_amortized(loaded, "e1", "three-pass", samples=4, blend=blend)
        with CachedRenderer(v, session, prepared, period=1000) as c:
            images = [c.render_frame(i).image for i in range(9)]
        return float(np.std(images[5:], axis=0).mean())

    assert spread(0.6) < 0.6 * spread(0.0)


def test_subset_indices_cover_all_indices():
    for total, m in ((16, 4), (16, 16), (12, 5), (8, 3)):
        cycle = total // m if total % m == 0 else total
        for pixel in ((0, 0), (3, 7)):
            for phase in ("frame", "pixel"):
                seen = [i for f in range(cycle) for i in subset_indices(total, m, f, pixel, phase)]
                assert sorted(seen) == sorted(list(range(total)) * (len(seen) // total))


def test_bad_arguments():
    from rrcache.errors import RRCacheError
    from rrcache.glsl.frontend import parse_shader

    s = parse_shader(ESTIMATORS["blur"][0], "b.frag")
    with pytest.raises(ValueError, match="samples"):
        instance_amortized(s, "e1", samples=9)
    with pytest.raises(ValueError, match="lambda"):
        instance_amortized(s, "e1", samples=2, blend=1.0)
    with pytest.raises(ValueError, match="phase"):
        instance_amortized(s, "e1", samples=2, phase="random")
    with pytest.raises(RRCacheError, match="no loop"):
        instance_amortized(s, "e7", samples=2)


@pytest.mark.parametrize("name,samples,algorithm", [("blur", 2, "three-pass"), ("conditional", 4, "two-pass"),
                                                    ("conditional", 4, "one-pass")])
def test_slots_history_is_exact_on_a_still_camera(gl_ctx, tmp_path, name, samples, algorithm):
    """Each slot holds one subset's sum: a still image is the original at every frame, with
    m of N samples computed per frame after the first."""
    source, (total,) = ESTIMATORS[name]
    loaded, prepared, session = _setup(tmp_path, source, moving=False, frames=6)
    variant = instance_amortized(loaded, "e1", algorithm, samples=samples, blend=0.0, history="slots")
    assert variant.components == total // samples and variant.amortized["cycle"] == total // samples
    result = compare(variant, session, prepared, range(6), period=1000)
    assert all(f.mean_error <= 1e-5 for f in result.frames), [f.mean_error for f in result.frames]
    if algorithm != "one-pass":
        assert result.hit_rate == 1.0


def test_slots_history_needs_room_in_the_payload():
    from rrcache.glsl.frontend import parse_shader

    s = parse_shader(ESTIMATORS["weighted"][0], "w.frag")
    with pytest.raises(ValueError, match="payload"):
        instance_amortized(s, "e1", samples=6, history="slots")  # 2 slots of 4 components
    with pytest.raises(ValueError, match="frame"):
        instance_amortized(s, "e1", samples=6, history="slots", phase="pixel")


def test_an_amortized_choice_is_a_kind_of_selection(tmp_path):
    """Selection(parts=(AmortizedLoop(...),)) round-trips through JSON and compiles through
    pipeline.variant_for_selection, like a cached node."""
    from rrcache.pipeline import load_for_session, variant_for_selection
    from rrcache.selection import AmortizedLoop, Selection, parts_from_json, parts_to_json

    part = AmortizedLoop("e1", 4, 0.6, history="slots")
    sel = Selection((part,), predicted_error=0.01, predicted_ms=3.0, predicted_speedup=2.0, algorithm="two-pass")
    assert sel.kind == "amortize" and sel.describe() == "e1 m=4 λ=0.6 slots/frame"
    assert parts_from_json(parts_to_json(sel.parts), "parts") == sel.parts
    with pytest.raises(Exception, match="blend"):
        parts_from_json([{"kind": "amortize", "estimator": "e1", "samples": 4, "blend": 1.5}], "parts")
    path = tmp_path / "c.frag"
    path.write_text(ESTIMATORS["conditional"][0])
    work = load_for_session(str(path))
    variant, _period = variant_for_selection(work, sel)
    assert variant.algorithm == "two-pass"
    assert variant.amortized == {"estimator": "e1", "samples": 4, "of": 16, "lambda": 0.6, "phase": "frame",
                                 "cycle": 4, "history": "slots", "accumulators": ["hits"]}


@pytest.mark.parametrize("name", sorted(ESTIMATORS))
def test_one_slots_rule_for_compiler_profiler_and_models(name):
    """The compiler builds a slots variant exactly at the m where rrcache.selection.slots_fit says
    it fits, and the profiler trains (and the models offer) the slots history at those m and no
    others: one rule, for every estimator of the corpus."""
    from rrcache.glsl.frontend import parse_shader
    from rrcache.model.amortize import training_samples
    from rrcache.profiler.amortize import _slots_record
    from rrcache.selection import slots_fit, slots_samples

    shader = parse_shader(ESTIMATORS[name][0], f"{name}.frag")
    for est in find_estimators(shader).estimators:
        total, comps = int(est.samples), int(est.components)
        compiled = []
        for m in range(1, total + 1):
            why = slots_fit(total, m, comps)
            try:
                v = instance_amortized(shader, est.id, "two-pass", samples=m, blend=0.0, history="slots")
            except ValueError as err:
                assert why is not None and why in str(err), (m, why, err)
                continue
            assert why is None, (m, why)
            assert v.components == (total // m) * comps <= 4 and v.amortized["history"] == "slots"
            compiled.append(m)
        assert compiled == slots_samples(total, comps) == training_samples(total, "slots", comps)
        record = _slots_record(est)
        assert (record.note is None) == bool(compiled)
        # the pixel phase never fits
        assert all(slots_fit(total, m, comps, "pixel") is not None for m in compiled)
