"""Keyframe tracks: linear interpolation between keyframes, held constant outside them.

Two keyframes on consecutive frames make a cut. A *step* track holds each keyframe's value
until the next keyframe (used for int and bool uniforms).

>>> t = Track([0, 10], [[0.0], [1.0]])
>>> t.at(5).tolist(), t.at(-3).tolist(), t.at(99).tolist()
([0.5], [0.0], [1.0])
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np


class Track:
    """Values (K×…) at strictly increasing integer ``frames`` (K of them)."""

    def __init__(self, frames: Sequence[int], values, step: bool = False):
        self.frames = np.asarray(frames, dtype=np.int64)
        self.values = np.asarray(values)
        if self.frames.ndim != 1 or len(self.frames) == 0 or len(self.frames) != len(self.values):
            raise ValueError("a track needs one value per keyframe and at least one keyframe")
        if np.any(np.diff(self.frames) <= 0):
            raise ValueError("keyframe frames must strictly increase")
        self.step = step

    def bracket(self, frame: int) -> tuple[int, int, float]:
        """(i, j, t): the value at ``frame`` is ``(1-t)·values[i] + t·values[j]``."""
        k = int(np.searchsorted(self.frames, frame, side="right"))
        if k == 0:
            return 0, 0, 0.0
        if k == len(self.frames):
            return k - 1, k - 1, 0.0
        i, j = k - 1, k
        if self.step:
            return i, i, 0.0
        return i, j, (frame - self.frames[i]) / float(self.frames[j] - self.frames[i])

    def at(self, frame: int):
        i, j, t = self.bracket(frame)
        if i == j or t == 0.0:
            return self.values[i].copy() if isinstance(self.values[i], np.ndarray) else self.values[i]
        return (1.0 - t) * self.values[i] + t * self.values[j]


def axis_angle_matrix(degrees: float, axis) -> np.ndarray:
    """Rotation matrix of ``degrees`` about ``axis`` (right-handed; a zero axis gives identity).

    >>> axis_angle_matrix(90, [0, 0, 1]).round(9) @ [1, 0, 0]
    array([0., 1., 0.])
    """
    axis = np.asarray(axis, dtype=np.float64)
    n = float(np.linalg.norm(axis))
    if n == 0.0:
        return np.eye(3)
    x, y, z = axis / n
    a = math.radians(degrees)
    c, s, C = math.cos(a), math.sin(a), 1.0 - math.cos(a)
    return np.array([
        [c + x * x * C, x * y * C - z * s, x * z * C + y * s],
        [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
        [z * x * C - y * s, z * y * C + x * s, c + z * z * C],
    ])


def _quat(degrees: float, axis: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(axis))
    if n == 0.0:
        return np.array([1.0, 0.0, 0.0, 0.0])
    h = math.radians(degrees) / 2.0
    return np.concatenate([[math.cos(h)], math.sin(h) * axis / n])


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _slerp(a: np.ndarray, b: np.ndarray, t: float) -> np.ndarray:
    d = float(np.dot(a, b))
    if d < 0.0:
        b, d = -b, -d
    if d > 0.9995:
        q = a + t * (b - a)
        return q / np.linalg.norm(q)
    th = math.acos(d)
    return (math.sin((1 - t) * th) * a + math.sin(t * th) * b) / math.sin(th)


class RotationTrack:
    """``rotate`` keyframes ``[degrees, ax, ay, az]`` → 3×3 matrices.

    Between two keyframes about the same (normalised) axis the *angle* is interpolated linearly,
    so 0° → 720° spins twice; between keyframes about different axes the rotations are
    interpolated by quaternion slerp (shortest path).

    >>> r = RotationTrack([0, 4], [[0, 0, 1, 0], [360, 0, 1, 0]])
    >>> (r.at(1) @ [0, 0, 1]).round(9).tolist()
    [1.0, 0.0, 0.0]
    """

    def __init__(self, frames: Sequence[int], values):
        self.track = Track(frames, np.asarray(values, dtype=np.float64))

    def at(self, frame: int) -> np.ndarray:
        i, j, t = self.track.bracket(frame)
        a, b = self.track.values[i], self.track.values[j]
        if i == j or t == 0.0:
            return axis_angle_matrix(a[0], a[1:])
        na, nb = np.linalg.norm(a[1:]), np.linalg.norm(b[1:])
        if na > 0 and nb > 0 and np.allclose(a[1:] / na, b[1:] / nb, atol=1e-9):
            return axis_angle_matrix((1 - t) * a[0] + t * b[0], a[1:])
        return _quat_matrix(_slerp(_quat(a[0], a[1:]), _quat(b[0], b[1:]), t))
