"""Per-vertex normals and tangents for indexed triangle meshes.

>>> import numpy as np
>>> p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
>>> i = np.array([[0, 1, 2]], np.uint32)
>>> vertex_normals(p, i)[0].tolist()
[0.0, 0.0, 1.0]
"""
from __future__ import annotations

import numpy as np


def _unit(v: np.ndarray, fallback: np.ndarray | None = None) -> np.ndarray:
    n = np.linalg.norm(v, axis=1, keepdims=True)
    out = np.divide(v, n, out=np.zeros_like(v), where=n > 1e-20)
    if fallback is not None:
        bad = (n[:, 0] <= 1e-20)
        out[bad] = fallback[bad]
    return out


def any_perpendicular(n: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to each row of ``n`` (N×3)."""
    axis = np.zeros_like(n)
    axis[np.arange(len(n)), np.argmin(np.abs(n), axis=1)] = 1.0
    return _unit(np.cross(n, axis))


def vertex_normals(positions: np.ndarray, indices: np.ndarray, weld: bool = False) -> np.ndarray:
    """Area-weighted vertex normals (float32, unit; +Z for isolated vertices).

    With ``weld=True`` vertices at the same position share one normal (smooth across UV seams).
    """
    p = positions.astype(np.float64)
    tri = p[indices]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    if weld:
        _, key = np.unique(np.round(p, 6), axis=0, return_inverse=True)
        key = key.reshape(-1)
    else:
        key = np.arange(len(p))
    acc = np.zeros((int(key.max()) + 1 if len(key) else 0, 3))
    for c in range(3):
        np.add.at(acc, key[indices[:, c]], fn)
    n = acc[key]
    return _unit(n, np.tile([0.0, 0.0, 1.0], (len(p), 1))).astype(np.float32)


def compute_tangents(positions, normals, texcoords, indices) -> np.ndarray:
    """Tangents (N×4 float32) from texcoord derivatives (Lengyel's method): xyz is the unit
    direction of increasing u, orthogonalised against the normal; w = ±1 is the handedness, so
    that ``bitangent = w * cross(normal, tangent)`` points along increasing v. Vertices with
    degenerate texcoords get an arbitrary tangent perpendicular to the normal, w = +1.
    """
    p = positions.astype(np.float64)
    n = normals.astype(np.float64)
    uv = texcoords.astype(np.float64)
    i0, i1, i2 = indices[:, 0], indices[:, 1], indices[:, 2]
    e1, e2 = p[i1] - p[i0], p[i2] - p[i0]
    d1, d2 = uv[i1] - uv[i0], uv[i2] - uv[i0]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    ok = np.abs(det) > 1e-20
    r = np.divide(1.0, det, out=np.zeros_like(det), where=ok)[:, None]
    sdir = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * r
    tdir = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * r
    tan1 = np.zeros_like(p)
    tan2 = np.zeros_like(p)
    for idx in (i0, i1, i2):
        np.add.at(tan1, idx, sdir)
        np.add.at(tan2, idx, tdir)
    t = tan1 - n * np.sum(n * tan1, axis=1, keepdims=True)
    t = _unit(t, any_perpendicular(n))
    w = np.where(np.sum(np.cross(n, t) * tan2, axis=1) < 0.0, -1.0, 1.0)
    return np.concatenate([t, w[:, None]], axis=1).astype(np.float32)
