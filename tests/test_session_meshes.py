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
