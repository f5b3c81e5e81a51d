"""View and projection matrices (OpenGL conventions, float64, column vectors).

>>> v = look_at([0, 0, 5], [0, 0, 0], [0, 1, 0])
>>> (v @ [0, 0, 0, 1]).tolist()
[0.0, 0.0, -5.0, 1.0]
"""
from __future__ import annotations

import math

import numpy as np


def _normalize(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else v


def look_at(eye, target, up) -> np.ndarray:
    """gluLookAt: world → eye space; ``target`` lands on the -Z axis, ``up`` projects onto +Y.

    When ``up`` is parallel to the view direction another axis (the world axis least aligned
    with the view direction) is used instead, so an interpolated camera never yields NaNs.
    ``eye == target`` looks down -Z.

    >>> look_at([0, 0, 0], [0, 0, -1], [0, 1, 0]).tolist() == np.eye(4).tolist()
    True
    """
    eye = np.asarray(eye, dtype=np.float64)
    f = np.asarray(target, dtype=np.float64) - eye
    if not np.linalg.norm(f) > 1e-12:
        f = np.array([0.0, 0.0, -1.0])
    f = _normalize(f)
    up = np.asarray(up, dtype=np.float64)
    s = np.cross(f, up)
    if np.linalg.norm(s) < 1e-9 * max(1.0, float(np.linalg.norm(up))):
        s = np.cross(f, np.eye(3)[int(np.argmin(np.abs(f)))])
    s = _normalize(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov_y_degrees: float, aspect: float, near: float, far: float) -> np.ndarray:
    """gluPerspective: eye space → clip space; depth ``-near`` → NDC -1, ``-far`` → NDC +1.

    >>> p = perspective(90, 1, 1, 10); c = p @ [0, 0, -1, 1]; float(c[2] / c[3])
    -1.0
    """
    if not (0 < fov_y_degrees < 180 and aspect > 0 and 0 < near < far):
        raise ValueError(f"bad perspective: fov={fov_y_degrees} aspect={aspect} near={near} far={far}")
    f = 1.0 / math.tan(math.radians(fov_y_degrees) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def orbit_position(center, radius: float, height: float, degrees: float) -> np.ndarray:
    """A point on a horizontal circle around ``center``: angle 0 is +Z, 90° is +X; ``height``
    is added to ``center``'s y.

    >>> orbit_position([0, 0, 0], 2, 1, 90).round(9).tolist()
    [2.0, 1.0, 0.0]
    """
    a = math.radians(degrees)
    c = np.asarray(center, dtype=np.float64)
    return c + np.array([radius * math.sin(a), height, radius * math.cos(a)])


def trs_matrix(translate, rotation: np.ndarray, scale) -> np.ndarray:
    """T·R·S from a translation 3-vector, a 3×3 rotation and a scale 3-vector."""
    m = np.eye(4)
    m[:3, :3] = np.asarray(rotation, dtype=np.float64) * np.asarray(scale, dtype=np.float64)[None, :]
    m[:3, 3] = translate
    return m
