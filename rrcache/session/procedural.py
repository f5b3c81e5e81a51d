"""Procedural meshes: icosphere, torus, box, plane, cylinder, revolve, torus_knot.

Every mesh has unit normals, texcoords (u around / along the shape, v up or along the tube)
and tangents; closed shapes are watertight once vertices duplicated along UV seams are welded
by position. Parameters and defaults (all optional):

- icosphere: radius 1, subdivisions 3 (20·4^s faces); u = longitude (0.5 at +Z, 0.75 at +X),
  v = 0 at the south pole, 1 at the north pole; faces across the seam use u slightly above 1
  (sample with repeat wrap).
- torus: major_radius 1, minor_radius 0.25, major_segments 64, minor_segments 32; axis +Y.
- box: size 1 (a number or [x, y, z]); each face maps the whole 0..1 square.
- plane: size 1 (a number or [x, z]), subdivisions 1; in y = 0 facing +Y, u along +X, v along -Z.
- cylinder: radius 0.5, height 1, segments 32; axis +Y, centred, with caps.
- revolve: profile (a chess pawn) of [radius, height] points, segments 32; rotated about +Y,
  radius 0 closes the surface; corners sharper than 45° get split normals (crisp edges).
- torus_knot: p 2, q 3, radius 1, tube_radius 0.25, segments 1024, tube_segments 36
  (73,728 faces); the curve is three.js's TorusKnot, lying near the XY plane.

>>> make_mesh({"type": "torus", "major_segments": 8, "minor_segments": 4}).face_count
64
"""
from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from rrcache.errors import SessionError
from rrcache.session.model import MeshData
from rrcache.session.tangents import compute_tangents

DEFAULT_PAWN = [[0.0, 0.0], [0.45, 0.0], [0.45, 0.08], [0.35, 0.14], [0.22, 0.3], [0.15, 0.6],
                [0.3, 0.66], [0.15, 0.72], [0.22, 0.85], [0.2, 0.98], [0.1, 1.06], [0.0, 1.08]]


def _finish(positions, normals, texcoords, indices) -> MeshData:
    p = np.asarray(positions, dtype=np.float64)
    n = np.asarray(normals, dtype=np.float64)
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    idx = np.asarray(indices, dtype=np.int64).reshape(-1, 3)
    tri = p[idx]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    if np.sum(fn * n[idx].sum(axis=1)) < 0.0:  # winding disagrees with the normals: flip it
        idx = idx[:, [0, 2, 1]]
    uv = np.asarray(texcoords, dtype=np.float64)
    return MeshData(positions=p.astype(np.float32), normals=n.astype(np.float32),
                    indices=idx.astype(np.uint32), texcoords=uv.astype(np.float32),
                    tangents=compute_tangents(p, n, uv, idx))


def _grid_indices(nu: int, nv: int) -> np.ndarray:
    """Two triangles per cell of an (nu+1)×(nv+1) vertex grid indexed ``i*(nv+1)+j``."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a = (i * (nv + 1) + j).ravel()
    b, c, d = a + (nv + 1), a + (nv + 2), a + 1
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def _angles(n: int) -> np.ndarray:
    """n+1 angles 0..2π with the last one exactly equal to the first (seams weld exactly)."""
    return 2.0 * math.pi * (np.arange(n + 1) % n) / n


def icosphere(radius: float = 1.0, subdivisions: int = 3) -> MeshData:
    import trimesh

    base = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    v = np.asarray(base.vertices, dtype=np.float64)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    faces = np.asarray(base.faces, dtype=np.int64)
    u = 0.5 + np.arctan2(v[:, 0], v[:, 2]) / (2.0 * math.pi)
    vv = 0.5 + np.arcsin(np.clip(v[:, 1], -1, 1)) / math.pi
    cu, cv = u[faces], vv[faces]
    wrap = (cu.max(axis=1) - cu.min(axis=1)) > 0.5
    cu[wrap] = np.where(cu[wrap] < 0.5, cu[wrap] + 1.0, cu[wrap])
    pole = np.abs(v[faces][:, :, 1]) > 1.0 - 1e-9
    for k in range(3):  # a pole takes the mean u of the face's two other corners
        others = [m for m in range(3) if m != k]
        cu[pole[:, k], k] = cu[pole[:, k]][:, others].mean(axis=1)
    key = np.stack([faces.ravel().astype(np.float64), np.round(cu.ravel(), 9), np.round(cv.ravel(), 9)], 1)
    uniq, inverse = np.unique(key, axis=0, return_inverse=True)
    src = uniq[:, 0].astype(np.int64)
    return _finish(v[src] * radius, v[src], uniq[:, 1:3], inverse.reshape(-1, 3))


def torus(major_radius: float = 1.0, minor_radius: float = 0.25, major_segments: int = 64,
          minor_segments: int = 32) -> MeshData:
    th, ph = np.meshgrid(_angles(major_segments), _angles(minor_segments), indexing="ij")
    n = np.stack([np.cos(ph) * np.cos(th), np.sin(ph), np.cos(ph) * np.sin(th)], -1).reshape(-1, 3)
    ring = np.stack([np.cos(th), np.zeros_like(th), np.sin(th)], -1).reshape(-1, 3)
    p = ring * major_radius + n * minor_radius
    uu, vv = np.meshgrid(np.linspace(0, 1, major_segments + 1), np.linspace(0, 1, minor_segments + 1), indexing="ij")
    return _finish(p, n, np.stack([uu.ravel(), vv.ravel()], 1), _grid_indices(major_segments, minor_segments))


def box(size: Any = 1.0) -> MeshData:
    half = np.broadcast_to(np.asarray(size, dtype=np.float64), (3,)) / 2.0
    pos, nor, uv, idx = [], [], [], []
    faces = [((1, 0, 0), (0, 1, 0)), ((-1, 0, 0), (0, 1, 0)), ((0, 1, 0), (0, 0, -1)),
             ((0, -1, 0), (0, 0, 1)), ((0, 0, 1), (0, 1, 0)), ((0, 0, -1), (0, 1, 0))]
    for k, (n, b) in enumerate(faces):
        n, b = np.array(n, float), np.array(b, float)
        a = np.cross(b, n)  # a × b = n: counter-clockwise seen from outside
        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            pos.append((n + su * a + sv * b) * half)
            nor.append(n)
            uv.append(((su + 1) / 2, (sv + 1) / 2))
        idx += [[4 * k, 4 * k + 1, 4 * k + 2], [4 * k, 4 * k + 2, 4 * k + 3]]
    return _finish(pos, nor, uv, idx)


def plane(size: Any = 1.0, subdivisions: int = 1) -> MeshData:
    sx, sz = np.broadcast_to(np.asarray(size, dtype=np.float64), (2,))
    t = np.linspace(0.0, 1.0, subdivisions + 1)
    uu, vv = np.meshgrid(t, t, indexing="ij")
    p = np.stack([(uu - 0.5) * sx, np.zeros_like(uu), (0.5 - vv) * sz], -1).reshape(-1, 3)
    n = np.tile([0.0, 1.0, 0.0], (len(p), 1))
    return _finish(p, n, np.stack([uu.ravel(), vv.ravel()], 1), _grid_indices(subdivisions, subdivisions))


def cylinder(radius: float = 0.5, height: float = 1.0, segments: int = 32) -> MeshData:
    th = _angles(segments)
    c, s = np.cos(th), np.sin(th)
    side_n = np.repeat(np.stack([s, np.zeros_like(s), c], 1), 2, axis=0)
    side_p = side_n * radius + np.tile([[0, -height / 2, 0], [0, height / 2, 0]], (segments + 1, 1))
    side_uv = np.stack([np.repeat(np.linspace(0, 1, segments + 1), 2), np.tile([0.0, 1.0], segments + 1)], 1)
    pos, nor, uv, idx = [side_p], [side_n], [side_uv], [_grid_indices(segments, 1)]
    base = len(side_p)
    for y in (-1.0, 1.0):
        ring = np.stack([s[:-1] * radius, np.full(segments, y * height / 2), c[:-1] * radius], 1)
        pos.append(np.vstack([[0.0, y * height / 2, 0.0], ring]))
        nor.append(np.tile([0.0, y, 0.0], (segments + 1, 1)))
        uv.append(np.vstack([[0.5, 0.5], np.stack([0.5 + 0.5 * s[:-1], 0.5 - 0.5 * y * c[:-1]], 1)]))
        k = np.arange(segments)
        tri = np.stack([np.zeros(segments, int), 1 + k, 1 + (k + 1) % segments], 1) + base
        idx.append(tri if y > 0 else tri[:, [0, 2, 1]])
        base += segments + 1
    return _finish(np.vstack(pos), np.vstack(nor), np.vstack(uv), np.vstack(idx))


def revolve(profile: Any = None, segments: int = 32) -> MeshData:
    pts = np.asarray(DEFAULT_PAWN if profile is None else profile, dtype=np.float64)
    keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-12])
    pts = pts[keep]
    if len(pts) < 2:
        raise ValueError("a revolve profile needs two distinct points")
    closed = np.vstack([[0.0, pts[0, 1]], pts, [0.0, pts[-1, 1]]])
    area = np.sum(closed[:, 0] * np.roll(closed[:, 1], -1) - np.roll(closed[:, 0], -1) * closed[:, 1])
    if area < 0.0:  # walk the profile so that the solid lies on its left (outside on its right)
        pts = pts[::-1]
    d = np.diff(pts, axis=0)
    seg_n = np.stack([d[:, 1], -d[:, 0]], 1) / np.linalg.norm(d, axis=1, keepdims=True)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(d, axis=1))])
    arc /= arc[-1]
    rings = []  # (radius, height, v, normal2d, profile index)
    for k in range(len(pts)):
        before = seg_n[k - 1] if k > 0 else None
        after = seg_n[k] if k < len(seg_n) else None
        if before is None or after is None:
            rings.append((pts[k], arc[k], before if after is None else after, k))
        elif np.dot(before, after) < math.cos(math.radians(45)):
            rings.append((pts[k], arc[k], before, k))
            rings.append((pts[k], arc[k], after, k))
        else:
            avg = before + after
            rings.append((pts[k], arc[k], avg / np.linalg.norm(avg), k))
    th = _angles(segments)
    c, s = np.cos(th), np.sin(th)
    pos, nor, uv, idx = [], [], [], []
    for (rh, v, n2, _k) in rings:
        pos.append(np.stack([rh[0] * s, np.full_like(s, rh[1]), rh[0] * c], 1))
        nor.append(np.stack([n2[0] * s, np.full_like(s, n2[1]), n2[0] * c], 1))
        uv.append(np.stack([np.linspace(0, 1, segments + 1), np.full_like(s, v)], 1))
    w = segments + 1
    for r in range(len(rings) - 1):
        a_pt, ka = rings[r][0], rings[r][3]
        b_pt, kb = rings[r + 1][0], rings[r + 1][3]
        if ka == kb:
            continue  # the two rings of a split corner share positions: no faces between them
        for i in range(segments):
            a0, a1, b0, b1 = r * w + i, r * w + i + 1, (r + 1) * w + i, (r + 1) * w + i + 1
            if b_pt[0] > 0.0:
                idx.append([a0, b0, b1])
            if a_pt[0] > 0.0:
                idx.append([a0, b1, a1])
    if not idx:
        raise ValueError("the revolve profile has no point off the axis, so the surface is empty")
    return _finish(np.vstack(pos), np.vstack(nor), np.vstack(uv), np.array(idx, dtype=np.int64))


def _knot_curve(t: np.ndarray, p: int, q: int, radius: float) -> np.ndarray:
    qt = q / p * t
    r = radius * (2.0 + np.cos(qt)) * 0.5
    return np.stack([r * np.cos(t), r * np.sin(t), radius * np.sin(qt) * 0.5], -1)


def torus_knot(p: int = 2, q: int = 3, radius: float = 1.0, tube_radius: float = 0.25,
               segments: int = 1024, tube_segments: int = 36) -> MeshData:
    t = p * _angles(segments)
    c = _knot_curve(t, p, q, radius)
    eps = 1e-4
    tangent = _knot_curve(t + eps, p, q, radius) - _knot_curve(t - eps, p, q, radius)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    binormal = np.cross(tangent, c)
    binormal /= np.linalg.norm(binormal, axis=1, keepdims=True)
    normal = np.cross(binormal, tangent)
    ph = _angles(tube_segments)
    n = (np.cos(ph)[None, :, None] * normal[:, None, :] + np.sin(ph)[None, :, None] * binormal[:, None, :])
    pos = c[:, None, :] + tube_radius * n
    uu, vv = np.meshgrid(np.linspace(0, 1, segments + 1), np.linspace(0, 1, tube_segments + 1), indexing="ij")
    return _finish(pos.reshape(-1, 3), n.reshape(-1, 3), np.stack([uu.ravel(), vv.ravel()], 1),
                   _grid_indices(segments, tube_segments))


BUILDERS: dict[str, Callable[..., MeshData]] = {
    "icosphere": icosphere, "torus": torus, "box": box, "plane": plane,
    "cylinder": cylinder, "revolve": revolve, "torus_knot": torus_knot,
}


#: The most faces a procedural mesh may have (a guard against a typo like 40960 segments).
MAX_FACES = 4_000_000


def face_count(spec: dict) -> int:
    """The number of faces ``make_mesh(spec)`` builds (an upper bound for ``revolve``).

    >>> face_count({"type": "torus_knot"})
    73728
    """
    defaults = {name: fn.__defaults__ for name, fn in BUILDERS.items()}
    args = dict(zip(BUILDERS[spec["type"]].__code__.co_varnames, defaults[spec["type"]] or ()))
    args.update({k: v for k, v in spec.items() if k != "type"})
    kind = spec["type"]
    if kind == "icosphere":
        return 20 * 4 ** args["subdivisions"]
    if kind == "torus":
        return 2 * args["major_segments"] * args["minor_segments"]
    if kind == "box":
        return 12
    if kind == "plane":
        return 2 * args["subdivisions"] ** 2
    if kind == "cylinder":
        return 4 * args["segments"]
    if kind == "revolve":
        return 2 * (len(args["profile"] or DEFAULT_PAWN) - 1) * args["segments"]
    return 2 * args["segments"] * args["tube_segments"]


def make_mesh(spec: dict, file: str = "<procedural>", where: str = "procedural") -> MeshData:
    """Build the procedural mesh described by ``spec`` (the session's ``procedural`` object).

    The spec is validated against the session schema; a bad one raises ``SessionError`` naming
    ``file`` and a JSON path under ``where`` (the session loader passes its own).

    >>> m = make_mesh({"type": "box", "size": [2, 1, 1]})
    >>> m.bounds()[1].tolist()
    [1.0, 0.5, 0.5]
    """
    from rrcache.session.validation import validate_fragment

    validate_fragment(spec, "procedural", file, where)
    params = {k: v for k, v in spec.items() if k != "type"}
    if face_count(spec) > MAX_FACES:
        raise SessionError(f"{spec['type']} would have {face_count(spec):,} faces, more than {MAX_FACES:,}",
                           file, where, "use fewer segments or subdivisions")
    try:
        return BUILDERS[spec["type"]](**params)
    except ValueError as exc:
        raise SessionError(str(exc), file, where) from None
