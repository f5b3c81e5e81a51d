"""The session baked for the WebGL2 page: meshes, per-frame uniform values and textures as JSON.

The page draws what the harness draws, so every value comes from the harness's own code: the
vertex attributes (:func:`rrcache.harness.drawer.attribute_data`), the built-in uniforms of each
frame and object (:func:`rrcache.harness.drawer.frame_builtins`), the session's uniforms encoded
for the original shader's active uniforms as the harness writes them
(:func:`rrcache.harness.bindings.plan_bindings`, :func:`rrcache.gl.uniforms.encode_uniform`; the
program is compiled once on this machine's GL for that), and the textures' pixels. The page needs
no network and no file besides itself.

Values are flat lists in the order ``gl.uniform*`` takes them (matrices column-major); a
uniform whose value is the same on every frame is stored once (``"constant"``), the others per
frame (``"frames"``). Meshes and textures are base64 of little-endian arrays.

A session whose light has a shadow map is refused: the page does not render shadow maps.
"""
from __future__ import annotations

import base64
from typing import Optional

import numpy as np

from rrcache.errors import RRCacheError, SessionError
from rrcache.harness.drawer import attribute_data, frame_builtins
from rrcache.compiler.vertex import ATTRIBUTES

#: the largest page the target writes (meshes and textures, before base64), bytes
MAX_BYTES = 96 * 2 ** 20


def b64(array: np.ndarray) -> str:
    """Base64 of the array's bytes, little-endian."""
    a = np.ascontiguousarray(array)
    if a.dtype.byteorder == ">":
        a = a.byteswap().view(a.dtype.newbyteorder("<"))
    return base64.b64encode(a.tobytes()).decode("ascii")


def flat(value) -> list:
    """A uniform value as the flat list ``gl.uniform*`` takes: numbers in element order, a
    matrix (a 2-D numpy array, math convention) column-major, booleans as 0/1."""
    arr = np.asarray(value)
    if arr.dtype == np.bool_:
        arr = arr.astype(np.int32)
    if arr.ndim == 2:
        arr = arr.T
    out = arr.reshape(-1).tolist()
    return [float(v) if isinstance(v, float) else int(v) for v in out]


def _meshes(session) -> tuple[list, int]:
    objects, total = [], 0
    for obj in session.objects:
        attributes = {}
        for attr, (glsl_type, _define) in ATTRIBUTES.items():
            size = int(glsl_type[-1])
            data = attribute_data(obj.mesh, attr, size)
            total += data.nbytes
            attributes[f"a_{attr}"] = {"size": size, "data": b64(data.astype("<f4"))}
        indices = np.ascontiguousarray(np.asarray(obj.mesh.indices, np.uint32).reshape(-1))
        total += indices.nbytes
        objects.append({"name": obj.name, "attributes": attributes, "indices": b64(indices.astype("<u4")),
                        "count": int(indices.size)})
    return objects, total


def _texture_format(data: np.ndarray) -> tuple[str, np.ndarray]:
    """The smallest exact upload of float32 pixels: ``u8`` when every value is k/255 (an 8-bit
    image), ``f2`` when half floats hold them exactly, else ``f4``."""
    d = np.asarray(data, np.float32)
    k = np.round(d * 255.0)
    if np.all((k >= 0) & (k <= 255)) and np.array_equal((k.astype(np.float32) / np.float32(255.0)), d):
        return "u8", k.astype(np.uint8)
    with np.errstate(over="ignore"):
        half = d.astype(np.float16)
    if np.array_equal(half.astype(np.float32), d):
        return "f2", half.astype("<f2")
    return "f4", d.astype("<f4")


def _textures(session, names) -> tuple[dict, int]:
    out, total = {}, 0
    textures = getattr(session, "textures", {}) or {}
    for name in sorted(names):
        asset = textures.get(name)
        if asset is None:
            continue
        data = np.asarray(asset.data)
        kind = getattr(asset, "kind", "2d")
        if kind == "2d":
            if data.ndim == 2:
                data = data[:, :, None]
            data = data[::-1]  # row 0 = the image's top; GL's t = 0 is its bottom
            h, w, c = data.shape
        else:
            if data.ndim == 3:
                data = data[..., None]
            _, h, w, c = data.shape
        if c < 4:  # RGBA everywhere: WebGL2 makes mipmaps of every RGBA format (not of RGB8, RGB32F ...);
            # the missing channels read as GL reads them from a narrower texture: 0, 0, alpha 1
            pad = np.zeros(data.shape[:-1] + (4 - c,), np.float32)
            pad[..., -1] = 1.0
            data = np.concatenate([np.asarray(data, np.float32), pad], axis=-1)
            c = 4
        fmt, stored = _texture_format(data)
        total += stored.nbytes
        out[name] = {"kind": kind, "width": int(w), "height": int(h), "channels": int(c), "format": fmt,
                     "filter": getattr(asset, "filter", None) or "mipmap", "wrap": getattr(asset, "wrap", None) or "repeat",
                     "data": b64(stored)}
    return out, total


def _uniform_track(values: list) -> dict:
    """``{"constant": v}`` when every frame has the same value, else ``{"frames": [...]}``."""
    first = values[0]
    if all(v == first for v in values[1:]):
        return {"constant": first}
    return {"frames": values}


def bake(session, prepared, size: tuple[int, int], frames: Optional[int] = None) -> dict:
    """The JSON-able scene of the page: ``size``, ``fps``, ``frames``, ``background``,
    ``objects`` (attributes and indices), ``builtins`` (per frame, the frame's built-ins),
    ``object_builtins`` (per frame, per object: matrices and ``cull``), ``uniforms`` (the
    session's, encoded for ``prepared``'s active uniforms) and ``textures``."""
    from rrcache.gl.context import get_context
    from rrcache.gl.program import build_program
    from rrcache.gl.uniforms import encode_uniform
    from rrcache.harness.bindings import lookup, plan_bindings
    from rrcache.compiler.vertex import vertex_for

    if getattr(session, "shadow_map", None) is not None:
        raise SessionError("the session's light has a shadow map, which the WebGL2 page does not render",
                           str(session.path), "light.shadow_map",
                           hint="give --session a session without a shadow map for the WebGL2 target")
    count = int(session.frames if frames is None else min(frames, session.frames))
    objects, mesh_bytes = _meshes(session)
    # the session's uniforms, encoded for the original's active uniforms exactly as the harness
    # writes them (struct members, arrays, matrices given as nested rows)
    ctx = get_context()
    inputs = {name: d.type for name, d in prepared.inputs.items()}
    program = build_program(ctx, vertex_for(inputs, None, getattr(prepared, "vertex", None)), prepared.source,
                            prepared.line_map, fragment_name=prepared.path)
    try:
        plan = plan_bindings(program, prepared, session)
        per_frame = {name: [] for name, _ in plan.session}
        for index in range(count):
            values = session.uniform_values(index)
            for name, uniform in plan.session:
                raw = np.frombuffer(encode_uniform(uniform, lookup(values, name)),
                                    {"f": np.float32, "i": np.int32, "I": np.uint32, "d": np.float64}[uniform.fmt[-1]])
                per_frame[name].append([float(v) if uniform.fmt[-1] in "fd" else int(v) for v in raw])
        samplers = [name for name, _uniform, _kind in plan.samplers]
        notes = list(plan.notes)
    finally:
        program.release()
    textures, texture_bytes = _textures(session, samplers)
    if mesh_bytes + texture_bytes > MAX_BYTES:
        raise RRCacheError(f"the session's meshes and textures take {(mesh_bytes + texture_bytes) / 2 ** 20:.0f} MiB; "
                           f"the WebGL2 page holds at most {MAX_BYTES / 2 ** 20:.0f} MiB", str(session.path),
                           hint="give --session a session with smaller meshes and textures for the page")
    builtins, object_builtins = [], []
    for index in range(count):
        frame, per_object = frame_builtins(session, index, size)
        builtins.append({name: flat(value) for name, value in frame.items()})
        object_builtins.append([{name: (bool(value) if name == "cull" else flat(value)) for name, value in o.items()}
                                for o in per_object])
    return {
        "size": [int(size[0]), int(size[1])],
        "fps": float(session.fps),
        "frames": count,
        "background": [float(v) for v in getattr(session, "background", (0.0, 0.0, 0.0, 0.0))],
        "objects": objects,
        "builtins": builtins,
        "object_builtins": object_builtins,
        "uniforms": {name: _uniform_track(values) for name, values in per_frame.items()},
        "textures": textures,
        "notes": notes,
    }
