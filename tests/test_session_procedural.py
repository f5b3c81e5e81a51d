"""Procedural meshes: counts, watertightness, normals, texcoords and tangents."""
import numpy as np
import pytest
import trimesh

from rrcache.errors import SessionError
from rrcache.session.procedural import MAX_FACES, face_count, make_mesh

CLOSED = [
    ({"type": "icosphere", "subdivisions": 2}, 320),
    ({"type": "torus", "major_segments": 12, "minor_segments": 6}, 144),
    ({"type": "box", "size": [1, 2, 3]}, 12),
    ({"type": "cylinder", "segments": 10}, 40),
    ({"type": "revolve"}, None),
    ({"type": "torus_knot", "segments": 64, "tube_segments": 8}, 1024),
]
OPEN = [({"type": "plane", "subdivisions": 3}, 18),
        ({"type": "revolve", "profile": [[0.5, 0], [0.3, 1]], "segments": 8}, 16)]


def _welded(mesh):
    t = trimesh.Trimesh(mesh.positions, mesh.indices, process=False)
    t.merge_vertices(merge_tex=True, merge_norm=True)
    return t


def _check_attributes(m):
    n = len(m.positions)
    assert m.positions.dtype == np.float32 and m.indices.dtype == np.uint32
    assert m.normals.shape == (n, 3) and m.texcoords.shape == (n, 2) and m.tangents.shape == (n, 4)
    assert np.allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-5)
    assert np.allclose(np.linalg.norm(m.tangents[:, :3], axis=1), 1.0, atol=1e-5)
    assert np.all(np.abs(np.sum(m.tangents[:, :3] * m.normals, axis=1)) < 1e-4)
    assert set(np.unique(m.tangents[:, 3])) <= {-1.0, 1.0}
    assert m.texcoords.min() >= -1e-6 and m.texcoords[:, 1].max() <= 1 + 1e-6
    assert m.texcoords[:, 0].max() <= 1.25  # icosphere faces across the seam run past u = 1
    assert m.indices.max() < n
    # counter-clockwise winding agrees with the normals
    tri = m.positions[m.indices].astype(np.float64)
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    agree = np.sum(fn * m.normals[m.indices].sum(axis=1), axis=1)
    assert np.mean(agree > 0) > 0.99


@pytest.mark.parametrize("spec,faces", CLOSED, ids=lambda x: x["type"] if isinstance(x, dict) else "")
def test_closed_shapes_are_watertight(spec, faces):
    m = make_mesh(spec)
    _check_attributes(m)
    if faces is not None:
        assert m.face_count == faces
    assert m.face_count <= face_count(spec)
    welded = _welded(m)
    assert welded.is_watertight and welded.is_winding_consistent
    assert welded.volume > 0  # outward facing


@pytest.mark.parametrize("spec,faces", OPEN, ids=["plane", "revolve_open"])
def test_open_shapes(spec, faces):
    m = make_mesh(spec)
    _check_attributes(m)
    assert m.face_count == faces == face_count(spec)
    assert not _welded(m).is_watertight


def test_default_sizes():
    assert make_mesh({"type": "icosphere"}).face_count == 1280
    r = np.linalg.norm(make_mesh({"type": "icosphere", "radius": 2.5}).positions, axis=1)
    assert np.allclose(r, 2.5, atol=1e-5)
    lo, hi = make_mesh({"type": "box", "size": [1, 2, 3]}).bounds()
    assert np.allclose(lo, [-0.5, -1, -1.5]) and np.allclose(hi, [0.5, 1, 1.5])
    lo, hi = make_mesh({"type": "cylinder", "radius": 2, "height": 4}).bounds()
    assert np.allclose(hi, [2, 2, 2], atol=1e-5) and np.allclose(lo, [-2, -2, -2], atol=1e-5)
    plane = make_mesh({"type": "plane", "size": [4, 2]})
    assert np.allclose(plane.normals, [0, 1, 0]) and np.allclose(plane.bounds()[1], [2, 0, 1])


def test_torus_knot_default_is_detailed():
    m = make_mesh({"type": "torus_knot"})
    assert m.face_count == 73728
    assert _welded(m).is_watertight


def test_revolve_reversed_profile_still_faces_out():
    profile = [[0, 1], [0.5, 1], [0.5, 0], [0, 0]]  # top to bottom: a closed can
    m = make_mesh({"type": "revolve", "profile": profile, "segments": 16})
    _check_attributes(m)
    welded = _welded(m)
    assert welded.is_watertight and welded.volume == pytest.approx(np.pi * 0.25, rel=0.05)


def test_bad_specs_raise_session_error():
    with pytest.raises(SessionError, match="did you mean 'radius'"):
        make_mesh({"type": "icosphere", "radiu": 1})
    with pytest.raises(SessionError, match="did you mean 'torus'"):
        make_mesh({"type": "toruss"})
    with pytest.raises(SessionError, match="faces"):
        make_mesh({"type": "torus", "major_segments": 4096, "minor_segments": 4096})
    with pytest.raises(SessionError, match="empty"):
        make_mesh({"type": "revolve", "profile": [[0, 0], [0, 1]]})
    assert face_count({"type": "torus", "major_segments": 4096, "minor_segments": 4096}) > MAX_FACES
