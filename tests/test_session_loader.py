"""load_session end to end: the fixture session, assets, uniforms, hash and every kind of bad input."""
import copy
import json
import os

import numpy as np
import OpenImageIO as oiio
import pytest
import trimesh

from rrcache.errors import AssetError, SessionError
from rrcache.session import MeshData, Session, load_session

FIXTURE = os.path.join(os.path.dirname(__file__), "data", "sessions", "minimal.json")
BASE = {
    "rrcache_session": 1, "resolution": [32, 16], "frames": 10,
    "camera": {"keyframes": [{"frame": 0, "eye": [0, 0, 5]}]},
    "objects": [{"procedural": {"type": "box"}}],
}


def write(tmp_path, doc, name="s.json"):
    path = tmp_path / name
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc, indent=1))
    return str(path)


def session(tmp_path, **changes):
    doc = copy.deepcopy(BASE)
    doc.update(changes)
    return load_session(write(tmp_path, doc))


def error(tmp_path, doc, kind=SessionError):
    with pytest.raises(kind) as info:
        load_session(write(tmp_path, doc))
    assert info.value.path.endswith("s.json")
    return info.value


def png(path, value=128, size=(2, 3)):
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(size[0], size[1], 3, oiio.UINT8))
    out.write_image(np.full((size[1], size[0], 3), value, np.uint8))
    out.close()


def test_fixture_session():
    s = load_session(FIXTURE)
    assert isinstance(s, Session) and s.name == "minimal"
    assert s.resolution == (64, 48) and s.frames == 4 and s.fps == 30.0 and s.aspect == 64 / 48
    cam = s.camera_at(0)
    assert np.allclose(cam.eye, [0, 1, 4]) and cam.fov == 45 and (cam.near, cam.far) == (0.1, 100)
    assert np.allclose(s.camera_at(3).eye, [4, 1, 0]) and np.allclose(s.camera_at(99).eye, [4, 1, 0])
    assert cam.view.shape == (4, 4) and cam.projection(s.aspect).dtype == np.float64
    assert np.allclose(s.light_at(0).position, [0, 3, 5]) and np.allclose(s.light_at(45).position, [5, 3, 0])
    assert np.allclose(s.light_at(0).color, [1, 1, 1])
    (obj,) = s.objects
    assert obj.name == "torus" and isinstance(obj.mesh, MeshData) and obj.mesh.face_count == 256
    assert np.allclose(obj.model_matrix(0), np.eye(4))
    assert np.allclose(obj.model_matrix(3)[:3, :3] @ [0, 0, 1], [1, 0, 0])
    u = s.uniform_values(1)
    assert u == {"u_shininess": 32.0, "u_octaves": 5, "u_wave": pytest.approx(1 / 3)}
    assert type(u["u_octaves"]) is int and type(u["u_shininess"]) is float
    assert s.background == (0.0, 0.0, 0.0, 0.0) and s.time_at(15) == 0.5
    with pytest.raises(TypeError):
        s.camera_at(1.5)


def test_defaults_orbit_camera_and_headlight(tmp_path):
    s = session(tmp_path, camera={"orbit": {"radius": 2, "height": 1, "degrees_per_frame": 90, "start_degrees": 90}},
                background=[0.1, 0.2, 0.3, 1])
    assert np.allclose(s.camera_at(0).eye, [2, 1, 0]) and np.allclose(s.camera_at(1).eye, [0, 1, -2])
    assert np.allclose(s.light_at(1).position, s.camera_at(1).eye)  # no light: a headlight
    assert s.fps == 30.0 and s.background == (0.1, 0.2, 0.3, 1.0) and s.textures == {}


def test_object_transforms_and_names(tmp_path):
    objects = [
        {"procedural": {"type": "box"}, "keyframes": [
            {"frame": 0, "translate": [0, 0, 0], "scale": 1},
            {"frame": 10, "translate": [10, 0, 0], "scale": [1, 2, 3], "rotate": [90, 0, 0, 1]}]},
        {"procedural": {"type": "box"}},
        {"name": "floor", "procedural": {"type": "plane"}},
    ]
    s = session(tmp_path, objects=objects)
    assert [o.name for o in s.objects] == ["box", "box_2", "floor"]
    m = s.objects[0].model_matrix(5)
    assert np.allclose(m[:3, 3], [5, 0, 0])
    assert np.allclose(s.objects[0].model_matrix(10) @ [1, 0, 0, 1], [10, 1, 0, 1])
    assert np.allclose(s.objects[0].model_matrix(10) @ [0, 0, 1, 0], [0, 0, 3, 0])


def test_uniform_kinds(tmp_path):
    uniforms = {
        "u_flag": True, "u_count": 3, "u_color": [1, 0.5, 0], "u_ivec": [1, 2],
        "u_bvec": [True, False], "u_mat": [[1, 2], [3, 4]], "u_flat": [1.0, 0, 0, 1],
        "u_step": {"keyframes": [{"frame": 0, "value": 1}, {"frame": 4, "value": 7}]},
        "u_mix": {"keyframes": [{"frame": 0, "value": 0}, {"frame": 4, "value": 2.0}]},
        "u_vec": {"keyframes": [{"frame": 0, "value": [0, 0, 0.0]}, {"frame": 2, "value": [1, 2, 4.0]}]},
        "u_on": {"keyframes": [{"frame": 0, "value": False}, {"frame": 2, "value": True}]},
    }
    s = session(tmp_path, uniforms=uniforms)
    u = s.uniform_values(1)
    assert u["u_flag"] is True and type(u["u_count"]) is int
    assert u["u_color"].dtype == np.float64 and u["u_ivec"].dtype == np.int64 and u["u_bvec"].dtype == np.bool_
    assert u["u_mat"].tolist() == [[1, 3], [2, 4]]  # columns [1,2] and [3,4]
    assert u["u_flat"].shape == (4,)
    assert u["u_step"] == 1 and type(u["u_step"]) is int and s.uniform_values(4)["u_step"] == 7
    assert u["u_mix"] == pytest.approx(0.5)
    assert u["u_vec"].tolist() == [0.5, 1.0, 2.0]
    assert u["u_on"] is False and s.uniform_values(2)["u_on"] is True
    u["u_color"][0] = 99  # values are copies
    assert s.uniform_values(1)["u_color"][0] == 1


def test_mesh_and_texture_assets_and_hash(tmp_path):
    (tmp_path / "meshes").mkdir()
    trimesh.creation.icosphere(subdivisions=1).export(tmp_path / "meshes" / "ball.obj")
    png(tmp_path / "albedo.png")
    for k in range(6):
        png(tmp_path / f"f{k}.png", value=40 * k, size=(2, 2))
    doc = dict(copy.deepcopy(BASE), objects=[{"mesh": "meshes/ball.obj"}], textures={
        "u_albedo": "albedo.png",
        "u_data": {"path": "albedo.png", "filter": "nearest", "wrap": "clamp"},
        "u_env": {"faces": [f"f{k}.png" for k in range(6)], "filter": "mipmap"}})
    path = write(tmp_path, doc)
    s = load_session(path)
    assert s.objects[0].name == "ball" and s.objects[0].mesh.face_count == 80
    t = s.textures
    assert t["u_albedo"].kind == "2d" and t["u_albedo"].data.shape == (3, 2, 3)
    # no filter given: mipmapped, as an application sets up a texture sampled with implicit LOD
    assert (t["u_albedo"].filter, t["u_albedo"].wrap) == ("mipmap", "repeat")
    assert (t["u_data"].filter, t["u_data"].wrap) == ("nearest", "clamp")
    env = t["u_env"]
    assert env.kind == "cube" and env.data.shape == (6, 2, 2, 3) and env.wrap == "clamp"
    assert np.allclose(env.data[:, 0, 0, 0], [40 * k / 255 for k in range(6)])
    h1 = s.hash
    assert load_session(path).hash == h1
    png(tmp_path / "albedo.png", value=129)
    h2 = load_session(path).hash
    assert h2 != h1
    doc["uniforms"] = {"u_x": 1.0}
    assert load_session(write(tmp_path, doc)).hash not in (h1, h2)


def test_invalid_json_reports_line_and_column(tmp_path):
    e = error(tmp_path, '{\n  "rrcache_session": 1,\n  "frames": 3\n  "resolution": [1, 1]\n}')
    assert "line 4, column 3" in str(e) and (e.line, e.col) == (4, 3)
    assert "s.json" in str(e)
    assert "duplicate key 'frames'" in str(error(tmp_path, '{"rrcache_session": 1, "frames": 1, "frames": 2}'))
    assert "NaN" in str(error(tmp_path, '{"rrcache_session": 1, "frames": NaN}'))
    e = error(tmp_path, json.dumps(dict(BASE, fps=12345)).replace("12345", "1e999"))
    assert "out of range" in e.message and e.json_path == "fps"


def test_version_errors(tmp_path):
    e = error(tmp_path, {k: v for k, v in BASE.items() if k != "rrcache_session"})
    assert "rrcache_session" in str(e) and "missing" in str(e)
    e = error(tmp_path, dict(BASE, rrcache_session=2))
    assert e.json_path == "rrcache_session" and "version 2" in str(e) and "version 1" in e.hint
    assert "JSON object" in str(error(tmp_path, "[1, 2]"))


def test_schema_violation_names_json_path(tmp_path):
    doc = copy.deepcopy(BASE)
    doc["camera"]["keyframes"] = [{"frame": 0, "eye": [0, 0, 5]}, {"frame": 1, "eye": [0, 0, 4]},
                                  {"frame": 2, "eye": [0, "x", 4]}]
    e = error(tmp_path, doc)
    assert e.json_path == "camera.keyframes[2].eye[1]" and "expected a number" in e.message
    e = error(tmp_path, dict(BASE, resolution=[32, 0]))
    assert e.json_path == "resolution[1]"
    e = error(tmp_path, dict(BASE, camera={"orbit": {"radius": 1}, "keyframes": [{"frame": 0, "eye": [0, 0, 1]}]}))
    assert e.json_path == "camera" and "only one" in e.message


def test_unknown_key_suggests_closest(tmp_path):
    doc = copy.deepcopy(BASE)
    doc["camera"]["keyframes"][0]["traget"] = [0, 0, 0]
    e = error(tmp_path, doc)
    assert e.json_path == "camera.keyframes[0].traget" and "unknown key 'traget'" in e.message
    assert "did you mean 'target'" in e.hint
    e = error(tmp_path, dict(BASE, textures={"u_t": {"path": "a.png", "wrapp": "clamp"}}))
    assert e.json_path == "textures.u_t.wrapp" and "'wrap'" in e.hint


def test_unsorted_keyframes(tmp_path):
    doc = copy.deepcopy(BASE)
    doc["objects"][0]["keyframes"] = [{"frame": 0}, {"frame": 5}, {"frame": 5}]
    e = error(tmp_path, doc)
    assert e.json_path == "objects[0].keyframes[2].frame" and "sorted" in e.message
    doc = dict(BASE, uniforms={"u_a": {"keyframes": [{"frame": 3, "value": 1}, {"frame": 1, "value": 2}]}})
    assert error(tmp_path, doc).json_path == "uniforms.u_a.keyframes[1].frame"


def test_inconsistent_values(tmp_path):
    assert error(tmp_path, dict(BASE, camera={"near": 5, "far": 1, "orbit": {"radius": 3}})).json_path == "camera.far"
    e = error(tmp_path, dict(BASE, camera={"keyframes": [{"frame": 0, "eye": [0, 0, 0]}]}))
    assert e.json_path == "camera.keyframes[0]" and "coincide" in e.message
    e = error(tmp_path, dict(BASE, uniforms={"u_time": 1.0}))
    assert e.json_path == "uniforms.u_time" and "built-in" in e.message
    e = error(tmp_path, dict(BASE, uniforms={"u_v": {"keyframes": [{"frame": 0, "value": [1, 2]}, {"frame": 1, "value": 3}]}}))
    assert e.json_path == "uniforms.u_v.keyframes[1].value"
    objects = [{"procedural": {"type": "box"}, "keyframes": [{"frame": 0, "scale": [1, 0, 1]}]}]
    assert error(tmp_path, dict(BASE, objects=objects)).json_path == "objects[0].keyframes[0].scale"
    objects = [{"name": "a", "procedural": {"type": "box"}}, {"name": "a", "procedural": {"type": "box"}}]
    assert error(tmp_path, dict(BASE, objects=objects)).json_path == "objects[1].name"


def test_missing_mesh_and_textures(tmp_path):
    doc = dict(BASE, objects=[{"procedural": {"type": "box"}}, {"mesh": "meshes/none.obj"}])
    e = error(tmp_path, doc, AssetError)
    assert e.json_path == "objects[1].mesh" and str(tmp_path / "meshes" / "none.obj") in str(e)
    e = error(tmp_path, dict(BASE, textures={"u_t": "missing.png"}), AssetError)
    assert e.json_path == "textures.u_t" and "not found" in e.message and "missing.png" in e.message
    (tmp_path / "bad.png").write_bytes(b"\x89PNG but not really" * 4)
    e = error(tmp_path, dict(BASE, textures={"u_t": {"path": "bad.png"}}), AssetError)
    assert e.json_path == "textures.u_t.path" and "cannot" in e.message
    png(tmp_path / "ok.png", size=(2, 2))
    faces = ["ok.png"] * 5 + ["bad.png"]
    e = error(tmp_path, dict(BASE, textures={"u_env": {"faces": faces}}), AssetError)
    assert e.json_path == "textures.u_env.faces[5]"
    e = error(tmp_path, dict(BASE, textures={"u_env": {"path": "ok.png", "kind": "cube"}}), AssetError)
    assert "6:1" in e.message


def test_missing_session_file(tmp_path):
    with pytest.raises(SessionError, match="cannot read"):
        load_session(tmp_path / "nope.json")


def test_committed_asset_fixture():
    s = load_session(os.path.join(os.path.dirname(FIXTURE), "assets.json"))
    tetra = s.objects[0].mesh
    assert s.objects[0].name == "tetra" and tetra.face_count == 4 and tetra.texcoords is None
    tri = tetra.positions[tetra.indices].astype(np.float64)
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(np.sum(normals * (tri.mean(axis=1) - [0.25, 0.25, 0.25]), axis=1) > 0)  # outward
    checker = s.textures["u_checker"]
    assert checker.size == (4, 4) and checker.channels == 3 and checker.filter == "nearest"
    assert checker.data[0, 0, 0] == 0.0 and checker.data[0, 1, 0] == 1.0
