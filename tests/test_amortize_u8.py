"""The 8-bit payload of amortized slots (rrcache.compiler.payload_encoding), through real GL:
the slots are stored by the range of the estimator's terms, decoded at every read, and a range
that does not hold falls back to 32-bit floats with a note."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from estimator_corpus import ESTIMATORS
from test_compiler_amortize import _setup
from rrcache.cli import cli
from rrcache.compiler.amortize import instance_amortized
from rrcache.errors import RRCacheError
from rrcache.harness.cached import CachedRenderer, compare

ROOT = Path(__file__).resolve().parent.parent
# "blur": each term is bump() = 0.5 + 0.5 sin(.) cos(.), in [0, 1]; 8 terms, 2 per frame: 4 slots
BLUR, BLUR_RANGE = ESTIMATORS["blur"][0], (0.0, 1.0)


def _payloads(variant, session, prepared, frames):
    out = []
    with CachedRenderer(variant, session, prepared, period=2 ** 30, keep_payload=True) as r:
        for index in frames:
            got = r.render_frame(index)
            out.append((got.payload, got.mask, got.image))
        return out, r.payload_dtype, r.payload_note


@pytest.mark.parametrize("algorithm", ["three-pass", "two-pass", "one-pass"])
def test_u8_slots_match_the_float_slots_to_a_step(gl_ctx, tmp_path, algorithm):
    loaded, prepared, session = _setup(tmp_path, BLUR, frames=5)
    f4 = instance_amortized(loaded, "e1", algorithm, samples=2, blend=0.6, history="slots")
    u8 = instance_amortized(loaded, "e1", algorithm, samples=2, blend=0.6, history="slots", payload_dtype="u8",
                            term_range=BLUR_RANGE)
    assert u8.payload_dtype == "u8" and u8.payload_decode == ([0.0] * 4, [2.0] * 4)
    frames = range(5)
    exact, dtype_f4, _ = _payloads(f4, session, prepared, frames)
    coarse, dtype_u8, note = _payloads(u8, session, prepared, frames)
    assert (dtype_f4, dtype_u8, note) == ("f4", "u8", None)
    step = 2.0 / 255.0  # one 8-bit step of a slot (2 terms in [0, 1])
    for (p32, mask, img32), (p8, mask8, img8) in zip(exact, coarse):
        assert np.array_equal(mask, mask8) and mask.sum() > 300
        # decoded back to the slots' values: on the 8-bit grid, within a few steps of the floats
        # (each frame's write rounds, and the reprojection carries it on)
        assert np.all(p8[mask] >= -1e-6) and np.all(p8[mask] <= 2.0 + 1e-6)
        assert 0 < np.abs(p8[mask] - p32[mask]).max() <= 4 * step
        assert np.abs(img8[mask] - img32[mask]).max() <= 4 * 4 * step / 8  # value = slots' sum / 8


def test_u8_slots_on_a_still_camera_are_the_original_to_rounding(gl_ctx, tmp_path):
    loaded, prepared, session = _setup(tmp_path, BLUR, moving=False, frames=5)
    u8 = instance_amortized(loaded, "e1", "two-pass", samples=2, blend=0.0, history="slots", payload_dtype="u8",
                            term_range=BLUR_RANGE)
    result = compare(u8, session, prepared, range(5), period=1000)
    assert result.hit_rate == 1.0
    # each of the 4 slots is off by at most half a step (2/255/2), the value is their sum / 8
    bound = 4 * (1.0 / 255.0) / 8
    assert all(0 < f.mean_error <= bound for f in result.frames[1:]), [f.mean_error for f in result.frames]


def test_a_range_that_does_not_hold_keeps_floats_with_a_note(gl_ctx, tmp_path):
    loaded, prepared, session = _setup(tmp_path, BLUR, frames=5)
    narrow = instance_amortized(loaded, "e1", "two-pass", samples=2, blend=0.6, history="slots",
                                payload_dtype="u8", term_range=(0.0, 0.25))
    f4 = instance_amortized(loaded, "e1", "two-pass", samples=2, blend=0.6, history="slots")
    with pytest.warns(RuntimeWarning, match="outside the range"):
        got, dtype, note = _payloads(narrow, session, prepared, range(3))
    assert dtype == "f4" and "the term range given for the loop at" in note
    want, _, _ = _payloads(f4, session, prepared, range(3))
    for (p, mask, img), (q, _, img_f4) in zip(got, want):
        # stored encoded in floats: decoded, the same values as the float variant's
        assert np.allclose(p[mask], q[mask], atol=1e-5) and np.allclose(img[mask], img_f4[mask], atol=1e-5)


def test_a_declared_range_that_does_not_hold_names_the_pragma(gl_ctx, tmp_path):
    source = BLUR.replace("    for (int i = 0; i < 8; i++) {", "    #pragma rrcache estimator range(0.0, 0.25)\n"
                                                                "    for (int i = 0; i < 8; i++) {")
    assert source != BLUR
    loaded, prepared, session = _setup(tmp_path, source, frames=5)
    variant = instance_amortized(loaded, "e1", "two-pass", samples=2, blend=0.6, history="slots", payload_dtype="u8")
    assert variant.amortized["range_source"] == "pragma"
    with pytest.warns(RuntimeWarning, match="outside the range"):
        _, dtype, note = _payloads(variant, session, prepared, range(2))
    line = source.splitlines().index("    for (int i = 0; i < 8; i++) {") + 1
    assert dtype == "f4" and "#pragma rrcache estimator range(LO, HI)' before the loop at" in note
    assert f"shader.frag:{line}:" in note


def test_u8_needs_the_slots_history_and_a_range(tmp_path):
    from rrcache.glsl.frontend import parse_shader

    blur = parse_shader(BLUR, str(tmp_path / "b.frag"))
    with pytest.raises(RRCacheError, match="slots history"):
        instance_amortized(blur, "e1", samples=2, history="blend", payload_dtype="u8", term_range=BLUR_RANGE)
    # a term read from a texture has no known range: the error says how to declare one, at the loop
    source = ("#version 330\nuniform sampler2D u_tex; in vec2 v_texcoord; out vec4 c;\nvoid main() {\n"
              "  float s = 0.0;\n  for (int i = 0; i < 8; i++) s += texture(u_tex, v_texcoord + float(i) * 0.01).r;\n"
              "  c = vec4(s / 8.0);\n}\n")
    tex = parse_shader(source, str(tmp_path / "t.frag"))
    with pytest.raises(RRCacheError) as err:
        instance_amortized(tex, "e1", samples=2, history="slots", payload_dtype="u8")
    assert "range" in err.value.message and "pragma rrcache estimator range" in err.value.hint
    assert err.value.where.startswith(str(tmp_path / "t.frag") + ":5")


def test_multi_node_cache_refuses_u8(gl_ctx):
    from rrcache.runtime.multi import MultiCacheRuntime

    with pytest.raises(ValueError, match="multi-node"):
        MultiCacheRuntime(gl_ctx, {}, "three-pass", (8, 8), period=(2, 3), payload_dtype="u8")


def test_bench_amortize_u8_on_the_temple(gl_ctx, tmp_path):
    """The PCF term (a bilinear mix of shadow comparisons) is proven in [0, 1], so the slots go
    in 8 bits; the run says so and measures both errors."""
    out = CliRunner().invoke(cli, [
        "bench-amortize", str(ROOT / "shaders" / "pcf_shadows.glsl"), str(ROOT / "sessions" / "temple.json"),
        "--estimator", "e1", "--samples", "4", "--lambda", "0.6", "--history", "slots", "--payload", "u8",
        "--filter", "catmull-rom-y", "--reference", "PCF_SAMPLES=64", "--frames", "4", "--repeats", "1",
        "--error-every", "2", "--resolution", "64x48", "--json"])
    assert out.exit_code == 0, out.output
    doc = json.loads(out.output[out.output.index("{"):])
    assert doc["payload"] == "u8" and "payload_note" not in doc
    assert (doc["history"], doc["filter"]) == ("slots", "catmull-rom-y")
    assert doc["error_frames"] == 2 and 0 < doc["original_error"] and 0 < doc["amortized_error"]


def test_instance_u8_only_for_an_estimator(tmp_path):
    out = CliRunner().invoke(cli, ["instance", str(ROOT / "shaders" / "pcf_shadows.glsl"), "--node", "n1",
                                   "--payload", "u8", "--out", str(tmp_path / "o")])
    assert out.exit_code == 2 and "--estimator" in out.output
