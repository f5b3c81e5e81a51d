"""The render cache (Walter et al. 2002) as a baseline (issue 26, item 3), on small real renders:

- with a budget of every pixel, it reproduces the original exactly (the renderer shades every
  pixel and each sample keeps its own pixel), for a still camera and a moving one;
- a point cloud moved by a known camera step lands where an independent pinhole projection
  says; a moving object's points follow its transform; a background sample goes far along its
  ray and comes back to its pixel;
- the filters on known point patterns: the depth cull's rule, the 3×3 weights at a hole, the 7×7
  prefilter only where the 3×3 filter finds nothing, the previous colour where nothing is near;
- eviction ages as specified: the paper's increment, faster when not visible, the colour-change
  penalty, evicted at 255 and overwritten by the ring;
- the sample budget is never exceeded (every block size, with and without prediction), the
  dither hands out the budget rounded down, prediction takes at most its share;
- bad settings are refused with the knob named.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rrcache.alternatives.render_cache import RenderCacheRenderer, RenderCacheSettings
from rrcache.alternatives.render_cache.filters import box7, depth_cull, reconstruct, weighted3
from rrcache.alternatives.render_cache.points import BACKGROUND, STATIC, PointCache
from rrcache.alternatives.render_cache.projection import Projector, screen_matrix, zbuffer
from rrcache.alternatives.render_cache.sampling import (blocks_to_pixels, dither, grid_size, hilbert_order,
                                                        predicted_requests, scaled)
from rrcache.alternatives.render_cache.tune import compare
from rrcache.errors import RRCacheError
from rrcache.compiler.prepared import prepare_file
from rrcache.harness.renderer import Renderer
from rrcache.session import load_session
from rrcache.session.camera import look_at, perspective

# a shader written as people write them: an #include'd lighting helper, a struct, glslViewer names
LIGHTING = """
struct Material { vec3 albedo; float shininess; };

vec3 shade(Material m, vec3 n, vec3 l, vec3 v) {
    float diffuse = max(dot(n, l), 0.0);
    vec3 h = normalize(l + v);
    float specular = pow(max(dot(n, h), 0.0), m.shininess);
    return m.albedo * (0.15 + 0.85 * diffuse) + vec3(0.3) * specular;
}
"""

SHADER = """#version 330
#include "lighting.glsl"
in vec4 v_position;
in vec3 v_normal;
in vec3 v_objectPosition;
uniform vec3 u_light;
uniform vec3 u_camera;
out vec4 fragColor;

void main() {
    vec3 p = v_objectPosition * 4.0;
    float stripes = 0.5 + 0.5 * sin(p.x + 2.0 * sin(p.y)) * cos(p.z);
    Material m = Material(mix(vec3(0.8, 0.3, 0.2), vec3(0.2, 0.5, 0.8), stripes), 24.0);
    vec3 n = normalize(v_normal);
    fragColor = vec4(shade(m, n, normalize(u_light - v_position.xyz), normalize(u_camera - v_position.xyz)), 1.0);
}
"""


def _session(camera_moves: bool, object_moves: bool, frames: int = 6) -> dict:
    end = [1.0, 0.7, 3.0] if camera_moves else [0.0, 0.5, 3.2]
    box = {"procedural": {"type": "box", "size": [0.6, 0.6, 0.6]},
           "keyframes": [{"frame": 0, "translate": [-1.2, 0.0, 0.3]}]
           + ([{"frame": frames - 1, "translate": [-0.6, 0.3, 0.3], "rotate": [40, 0, 1, 0]}] if object_moves else [])}
    return {
        "rrcache_session": 1, "resolution": [48, 36], "frames": frames, "fps": 30, "background": [0.1, 0.1, 0.15, 1.0],
        "camera": {"fov": 45, "near": 0.1, "far": 50, "keyframes": [
            {"frame": 0, "eye": [0, 0.5, 3.2], "target": [0, 0, 0], "up": [0, 1, 0]},
            {"frame": frames - 1, "eye": end, "target": [0, 0, 0], "up": [0, 1, 0]}]},
        "light": {"color": [1, 1, 1], "orbit": {"center": [0, 0, 0], "radius": 4, "height": 3, "degrees_per_frame": 5}},
        "objects": [{"procedural": {"type": "icosphere", "radius": 0.8, "subdivisions": 3}}, box],
    }


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("render_cache")
    (folder / "lighting.glsl").write_text(LIGHTING)
    (folder / "shader.frag").write_text(SHADER)
    out = {}
    for name, cam, obj in (("still", False, False), ("moving", True, True)):
        path = folder / f"{name}.json"
        path.write_text(json.dumps(_session(cam, obj)))
        session = load_session(path)
        out[name] = (prepare_file(folder / "shader.frag", session), session)
    return out


# ---------------------------------------------------------------- every pixel: the original
@pytest.mark.parametrize("which", ["still", "moving"])
def test_a_budget_of_every_pixel_reproduces_the_original(scene, gl_ctx, which):
    prepared, session = scene[which]
    with Renderer(prepared, session) as original, \
            RenderCacheRenderer(prepared, session, settings=RenderCacheSettings(samples=1.0)) as rc:
        for index in range(session.frames):
            ref, got = original.render_frame(index), rc.render_frame(index)
            assert got.shaded == rc.pixels
            assert np.abs(got.image[..., :3] - ref.image[..., :3]).max() <= 1e-6, index
            assert got.filled["point"] == rc.pixels


def test_every_pixel_of_a_shader_that_discards_is_the_original(tmp_path, gl_ctx):
    """Where the shader discards, the original shows the background: so does the render cache
    (a background sample), and after it its points are background points."""
    shader, session_path = _cli_files(tmp_path)
    shader.write_text(SHADER.replace("    vec3 n = normalize(v_normal);", "    if (stripes > 0.8) discard;\n"
                                     "    vec3 n = normalize(v_normal);"))
    session = load_session(session_path)
    prepared = prepare_file(shader, session)
    with Renderer(prepared, session) as original, \
            RenderCacheRenderer(prepared, session, settings=RenderCacheSettings(samples=1.0)) as rc:
        for index in range(3):
            ref, got = original.render_frame(index), rc.render_frame(index)
            assert np.abs(got.image[..., :3] - ref.image[..., :3]).max() <= 1e-6
        # a pixel the shader discarded is not covered (no depth written): one background point each
        assert (rc.cache.object == BACKGROUND).sum() == rc.pixels - int(ref.mask.sum())
    whole = prepare_file(_cli_files(tmp_path / "plain")[0], session)
    with Renderer(whole, session) as plain:
        assert plain.render_frame(2).mask.sum() > ref.mask.sum()  # the shader did discard pixels


def test_a_small_budget_is_not_the_original_but_close(scene, gl_ctx):
    """The comparison's error is real: below every pixel the image differs, yet stays near the
    original (a broken projection would put it far off)."""
    prepared, session = scene["moving"]
    result = compare(prepared, session, range(session.frames), RenderCacheSettings(samples=0.1))
    assert 0.0 < result.mean_error < 0.1
    assert 15.0 < result.psnr < 60.0
    assert result.skip_first == 1 and result.budget == math.floor(0.1 * 48 * 36)
    assert set(result.stages) >= {"shade", "project", "z-buffer", "depth cull", "prefilter", "interpolate"}


# ---------------------------------------------------------------- projection
def _pinhole(points, eye_x, size, fov=90.0):
    """Pixel (col, row) of world points for a camera at (eye_x, 0, 0) looking down -z, by hand."""
    w, h = size
    f = 1.0 / math.tan(math.radians(fov) / 2)
    x, y, z = points[:, 0] - eye_x, points[:, 1], points[:, 2]
    col = (f * (w / h) ** -1 * x / -z * 0.5 + 0.5) * w
    row = (f * y / -z * 0.5 + 0.5) * h
    return np.floor(col).astype(int), np.floor(row).astype(int)


def test_a_point_cloud_moved_by_a_camera_step_lands_where_the_projection_says():
    size = (40, 30)
    rng = np.random.default_rng(3)
    pts = np.c_[rng.uniform(-1.5, 1.5, 400), rng.uniform(-1, 1, 400), rng.uniform(-6, -2, 400)].astype(np.float32)
    cache = PointCache(500)
    cache.insert(pts, rng.uniform(size=(400, 3)), np.full(400, STATIC, np.int16), frame=0)
    proj = perspective(90.0, size[0] / size[1], 0.1, 100.0)
    for step in (0.0, 0.25, -0.4):
        view = look_at([step, 0, 0], [step, 0, -1], [0, 1, 0])
        pix, depth, slots = Projector(500).project(cache, screen_matrix(proj @ view, size), size)
        col, row = _pinhole(pts.astype(np.float64), step, size)
        inside = (col >= 0) & (col < size[0]) & (row >= 0) & (row < size[1])
        assert slots.tolist() == np.flatnonzero(inside).tolist()
        assert pix.tolist() == (row * size[0] + col)[inside].tolist()
        assert np.allclose(depth, -pts[inside, 2], rtol=1e-5)  # the depth is the distance along the view axis
        owner, nearest = zbuffer(pix, depth, slots, size[0] * size[1])
        for p in np.unique(pix):  # the nearest point of each pixel wins
            here = slots[pix == p]
            assert owner[p] == here[np.argmin(-pts[here, 2])] and nearest[p] == np.min(-pts[here, 2])
    tiled = zbuffer(pix, depth, slots, size[0] * size[1], tiled=True, width=size[0], tile=8)
    assert np.array_equal(tiled[0], owner) and np.array_equal(tiled[1], nearest)


def test_points_follow_moving_objects_and_background_samples_come_back(scene, gl_ctx):
    prepared, session = scene["moving"]
    with RenderCacheRenderer(prepared, session, settings=RenderCacheSettings(samples=0.05, predict=False)) as rc:
        rc.render_frame(0)  # a cold start: one point per pixel
        cache = rc.cache
        assert rc.shader.moving == [1]
        on_box, background = cache.object == 1, cache.object == BACKGROUND
        assert on_box.any() and background.any() and (cache.object == STATIC).any()
        # at the frame they were shaded, every point projects back onto its own pixel
        screen, moving = rc._matrices(0)
        pix, _, slots = rc.projector.project(cache, screen, rc.size, moving)
        assert np.array_equal(pix, slots) and len(slots) == rc.pixels
        # two frames later: a box point lands where the box's new transform takes it
        w, h = rc.size
        cam = session.camera_at(2)
        vp = cam.projection(w / h) @ cam.view
        screen, moving = rc._matrices(2)
        pix, _, slots = rc.projector.project(cache, screen, rc.size, moving)
        box = np.flatnonzero(on_box)
        world0 = session.objects[1].model_matrix(0) @ np.vstack([cache.x[box], cache.y[box], cache.z[box], np.ones(len(box))])
        world2 = session.objects[1].model_matrix(2) @ np.linalg.inv(session.objects[1].model_matrix(0)) @ world0
        clip = vp @ world2
        col = np.floor((clip[0] / clip[3] * 0.5 + 0.5) * w).astype(int)
        row = np.floor((clip[1] / clip[3] * 0.5 + 0.5) * h).astype(int)
        landed = dict(zip(slots.tolist(), pix.tolist()))
        inside = (col >= 0) & (col < w) & (row >= 0) & (row < h)
        assert inside.sum() > 20
        for s, c, r in zip(box[inside], col[inside], row[inside]):
            assert landed[int(s)] == r * w + c
        assert not np.allclose(world0, world2)  # the box did move


# ---------------------------------------------------------------- filters
def test_depth_cull_rule():
    depth = np.full((5, 5), 2.0, np.float32)
    has = np.ones((5, 5), bool)
    depth[2, 2] = 2.4  # 20% behind a uniform neighbourhood: its mean is (8·2 + 2.4)/9
    keep = depth_cull(depth, has, 0.1)
    assert not keep[2, 2] and keep.sum() == 24
    assert depth_cull(depth, has, 0.2)[2, 2]  # within a 20% tolerance it stays
    exempt = np.zeros_like(has)
    exempt[2, 2] = True
    assert depth_cull(depth, has, 0.1, exempt)[2, 2]  # shaded for this frame: it stays
    holes = has.copy()
    holes[1:4, 1:4] = False
    holes[2, 2] = True  # alone: its mean is its own depth
    assert depth_cull(depth, holes, 0.0)[2, 2]


def test_interpolation_at_a_hole_and_the_prefilter_only_where_needed():
    h, w = 9, 15
    keep = np.zeros((h, w), bool)
    colors = np.zeros((3, h, w), np.float32)
    # a hole at (4, 3) with four points around it: left, right (weight 2 each) and two corners (1 each)
    for (r, c), value in {(4, 2): 0.2, (4, 4): 0.6, (3, 2): 1.0, (5, 4): 0.0}.items():
        keep[r, c] = True
        colors[:, r, c] = value
    previous = np.full((3, h, w), 0.5, np.float32)
    ages = np.full((h, w), 51.0, np.float32)
    image, priority, counts = reconstruct(colors, keep, ages, previous)
    expected = (2 * 0.2 + 2 * 0.6 + 1 * 1.0 + 1 * 0.0) / 6
    assert image[0, 4, 3] == pytest.approx(expected)
    # a pixel holding a point shows it exactly
    assert image[0, 4, 2] == pytest.approx(0.2) and image[0, 3, 2] == pytest.approx(1.0)
    # no point in its 3×3 but some in its 7×7: the uniform mean of those (columns 4..10, rows 1..7)
    assert image[0, 4, 7] == pytest.approx((0.6 + 0.0) / 2)
    assert image[0, 1, 4] == pytest.approx((0.2 + 0.6 + 1.0) / 3)  # rows -2..4: (5, 4) is outside
    # nothing within 7×7: the previous frame's colour
    assert image[0, 4, 14] == 0.5 and image[0, 0, 12] == 0.5
    assert counts["point"] == 4 and counts["empty"] > 0 and counts["prefiltered"] > 0
    # priority: the point's age / 255 where there is one, 1 elsewhere
    assert priority[4, 2] == pytest.approx(0.2) and priority[4, 3] == 1.0
    # with smoothing, a pixel holding a point takes the weighted mean around it
    smooth, _, _ = reconstruct(colors, keep, ages, previous, smooth=True)
    assert smooth[0, 4, 2] == pytest.approx((4 * 0.2 + 2 * 1.0) / 6)


def test_weighted3_and_box7_on_patterns():
    a = np.zeros((7, 7), np.float32)
    a[3, 3] = 1.0
    assert weighted3(a)[2:5, 2:5].tolist() == [[1, 2, 1], [2, 4, 2], [1, 2, 1]]
    sums, first = box7(a)
    assert first == 0 and sums.shape == (7, 7) and (sums == 1.0).all()  # every pixel sees the centre
    sums, first = box7(np.ones((3, 10, 12), np.float32), np.array([0, 4]))
    assert first == 0 and sums.shape == (3, 5, 12)
    assert sums[0, 0, 0] == 16 and sums[0, 4, 5] == 49 and sums[0, 3, 0] == 28


# ---------------------------------------------------------------- eviction
def test_eviction_ages_as_specified():
    cache = PointCache(10)
    slots = cache.insert(np.zeros((8, 3), np.float32), np.ones((8, 3), np.float32), np.full(8, STATIC), frame=0)
    assert slots.tolist() == list(range(8)) and cache.count() == 8
    inc = cache.age_increment(2)
    assert inc == pytest.approx(128 * 2 / 10)  # reaches 128 when the ring comes round (10 / 2 frames)
    age = cache.age_points(2, visible=np.arange(4), invisible_rate=3.0, changed=np.array([0]), change_penalty=50.0)
    assert age[1] == pytest.approx(inc) and age[5] == pytest.approx(3 * inc)  # visible / not visible
    assert age[0] == pytest.approx(inc + 50.0) and age[9] == 0.0  # colour change nearby / empty slot
    def frames(k):
        for _ in range(k):
            cache.age_points(2, visible=np.arange(4), invisible_rate=3.0)
            assert (cache.age <= 255.0).all()

    frames(2)  # 3 frames: the unseen ones are at 3 · 76.8 = 230.4, alive
    assert cache.live()[:8].all()
    frames(1)  # the fourth takes them past 255: evicted, their age back to 0
    live = cache.live()
    assert not live[4:8].any() and live[:4].all() and (cache.age[4:8] == 0).all()
    frames(5)  # 9 frames: the one near a colour change is at 50 + 9 · 25.6 >= 255, the others at 230.4
    live = cache.live()
    assert not live[0] and live[1:4].all()
    frames(1)
    assert cache.count() == 0  # 10 · 25.6 >= 255: a visible point lives out the ring's 5 frames twice over
    cache.insert(np.zeros((3, 3), np.float32), np.ones((3, 3), np.float32), np.full(3, STATIC), frame=1)
    # an evicted point is never projected
    cache.age_points(2)
    cache.x[9] = np.nan  # evicted
    pix, _, slots = Projector(10).project(cache, screen_matrix(perspective(60, 1, 0.1, 10) @ look_at([0, 0, 1], [0, 0, 0], [0, 1, 0]), (8, 8)), (8, 8))
    assert slots.tolist() == [0, 8]  # the ring wrote 8, 9, 0; 9 was evicted
    # the ring overwrites from where it stopped
    assert cache.insert(np.zeros((4, 3), np.float32), np.zeros((4, 3), np.float32), np.full(4, STATIC), 2).tolist() == [1, 2, 3, 4]
    assert cache.age[[1, 2, 3, 4]].tolist() == [0, 0, 0, 0] and cache.frame[4] == 2 and cache.age[0] > 0


# ---------------------------------------------------------------- the budget
@pytest.mark.parametrize("block", [1, 2, 4])
@pytest.mark.parametrize("predict", [True, False])
def test_the_sample_budget_is_never_exceeded(scene, gl_ctx, block, predict):
    prepared, session = scene["moving"]
    settings = RenderCacheSettings(samples=0.07, block=block, predict=predict)
    with RenderCacheRenderer(prepared, session, settings=settings) as rc:
        frames = [rc.render_frame(i) for i in range(session.frames)]
    budget = frames[0].budget
    assert budget == max(block * block, math.floor(0.07 * rc.pixels))
    assert frames[0].cold and frames[0].shaded == rc.pixels
    for f in frames[1:]:
        assert not f.cold and 0 < f.shaded <= budget and f.requested <= budget
        assert f.predicted <= budget // 2 + block * block
    if not predict:
        assert all(f.predicted == 0 for f in frames)


def test_dither_hands_out_the_budget_rounded_down():
    rng = np.random.default_rng(5)
    order = hilbert_order(37, 23)
    assert sorted(order.tolist()) == list(range(37 * 23))
    for budget in (1, 17, 100, 850):
        for prio in (rng.uniform(size=37 * 23), rng.uniform(size=37 * 23) ** 8, np.zeros(37 * 23)):
            chosen = dither(prio, order, budget, phase=float(rng.random()))
            assert len(chosen) == min(budget, 37 * 23) and len(np.unique(chosen)) == len(chosen)
    p = scaled(np.r_[100.0, np.ones(9)], 4.0)
    assert p.max() <= 1.0 and p.sum() == pytest.approx(4.0) and p[0] == 1.0
    # the dither follows the priority: a hot corner gets most of the samples
    prio = np.full(37 * 23, 0.01)
    prio.reshape(23, 37)[:8, :8] = 1.0
    chosen = dither(prio, order, 50, 0.5)
    assert ((chosen // 37 < 8) & (chosen % 37 < 8)).sum() >= 40


def test_predicted_requests_fill_empty_quarter_pixels_within_their_share():
    size, quarter = (40, 24), (10, 6)
    occupied = np.ones(60, bool)
    occupied[[0, 11, 59]] = False
    blocks = predicted_requests(occupied, quarter, size, 2, allowed=10)
    gw, _ = grid_size(size, 2)
    assert sorted(blocks.tolist()) == sorted([(2 // 2) * gw + 2 // 2, (6 // 2) * gw + 6 // 2, (22 // 2) * gw + 38 // 2])
    many = predicted_requests(np.zeros(60, bool), quarter, size, 2, allowed=7)
    assert len(many) == 7  # every 9th empty pixel in scanline order, at most 7
    assert len(blocks_to_pixels(many, size, 2)) == 28


def test_bad_settings_are_refused_with_the_knob_named():
    for kwargs, word in ((dict(samples=0.0), "samples"), (dict(samples=1.5), "samples"),
                         (dict(samples=float("nan")), "samples"), (dict(block=3), "block"),
                         (dict(points_per_pixel=0), "points_per_pixel"), (dict(cull=-1), "cull"),
                         (dict(min_points=0), "min_points"), (dict(predict_share=2), "predict_share")):
        with pytest.raises(RRCacheError, match=word):
            RenderCacheSettings(**kwargs).checked()


# ---------------------------------------------------------------- the command
def _cli_files(tmp_path):
    tmp_path.mkdir(parents=True, exist_ok=True)
    (tmp_path / "lighting.glsl").write_text(LIGHTING)
    (tmp_path / "shader.frag").write_text(SHADER)
    (tmp_path / "moving.json").write_text(json.dumps(_session(True, True)))
    return tmp_path / "shader.frag", tmp_path / "moving.json"


def test_render_method_render_cache_json_and_images(gl_ctx, tmp_path, capsys):
    from rrcache.cli import main

    shader, session = _cli_files(tmp_path)
    main(["render", str(shader), str(session), "--method", "render-cache", "--samples", "0.1", "--json",
          "--color-format", "rgba32f"])
    doc = json.loads(capsys.readouterr().out)
    assert doc["method"] == "render-cache" and doc["samples"] == 0.1 and doc["frames"] == 6
    assert doc["budget_pixels"] == math.floor(0.1 * 48 * 36) and 0 < doc["shaded_pixels"] <= doc["budget_pixels"]
    assert 0 < doc["mean_error"] < 0.1 and doc["psnr"] > 15 and doc["speedup"] > 0
    assert set(doc["stage_ms"]) >= {"shade", "z-buffer", "sampling"} and doc["color_format"] == "rgba32f"
    assert "hit_rate" not in doc and doc["settings"]["block"] == 2
    out = tmp_path / "frames"
    main(["render", str(shader), str(session), "--method", "render-cache", "--samples", "1", "--frames", "2",
          "--out", str(out)])
    text = capsys.readouterr().out
    assert "speed-up" in text and "budget 1728 pixels" in text and "ms per stage" in text
    assert (out / "frame_0001.exr").is_file() and (out / "original_0001.png").is_file()
    import OpenImageIO as oiio

    # every pixel shaded: the frame written is the original's
    frame, original = (oiio.ImageBuf(str(out / f"{n}_0001.png")).get_pixels() for n in ("frame", "original"))
    assert frame.shape == (36, 48, 4) and np.array_equal(frame, original)


@pytest.mark.parametrize("args, message", [
    (["--method", "render-cache", "--samples", "0"], "samples=0.0 is not a share"),
    (["--method", "render-cache", "--samples", "nan"], "is not a share"),
    (["--method", "render-cache", "--node", "n1"], "--node chooses a reprojection-cache variant"),
    (["--samples", "0.05"], "give it with --method render-cache"),
])
def test_render_method_bad_input_is_one_line_exit_2(tmp_path, capsys, args, message):
    from rrcache.cli import main

    shader, session = _cli_files(tmp_path)
    with pytest.raises(SystemExit) as info:
        main(["render", str(shader), str(session), "--frames", "2"] + args)
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "Traceback" not in err


def test_the_equal_time_tool_writes_its_table_sheet_and_stages(gl_ctx, tmp_path):
    """``python -m rrcache.bench.render_cache equal-time`` on the small scene: the reprojection
    cache, dynamic resolution and the render cache in one table (shapes only: timings are not
    asserted), the per-stage table, the contact sheet."""
    from rrcache.bench import render_cache as bench
    from rrcache.pipeline import load_for_session

    shader, session = _cli_files(tmp_path)
    work = load_for_session(shader, load_session(session))
    (node,) = [n.id for n in work.table.nodes if n.text == "m.albedo * (0.15 + 0.85 * diffuse)"]
    assert bench.main(["equal-time", "--choice", f"{shader}:{session}={node}:4", "--search-frames", "3",
                       "--out", str(tmp_path / "out")]) == 0
    doc = json.loads((tmp_path / "out" / "equal_time.json").read_text())
    (scene,) = doc["scenes"]
    assert [r["method"] for r in scene["rows"]] == ["reprojection cache (ours)", "dynamic resolution",
                                                     "render cache (Walter 2002)"]
    assert scene["texts"] == ["m.albedo * (0.15 + 0.85 * diffuse)"] and scene["sheet_frame"] == 3
    assert set(scene["sheet"]) == {"reprojection cache", "dynamic resolution", "render cache"}
    assert scene["rows"][2]["stages"]["shade"] > 0 and scene["rows"][0]["speedup"] == scene["target_speedup"]
    md = (tmp_path / "out" / "equal_time.md").read_text()
    assert "| shader (48×36, 6 frames) | render cache (Walter 2002)" in md and "| shader | " in md
    assert (tmp_path / "out" / "contact_sheet.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(RRCacheError, match="not a choice"):
        bench.Choice.parse("n66")
    with pytest.raises(RRCacheError, match="'blurry' is not a cache filter"):
        bench.Choice.parse("n66:4@two-pass/blurry")


def test_the_render_cache_is_a_registered_kind_that_is_never_compiled():
    from rrcache import kinds
    from rrcache.selection import Selection

    part = RenderCacheSettings(samples=0.05, block=1)
    kind = kinds.get("render-cache")
    assert kinds.kind_of((part,)) is kind and kind.part is RenderCacheSettings
    assert kind.training("anything", None) == [] and not kind.tables
    sel = Selection((part,), 0.0, float("nan"), 1.0, label="render cache")
    assert kind.cells(sel) == ("render cache: 5% of the pixels per frame in 1×1 blocks", "–")
    assert kind.summary(sel)["samples"] == 0.05
    (back,) = kinds.parts_from_json(kinds.parts_to_json((part,)), "parts")
    assert back == part and back.key() == part.key()
    for call in (lambda: kinds.spec_for(sel), lambda: kind.compile(None, None)):
        with pytest.raises(RRCacheError, match="an alternative to compare"):
            call()
    for data, where in (({"kind": "render-cache", "samples": 2.0}, "parts[0]"),
                        ({"kind": "render-cache", "samples": 0.1, "blocks": 2}, "parts[0]"),
                        ({"kind": "render-cache", "samples": "0.1"}, "parts[0].samples"),
                        ({"kind": "render-cache", "predict": 1}, "parts[0].predict")):
        with pytest.raises(RRCacheError) as info:
            kinds.parts_from_json([data], "parts")
        assert str(info.value).startswith(where), str(info.value)
