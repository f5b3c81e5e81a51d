"""Colour target formats: what a frame is drawn into.

Applications draw into 8-bit (``rgba8``) or half-float (``rgba16f``) colour targets; the error
runs of the profiler need the full float precision (``rgba32f``), so the harness and the cache
runtime take the format as an option. Timing depends on it: the colour write is part of every
pass that shades (16 bytes a pixel in ``rgba32f``, 4 in ``rgba8``).

>>> color_dtype("rgba8"), bytes_per_texel("rgba16f")
('f1', 8)
>>> color_dtype("rgb9")
Traceback (most recent call last):
    ...
ValueError: unknown colour format 'rgb9' (one of rgba8, rgba16f, rgba32f)
"""
from __future__ import annotations

import numpy as np

#: colour format name → moderngl dtype (four components each)
COLOR_FORMATS = {"rgba8": "f1", "rgba16f": "f2", "rgba32f": "f4"}
#: what timed runs draw into unless told otherwise (what applications use)
DEFAULT_TIMING_FORMAT = "rgba8"
#: what error runs draw into (exact)
ERROR_FORMAT = "rgba32f"
_NUMPY = {"f1": np.uint8, "f2": np.float16, "f4": np.float32}


def color_dtype(name: str) -> str:
    """The moderngl dtype of colour format ``name``; ValueError for an unknown name."""
    try:
        return COLOR_FORMATS[name]
    except KeyError:
        raise ValueError(f"unknown colour format {name!r} (one of {', '.join(COLOR_FORMATS)})") from None


def bytes_per_texel(name: str) -> int:
    """Bytes per pixel of an RGBA target of format ``name``."""
    return 4 * np.dtype(_NUMPY[color_dtype(name)]).itemsize


def texture_floats(data: bytes, dtype: str, shape) -> np.ndarray:
    """A texture's bytes (moderngl ``dtype``) as float32 of ``shape`` (8-bit normalised to [0, 1])."""
    arr = np.frombuffer(data, dtype=_NUMPY[dtype]).reshape(shape)
    if dtype == "f1":
        return arr.astype(np.float32) / np.float32(255.0)
    return arr.astype(np.float32) if dtype != "f4" else arr
