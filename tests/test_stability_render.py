"""Extreme rendering cases through real EGL rendering, tiny (issue 7, part 2), one row of
docs/stability.md each: nothing covered, 1×1, a resolution too large (refused before allocating),
one frame, Δn = 1 and Δn beyond the session, NaN/Inf pixels, an extreme depth range, payloads
beyond the 16-bit float range.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from rrcache.analysis import cacheable_nodes
from rrcache.compiler import instance
from rrcache.errors import GLError, RRCacheError
from rrcache.gl import limits
from rrcache.glsl.frontend import load_shader
from rrcache.harness.cached import HALF_MAX, CachedRenderer, compare
from rrcache.compiler.prepared import prepare_file
from rrcache.harness.renderer import Renderer, render
from rrcache.compiler.vertex import mesh_defines, session_attributes
from rrcache.profiles.settings import TrainingSettings
from rrcache.runtime import CacheRuntime
from rrcache.session import load_session

from scene_files import FIXED_LIGHT, STATIC_CAMERA, fragment, node_named, session_doc, write_scene

AREA = "rendering (EGL, llvmpipe)"

# u_zero is 0: the left 8 columns divide 0 by 0 (NaN), the next 4 divide 1 by 0 (+Inf)
SHADER = fragment("""void main() {
    float b = 0.5 + 0.25 * sin(v_objectPosition.x * u_scale) * cos(v_objectPosition.y * u_scale);
    float big = b * u_gain;
    vec3 albedo = vec3(b, b * b, 1.0 - b) * (big / u_gain);
    float diffuse = max(dot(normalize(v_normal), normalize(u_light - v_position.xyz)), 0.0);
    vec3 color = albedo * (0.2 + 0.8 * diffuse);
    if (u_poison > 0.5 && gl_FragCoord.x < 8.0) color = vec3(u_zero / u_zero);
    else if (u_poison > 0.5 && gl_FragCoord.x < 12.0) color = vec3(1.0 / u_zero);
    fragColor = vec4(color, 1.0);
}
""", uniforms=("float u_gain", "float u_zero", "float u_poison"))
CAMERA = STATIC_CAMERA
SPHERE = {"procedural": {"type": "icosphere", "radius": 1.0, "subdivisions": 2}}


def _files(tmp_path, frames=4, resolution=(32, 32), objects=None, near=0.1, far=50.0, uniforms=None, camera=None):
    doc = session_doc(resolution, frames, camera or CAMERA, FIXED_LIGHT,
                      objects if objects is not None else [SPHERE],
                      {"u_scale": 7.0, "u_gain": 1.0, "u_zero": 0.0, "u_poison": 0.0, **(uniforms or {})},
                      near, far)
    return write_scene(tmp_path, SHADER, doc, "extreme.frag", "session.json")


def _work(shader_path, session, text="vec3(b, b * b, 1.0 - b)"):
    return node_named(shader_path, session, text)


def _summary_finite(summary: dict) -> list[str]:
    return [k for k, v in summary.items() if isinstance(v, float) and not math.isfinite(v)]


def test_object_off_screen(gl_ctx, tmp_path, stability_case):
    off = {"procedural": {"type": "icosphere", "radius": 1.0, "subdivisions": 2},
           "keyframes": [{"frame": 0, "translate": [0, 0, 40.0]}]}  # behind the camera
    shader, session_path = _files(tmp_path, objects=[off])
    session = load_session(session_path)
    case = stability_case("zero covered pixels (object off-screen)", AREA,
                          "32×32, 4 frames, the only object behind the camera; plain render and Δn = 4 cache")
    plain = render(shader, session, frames=4)
    table, prepared, node = _work(shader, session)
    result = compare(instance(table, node.id), session, prepared, range(4), period=4)
    summary = result.summary()
    case.observe(covered=[f.covered_pixels for f in plain.frames], plain_ms=plain.ms_per_frame,
                 mean_error=summary["mean_error"], psnr=summary["psnr"], hit_rate=summary["hit_rate"],
                 speedup=summary["speedup"])
    assert all(f.covered_pixels == 0 for f in plain.frames) and math.isfinite(plain.ms_per_frame)
    assert summary["mean_error"] == 0.0 and summary["hit_rate"] == 0.0
    assert not _summary_finite(summary), summary


def test_one_by_one(gl_ctx, tmp_path, stability_case):
    shader, session_path = _files(tmp_path, resolution=(1, 1), camera=[
        {"frame": 0, "eye": [0, 0, 3.0], "target": [0, 0, 0], "up": [0, 1, 0]}])
    session = load_session(session_path)
    case = stability_case("1×1 resolution", AREA, "a sphere filling the one pixel, 4 frames, plain and Δn = 4")
    plain = render(shader, session, frames=4)
    table, prepared, node = _work(shader, session)
    result = compare(instance(table, node.id), session, prepared, range(4), period=4)
    summary = result.summary()
    case.observe(image_shape=list(plain.frames[0].image.shape), covered=plain.frames[0].covered_pixels,
                 mean_error=summary["mean_error"], hits=summary["hits"], misses=summary["misses"])
    assert plain.frames[0].image.shape == (1, 1, 4) and plain.frames[0].covered_pixels == 1
    assert np.all(np.isfinite(plain.frames[0].image))
    assert summary["hits"] + summary["misses"] == 3 and not _summary_finite(summary)
    assert summary["mean_error"] <= 1e-5


def test_resolution_too_large_is_refused_before_allocating(gl_ctx, tmp_path, stability_case, monkeypatch):
    shader, session_path = _files(tmp_path)
    session = load_session(session_path)
    case = stability_case("resolution too large for memory", AREA,
                          "render(resolution=100000×100000) and CacheRuntime at 100000×100000")
    with pytest.raises(GLError) as plain:
        render(shader, session, frames=1, resolution=(100000, 100000))
    with pytest.raises(GLError) as runtime:
        CacheRuntime(gl_ctx, {"reproject": None, "payload": None, "shade": None}, "three-pass", (100000, 100000))
    largest = min(int(gl_ctx.info["GL_MAX_TEXTURE_SIZE"]), int(gl_ctx.info["GL_MAX_RENDERBUFFER_SIZE"]))
    # within the driver's limit but beyond memory: this machine has more memory than the largest
    # target needs, so the memory it reports is replaced by 1 GiB (the only stand-in here)
    monkeypatch.setattr(limits, "available_memory", lambda: 2 ** 30)
    with pytest.raises(GLError) as memory:
        render(shader, session, frames=1, resolution=(8192, 8192))
    monkeypatch.undo()
    case.observe(render=str(plain.value), runtime=str(runtime.value), memory_1GiB=str(memory.value))
    assert f"{100000 * 100000 * 57:,} bytes" in str(plain.value) and f"{largest}x{largest}" in str(plain.value)
    assert "hint:" in str(plain.value) and "cache size" in str(runtime.value)
    assert f"{8192 * 8192 * 57:,} bytes" in str(memory.value) and f"{2 ** 30:,} bytes" in str(memory.value)
    # nothing was allocated: the context is fine and renders the next frame
    assert render(shader, session, frames=1).frames[0].covered_pixels > 0


def test_one_frame_session(gl_ctx, tmp_path, stability_case):
    shader, session_path = _files(tmp_path, frames=1)
    session = load_session(session_path)
    case = stability_case("one-frame session", AREA, "frames = 1: render, a Δn = 8 cache, and training settings")
    plain = render(shader, session)
    table, prepared, node = _work(shader, session)
    summary = compare(instance(table, node.id), session, prepared, range(1), period=8).summary()
    with pytest.raises(RRCacheError) as refused:
        TrainingSettings(periods=(2, 4)).resolved(session)
    case.observe(frames=len(plain.frames), covered=plain.frames[0].covered_pixels, hit_rate=summary["hit_rate"],
                 profile=str(refused.value).replace(str(tmp_path), "TMP"))
    assert len(plain.frames) == 1 and summary["hit_rate"] == 0.0 and not _summary_finite(summary)
    assert "one frame" in str(refused.value) and "hint:" in str(refused.value)


@pytest.mark.parametrize("period,frames", [(1, 4), (100, 4)], ids=["period-1", "period-beyond-session"])
def test_period_extremes(gl_ctx, tmp_path, stability_case, period, frames):
    shader, session_path = _files(tmp_path, frames=frames)
    session = load_session(session_path)
    case = stability_case(f"Δn = {period}" + (" (larger than the session)" if period > frames else ""), AREA,
                          f"static camera, {frames} frames, three-pass, exact hit maps")
    table, prepared, node = _work(shader, session)
    result = compare(instance(table, node.id), session, prepared, range(frames), period=period, hit_maps=True)
    summary = result.summary()
    case.observe(hit_rate=summary["hit_rate"], expected=1 - 1 / period, mean_error=summary["mean_error"])
    assert not _summary_finite(summary)
    if period == 1:
        assert summary["hit_rate"] == 0.0 and summary["mean_error"] <= 1e-6
    else:
        # fewer frames than Δn: the blocks whose refresh falls in these frames miss, the rest hit
        assert summary["hit_rate"] >= 1 - (frames - 1) / period - 0.05


def test_nan_and_inf_pixels(gl_ctx, tmp_path, stability_case):
    shader, session_path = _files(tmp_path, uniforms={"u_poison": 1.0})
    session = load_session(session_path)
    case = stability_case("shader output NaN/Inf at some pixels", AREA,
                          "columns x < 8 give 0/0 (NaN), 8 ≤ x < 12 give 1/0 (+Inf); plain and Δn = 4")
    plain = render(shader, session, frames=3)
    from rrcache.harness.metrics import nonfinite_count
    counts = [nonfinite_count(f.image) for f in plain.frames]
    covered_bad = [int((f.mask[:, :12]).sum()) for f in plain.frames]
    table, prepared, node = _work(shader, session)
    summary = compare(instance(table, node.id), session, prepared, range(3), period=4).summary()
    case.observe(nonfinite_per_frame=counts, mean_error=summary["mean_error"],
                 error_left_out=summary["error_left_out_pixels"], variant_nonfinite=summary["nonfinite_pixels"])
    assert counts == covered_bad and counts[0] > 0
    assert math.isfinite(summary["mean_error"]) and summary["mean_error"] <= 1e-5
    assert summary["error_left_out_pixels"] == sum(covered_bad[1:])  # the summary leaves out frame 0


def test_extreme_depth_range(gl_ctx, tmp_path, stability_case):
    period, frames = 8, 9
    shader, session_path = _files(tmp_path, frames=frames, near=1e-4, far=1e6)
    session = load_session(session_path)
    case = stability_case("extreme depth range", AREA, f"near 1e-4, far 1e6, static camera, Δn = {period}, "
                                                       f"{frames} frames")
    table, prepared, node = _work(shader, session)
    summary = compare(instance(table, node.id), session, prepared, range(frames), period=period,
                      hit_maps=True).summary()
    case.observe(hit_rate=summary["hit_rate"], expected=1 - 1 / period, mean_error=summary["mean_error"])
    assert abs(summary["hit_rate"] - (1 - 1 / period)) <= 0.05
    assert summary["mean_error"] <= 1e-4


@pytest.mark.parametrize("gain", [1e5, 100.0], ids=["beyond-half", "within-half"])
def test_half_float_payload_overflow(gl_ctx, tmp_path, stability_case, gain):
    shader, session_path = _files(tmp_path, uniforms={"u_gain": gain})
    session = load_session(session_path)
    case = stability_case(f"16-bit payload asked, values up to {gain * 0.75:g}", AREA,
                          f"payload = b·{gain:g} (b ≤ 0.75), --payload f2, Δn = 4")
    table, prepared, node = _work(shader, session, "b * u_gain")
    variant = instance(table, node.id, payload_dtype="f2")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = compare(variant, session, prepared, range(4), period=4)
    summary = result.summary()
    said = [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
    case.observe(payload_dtype=summary["payload_dtype"], warning=said[0] if said else "none",
                 mean_error=summary["mean_error"])
    if gain * 0.75 > HALF_MAX:
        assert summary["payload_dtype"] == "f4" and said and "32-bit" in said[0]
        assert any("16-bit" in n for n in result.notes)
        assert summary["mean_error"] <= 1e-5  # the values were kept exactly
    else:
        assert summary["payload_dtype"] == "f2" and not said
    assert math.isfinite(summary["mean_error"])
