"""Projecting the point cache into a frame: the z-buffer and the predicted occupancy image.

Images here are in GL's orientation (row 0 at the bottom), flattened row-major: pixel
``(col, row)`` of a ``W×H`` image is index ``row·W + col``.

:func:`screen_matrix` folds the viewport into a camera's view-projection: its three rows map a
homogeneous world point to ``(x·w, y·w, w)`` with ``x, y`` in pixels and ``w`` the clip w, the
distance along the view axis for a perspective camera (the depth the z-buffer and the depth cull
compare: linear, so "10% farther" means what it says). :class:`Projector` projects every live
point of a :class:`~rrcache.alternatives.render_cache.points.PointCache` (a moving object's points
with that object's matrix of the frame) and keeps those in front of the camera inside the frame.

:func:`zbuffer` keeps the nearest point per pixel in one ``np.minimum.at`` over 64-bit keys (the
depth's float bits above the slot: positive floats order as their bits), so the winner's slot and
depth come out of one scatter. ``tiled=True`` first bucket-sorts the points into tiles (the
paper's §3.2, for the memory coherence of a C loop); docs/render_cache.md measures both.

>>> import numpy as np
>>> from rrcache.alternatives.render_cache.points import PointCache, STATIC
>>> cache = PointCache(2)
>>> _ = cache.insert(np.array([[0, 0, -2], [0, 0, -4]], np.float32), np.eye(3, dtype=np.float32)[:2],
...                  np.full(2, STATIC), frame=0)
>>> A = screen_matrix(np.diag([1.0, 1.0, 1.0, 1.0]) @ _perspective(), (4, 4))
>>> pix, depth, slots = Projector(2).project(cache, A, (4, 4))
>>> pix.tolist(), depth.tolist(), slots.tolist()
([10, 10], [2.0, 4.0], [0, 1])
>>> owner, nearest = zbuffer(pix, depth, slots, 16)
>>> int(owner[10]), float(nearest[10]), int((owner >= 0).sum())
(0, 2.0, 1)
"""
from __future__ import annotations

from typing import Mapping, Optional

import numpy as np

from rrcache.alternatives.render_cache.points import PointCache

#: points nearer than this (clip w) are behind the camera or on its plane: left out
NEAR_W = 1e-6
_NO_KEY = np.iinfo(np.int64).max


def _perspective(fov: float = 90.0, near: float = 0.1, far: float = 100.0) -> np.ndarray:
    """A GL perspective matrix (aspect 1): for the doctests."""
    f = 1.0 / np.tan(np.radians(fov) / 2)
    return np.array([[f, 0, 0, 0], [0, f, 0, 0], [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)],
                     [0, 0, -1, 0]], np.float64)


def screen_matrix(view_projection: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """The 3×4 matrix taking a homogeneous world point to ``(x·w, y·w, w)``, ``x, y`` in pixels
    (GL window coordinates, origin at the bottom left) and ``w`` the clip w."""
    w, h = size
    viewport = np.array([[w / 2.0, 0, 0, w / 2.0], [0, h / 2.0, 0, h / 2.0], [0, 0, 0, 1.0]])
    return viewport @ np.asarray(view_projection, np.float64)


class Projector:
    """Scratch arrays for projecting up to ``capacity`` points without allocating per frame."""

    def __init__(self, capacity: int):
        self.capacity = int(capacity)
        self._rows = [np.empty(self.capacity, np.float32) for _ in range(3)]
        self._tmp = np.empty(self.capacity, np.float32)

    def _row(self, cache: PointCache, r: np.ndarray, out: np.ndarray) -> None:
        tmp = self._tmp
        np.multiply(cache.x, np.float32(r[0]), out=out)
        np.multiply(cache.y, np.float32(r[1]), out=tmp)
        out += tmp
        np.multiply(cache.z, np.float32(r[2]), out=tmp)
        out += tmp
        out += np.float32(r[3])

    def clip(self, cache: PointCache, matrix: np.ndarray,
             moving: Optional[Mapping[int, np.ndarray]] = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(x·w, y·w, w)`` of every slot (scratch arrays, valid until the next call); the points of
        object ``k`` in ``moving`` use ``moving[k]`` (that object's screen matrix) instead."""
        a, b, w = self._rows
        self._row(cache, matrix[0], a)
        self._row(cache, matrix[1], b)
        self._row(cache, matrix[2], w)
        for k, m in (moving or {}).items():
            idx = np.flatnonzero(cache.object == k)
            if idx.size:
                p = np.stack([cache.x[idx], cache.y[idx], cache.z[idx], np.ones(idx.size, np.float32)]).astype(np.float64)
                q = np.asarray(m, np.float64) @ p
                a[idx], b[idx], w[idx] = q[0], q[1], q[2]
        return a, b, w

    @staticmethod
    def depth_of(cache: PointCache, slots: np.ndarray, matrix: np.ndarray,
                 moving: Optional[Mapping[int, np.ndarray]] = None) -> np.ndarray:
        """The depth (clip w) of the points in ``slots`` (a few: computed on their own)."""
        p = np.stack([cache.x[slots], cache.y[slots], cache.z[slots], np.ones(len(slots), np.float32)]).astype(np.float64)
        depth = np.asarray(matrix, np.float64)[2] @ p
        objects = cache.object[slots]
        for k, m in (moving or {}).items():
            on = objects == k
            if on.any():
                depth[on] = np.asarray(m, np.float64)[2] @ p[:, on]
        return depth.astype(np.float32)

    def project(self, cache: PointCache, matrix: np.ndarray, size: tuple[int, int],
                moving: Optional[Mapping[int, np.ndarray]] = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The points inside a ``size`` frame: ``(pixel index, depth, slot)`` arrays of equal length,
        slots in increasing order; the depth is the clip w."""
        width, height = size
        a, b, w = self.clip(cache, matrix, moving)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            inv = np.divide(1.0, w, out=self._tmp)
            np.multiply(a, inv, out=a)
            np.multiply(b, inv, out=b)
            # floor by truncation of x + 1 (exact for x > -1; anything below is outside anyway), then
            # one unsigned compare per axis; NaN (empty slots) and inf cast to out-of-range integers
            a += 1.0
            b += 1.0
            xi = a.astype(np.int32)
            yi = b.astype(np.int32)
        xi -= 1
        yi -= 1
        ok = xi.view(np.uint32) < width
        ok &= yi.view(np.uint32) < height
        ok &= w > NEAR_W
        slots = np.flatnonzero(ok)
        pix = yi[slots].astype(np.int64)
        pix *= width
        pix += xi[slots]
        return pix, w[slots].copy(), slots

    def occupancy(self, cache: PointCache, matrix: np.ndarray, size: tuple[int, int],
                  moving: Optional[Mapping[int, np.ndarray]] = None) -> np.ndarray:
        """The paper's predicted occupancy image: which pixels of a ``size`` frame at least one
        point lands in (no z-buffer); flat bool."""
        pix, _depth, _slots = self.project(cache, matrix, size, moving)
        occupied = np.zeros(size[0] * size[1], bool)
        occupied[pix] = True
        return occupied


def zbuffer(pix: np.ndarray, depth: np.ndarray, slots: np.ndarray, pixels: int, tiled: bool = False,
            width: int = 0, tile: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """The nearest point per pixel: ``(owner, depth)`` flat arrays of ``pixels`` entries (owner -1
    and depth inf where no point lands). ``tiled``: sort the points by ``tile``×``tile`` tile of a
    ``width``-wide image first (see the module docstring)."""
    keys = depth.view(np.int32).astype(np.int64)
    keys <<= 32
    keys |= slots
    if tiled:
        if width <= 0:
            raise ValueError("a tiled z-buffer needs the image width")
        tiles_x = -(-width // tile)
        tile_of = (pix // width // tile) * tiles_x + (pix % width) // tile
        order = np.argsort(tile_of, kind="stable")
        pix, keys = pix[order], keys[order]
    buf = np.full(pixels, _NO_KEY, np.int64)
    np.minimum.at(buf, pix, keys)
    empty = buf == _NO_KEY
    owner = buf & 0xFFFFFFFF
    owner[empty] = -1
    nearest = (buf >> 32).astype(np.int32).view(np.float32)
    nearest[empty] = np.inf
    return owner, nearest
