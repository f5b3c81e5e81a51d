"""Session uniforms: constants or keyframed values.

A value is a number (an int stays an int, a bool stays a bool), a flat array of numbers or
booleans (a vecN, an array uniform, or a matN written as N·N numbers in column-major order, the
order GL uploads) or a matrix written as a nested list of *columns*. Flat arrays come back as
1-D numpy arrays: int64 when every element is a JSON integer, bool when every element is a
boolean, float64 otherwise. Nested columns come back as a rows×cols float64 matrix ``M`` with
``M[:, j]`` = column ``j`` (the project's row-major convention; upload ``M.T.ravel()``).
Keyframed floats (and float arrays) are interpolated component-wise; ints and bools are held
(a step) until the next keyframe. When the keyframes of one uniform mix ints and floats, all
are treated as floats.

>>> f = uniform_function("u_wave", {"keyframes": [{"frame": 0, "value": 0.0}, {"frame": 4, "value": 1.0}]}, "s.json")
>>> f(1), f(9)
(0.25, 1.0)
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from rrcache.errors import SessionError
from rrcache.session.keyframes import Track
from rrcache.session.validation import json_path

#: Uniforms the harness sets itself (docs/design.md §4); a session may not set them.
BUILTIN_UNIFORMS = frozenset({
    "u_camera", "u_light", "u_lightColor", "u_resolution", "u_time", "u_frame", "u_modelMatrix",
    "u_viewMatrix", "u_projectionMatrix", "u_modelViewProjectionMatrix", "u_normalMatrix"})

_INT_MIN, _INT_MAX = -(2 ** 31), 2 ** 32 - 1  # int and uint uniforms


def _classify(value: Any, file: str, where: str) -> tuple[str, np.ndarray | Any]:
    """(kind, array) with kind in bool/int/float/matrix."""
    if isinstance(value, bool):
        return "bool", np.bool_(value)
    if isinstance(value, int):
        if not _INT_MIN <= value <= _INT_MAX:
            raise SessionError(f"integer {value} does not fit a 32-bit int or uint uniform", file, where)
        return "int", np.int64(value)
    if isinstance(value, float):
        return "float", np.float64(value)
    if value and all(isinstance(col, list) for col in value):
        if len({len(col) for col in value}) != 1:
            raise SessionError("matrix columns have different lengths", file, where,
                               "write a matrix as a list of equally long columns")
        return "matrix", np.array(value, dtype=np.float64).T
    bools = [isinstance(x, bool) for x in value]
    if any(bools) and not all(bools):
        raise SessionError("an array mixes booleans and numbers", file, where)
    if all(bools):
        return "bool", np.array(value, dtype=np.bool_)
    if all(isinstance(x, int) for x in value):
        for x in value:
            if not _INT_MIN <= x <= _INT_MAX:
                raise SessionError(f"integer {x} does not fit a 32-bit int or uint uniform", file, where)
        return "int", np.array(value, dtype=np.int64)
    return "float", np.array(value, dtype=np.float64)


def _python(kind: str, value: Any) -> Any:
    if np.ndim(value) == 0:
        return {"bool": bool, "int": int}.get(kind, float)(value)
    return np.array(value, dtype={"bool": np.bool_, "int": np.int64}.get(kind, np.float64))


def uniform_function(name: str, spec: Any, file: str) -> Callable[[int], Any]:
    """frame → value for the uniform ``name`` given as ``spec`` (already schema-validated)."""
    base = json_path(["uniforms", name])
    if name in BUILTIN_UNIFORMS:
        raise SessionError(f"{name} is a built-in uniform", file, base,
                           "the harness sets it from the camera, light and frame; remove it here")
    if not (isinstance(spec, dict) and "keyframes" in spec):
        kind, value = _classify(spec, file, base)
        return lambda frame: _python(kind, value)
    kfs = spec["keyframes"]
    frames, kinds, values = [], [], []
    for k, kf in enumerate(kfs):
        where = json_path(["uniforms", name, "keyframes", k])
        if frames and kf["frame"] <= frames[-1]:
            raise SessionError(f"keyframes must be sorted by frame: frame {kf['frame']} comes after "
                               f"frame {frames[-1]}", file, where + ".frame", "list keyframes in increasing frame order")
        kind, value = _classify(kf["value"], file, where + ".value")
        if values and np.shape(value) != np.shape(values[0]):
            raise SessionError(f"value has shape {list(np.shape(value))} but keyframe 0 has "
                               f"{list(np.shape(values[0]))}", file, where + ".value")
        if values and (kind == "bool") != (kinds[0] == "bool"):
            raise SessionError("keyframes mix booleans and numbers", file, where + ".value")
        if values and (kind == "matrix") != (kinds[0] == "matrix"):
            raise SessionError("keyframes mix matrices and flat arrays", file, where + ".value")
        frames.append(int(kf["frame"]))
        kinds.append(kind)
        values.append(value)
    kind = kinds[0] if len(set(kinds)) == 1 else "float"
    step = kind in ("bool", "int")
    dtype = {"bool": np.bool_, "int": np.int64}.get(kind, np.float64)
    track = Track(frames, np.array(values, dtype=dtype), step=step)
    return lambda frame: _python(kind, track.at(frame))
