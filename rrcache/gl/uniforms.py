"""Writing Python/numpy values into the active uniforms of a moderngl program.

Values follow the project's conventions: scalars, sequences or numpy arrays; a matrix given as a
nested ``rows×cols`` array is a mathematical (row-major) matrix and is transposed for GL, a flat
matrix value is taken in GLSL constructor (column-major) order; arrays of any type are flattened
in element order. Booleans become 0/1. Arrays may be given longer than the active part of a GLSL
array (the driver trims unused trailing elements); the extra elements are ignored.

>>> import numpy as np
>>> from rrcache.gl.context import get_context
>>> from rrcache.gl.program import build_program
>>> prog = build_program(get_context(), "#version 330\\nvoid main(){gl_Position=vec4(0);}",
...     "#version 330\\nuniform mat2 m; out vec4 c; void main(){c=vec4(m[0], m[1]);}")
>>> write_uniform(prog["m"], np.array([[1.0, 2.0], [3.0, 4.0]]))
>>> prog["m"].value          # column-major: first column (1, 3)
(1.0, 3.0, 2.0, 4.0)
>>> prog.release()
"""
from __future__ import annotations

import numpy as np

# GL type enum -> (columns, rows) of float and double matrices
MATRIX_SHAPES = {
    0x8B5A: (2, 2), 0x8B5B: (3, 3), 0x8B5C: (4, 4),
    0x8B65: (2, 3), 0x8B66: (2, 4), 0x8B67: (3, 2), 0x8B68: (3, 4), 0x8B69: (4, 2), 0x8B6A: (4, 3),
    0x8F46: (2, 2), 0x8F47: (3, 3), 0x8F48: (4, 4),
    0x8F49: (2, 3), 0x8F4A: (2, 4), 0x8F4B: (3, 2), 0x8F4C: (3, 4), 0x8F4D: (4, 2), 0x8F4E: (4, 3),
}
SAMPLER_2D_TYPES = {0x8B5E: "sampler2D", 0x8DCA: "isampler2D", 0x8DD2: "usampler2D"}
SAMPLER_CUBE_TYPES = {0x8B60: "samplerCube", 0x8DCC: "isamplerCube", 0x8DD4: "usamplerCube"}
_OTHER_OPAQUE = {
    0x8B5D: "sampler1D", 0x8B5F: "sampler3D", 0x8B61: "sampler1DShadow", 0x8B62: "sampler2DShadow",
    0x8B63: "sampler2DRect", 0x8B64: "sampler2DRectShadow", 0x8DC0: "sampler1DArray",
    0x8DC1: "sampler2DArray", 0x8DC2: "samplerBuffer", 0x8DC3: "sampler1DArrayShadow",
    0x8DC4: "sampler2DArrayShadow", 0x8DC5: "samplerCubeShadow", 0x9108: "sampler2DMS",
    0x900C: "samplerCubeArray",
}
_NUMPY = {"f": np.float32, "i": np.int32, "I": np.uint32, "d": np.float64}


def sampler_kind(uniform) -> str | None:
    """``"2d"``, ``"cube"``, ``"other"`` (a sampler type the harness does not bind) or None (not a sampler)."""
    if uniform.gl_type in SAMPLER_2D_TYPES:
        return "2d"
    if uniform.gl_type in SAMPLER_CUBE_TYPES:
        return "cube"
    if uniform.gl_type in _OTHER_OPAQUE:
        return "other"
    return None


def opaque_type_name(uniform) -> str:
    """The GLSL name of a sampler uniform's type (``sampler2D``...)."""
    return {**SAMPLER_2D_TYPES, **SAMPLER_CUBE_TYPES, **_OTHER_OPAQUE}.get(uniform.gl_type, hex(uniform.gl_type))


def encode_uniform(uniform, value) -> bytes:
    """The bytes ``uniform.write`` takes for ``value``; raises ``ValueError`` (with the expected
    shape) when the value does not fit the uniform's type.

    >>> from types import SimpleNamespace
    >>> u = SimpleNamespace(fmt="3f", dimension=3, array_length=1, gl_type=0x8B51)
    >>> np.frombuffer(encode_uniform(u, [1, 2, 3]), np.float32).tolist()
    [1.0, 2.0, 3.0]
    """
    kind = uniform.fmt[-1]
    dtype = _NUMPY.get(kind)
    if dtype is None:
        raise ValueError(f"uniform format {uniform.fmt!r} is not supported")
    dim, count = uniform.dimension, uniform.array_length
    arr = np.asarray(value)
    if arr.dtype == object:
        raise ValueError("the value is not a regular array of numbers")
    if arr.dtype == np.bool_:
        arr = arr.astype(np.int32)
    if not (np.issubdtype(arr.dtype, np.number)):
        raise ValueError(f"expected numbers, got {arr.dtype}")
    if kind in "iI" and np.issubdtype(arr.dtype, np.floating) and not np.all(np.isfinite(arr) & (arr == np.round(arr))):
        raise ValueError("expected integer values")
    shape = MATRIX_SHAPES.get(uniform.gl_type)
    if shape is not None and arr.ndim >= 2:
        cols, rows = shape
        if arr.shape[-2:] != (rows, cols):
            raise ValueError(f"expected {rows}×{cols} matrices (rows × columns), got shape {arr.shape}")
        arr = np.swapaxes(arr, -1, -2)
    flat = arr.reshape(-1)
    need = dim * count
    if flat.size < need or flat.size % dim != 0:
        what = f"{dim} component{'s' if dim > 1 else ''}" + (f" × {count} elements" if count > 1 else "")
        raise ValueError(f"expected {what}, got {flat.size} value{'s' if flat.size != 1 else ''}")
    return flat[:need].astype(dtype).tobytes()


def write_uniform(uniform, value) -> None:
    """Set a moderngl uniform from a Python/numpy value (see :func:`encode_uniform`)."""
    uniform.write(encode_uniform(uniform, value))
