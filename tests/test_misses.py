"""Why pixels miss (rrcache.runtime.misses), rendered for real.

A ball over a floor seen by a fixed camera, the ball sliding to the right, and the same scene with
the camera panning: each pixel's cause is checked against what the scene says it must be. The
ball's pixels come from the depth of the frame against the depth of the floor alone (the same
session without the ball).
"""
from __future__ import annotations

import json

import numpy as np

from rrcache.harness.cached import CachedRenderer
from rrcache.pipeline import load_for_session, variant_for
from rrcache.runtime.misses import MISS_CAUSES
from rrcache.runtime.refresh import refresh_mask
from rrcache.session import load_session

SIZE = (64, 48)
#: a refresh period no frame reaches: only the geometry misses
NEVER = 2 ** 30

SHADER = """#version 330
in vec4 v_position;
in vec3 v_normal;
uniform vec3 u_light;
out vec4 fragColor;
void main() {
    vec3 n = normalize(v_normal);
    float d = max(dot(n, normalize(u_light - v_position.xyz)), 0.0);
    vec3 albedo = 0.5 + 0.5 * sin(v_position.xyz * 7.0);
    fragColor = vec4(albedo * (0.2 + d), 1.0);
}
"""


def _load(tmp_path, name, ball_moves=False, camera_pans=False, ball=True):
    eye1, target1 = ([0.6, 2.0, 4.0], [0.6, 0, 0]) if camera_pans else ([0, 2.0, 4.0], [0, 0, 0])
    objects = [{"name": "floor", "procedural": {"type": "plane", "size": [6, 6], "subdivisions": 1},
                "double_sided": True, "keyframes": [{"frame": 0, "translate": [0, 0, 0]}]}]
    if ball:
        objects.append({"name": "ball", "procedural": {"type": "icosphere", "radius": 0.6, "subdivisions": 3},
                        "keyframes": [{"frame": 0, "translate": [-0.4, 0.6, 0]},
                                      {"frame": 5, "translate": [0.4 if ball_moves else -0.4, 0.6, 0]}]})
    doc = {"rrcache_session": 1, "resolution": list(SIZE), "frames": 6, "fps": 30,
           "camera": {"fov": 45, "near": 0.1, "far": 20,
                      "keyframes": [{"frame": 0, "eye": [0, 2.0, 4.0], "target": [0, 0, 0], "up": [0, 1, 0]},
                                    {"frame": 5, "eye": eye1, "target": target1, "up": [0, 1, 0]}]},
           "light": {"color": [1, 1, 1], "keyframes": [{"frame": 0, "position": [2, 4, 3]}]},
           "objects": objects}
    shader = tmp_path / "ball.frag"
    shader.write_text(SHADER)
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(doc))
    session = load_session(path)
    work = load_for_session(shader, session)
    return session, work, work.table.nodes[-1].id   # the final colour


def _run(session, work, node, period, filter_="bilinear", frames=4):
    """(clock, frame, depth) per frame, the misses sorted by cause."""
    variant = variant_for(work, node, "three-pass", filter=filter_)
    out = []
    with CachedRenderer(variant, session, work.prepared, SIZE, period=period, miss_causes=True) as cached:
        for i in range(frames):
            frame = cached.render_frame(i)
            out.append((cached.runtime.clock - 1, frame, cached.runtime.read_depth()))
    return out


def _dilate(mask: np.ndarray, r: int) -> np.ndarray:
    out = mask.copy()
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out |= np.roll(np.roll(mask, dy, 0), dx, 1)
    return out


def _outline(mask: np.ndarray) -> np.ndarray:
    return mask & ~(np.roll(mask, 1, 0) & np.roll(mask, -1, 0) & np.roll(mask, 1, 1) & np.roll(mask, -1, 1))


def test_the_first_frame_is_empty_and_a_still_scene_misses_only_by_refresh(gl_ctx, tmp_path):
    session, work, node = _load(tmp_path, "still")
    frames = _run(session, work, node, period=4)
    first = frames[0][1].miss_causes
    assert first["pixels"]["empty"] == first["covered"] > 1000
    for clock, frame, _depth in frames[1:]:
        counts = frame.miss_causes["pixels"]
        assert {c: n for c, n in counts.items() if n} == {"refresh": frame.misses}
        # exactly the pixels the refresh rule picks this frame (row 0 = top in both)
        refreshed = refresh_mask(SIZE, 4, "random", 0, 4, clock)[::-1] & frame.mask
        assert frame.misses == int(refreshed.sum()) > 0
        assert not (frame.hit_map & refreshed).any()
        blocks = frame.miss_causes["blocks"]
        assert blocks["refresh"] > 0 and sum(blocks.values()) == blocks["refresh"]


def test_a_moving_ball_misses_along_its_outline_and_where_it_uncovers_the_floor(gl_ctx, tmp_path):
    session, work, node = _load(tmp_path, "moving", ball_moves=True)
    floor_session, floor_work, floor_node = _load(tmp_path, "floor", ball=False)
    floor = [depth for _c, _f, depth in _run(floor_session, floor_work, floor_node, NEVER)]
    runs = {f: _run(session, work, node, NEVER, f) for f in ("bilinear", "edge", "plane")}
    balls = [depth < floor_depth - 1e-5 for (_c, _f, depth), floor_depth in zip(runs["bilinear"], floor)]
    totals = {f: {c: sum(fr.miss_causes["pixels"][c] for _c, fr, _d in runs[f][1:]) for c in MISS_CAUSES}
              for f in runs}
    for f in runs:  # nothing refreshed, nothing came in from off screen: the ball's doing only
        assert totals[f]["refresh"] == totals[f]["outside"] == totals[f]["empty"] == 0
        assert totals[f]["disocclusion"] > 0
    # the band: misses that a texel of the same surface could have served; edge serves some of
    # them (within twice the tolerance of the depth here), plane every one (the depth predicted
    # at each texel)
    assert totals["bilinear"]["band"] > totals["edge"]["band"] and totals["plane"]["band"] == 0
    for k in range(1, len(balls)):
        (_c, bil, _d), (_c2, edge, _d2) = runs["bilinear"][k], runs["edge"][k]
        ball, last = balls[k], balls[k - 1]
        assert ball.sum() > 100 and (ball ^ last).any()
        # every miss is on the ball's outline or where it was and is no more (or the reverse)
        outline, outline_last = _outline(ball), _outline(last)
        near = _dilate(outline | (ball ^ last), 2)
        assert not (bil.mask & ~bil.hit_map & ~near).any()
        # the band hugs the outlines; the floor the ball uncovered is a disocclusion
        band = bil.miss_map == MISS_CAUSES.index("band")
        assert band.any() and not (band & ~_dilate(outline | outline_last, 2)).any()
        uncovered = last & ~_dilate(ball, 2) & ~_dilate(outline_last, 2)
        assert (bil.miss_map[uncovered] == MISS_CAUSES.index("disocclusion")).all()
        # the edge filter hits wherever bilinear hits, and more
        assert not (bil.hit_map & ~edge.hit_map & bil.mask).any()
        assert edge.hits > bil.hits


def test_panning_brings_surfaces_in_from_outside_the_screen(gl_ctx, tmp_path):
    session, work, node = _load(tmp_path, "pan", camera_pans=True)
    for _clock, frame, _depth in _run(session, work, node, NEVER)[1:]:
        counts = frame.miss_causes["pixels"]
        assert counts["outside"] > 0 and counts["refresh"] == counts["empty"] == 0
        # the camera moves right: what is new comes in at the right edge
        outside = frame.miss_map == MISS_CAUSES.index("outside")
        columns = np.nonzero(outside.any(axis=0))[0]
        assert columns.min() >= SIZE[0] - 4 and outside[:, -1][frame.mask[:, -1]].all()
        share = frame.miss_causes["blocks"]["outside"] / frame.miss_causes["covered_blocks"]
        assert 0 < share < 0.5


def test_plane_with_the_depth_packed_in_the_payload_hits_alike(gl_ctx, tmp_path):
    """``instance(..., filter="plane", pack_depth=True)``: the texel test reads the payload's
    channel instead of the inverse-depth texture, and hits the same pixels with the same colours."""
    from rrcache.compiler import instance

    session, work, _node = _load(tmp_path, "packed", ball_moves=True)
    node = [n for n in work.table.nodes if n.type in ("float", "vec2", "vec3")][-1]  # a free channel
    runs = []
    for packed in (False, True):
        variant = instance(work.table, node.id, "three-pass", "plane", "f4", work.vertex, pack_depth=packed)
        assert (variant.depth_channel is not None) == packed
        with CachedRenderer(variant, session, work.prepared, SIZE, period=NEVER, hit_maps=True) as cached:
            runs.append([cached.render_frame(i) for i in range(4)])
    for plain, packed in list(zip(*runs))[1:]:  # frame 0 has no cache
        assert (plain.hit_map == packed.hit_map).all() and plain.hits > 0
        assert np.abs(plain.image - packed.image).max() <= 2e-4
