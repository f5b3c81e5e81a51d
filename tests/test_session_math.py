"""Keyframe interpolation, rotations, orbits and the camera matrices."""
import math

import numpy as np
import pytest

from rrcache.session.camera import look_at, orbit_position, perspective, trs_matrix
from rrcache.session.keyframes import RotationTrack, Track, axis_angle_matrix


def test_linear_interpolation_and_hold_outside():
    t = Track([2, 6, 10], [[0.0, 10.0], [4.0, 10.0], [4.0, 0.0]])
    assert t.at(0).tolist() == [0.0, 10.0]
    assert t.at(2).tolist() == [0.0, 10.0]
    assert t.at(4).tolist() == [2.0, 10.0]
    assert t.at(8).tolist() == [4.0, 5.0]
    assert t.at(10).tolist() == [4.0, 0.0]
    assert t.at(1000).tolist() == [4.0, 0.0]


def test_consecutive_keyframes_make_a_cut():
    t = Track([0, 4, 5], [[0.0], [0.0], [9.0]])
    assert t.at(4)[0] == 0.0 and t.at(5)[0] == 9.0


def test_step_track_holds_until_next_keyframe():
    t = Track([0, 10], [1, 5], step=True)
    assert [int(t.at(f)) for f in (0, 5, 9, 10, 20)] == [1, 1, 1, 5, 5]


def test_track_rejects_unsorted_frames():
    with pytest.raises(ValueError):
        Track([3, 1], [[0.0], [1.0]])


def test_rotation_same_axis_lerps_angle_through_full_turns():
    r = RotationTrack([0, 8], [[0, 0, 1, 0], [720, 0, 1, 0]])
    # 720° over 8 frames = 90° per frame about +Y: +Z goes to +X after one frame
    assert np.allclose(r.at(1) @ [0, 0, 1], [1, 0, 0], atol=1e-12)
    assert np.allclose(r.at(2) @ [0, 0, 1], [0, 0, -1], atol=1e-12)
    assert np.allclose(r.at(4), np.eye(3), atol=1e-12)


def test_rotation_different_axes_slerps_to_endpoints():
    r = RotationTrack([0, 10], [[90, 1, 0, 0], [90, 0, 0, 1]])
    assert np.allclose(r.at(0), axis_angle_matrix(90, [1, 0, 0]))
    assert np.allclose(r.at(10), axis_angle_matrix(90, [0, 0, 1]))
    mid = r.at(5)
    assert np.allclose(mid @ mid.T, np.eye(3), atol=1e-12) and math.isclose(np.linalg.det(mid), 1.0)


def test_axis_angle_right_handed():
    assert np.allclose(axis_angle_matrix(90, [0, 0, 2]) @ [1, 0, 0], [0, 1, 0])
    assert np.allclose(axis_angle_matrix(30, [0, 0, 0]), np.eye(3))


def test_orbit_position():
    assert np.allclose(orbit_position([1, 2, 3], 2, 0.5, 0), [1, 2.5, 5])
    assert np.allclose(orbit_position([0, 0, 0], 2, 0, 90), [2, 0, 0])
    assert np.allclose(orbit_position([0, 0, 0], 2, 0, 180), [0, 0, -2])


def test_look_at_maps_target_to_minus_z_and_up_to_plus_y():
    eye, target = np.array([3.0, 2.0, -1.0]), np.array([0.5, 0.0, 1.0])
    v = look_at(eye, target, [0, 1, 0])
    t = v @ np.append(target, 1.0)
    assert np.allclose(t[:2], 0, atol=1e-12) and t[2] == pytest.approx(-np.linalg.norm(target - eye))
    assert np.allclose(v @ np.append(eye, 1.0), [0, 0, 0, 1], atol=1e-12)
    assert np.allclose(v[:3, :3] @ v[:3, :3].T, np.eye(3), atol=1e-12)
    assert (v[:3, :3] @ [0, 1, 0])[1] > 0


def test_look_at_survives_up_parallel_to_view():
    v = look_at([0, 5, 0], [0, 0, 0], [0, 1, 0])
    assert np.all(np.isfinite(v))
    assert np.allclose(v @ [0, 0, 0, 1], [0, 0, -5, 1], atol=1e-12)


def test_perspective_maps_near_and_far_to_ndc_bounds():
    p = perspective(60, 16 / 9, 0.5, 50)
    for z, ndc in ((-0.5, -1.0), (-50.0, 1.0)):
        c = p @ [0, 0, z, 1]
        assert c[2] / c[3] == pytest.approx(ndc)
    # the top edge of the frustum at the near plane maps to y = 1
    top = 0.5 * math.tan(math.radians(30))
    c = p @ [top * 16 / 9, top, -0.5, 1]
    assert c[0] / c[3] == pytest.approx(1.0) and c[1] / c[3] == pytest.approx(1.0)
    with pytest.raises(ValueError):
        perspective(45, 1, 2, 1)


def test_trs_order_scales_then_rotates_then_translates():
    m = trs_matrix([1, 0, 0], axis_angle_matrix(90, [0, 0, 1]), [2, 1, 1])
    assert np.allclose(m @ [1, 0, 0, 1], [1, 2, 0, 1])
