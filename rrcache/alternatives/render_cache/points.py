"""The point cache: a fixed number of shaded 3D points, replaced as a ring, aged and evicted.

Each point has a position (``x``, ``y``, ``z``, float32), the ``object`` it lies on (``STATIC``:
a static object, the position is in world space; ``BACKGROUND``: no surface, the position is far
along the sample's view ray; ``k >= 0``: object ``k`` of the session moves, the position is in its
object space, so the point follows the object's transform), a ``color`` (RGB float32, planar:
``color[c, slot]``), an ``age``
(float32 in [0, 255], the paper's byte) and the ``frame`` it was shaded in. An empty or evicted
slot has a NaN ``x``, which every projection leaves out.

New points go into the next slots of the ring (:meth:`PointCache.insert`), overwriting the oldest.
:meth:`PointCache.age_points` is the paper's §3.4: every live point ages by ``128 · new / capacity``
per frame, so that on average a point is 128 when the ring overwrites it; a point that was not
visible in the last frame ages ``invisible_rate`` times as fast, a point near a detected colour
change gains ``change_penalty`` more; at 255 it is evicted.

>>> cache = PointCache(4)
>>> cache.insert(np.zeros((3, 3), np.float32), np.ones((3, 3), np.float32), np.full(3, STATIC), frame=0).tolist()
[0, 1, 2]
>>> cache.live().tolist()
[True, True, True, False]
>>> cache.age_points(new=2, visible=np.array([0, 1]), invisible_rate=2.0).tolist()  # 128·2/4 = 64
[64.0, 64.0, 128.0, 0.0]
"""
from __future__ import annotations

from typing import Optional

import numpy as np

#: the largest age; a point reaching it is evicted (the paper's byte)
MAX_AGE = 255.0
#: the age a point should reach, on average, when the ring overwrites it (the paper's 128)
TARGET_AGE = 128.0

#: the ``object`` of a point on a static object (world-space position)
STATIC = -1
#: the ``object`` of a background point (no surface: far along the view ray)
BACKGROUND = -2


class PointCache:
    """``capacity`` points in structure-of-arrays form (see the module docstring)."""

    def __init__(self, capacity: int):
        if capacity < 1:
            raise ValueError(f"a point cache needs at least one slot, got {capacity}")
        self.capacity = int(capacity)
        c = self.capacity
        self.x = np.full(c, np.nan, np.float32)
        self.y = np.zeros(c, np.float32)
        self.z = np.zeros(c, np.float32)
        self.object = np.full(c, STATIC, np.int16)
        self.color = np.zeros((3, c), np.float32)  # planar: one row per channel
        self.age = np.zeros(c, np.float32)
        self.frame = np.full(c, -1, np.int32)
        self.head = 0  # the next slot the ring writes

    def clear(self) -> None:
        """Empty every slot (a cold start)."""
        self.x[:] = np.nan
        self.age[:] = 0.0
        self.frame[:] = -1
        self.object[:] = STATIC
        self.head = 0

    def live(self) -> np.ndarray:
        """Which slots hold a point."""
        return ~np.isnan(self.x)

    def count(self) -> int:
        return int(self.live().sum())

    def insert(self, positions: np.ndarray, colors: np.ndarray, objects: np.ndarray, frame: int) -> np.ndarray:
        """Write ``n`` new points (age 0) into the next ``n`` slots of the ring; returns their slots.
        More points than the capacity: the last ``capacity`` are kept (the ring wraps over the others)."""
        n = int(len(positions))
        if n == 0:
            return np.zeros(0, np.int64)
        if n > self.capacity:
            positions, colors, objects = positions[-self.capacity:], colors[-self.capacity:], objects[-self.capacity:]
            self.head = (self.head + n - self.capacity) % self.capacity
            n = self.capacity
        slots = (self.head + np.arange(n)) % self.capacity
        positions = np.asarray(positions, np.float32)
        self.x[slots], self.y[slots], self.z[slots] = positions[:, 0], positions[:, 1], positions[:, 2]
        self.color[:, slots] = np.asarray(colors, np.float32).T
        self.object[slots] = objects
        self.age[slots] = 0.0
        self.frame[slots] = frame
        self.head = int((self.head + n) % self.capacity)
        return slots

    def age_increment(self, new: int) -> float:
        """The paper's per-frame increment: a point reaches 128 when the ring overwrites it."""
        return TARGET_AGE * float(new) / self.capacity

    def age_points(self, new: int, visible: Optional[np.ndarray] = None, invisible_rate: float = 1.0,
                   changed: Optional[np.ndarray] = None, change_penalty: float = 0.0) -> np.ndarray:
        """Age every live point for a frame that adds ``new`` points and evict those reaching 255.

        ``visible``: the slots visible in the last frame (the others age ``invisible_rate`` times as
        fast; None: all visible); ``changed``: slots near a detected colour change (gain
        ``change_penalty``). Returns the ages (0 in empty and evicted slots)."""
        inc = self.age_increment(new)
        age = self.age
        if visible is None or invisible_rate == 1.0:
            age += inc
        else:
            age += inc * invisible_rate
            age[visible] -= inc * (invisible_rate - 1.0)
        if changed is not None and len(changed) and change_penalty:
            age[changed] += change_penalty
        np.minimum(age, MAX_AGE, out=age)
        dead = age >= MAX_AGE
        self.x[dead] = np.nan
        age[np.isnan(self.x)] = 0.0  # empty slots stay at 0 so a new point starts fresh
        return age
