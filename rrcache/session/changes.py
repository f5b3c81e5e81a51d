"""What changes between the frames of a session: the inputs a cached value must not depend on to
stay valid (the profiler groups nodes by them; the analysis puts the terms of a sum that read
none of them first, so that the static part of the sum is a node: rrcache.analysis.sums).

>>> from rrcache.session import load_session
>>> sorted(per_frame_uniforms(load_session("sessions/chess.json")))[:4]
['u_camera', 'u_frame', 'u_kingOffset', 'u_light']
"""
from __future__ import annotations

#: glslViewer built-in uniforms that change from frame to frame in every session, and those that
#: follow the camera, the light or an object (they change when it moves)
ALWAYS = ("u_time", "u_frame")
CAMERA = ("u_camera", "u_viewMatrix", "u_projectionMatrix", "u_modelViewProjectionMatrix")
LIGHT_POSITION = ("u_light", "u_lightMatrix")
LIGHT_COLOR = ("u_lightColor",)
OBJECT = ("u_modelMatrix", "u_normalMatrix", "u_modelViewProjectionMatrix")


def per_frame_uniforms(session) -> set[str]:
    """The uniforms whose value differs between frames of ``session`` (compared at the first,
    middle and last frames): ``u_time`` and ``u_frame``, the camera's, the light's and the
    objects' built-ins when they move or change, and the keyframed session uniforms."""
    names = set(ALWAYS)
    frames = int(getattr(session, "frames", 1))
    if frames < 2:
        return names
    probe = (0, frames // 2, frames - 1)

    def varies(get) -> bool:
        try:
            values = [get(f) for f in probe]
        except (AttributeError, TypeError, ValueError):
            return True  # unknown: assume it changes
        return not all(_equal(values[0], v) for v in values[1:])

    if varies(lambda f: session.camera_at(f).eye) or varies(lambda f: session.camera_at(f).target):
        names.update(CAMERA)
    if varies(lambda f: session.light_at(f).position):
        names.update(LIGHT_POSITION)
    if varies(lambda f: session.light_at(f).color):
        names.update(LIGHT_COLOR)
    if any(varies(lambda f, o=o: o.model_matrix(f)) for o in getattr(session, "objects", ())):
        names.update(OBJECT)
    first = session.uniform_values(0)
    for name in first:
        if varies(lambda f: session.uniform_values(f).get(name)):
            names.add(name)
    return names


def _equal(a, b) -> bool:
    import numpy as np

    return b is not None and np.array_equal(np.asarray(a), np.asarray(b))
