"""Mesh files through trimesh: every format, attributes, scenes, and failures."""
import numpy as np
import pytest
import trimesh

from rrcache.session.meshes import MeshLoadError, load_mesh_file


@pytest.mark.parametrize("ext", ["obj", "ply", "stl", "glb", "off"])
def test_each_format_round_trips(tmp_path, ext):
    src = trimesh.creation.icosphere(subdivisions=1, radius=2.0)
    path = tmp_path / f"sphere.{ext}"
    src.export(path)
    m = load_mesh_file(str(path))
    assert m.face_count == 80
    assert m.positions.dtype == np.float32 and m.indices.dtype == np.uint32
    assert np.allclose(np.linalg.norm(m.positions, axis=1), 2.0, atol=1e-4)
    assert np.allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-5)
    # normals (from the file or computed) point outward
    assert np.mean(np.sum(m.normals * m.positions, axis=1) > 0) > 0.99


def test_obj_keeps_file_normals_texcoords_and_gets_tangents(tmp_path):
    path = tmp_path / "tri.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                    "vn 0 0.6 0.8\nvn 0 0.6 0.8\nvn 0 0.6 0.8\nf 1/1/1 2/2/2 3/3/3\n")
    m = load_mesh_file(str(path))
    assert np.allclose(m.normals, [0, 0.6, 0.8])
    assert np.allclose(m.texcoords, [[0, 0], [1, 0], [0, 1]])
    assert m.tangents.shape == (3, 4)
    t = m.tangents[:, :3]
    assert np.allclose(np.sum(t * m.normals, axis=1), 0, atol=1e-6)
    assert np.all(t[:, 0] > 0.99) and np.all(m.tangents[:, 3] == 1.0)  # u grows along +X
    assert m.colors is None


def test_obj_without_normals_or_texcoords(tmp_path):
    path = tmp_path / "quad.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
    m = load_mesh_file(str(path))
    assert np.allclose(m.normals, [0, 0, 1])
    assert m.texcoords is None and m.tangents is None


def test_ply_vertex_colors(tmp_path):
    src = trimesh.creation.box()
    src.visual.vertex_colors = np.tile([255, 0, 51, 255], (len(src.vertices), 1)).astype(np.uint8)
    path = tmp_path / "box.ply"
    src.export(path)
    m = load_mesh_file(str(path))
    assert m.colors.shape == (8, 4)
    assert np.allclose(m.colors, [1.0, 0.0, 0.2, 1.0], atol=1e-6)


def test_glb_scene_is_flattened_with_transforms(tmp_path):
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box(), node_name="a",
                       transform=trimesh.transformations.translation_matrix([5, 0, 0]))
    scene.add_geometry(trimesh.creation.icosphere(subdivisions=0), node_name="b")
    path = tmp_path / "scene.glb"
    scene.export(path)
    m = load_mesh_file(str(path))
    assert m.face_count == 12 + 20
    lo, hi = m.bounds()
    sphere_min_x = trimesh.creation.icosphere(subdivisions=0).vertices[:, 0].min()
    assert hi[0] == pytest.approx(5.5) and lo[0] == pytest.approx(sphere_min_x, abs=1e-5)


def test_failures(tmp_path):
    with pytest.raises(MeshLoadError, match="not found"):
        load_mesh_file(str(tmp_path / "missing.obj"))
    with pytest.raises(MeshLoadError, match="unsupported mesh format"):
        load_mesh_file(str(tmp_path / "thing.xyz"))
    bad = tmp_path / "bad.glb"
    bad.write_bytes(b"\x00garbage" * 20)
    with pytest.raises(MeshLoadError):
        load_mesh_file(str(bad))
    empty = tmp_path / "empty.obj"
    empty.write_text("v 0 0 0\nv 1 0 0\n")
    with pytest.raises(MeshLoadError, match="no triangles"):
        load_mesh_file(str(empty))


# --- the mesh loader's own output never reaches the user unfiltered (issue 14) ------------------

TEXTURED_PLY = """ply
format ascii 1.0
comment TextureFile missing_texture.png
element vertex 3
property float x
property float y
property float z
property float texture_u
property float texture_v
element face 1
property list uchar int vertex_indices
end_header
0 0 0 0 0
1 0 0 1 0
0 1 0 0 1
3 0 1 2
"""


def _garbage_stl(path):
    # 'solid' then bytes that are neither a binary STL of this size nor UTF-8 text
    path.write_bytes(b"solid x\n" + bytes(range(128, 256)) * 4)
    return path


def _session(tmp_path, mesh):
    import json

    doc = {"rrcache_session": 1, "resolution": [8, 8], "frames": 1,
           "camera": {"keyframes": [{"frame": 0, "eye": [0, 0, 3], "target": [0, 0, 0]}]},
           "objects": [{"mesh": mesh}]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    return path


def test_missing_texture_is_a_note_not_a_traceback(tmp_path, capfd):
    from rrcache.session import load_session

    (tmp_path / "tri.ply").write_text(TEXTURED_PLY)
    m = load_mesh_file(str(tmp_path / "tri.ply"))
    assert m.face_count == 1 and m.texcoords is not None
    assert len(m.notes) == 1 and "missing_texture.png" in m.notes[0] and "\n" not in m.notes[0]
    session = load_session(_session(tmp_path, "tri.ply"))
    assert session.notes == [f"{tmp_path / 'tri.ply'}: {m.notes[0]}"]
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_render_prints_the_note_once(tmp_path):
    import subprocess
    import sys

    (tmp_path / "tri.ply").write_text(TEXTURED_PLY)
    session = _session(tmp_path, "tri.ply")
    (tmp_path / "s.frag").write_text("#version 330\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n")
    proc = subprocess.run([sys.executable, "-m", "rrcache", "render", str(tmp_path / "s.frag"), str(session),
                           "--json"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr and "unable to load image" not in proc.stderr
    notes = [line for line in proc.stderr.splitlines() if "missing_texture.png" in line]
    assert len(notes) == 1 and notes[0].startswith("note: ")


def test_garbage_stl_is_one_line(tmp_path, capfd):
    path = _garbage_stl(tmp_path / "bad.stl")
    with pytest.raises(MeshLoadError) as info:
        load_mesh_file(str(path))
    assert "\n" not in str(info.value)
    out, err = capfd.readouterr()
    assert "Traceback" not in out + err


def test_missing_optional_package_is_named(tmp_path, monkeypatch, capfd):
    """Without charset-normalizer (an optional dependency of trimesh), a non-UTF-8 STL says which
    package to install, as an AssetError at the session's mesh."""
    import sys

    from rrcache.errors import AssetError
    from rrcache.session import load_session

    monkeypatch.setitem(sys.modules, "charset_normalizer", None)
    _garbage_stl(tmp_path / "bad.stl")
    with pytest.raises(AssetError) as info:
        load_session(_session(tmp_path, "bad.stl"))
    msg = str(info.value)
    assert "objects[0].mesh" in msg and "bad.stl" in msg and "pip install charset-normalizer" in msg
    assert "ModuleNotFoundError" not in msg and "\n" not in msg
    out, err = capfd.readouterr()
    assert "Traceback" not in out + err


def test_optional_dependencies_are_declared():
    import pathlib
    import re

    text = (pathlib.Path(__file__).resolve().parents[1] / "pyproject.toml").read_text()
    deps = text.split("dependencies = [", 1)[1].split("]", 1)[0]
    names = {re.split(r"[<>=\[ ;]", line.strip().strip('",'))[0].lower()
             for line in deps.splitlines() if line.strip().startswith('"')}
    assert {"trimesh", "charset-normalizer", "pillow"} <= names
