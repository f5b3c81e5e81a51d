"""Variants caching several nodes (k ≥ 2), each at its own period and phase.

Real compilation and rendering (EGL, llvmpipe) of a tiny scene (tests/compiler_scene.py) with a
static camera, so every covered pixel reprojects and a node's value changes only where that node
refreshes: each node's values are ``texcoord·0.5 + u_t`` with ``u_t`` advanced by 0.1 a frame, so
a pixel's colour tells whether that node was recomputed there this frame.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

import moderngl

from compiler_scene import Scene, original_program
from rrcache.gl.context import bind_default_framebuffer
from rrcache.cli import main
from rrcache.compiler import ALGORITHMS, instance, instance_nodes
from rrcache.errors import UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.frontend import parse_shader
from rrcache.runtime import DEFAULT_BLOCK, DEFAULT_REFRESH
from rrcache.runtime.multi import MultiCacheRuntime
from rrcache.runtime.refresh import refresh_mask

SIZE = (48, 48)

DISJOINT = """#version 330
in vec2 v_texcoord;
uniform float u_t;
out vec4 fragColor;
void main() {
    float a = v_texcoord.x * 0.5 + u_t;
    float b = v_texcoord.y * 0.5 + u_t;
    fragColor = vec4(a, b, 0.0, 1.0);
}
"""

NESTED = """#version 330
in vec2 v_texcoord;
uniform float u_t;
out vec4 fragColor;
void main() {
    float a = (v_texcoord.x * 0.5 + u_t) * 2.0;
    fragColor = vec4(a, 0.0, 0.0, 1.0);
}
"""


def _nodes(shader, op, count):
    """The ``count`` outermost binary expressions with operator ``op`` in main, in source order."""
    return [n for n in shader.unit.walk() if isinstance(n, A.Binary) and n.op == op][:count]


def _run(ctx, variant, periods, frames, seed=0):
    """Colour images and the runtime's payloads per frame, the static camera, u_t = 0.1·frame."""
    scene = Scene(ctx, SIZE, degrees_per_frame=0.0)
    programs = variant.build_programs(ctx)
    rt = variant.runtime(ctx, programs, SIZE, variant.spec.with_runtime(periods=tuple(periods)), seed=seed)
    out = []
    try:
        assert isinstance(rt, MultiCacheRuntime)
        for frame in range(frames):
            scene.uniforms["u_t"] = 0.1 * frame
            rt.frame(lambda prog, _name: scene.draw(prog, frame))
            out.append((rt.clock - 1, rt.read_color(), rt.read_payloads()))
    finally:
        rt.release()
        for prog in programs.values():
            scene.forget(prog)
            prog.release()
        scene.release()
    return out


def _originals(ctx, shader, frames):
    scene = Scene(ctx, SIZE, degrees_per_frame=0.0)
    prog = original_program(ctx, shader)
    color, depth = ctx.texture(SIZE, 4, dtype="f4"), ctx.depth_texture(SIZE)
    fbo = ctx.framebuffer([color], depth)
    images = []
    try:
        for frame in range(frames):
            scene.uniforms["u_t"] = 0.1 * frame
            fbo.use()
            fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
            ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
            ctx.depth_func = "<"
            scene.draw(prog, frame)
            images.append(np.frombuffer(color.read(), "f4").reshape(SIZE[1], SIZE[0], 4)[::-1].copy())
    finally:
        bind_default_framebuffer(ctx)
        for res in (fbo, color, depth):
            res.release()
        scene.forget(prog)
        prog.release()
        scene.release()
    return images


@pytest.mark.parametrize("algorithm", list(ALGORITHMS))
def test_each_node_refreshes_with_its_own_period_and_phase(gl_ctx, algorithm):
    shader = parse_shader(DISJOINT, "disjoint.frag")
    a, b = _nodes(shader, "+", 2)
    variant = instance_nodes(shader, [a, b], algorithm)
    periods, seed, frames = (3, 5), 7, 7
    originals = _originals(gl_ctx, shader, frames)
    covered = originals[0][..., 3] > 0
    assert covered.sum() > 300
    for (clock, image, payloads), original in zip(_run(gl_ctx, variant, periods, frames, seed), originals):
        for j, channel in ((0, 0), (1, 1)):
            fresh = np.abs(image[..., channel] - original[..., channel]) < 0.02
            if clock == 0:
                expected = covered
            else:   # node j: its own period, and its own seed (seed + j)
                expected = covered & refresh_mask(SIZE, DEFAULT_BLOCK, DEFAULT_REFRESH, seed + j, periods[j], clock)[::-1]
            np.testing.assert_array_equal(fresh & covered, expected, err_msg=f"node {j} frame {clock}")
            # the colour is what node j's payload holds
            np.testing.assert_allclose(image[..., channel][covered], payloads[j][..., 0][covered], atol=1e-6)
    # the two nodes refresh different pixels (their own seeds), not the same pattern
    m0 = refresh_mask(SIZE, DEFAULT_BLOCK, DEFAULT_REFRESH, seed, 3, 3)
    m1 = refresh_mask(SIZE, DEFAULT_BLOCK, DEFAULT_REFRESH, seed + 1, 3, 3)
    assert (m0 != m1).any()


@pytest.mark.parametrize("algorithm", list(ALGORITHMS))
def test_a_nested_outer_node_is_recomputed_from_the_inner_nodes_cached_value(gl_ctx, algorithm):
    """Outer (… + u_t) * 2.0 at Δn = 1, inner (… + u_t) at Δn = 4: the outer is recomputed every
    frame from the inner's value of this frame (reprojected where the inner hits), so the colour
    is twice the inner's payload, fresh only where the inner refreshes."""
    shader = parse_shader(NESTED, "nested.frag")
    outer = _nodes(shader, "*", 1)[0]
    inner = outer.left
    assert isinstance(inner, A.Binary) and inner.op == "+"
    variant = instance_nodes(shader, [outer, inner], algorithm)
    frames = 6
    originals = _originals(gl_ctx, shader, frames)
    covered = originals[0][..., 3] > 0
    for (clock, image, payloads), original in zip(_run(gl_ctx, variant, (1, 4), frames), originals):
        np.testing.assert_allclose(image[..., 0][covered], 2.0 * payloads[1][..., 0][covered], atol=1e-5)
        fresh = np.abs(image[..., 0] - original[..., 0]) < 0.02
        expected = covered if clock == 0 else covered & refresh_mask(SIZE, DEFAULT_BLOCK, DEFAULT_REFRESH, 1, 4, clock)[::-1]
        np.testing.assert_array_equal(fresh & covered, expected, err_msg=f"frame {clock}")


def test_nesting_is_recorded_and_one_node_is_the_one_node_compiler():
    shader = parse_shader(NESTED, "nested.frag")
    outer = _nodes(shader, "*", 1)[0]
    inner = outer.left
    v = instance_nodes(shader, [outer, inner])
    assert [n["text"] for n in v.nodes] == ["(v_texcoord.x * 0.5 + u_t) * 2.0", "v_texcoord.x * 0.5 + u_t"]
    assert v.components == (1, 1) and v.nodes[1]["inside"] is None  # ids only for table nodes
    with pytest.raises(UnsupportedShaderError, match="given twice"):
        instance_nodes(shader, [outer, outer])
    with pytest.raises(ValueError, match="two nodes or more"):
        instance_nodes(shader, [outer])
    assert "float a = rr_current().x;" in instance(shader, outer).passes["shade"].fragment


def test_render_target_budget_is_checked(gl_ctx):
    """Each node takes two render targets (payload, inverse depth): past the driver's
    GL_MAX_DRAW_BUFFERS the runtime says how many nodes fit, before allocating anything."""
    limit = min(int(gl_ctx.info["GL_MAX_DRAW_BUFFERS"]), int(gl_ctx.info["GL_MAX_COLOR_ATTACHMENTS"]))
    k = limit // 2 + 1
    with pytest.raises(ValueError, match=rf"needs {2 * k} render targets.*allows {limit}.*at most {limit // 2} nodes"):
        MultiCacheRuntime(gl_ctx, {"reproject": None, "payload": None, "shade": None}, "three-pass", SIZE,
                          period=(4,) * k, payload_components=(1,) * k)
    with pytest.raises(ValueError, match=r"plus the colour.*or use three-pass"):
        MultiCacheRuntime(gl_ctx, {"hit": None, "miss": None}, "two-pass", SIZE,
                          period=(4,) * (limit // 2), payload_components=(1,) * (limit // 2))


def test_cli_render_and_instance_pair_nodes_with_periods(gl_ctx, tmp_path, capsys):
    from rrcache.pipeline import load_for_session
    from rrcache.session import load_session

    shader, session = "shaders/marble.glsl", "sessions/marble.json"
    work = load_for_session(shader, load_session(session))
    a, b = [n.id for n in sorted(work.table.nodes, key=lambda n: -n.cost)[:2]]
    main(["render", shader, session, "--node", a, "--period", "50", "--node", b, "--period", "4",
          "--frames", "2", "--resolution", "32x32", "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert summary["nodes"] == [a, b] and summary["period"] == [50, 4] and summary["frames"] == 2
    assert summary["mean_error"] >= 0.0 and 0.0 <= summary["hit_rate"] <= 1.0
    with pytest.raises(SystemExit) as info:
        main(["render", shader, session, "--node", a, "--period", "50", "--node", b, "--period", "4",
              "--period", "2", "--frames", "2"])
    assert info.value.code == 2
    assert "2 --node but 3 --period" in capsys.readouterr().err
    main(["instance", shader, "--session", session, "--node", a, "--period", "50", "--node", b,
          "--period", "4", "--algorithm", "two-pass", "--out", str(tmp_path / "v")])
    manifest = json.loads((tmp_path / "v" / "manifest.json").read_text())
    assert [(n["id"], n["period"]) for n in manifest["nodes"]] == [(a, 50), (b, 4)]
    assert manifest["period"] == [50, 4] and manifest["algorithm"] == "two-pass"


def test_three_pass_layout_per_node_unless_the_shader_discards():
    """Three-pass runs two passes per node (hit_j, node_j) so a pixel pays only for the nodes
    that miss there; a shader that can discard keeps one pass 2 over the union."""
    shader = parse_shader(DISJOINT, "disjoint.frag")
    v = instance_nodes(shader, _nodes(shader, "+", 2), "three-pass")
    assert list(v.passes) == ["hit_0", "node_0", "hit_1", "node_1", "shade"]
    body = v.passes["node_1"].fragment.split("void main()")[1]
    assert "discard;" not in body and "rr_current_0()" not in body   # culled by depth; disjoint
    discarding = parse_shader(DISJOINT.replace("fragColor = vec4(a, b, 0.0, 1.0);",
                                               "if (a > 0.9) discard; fragColor = vec4(a, b, 0.0, 1.0);"), "d.frag")
    v = instance_nodes(discarding, _nodes(discarding, "+", 2), "three-pass")
    assert list(v.passes) == ["reproject", "payload", "shade"]


@pytest.mark.parametrize("color_format", ["rgba8", "rgba16f"])
def test_a_pair_draws_into_the_timing_colour_format(gl_ctx, capsys, color_format):
    """The multi-node runtime draws its colour into the same format as the original it is timed
    beside (it used to keep an rgba32f target whatever was asked: an unfair timing, and at Δn = 1
    an error of the 8-bit rounding instead of 0)."""
    main(["render", "tests/corpus/fragcoord_redeclared.glsl", "tests/corpus/default_session.json",
          "--node", "n130", "--period", "1", "--node", "n310", "--period", "1", "--frames", "2",
          "--color-format", color_format, "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert summary["color_format"] == color_format
    assert summary["mean_error"] == 0.0 and summary["hit_rate"] == 0.0
    assert summary["exact"] is True and summary["psnr"] is None  # never "100 dB"
