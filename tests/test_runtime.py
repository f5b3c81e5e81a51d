"""CacheRuntime on hand-written pass shaders (the compiler's output is tested in test_compiler*).

Real rendering through EGL at 64×64: the three-pass scheme reproduces the original at Δn = 1,
a static scene hits at the rate the refresh rule predicts, and disocclusion misses exactly where
a moving occluder uncovers the background.
"""
from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("LP_NUM_THREADS", "1")

import moderngl  # noqa: E402

from rrcache.gl.context import get_context  # noqa: E402
from rrcache.runtime import CacheRuntime  # noqa: E402
from rrcache.runtime import glsl as G  # noqa: E402
from rrcache.runtime.refresh import refresh_mask, refresh_phases  # noqa: E402
from masks import dilate, erode  # noqa: E402

W, H = 64, 64

VERTEX = """#version 330 core
in vec3 a_position;
uniform mat4 u_modelViewProjectionMatrix;
""" + G.vertex_glsl() + """
out vec3 v_objectPosition;
invariant gl_Position;
void main() {
    vec4 p = vec4(a_position, 1.0);
    v_objectPosition = a_position;
    rr_prevClip = u_prevModelViewProjectionMatrix * p;
    gl_Position = u_modelViewProjectionMatrix * p;
}
"""

HEAD = """#version 330 core
in vec3 v_objectPosition;
uniform float u_tint;
float pattern(vec3 p) { return 0.5 + 0.5 * sin(p.x * 9.0) * cos(p.y * 7.0); }
"""
ORIGINAL = HEAD + "out vec4 fragColor;\nvoid main() { fragColor = vec4(vec3(pattern(v_objectPosition)) * u_tint, 1.0); }\n"
REPROJECT = HEAD + G.lookup_glsl("bilinear") + G.output_glsl() + """
void main() {
    rr_outInvDepth = 0.0;
    rr_outPayload = vec4(0.0);
    if (!rr_hit() || rr_refreshNow()) discard;
    rr_outPayload = rr_previous();
    rr_outInvDepth = gl_FragCoord.w;
}
"""
PAYLOAD = HEAD + G.output_glsl() + """
void main() {
    rr_outPayload = vec4(pattern(v_objectPosition), 0.0, 0.0, 0.0);
    rr_outInvDepth = gl_FragCoord.w;
}
"""
SHADE = HEAD + G.current_glsl() + "out vec4 fragColor;\nvoid main() { fragColor = vec4(vec3(rr_current().x) * u_tint, 1.0); }\n"


def _perspective(fov_deg, aspect, near, far):
    t = 1.0 / np.tan(np.radians(fov_deg) / 2)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = t / aspect, t
    m[2, 2], m[2, 3], m[3, 2] = (far + near) / (near - far), 2 * far * near / (near - far), -1.0
    return m


def _translate(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def _scale(s):
    return np.diag([s, s, s, 1.0])


class Scene:
    """A background quad and an optional occluder quad in front of it; static camera."""

    def __init__(self, ctx):
        self.ctx = ctx
        quad = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype="f4")
        self.vbo = ctx.buffer(quad.tobytes())
        self.ibo = ctx.buffer(np.array([0, 1, 2, 0, 2, 3], dtype="u4").tobytes())
        self.proj = _perspective(60.0, 1.0, 0.1, 10.0)
        self.background = _translate(0, 0, -3) @ _scale(3.0)
        self.occluder_x = [None, None]  # previous, current x offset (None: no occluder)
        self._vaos = {}
        self.programs = {name: ctx.program(vertex_shader=VERTEX, fragment_shader=src)
                         for name, src in [("original", ORIGINAL), ("reproject", REPROJECT),
                                           ("payload", PAYLOAD), ("shade", SHADE)]}
        self.color = ctx.texture((W, H), 4, dtype="f4")
        self.depth = ctx.depth_texture((W, H))
        self.fbo = ctx.framebuffer([self.color], self.depth)

    def occluder(self, x):
        return _translate(x, 0, -2) @ _scale(0.4)

    def objects(self):
        objs = [(self.background, self.background)]
        prev_x, cur_x = self.occluder_x
        if cur_x is not None:
            prev = self.occluder(prev_x if prev_x is not None else cur_x)
            objs.append((self.occluder(cur_x), prev))
        return objs

    def draw(self, program, pass_name):
        vao = self._vaos.get(id(program))
        if vao is None:
            vao = self._vaos[id(program)] = self.ctx.vertex_array(program, [(self.vbo, "3f", "a_position")], self.ibo)
        if "u_tint" in program:
            program["u_tint"].value = 0.9
        for model, prev_model in self.objects():
            program["u_modelViewProjectionMatrix"].write((self.proj @ model).T.astype("f4").tobytes())
            if "u_prevModelViewProjectionMatrix" in program:
                program["u_prevModelViewProjectionMatrix"].write((self.proj @ prev_model).T.astype("f4").tobytes())
            vao.render()

    def occluder_mask(self, x):
        """Pixels where the occluder at offset ``x`` is visible (it is always in front)."""
        saved = self.background
        self.background = _translate(0, 0, 50)  # behind the camera: not drawn
        self.occluder_x = [x, x]
        mask = self.render_original()[..., 3] > 0
        self.background = saved
        return mask

    def render_original(self):
        self.fbo.use()
        self.fbo.clear(0, 0, 0, 0, depth=1.0)
        self.ctx.enable(moderngl.DEPTH_TEST)
        self.ctx.depth_func = "<"
        self.draw(self.programs["original"], "original")
        return np.frombuffer(self.color.read(), dtype="f4").reshape(H, W, 4)[::-1].copy()

    def runtime(self, **kw):
        passes = {k: self.programs[k] for k in ("reproject", "payload", "shade")}
        return CacheRuntime(self.ctx, passes, "three-pass", (W, H), cull_back_faces=False, **kw)


@pytest.fixture(scope="module")
def scene():
    return Scene(get_context())


def _frame_with_hits(rt, scene):
    hits = {}
    stats = rt.frame(scene.draw, after_first_pass=lambda: hits.setdefault("map", rt.read_inverse_depth(current=True) > 0))
    return stats, hits["map"]


@pytest.mark.parametrize("mode, block, seed, period", [("random", 1, 3, 7), ("random", 2, 0, 16), ("random", 8, 5, 4),
                                                     ("tiled", 4, 0, 10), ("tiled", 1, 0, 3)])
def test_refresh_rule_in_the_shader_matches_refresh_mask(scene, mode, block, seed, period):
    """The shader's refresh rule (a hash of the block coordinates, no texture) refreshes exactly
    the pixels :func:`refresh_mask` predicts, for every mode and block size, frame after frame."""
    scene.occluder_x = [None, None]
    covered = scene.render_original()[..., 3] > 0
    rt = scene.runtime(period=period, block=block, refresh=mode, seed=seed)
    try:
        _frame_with_hits(rt, scene)
        for _ in range(period + 1):
            clock = rt.clock
            _stats, hit_map = _frame_with_hits(rt, scene)
            refreshed = refresh_mask((W, H), block, mode, seed, period, clock)[::-1]
            np.testing.assert_array_equal(hit_map, covered & ~refreshed)
    finally:
        rt.release()


def test_random_phases_are_uniform_and_seeded():
    """Every phase in [0, Δn) gets about 1/Δn of the blocks; another seed gives another pattern;
    tiled phases run in raster order."""
    for period in (2, 16, 50):
        phases = refresh_phases((640, 480), 4, "random", 0, period)
        counts = np.bincount(phases.ravel(), minlength=period)
        assert counts.size == period
        expected = phases.size / period
        assert np.all(np.abs(counts - expected) < 5 * np.sqrt(expected)), counts
    assert (refresh_phases((640, 480), 4, "random", 1, 16) != refresh_phases((640, 480), 4, "random", 0, 16)).mean() > 0.9
    tiled = refresh_phases((64, 48), 4, "tiled", 0, 6).ravel()
    assert np.all(np.diff(tiled) >= 0) and set(tiled.tolist()) == set(range(6))


def test_period_one_reproduces_the_original(scene):
    scene.occluder_x = [0.0, 0.3]
    reference = scene.render_original()
    rt = scene.runtime(period=1)
    try:
        for _ in range(3):
            stats = rt.frame(scene.draw)
        assert stats.covered == W * H and stats.misses >= stats.covered  # misses count overdraw
        assert np.abs(rt.read_color() - reference).max() <= 1e-5
    finally:
        rt.release()


def test_static_scene_hit_rate_matches_refresh_rule(scene):
    scene.occluder_x = [None, None]
    reference = scene.render_original()
    covered = reference[..., 3] > 0
    period = 50
    rt = scene.runtime(period=period, block=4)
    try:
        stats, hit_map = _frame_with_hits(rt, scene)
        assert not hit_map.any(), "the first frame has no cache: every pixel misses"
        rates = []
        for _ in range(8):
            clock = rt.clock
            stats, hit_map = _frame_with_hits(rt, scene)
            refreshed = refresh_mask((W, H), 4, "random", 0, period, clock)[::-1]
            # exactly the covered pixels that are not refreshed hit
            np.testing.assert_array_equal(hit_map, covered & ~refreshed)
            rates.append(hit_map.sum() / covered.sum())
            assert np.abs(rt.read_color() - reference).max() <= 1e-5
        assert abs(np.mean(rates) - (1 - 1 / period)) <= 0.02
    finally:
        rt.release()


def test_disocclusion_misses_where_background_is_uncovered(scene):
    """An occluder slides right in front of a static background: the background pixels it
    uncovers must miss (they were not in the cache); elsewhere misses happen only along the
    occluder's edges (bilinear depth mixes across them), never in the interior."""
    rt = scene.runtime(period=10_000, block=1)
    try:
        positions = [-0.6, -0.6, -0.3, 0.0]
        previous_mask = None
        for i, x in enumerate(positions):
            prev_x = positions[i - 1] if i else x
            scene.occluder_x = [prev_x, x]
            mask = scene.occluder_mask(x)
            stats, hit_map = _frame_with_hits(rt, scene)
            if i >= 2:
                covered = scene.render_original()[..., 3] > 0
                uncovered = previous_mask & ~mask
                assert uncovered.sum() > 20
                assert not (uncovered & hit_map).any(), "a newly uncovered pixel reused the occluder's payload"
                misses = covered & ~hit_map
                edges = dilate(previous_mask & ~erode(previous_mask)) | dilate(mask & ~erode(mask))
                assert not (misses & ~uncovered & ~edges).any(), "misses away from the disocclusion"
                assert (hit_map & mask).sum() > 0.5 * mask.sum(), "the moving occluder itself should mostly hit"
            previous_mask = mask
    finally:
        rt.release()



def test_reset_makes_every_pixel_miss(scene):
    scene.occluder_x = [None, None]
    rt = scene.runtime(period=50)
    try:
        rt.frame(scene.draw)
        rt.frame(scene.draw)
        rt.reset()
        stats, hit_map = _frame_with_hits(rt, scene)
        assert not hit_map.any()
        assert stats.misses == stats.covered
    finally:
        rt.release()


def test_runtime_rejects_bad_settings(scene):
    with pytest.raises(ValueError, match="period"):
        scene.runtime(period=0)
    with pytest.raises(ValueError, match="block"):
        scene.runtime(block=3)
    with pytest.raises(ValueError, match="needs programs"):
        CacheRuntime(scene.ctx, {"reproject": scene.programs["reproject"]}, "three-pass", (W, H))
