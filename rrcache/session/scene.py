"""Build the animated parts of a session from its (schema-valid) JSON: camera, light, objects.

Every builder returns a function ``frame -> value``; the errors the schema cannot express
(unsorted keyframes, far <= near, a degenerate view, a zero scale) are SessionErrors with the
session file and the JSON path.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from rrcache.errors import SessionError
from rrcache.session.camera import orbit_position, trs_matrix
from rrcache.session.keyframes import RotationTrack, Track
from rrcache.session.model import Camera, Light, ShadowMap
from rrcache.session.validation import json_path


def check_sorted(keyframes: list, file: str, base: list) -> None:
    """Keyframe frames must strictly increase; the error points at the first one out of order."""
    for k in range(1, len(keyframes)):
        a, b = keyframes[k - 1]["frame"], keyframes[k]["frame"]
        if b <= a:
            what = "repeats" if a == b else "comes after"
            raise SessionError(f"keyframes must be sorted by frame: frame {b} {what} frame {a}", file,
                               json_path(base + [k, "frame"]), "list keyframes in increasing frame order")


def channel(keyframes: list, key: str, default, transform=np.asarray) -> Track:
    """A track of the keyframes that set ``key`` (a constant ``default`` when none does)."""
    have = [kf for kf in keyframes if key in kf]
    if not have:
        return Track([0], [np.asarray(default, dtype=np.float64)])
    return Track([kf["frame"] for kf in have], [np.asarray(transform(kf[key]), dtype=np.float64) for kf in have])


def _orbit(spec: dict) -> Callable[[int], np.ndarray]:
    center = np.asarray(spec.get("center", [0.0, 0.0, 0.0]), dtype=np.float64)
    radius, height = float(spec["radius"]), float(spec.get("height", 0.0))
    start, step = float(spec.get("start_degrees", 0.0)), float(spec.get("degrees_per_frame", 1.0))
    return lambda frame: orbit_position(center, radius, height, start + step * frame)


#: the largest coordinate a camera may have: beyond it a 32-bit GPU float cannot place anything
#: near the camera (and squaring it overflows even 64-bit floats near 1e154)
MAX_COORDINATE = 1e15


def _check_view(eye, target, up, file: str, where: str) -> None:
    for name, value in (("eye", eye), ("target", target), ("up", up)):
        big = float(np.max(np.abs(np.asarray(value, float))))
        if not big <= MAX_COORDINATE:
            raise SessionError(f"the camera's {name} has a coordinate of magnitude {big:.3g}, beyond the "
                               f"{MAX_COORDINATE:.0e} a GPU's 32-bit floats can place", file, where,
                               "scale the scene down (orbit radius, eye and target positions)")
    f = np.asarray(target, float) - np.asarray(eye, float)
    scale = max(1.0, float(np.abs(eye).max()), float(np.abs(target).max()))
    if np.linalg.norm(f) <= 1e-9 * scale:
        raise SessionError("the eye and the target coincide, so there is no view direction", file, where)
    if np.linalg.norm(up) == 0.0:
        raise SessionError("the up vector is zero", file, where)
    if np.linalg.norm(np.cross(f / np.linalg.norm(f), np.asarray(up, float) / np.linalg.norm(up))) < 1e-6:
        raise SessionError("the up vector is parallel to the view direction", file, where,
                           "give an 'up' that is not along eye→target")


def _first_bad_view(eyes: np.ndarray, targets: np.ndarray, ups: np.ndarray):
    """The index of the first view (rows of n×3 arrays) :func:`_check_view` refuses, or None: the
    same tests for every keyframe at once (one keyframe at a time took a millisecond each)."""
    with np.errstate(all="ignore"):
        big = np.max(np.abs(np.concatenate([eyes, targets, ups], axis=1)), axis=1)
        f = targets - eyes
        scale = np.maximum(1.0, np.maximum(np.abs(eyes).max(axis=1), np.abs(targets).max(axis=1)))
        fn, un = np.linalg.norm(f, axis=1), np.linalg.norm(ups, axis=1)
        cross = np.linalg.norm(np.cross(f / fn[:, None], ups / un[:, None]), axis=1)
        ok = (big <= MAX_COORDINATE) & (fn > 1e-9 * scale) & (un != 0.0) & (cross >= 1e-6)
    bad = np.flatnonzero(~ok)
    return int(bad[0]) if len(bad) else None


def camera_function(cam: dict, file: str) -> Callable[[int], Camera]:
    """frame → Camera; ``fov`` 45, ``near`` 0.1, ``far`` 100 and ``up`` [0, 1, 0] by default."""
    fov, near, far = float(cam.get("fov", 45.0)), float(cam.get("near", 0.1)), float(cam.get("far", 100.0))
    if far <= near:
        raise SessionError(f"far ({far:g}) must be greater than near ({near:g})", file, "camera.far")
    up0 = np.asarray(cam.get("up", [0.0, 1.0, 0.0]), dtype=np.float64)
    if "orbit" in cam:
        pos = _orbit(cam["orbit"])
        center = np.asarray(cam["orbit"].get("center", [0.0, 0.0, 0.0]), dtype=np.float64)
        _check_view(pos(0), center, up0, file, "camera.orbit")
        return lambda frame: Camera(pos(frame), center.copy(), up0.copy(), fov, near, far)
    kfs = cam["keyframes"]
    check_sorted(kfs, file, ["camera", "keyframes"])
    eye, target = channel(kfs, "eye", [0.0, 0.0, 1.0]), channel(kfs, "target", [0.0, 0.0, 0.0])
    up = channel(kfs, "up", up0)
    views = [np.array([track.at(kf["frame"]) for kf in kfs], dtype=np.float64) for track in (eye, target, up)]
    k = _first_bad_view(*views)
    if k is not None:
        _check_view(views[0][k], views[1][k], views[2][k], file, json_path(["camera", "keyframes", k]))
    return lambda frame: Camera(eye.at(frame), target.at(frame), up.at(frame), fov, near, far)


def light_function(light: dict | None, camera: Callable[[int], Camera], file: str) -> Callable[[int], Light]:
    """frame → Light; without a ``light`` key the light sits at the camera's eye (a headlight)."""
    light = light or {}
    color = np.asarray(light.get("color", [1.0, 1.0, 1.0]), dtype=np.float64)
    if "orbit" in light:
        pos = _orbit(light["orbit"])
    elif "keyframes" in light:
        check_sorted(light["keyframes"], file, ["light", "keyframes"])
        pos = channel(light["keyframes"], "position", [0.0, 0.0, 0.0]).at
    else:
        pos = lambda frame: camera(frame).eye  # noqa: E731
    spec = light.get("shadow_map")
    shadow = None
    if spec is not None:
        target = spec.get("target")
        shadow = ShadowMap(int(spec["size"]), tuple(float(v) for v in target) if target is not None else None,
                           float(spec["extent"]) if "extent" in spec else None)
    return lambda frame: Light(np.asarray(pos(frame), dtype=np.float64), color.copy(), shadow)


def _scale3(value) -> np.ndarray:
    return np.broadcast_to(np.asarray(value, dtype=np.float64), (3,)).copy()


def model_function(keyframes: list, file: str, index: int) -> Callable[[int], np.ndarray]:
    """frame → T·R·S for ``objects[index].keyframes`` (identity when there are none)."""
    base = ["objects", index, "keyframes"]
    check_sorted(keyframes, file, base)
    for k, kf in enumerate(keyframes):
        if "rotate" in kf and kf["rotate"][0] != 0 and not any(kf["rotate"][1:]):
            raise SessionError("rotation axis is zero", file, json_path(base + [k, "rotate"]),
                               "rotate is [degrees, axis_x, axis_y, axis_z]")
        if "scale" in kf and not np.all(_scale3(kf["scale"])):
            raise SessionError("scale must not be 0 (the model matrix would be singular)", file,
                               json_path(base + [k, "scale"]))
    translate = channel(keyframes, "translate", [0.0, 0.0, 0.0])
    scale = channel(keyframes, "scale", [1.0, 1.0, 1.0], _scale3)
    have = [kf for kf in keyframes if "rotate" in kf]
    rotate = RotationTrack([kf["frame"] for kf in have] or [0], [kf["rotate"] for kf in have] or [[0, 0, 1, 0]])
    return lambda frame: trs_matrix(translate.at(frame), rotate.at(frame), scale.at(frame))
