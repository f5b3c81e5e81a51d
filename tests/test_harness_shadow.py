"""Shadow maps in the harness, glslViewer's way: a session light with ``"shadow_map"`` gives the
shader ``u_lightShadowMap``, ``u_lightMatrix``, ``v_lightCoord`` and the ``LIGHT_SHADOWMAP*``
defines; the shadow falls where the geometry says it must, for the original and the cached
variants alike."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

from rrcache.errors import SessionError
from rrcache.compiler.prepared import prepare_file
from rrcache.harness.renderer import render
from rrcache.session import load_session
from rrcache.session.shadow import light_matrix

SHADER = os.path.join(os.path.dirname(__file__), "data", "shaders", "glslviewer_shadow.frag")


def write_session(tmp_path, shadow=True, frames=2):
    light = {"keyframes": [{"frame": 0, "position": [6, 10, 0]}]}
    if shadow:
        light["shadow_map"] = {"size": 256}
    doc = {
        "rrcache_session": 1, "resolution": [64, 64], "frames": frames,
        "camera": {"fov": 40, "near": 1, "far": 30,
                   "keyframes": [{"frame": 0, "eye": [0, 8, 0.01], "target": [0, 0, 0], "up": [0, 0, -1]}]},
        "light": light,
        "objects": [
            {"name": "floor", "procedural": {"type": "plane", "size": 4}},
            {"name": "box", "procedural": {"type": "box", "size": 1},
             "keyframes": [{"frame": 0, "translate": [0, 0.5, 0]}]},
        ],
    }
    path = tmp_path / "shadow.json"
    path.write_text(json.dumps(doc))
    return load_session(path)


def pixel_of(session, world):
    cam = session.camera_at(0)
    clip = cam.projection(session.aspect) @ cam.view @ np.array([*world, 1.0])
    ndc = clip[:3] / clip[3]
    w, h = session.resolution
    return int((1 - (ndc[1] * 0.5 + 0.5)) * h), int((ndc[0] * 0.5 + 0.5) * w)


def test_light_matrix_maps_the_scene_into_the_unit_cube(tmp_path):
    session = write_session(tmp_path)
    m = light_matrix(session.light_at(0).position, session.shadow_map, session, 0)
    for corner in ([2, 0, 2], [-2, 0, -2], [0.5, 1, 0.5], [-2, 0, 2]):
        p = m @ np.array([*corner, 1.0])
        assert np.all((p[:3] / p[3] > 0) & (p[:3] / p[3] < 1))


def test_defines_follow_the_session(tmp_path):
    with_map = prepare_file(SHADER, write_session(tmp_path))
    assert with_map.defines["LIGHT_SHADOWMAP"] == "u_lightShadowMap"
    assert float(with_map.defines["LIGHT_SHADOWMAP_SIZE"]) == 256.0
    assert "v_lightCoord" in with_map.inputs
    without = prepare_file(SHADER, write_session(tmp_path, shadow=False))
    assert "LIGHT_SHADOWMAP" not in without.defines and "v_lightCoord" not in without.inputs


def test_the_shadow_falls_behind_the_box(gl_ctx, tmp_path):
    session = write_session(tmp_path)
    image = render(SHADER, session, frames=1).frames[0].image[..., 0]
    # the box's top edge at x = -0.5, height 1, seen from the light at (6, 10, 0): its shadow
    # reaches x = -1.1 on the floor
    shaded, lit, beside = (pixel_of(session, p) for p in ([-0.8, 0, 0], [1.2, 0, 0], [-0.8, 0, 1.2]))
    assert image[shaded] < 0.15
    assert image[lit] > 0.5 and image[beside] > 0.5
    # without the shadow map the same shader (no LIGHT_SHADOWMAP) lights that spot
    plain = render(SHADER, write_session(tmp_path, shadow=False), frames=1).frames[0].image[..., 0]
    assert plain[shaded] > 0.5


def test_a_shader_needing_a_shadow_map_names_the_light(gl_ctx, tmp_path):
    src = tmp_path / "needs.frag"
    src.write_text("uniform sampler2D u_lightShadowMap; varying vec2 v_texcoord;\n"
                   "void main() { gl_FragColor = texture2D(u_lightShadowMap, v_texcoord); }\n")
    with pytest.raises(SessionError) as err:
        render(str(src), write_session(tmp_path, shadow=False), frames=1)
    assert "shadow_map" in str(err.value) and "light" in str(err.value)


@pytest.mark.parametrize("algorithm", ["three-pass", "two-pass", "one-pass"])
def test_cached_variants_receive_the_shadow_map(gl_ctx, tmp_path, algorithm):
    from rrcache.compiler import instance
    from rrcache.harness.cached import compare
    from rrcache.pipeline import load_for_session

    session = write_session(tmp_path, frames=3)
    work = load_for_session(SHADER, session)
    # the diffuse term: every pass that shades still samples the shadow map itself
    node = next(n for n in work.table.excluded if n.text.startswith("max(dot("))
    variant = instance(work.table, node.id, algorithm)
    assert any("u_lightMatrix" in names for names in variant.uniforms.values())
    result = compare(variant, session, work.prepared, range(3), period=1)
    assert all(f.mean_error <= 1e-6 for f in result.frames)
    # and the shadow is there in the cached frames too (the original's image is the reference)
    assert result.frames[-1].covered > 1000


@pytest.mark.parametrize("spec,where", [({"size": 8}, "light.shadow_map.size"),
                                         ({"size": 64, "extent": -1}, "light.shadow_map.extent"),
                                         ({"size": 64, "blur": 1}, "light.shadow_map")])
def test_bad_shadow_map_settings_name_the_json_path(tmp_path, spec, where):
    session = write_session(tmp_path)
    doc = dict(session.document)
    doc["light"] = {**doc["light"], "shadow_map": spec}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(SessionError) as err:
        load_session(path)
    assert where in str(err.value)
