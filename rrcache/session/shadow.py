"""The light's view for a shadow map (glslViewer's ``u_lightMatrix``).

A session light with ``"shadow_map": {"size": 1024}`` is rendered from, each frame, with an
orthographic projection looking from the light's position at ``target`` (default: the centre of
the scene's world bounds at that frame) and ``extent`` wide on each side (default: the radius of
those bounds), so every object casts into the map. :func:`light_view_projection` gives the clip
matrix of that depth pass; :func:`light_matrix` the same followed by the bias that maps clip
space to [0, 1]: ``v_lightCoord = u_lightMatrix * world`` has, after the divide by ``w``, the
shadow-map texture coordinates in ``xy`` and the depth the map stores in ``z``.

>>> import numpy as np
>>> from rrcache.session.model import ShadowMap
>>> m = light_matrix(np.array([0., 10, 0]), ShadowMap(64, target=(0, 0, 0), extent=2.0), None, 0)
>>> (m @ [0, 0, 0, 1]).round(6).tolist()
[0.5, 0.5, 0.5, 1.0]
"""
from __future__ import annotations

import numpy as np

from rrcache.session.camera import look_at

#: clip space [-1, 1] → [0, 1] on every axis
BIAS = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])


def scene_bounds(session, frame: int) -> tuple[np.ndarray, float]:
    """(centre, radius) of the world-space bounding box of every object at ``frame``."""
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for obj in session.objects:
        a, b = obj.mesh.bounds()
        corners = np.array([[x, y, z, 1.0] for x in (a[0], b[0]) for y in (a[1], b[1]) for z in (a[2], b[2])])
        world = (obj.model_matrix(frame) @ corners.T).T[:, :3]
        lo, hi = np.minimum(lo, world.min(axis=0)), np.maximum(hi, world.max(axis=0))
    centre = (lo + hi) / 2.0
    return centre, max(float(np.linalg.norm(hi - lo)) / 2.0, 1e-6)


def _ortho(half: float, near: float, far: float) -> np.ndarray:
    m = np.eye(4)
    m[0, 0] = m[1, 1] = 1.0 / half
    m[2, 2] = -2.0 / (far - near)
    m[2, 3] = -(far + near) / (far - near)
    return m


def light_view_projection(position, shadow, session, frame: int) -> np.ndarray:
    """world → the light's clip space (orthographic, see the module doc)."""
    position = np.asarray(position, dtype=np.float64)
    if shadow.target is None or shadow.extent is None:
        centre, radius = scene_bounds(session, frame)
    target = np.asarray(shadow.target if shadow.target is not None else centre, dtype=np.float64)
    extent = float(shadow.extent if shadow.extent is not None else radius)
    view = look_at(position, target, [0.0, 1.0, 0.0])
    distance = float(np.linalg.norm(target - position))
    # depth range: the sphere of radius `extent` around the target, a little margin either side
    near, far = distance - 1.05 * extent, distance + 1.05 * extent
    return _ortho(extent, near, far) @ view


def light_matrix(position, shadow, session, frame: int) -> np.ndarray:
    """world → shadow-map coordinates in [0, 1] (``u_lightMatrix``)."""
    return BIAS @ light_view_projection(position, shadow, session, frame)
