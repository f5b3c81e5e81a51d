"""Adaptive refresh (rrcache.runtime.adaptive) and the edge-aware filter, rendered for real.

A tiny scene (tests/compiler_scene.py: an icosphere) with a static camera: every covered pixel
reprojects exactly, so a pixel's colour tells whether its value was recomputed this frame. The
cached value is ``x·0.5 + u_t`` where the texture coordinate ``x > 0.5`` (volatile: ``u_t``
advances 0.1 a frame) and ``x·0.5`` elsewhere (calm).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from compiler_scene import Scene
from test_multinode import _originals
from rrcache.cli import main
from rrcache.compiler import instance
from rrcache.glsl import ast as A
from rrcache.glsl.frontend import parse_shader
from rrcache.runtime import DEFAULT_BLOCK, DEFAULT_REFRESH, CacheRuntime
from rrcache.runtime.refresh import refresh_mask
from rrcache.selection import AdaptiveNode, Selection, parts_from_json, parts_to_json

SIZE = (48, 48)

HALF = """#version 330
in vec2 v_texcoord;
uniform float u_t;
out vec4 fragColor;
void main() {
    float a = v_texcoord.x * 0.5 + (v_texcoord.x > 0.5 ? u_t : 0.0);
    fragColor = vec4(a, 0.0, 0.0, 1.0);
}
"""


def _node(shader):
    return [n for n in shader.unit.walk() if isinstance(n, A.Binary) and n.op == "+"][0]


def _run(ctx, variant, frames, **runtime):
    """(clock, colour, hit map after the first pass) per frame; static camera, u_t = 0.1·frame."""
    scene = Scene(ctx, SIZE, degrees_per_frame=0.0)
    programs = variant.build_programs(ctx)
    rt = CacheRuntime(ctx, programs, variant.algorithm, SIZE, payload_components=variant.components, **runtime)
    out = []
    try:
        for frame in range(frames):
            scene.uniforms["u_t"] = 0.1 * frame
            box = {}
            rt.frame(lambda prog, _name: scene.draw(prog, frame),
                     after_first_pass=lambda: box.setdefault("hits", rt.read_inverse_depth(current=True) > 0))
            out.append((rt.clock - 1, rt.read_color(), box["hits"]))
    finally:
        rt.release()
        for prog in programs.values():
            scene.forget(prog)
            prog.release()
        scene.release()
    return out


@pytest.mark.parametrize("algorithm", ["three-pass", "two-pass"])
def test_volatile_entries_refresh_at_the_fast_period_and_calm_ones_at_the_max_age(gl_ctx, algorithm):
    shader = parse_shader(HALF, "half.frag")
    variant = instance(shader, _node(shader), algorithm, adaptive=True)
    period, fast, frames = 8, 2, 24
    originals = _originals(gl_ctx, shader, frames)
    covered = originals[0][..., 3] > 0
    # volatile: the pixels whose original value changes from frame to frame
    volatile = covered & (np.abs(originals[1][..., 0] - originals[0][..., 0]) > 0.05)
    calm = covered & ~volatile
    assert volatile.sum() > 100 and calm.sum() > 100
    runs = _run(gl_ctx, variant, frames, period=period, threshold=0.05, fast_period=fast)
    for (clock, image, hits), original in zip(runs, originals):
        # the masks' row 0 is window y 0 (the bottom); the images' row 0 the top
        fixed = refresh_mask(SIZE, DEFAULT_BLOCK, DEFAULT_REFRESH, 0, period, clock)[::-1]
        quick = refresh_mask(SIZE, DEFAULT_BLOCK, DEFAULT_REFRESH, 0, fast, clock)[::-1]
        if clock == 0:
            assert not hits[covered].any()
            continue
        # calm entries (their change measured 0): the fixed rule at the max age alone
        np.testing.assert_array_equal(hits[calm], ~fixed[calm], err_msg=f"calm, frame {clock}")
        if clock > period:  # every volatile entry has been recomputed once and measured its change
            np.testing.assert_array_equal(hits[volatile], ~(fixed | quick)[volatile], err_msg=f"volatile, frame {clock}")
        # where an entry was recomputed, the colour is the original's
        fresh = covered & ~hits
        np.testing.assert_allclose(image[..., 0][fresh], original[..., 0][fresh], atol=1e-6)


@pytest.mark.parametrize("algorithm", ["three-pass", "two-pass"])
def test_threshold_zero_at_fast_period_one_is_the_original(gl_ctx, algorithm):
    shader = parse_shader(HALF, "half.frag")
    variant = instance(shader, _node(shader), algorithm, adaptive=True)
    originals = _originals(gl_ctx, shader, 4)
    covered = originals[0][..., 3] > 0
    for (clock, image, hits), original in zip(_run(gl_ctx, variant, 4, period=50, threshold=0.0, fast_period=1),
                                              originals):
        assert not hits[covered].any()
        np.testing.assert_array_equal(image[covered], original[covered])


def test_adaptive_needs_a_threshold_and_no_one_pass(gl_ctx):
    shader = parse_shader(HALF, "half.frag")
    with pytest.raises(ValueError, match="three-pass and two-pass"):
        instance(shader, _node(shader), "one-pass", adaptive=True)
    variant = instance(shader, _node(shader), "three-pass", adaptive=True)
    programs = variant.build_programs(gl_ctx)
    try:
        with pytest.raises(ValueError, match="give a threshold"):
            CacheRuntime(gl_ctx, programs, "three-pass", SIZE, payload_components=1)
    finally:
        for p in programs.values():
            p.release()
    plain = instance(shader, _node(shader), "three-pass")
    programs = plain.build_programs(gl_ctx)
    try:
        with pytest.raises(ValueError, match="adaptive=True"):
            CacheRuntime(gl_ctx, programs, "three-pass", SIZE, payload_components=1, threshold=0.1)
    finally:
        for p in programs.values():
            p.release()


def test_the_selection_part_round_trips_and_is_checked():
    s = Selection((AdaptiveNode("n215", 100, 0.02, 8),), 0.01, 2.0, 1.5)
    assert s.kind == "adaptive" and s.node == "n215" and s.period == 100 and s.threshold == 0.02
    assert parts_from_json(parts_to_json(s.parts), "parts") == s.parts
    from rrcache.errors import RRCacheError
    with pytest.raises(RRCacheError, match="threshold"):
        parts_from_json([{"kind": "adaptive", "node": "n1", "period": 4, "threshold": -1}], "parts")


def test_cli_render_adaptive_and_bad_options(tmp_path, capsys):
    shader = tmp_path / "half.frag"
    shader.write_text(HALF.replace("uniform float u_t;", "uniform float u_time;").replace("u_t ", "u_time "))
    session = Path(__file__).parent / "corpus" / "default_session.json"
    from rrcache.pipeline import load_for_session
    from rrcache.session import load_session
    work = load_for_session(str(shader), load_session(str(session)))
    node = max(work.table.nodes, key=lambda n: n.cost).id
    main(["render", str(shader), str(session), "--node", node, "--period", "8", "--adaptive", "0",
          "--fast-period", "1", "--json", "-q", "--color-format", "rgba32f", "--resolution", "32x32"])
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert out["mean_error"] == 0.0 and out["adaptive"]["fast_period"] == 1
    for bad in (["--adaptive", "-1"], ["--adaptive", "0.1", "--algorithm", "one-pass"]):
        with pytest.raises(SystemExit) as exc:
            main(["render", str(shader), str(session), "--node", node, *bad, "-q"])
        assert exc.value.code == 2
    main(["instance", str(shader), "--session", str(session), "--node", node, "--adaptive", "0.05",
          "--out", str(tmp_path / "v")])
    manifest = json.loads((tmp_path / "v" / "manifest.json").read_text())
    assert manifest["adaptive"] is True and manifest["runtime"]["threshold"] == 0.05
    assert "rr_outState" in (tmp_path / "v" / "payload.frag").read_text()


SMOOTH = """#version 330
in vec2 v_texcoord;
out vec4 fragColor;
void main() {
    float a = v_texcoord.y * 0.5 + 0.25;
    fragColor = vec4(a, 0.0, 0.0, 1.0);
}
"""


@pytest.mark.parametrize("algorithm", ["three-pass", "two-pass"])
def test_edge_filter_hits_along_silhouettes_where_bilinear_misses(gl_ctx, algorithm):
    """An orbiting camera around the icosphere: bilinear's inverse depth mixes the sphere with
    the empty background along the silhouette (a miss); the edge filter keeps the sphere's own
    texels there. Its values stay close to the original's (the value is smooth on the surface)."""
    from compiler_scene import original_program, render_original, render_variant

    shader = parse_shader(SMOOTH, "smooth.frag")
    frames = 4
    scene = Scene(gl_ctx, SIZE, degrees_per_frame=1.5)
    prog = original_program(gl_ctx, shader)
    try:
        originals = render_original(scene, prog, frames)
        results = {}
        for filter in ("bilinear", "edge"):
            variant = instance(shader, _node(shader), algorithm, filter=filter)
            images, stats = render_variant(scene, variant, frames, period=1000)
            results[filter] = (images, sum(s.hits for s in stats[1:]))
    finally:
        scene.forget(prog)
        prog.release()
        scene.release()
    assert results["edge"][1] > results["bilinear"][1] > 0
    covered = originals[-1][..., 3] > 0
    for image, original in zip(results["edge"][0][1:], originals[1:]):
        assert float(np.abs(image[..., 0] - original[..., 0])[covered].max()) < 0.05


def test_edge_filter_compiles_for_several_nodes(gl_ctx):
    from test_multinode import DISJOINT
    from test_multinode import _nodes as binary_nodes
    from rrcache.compiler import instance_nodes

    shader = parse_shader(DISJOINT, "disjoint.frag")
    variant = instance_nodes(shader, binary_nodes(shader, "+", 2), "two-pass", filter="edge")
    for program in variant.build_programs(gl_ctx).values():
        program.release()
