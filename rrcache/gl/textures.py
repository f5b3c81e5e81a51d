"""GL textures from image arrays (session textures and test data).

Arrays follow image conventions: a 2D image is ``H×W×C`` (``C`` in 1..4) with row 0 the *top* of
the image; a cube map is ``6×H×W×C`` in the order +X −X +Y −Y +Z −Z. A 2D image is flipped on
upload so that texture coordinate ``t = 1`` is the top row (OpenGL's origin is bottom-left); cube
faces are uploaded as they are, since the cube-map convention already puts a face's row 0 at the
top. The element type picks the texture format: ``float32`` → 32-bit float (``RGBA32F`` ...),
``float16`` → half floats, ``uint8`` → normalised 8-bit.

>>> import numpy as np
>>> from rrcache.gl.context import get_context
>>> tex = texture_from_array(get_context(), np.zeros((2, 3, 4), np.float32))
>>> tex.size, tex.components, tex.dtype
((3, 2), 4, 'f4')
>>> tex.release()
"""
from __future__ import annotations

import moderngl
import numpy as np

from rrcache.errors import GLError

_DTYPES = {np.dtype(np.float32): "f4", np.dtype(np.float16): "f2", np.dtype(np.uint8): "f1"}
FILTERS = ("linear", "nearest", "mipmap")
WRAPS = ("repeat", "clamp", "mirror")
_GL_TEXTURE_2D, _GL_TEXTURE_WRAP_S, _GL_TEXTURE_WRAP_T, _GL_MIRRORED_REPEAT = 0x0DE1, 0x2802, 0x2803, 0x8370
_tex_parameteri = None


def _gl_tex_parameteri():
    """``glTexParameteri`` through EGL (moderngl exposes no mirrored-repeat wrap mode)."""
    global _tex_parameteri
    if _tex_parameteri is None:
        import ctypes

        try:
            egl = ctypes.CDLL("libEGL.so.1")
        except OSError as err:
            raise GLError(f"cannot load libEGL.so.1 for the mirrored wrap mode: {err}",
                          hint="install libegl1, or use wrap 'repeat' or 'clamp'") from err
        egl.eglGetProcAddress.restype = ctypes.c_void_p
        egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
        addr = egl.eglGetProcAddress(b"glTexParameteri")
        if not addr:
            raise GLError("the EGL driver does not expose glTexParameteri", hint="use wrap 'repeat' or 'clamp'")
        _tex_parameteri = ctypes.CFUNCTYPE(None, ctypes.c_uint, ctypes.c_uint, ctypes.c_int)(addr)
    return _tex_parameteri


def _set_mirrored(tex) -> None:
    fn = _gl_tex_parameteri()
    tex.use(0)
    fn(_GL_TEXTURE_2D, _GL_TEXTURE_WRAP_S, _GL_MIRRORED_REPEAT)
    fn(_GL_TEXTURE_2D, _GL_TEXTURE_WRAP_T, _GL_MIRRORED_REPEAT)


def _gl_dtype(data: np.ndarray, name: str) -> str:
    if data.dtype == np.float64:
        return "f4"
    try:
        return _DTYPES[data.dtype]
    except KeyError:
        raise GLError(f"texture {name}: unsupported element type {data.dtype}",
                      hint="use float32, float16 or uint8 image data") from None


def _filters(filter: str, mipmaps: bool) -> tuple[int, int]:
    if filter not in FILTERS:
        raise GLError(f"unknown texture filter {filter!r}", hint=f"use one of {', '.join(FILTERS)}")
    if filter == "mipmap":
        return (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
    if filter == "nearest":
        return (moderngl.NEAREST_MIPMAP_NEAREST if mipmaps else moderngl.NEAREST, moderngl.NEAREST)
    return (moderngl.LINEAR_MIPMAP_LINEAR if mipmaps else moderngl.LINEAR, moderngl.LINEAR)


def texture_from_array(
    ctx: moderngl.Context,
    data: np.ndarray,
    kind: str = "2d",
    filter: str = "linear",
    wrap: str = "repeat",
    mipmaps: bool = False,
    name: str = "<texture>",
):
    """A ``moderngl.Texture`` (``kind="2d"``) or ``TextureCube`` (``kind="cube"``) holding ``data``.

    ``filter``: ``linear``, ``nearest`` or ``mipmap`` (trilinear; ``mipmaps=True`` adds mipmaps to
    the other two); ``wrap`` (2D only): ``repeat``, ``clamp`` (to edge) or ``mirror``. The caller
    owns the texture and releases it. Raises :class:`GLError` for a shape or element
    type the GL cannot take.

    >>> import numpy as np
    >>> from rrcache.gl.context import get_context
    >>> faces = np.ones((6, 4, 4, 3), np.float32)
    >>> cube = texture_from_array(get_context(), faces, kind="cube", mipmaps=False)
    >>> cube.size
    (4, 4)
    >>> cube.release()
    """
    data = np.asarray(data)
    dtype = _gl_dtype(data, name)
    if data.dtype == np.float64:
        data = data.astype(np.float32)
    mipmaps = mipmaps or filter == "mipmap"
    min_f, mag_f = _filters(filter, mipmaps)
    if wrap not in WRAPS:
        raise GLError(f"texture {name}: unknown wrap mode {wrap!r}", hint=f"use one of {', '.join(WRAPS)}")
    if kind == "2d":
        if data.ndim == 2:
            data = data[:, :, None]
        if data.ndim != 3 or not 1 <= data.shape[2] <= 4 or data.shape[0] < 1 or data.shape[1] < 1:
            raise GLError(f"texture {name}: a 2D texture needs an H×W×C array with C in 1..4, got shape {data.shape}")
        h, w, c = data.shape
        tex = ctx.texture((w, h), c, np.ascontiguousarray(data[::-1]).tobytes(), dtype=dtype, alignment=1)
        tex.repeat_x = tex.repeat_y = wrap == "repeat"
        if wrap == "mirror":
            _set_mirrored(tex)
    elif kind == "cube":
        if data.ndim == 3:
            data = data[..., None]
        if data.ndim != 4 or data.shape[0] != 6 or not 1 <= data.shape[3] <= 4 or data.shape[1] != data.shape[2]:
            raise GLError(f"texture {name}: a cube map needs a 6×N×N×C array with C in 1..4, got shape {data.shape}")
        _, h, w, c = data.shape
        tex = ctx.texture_cube((w, h), c, np.ascontiguousarray(data).tobytes(), dtype=dtype, alignment=1)
    else:
        raise GLError(f"texture {name}: unknown kind {kind!r}", hint="use '2d' or 'cube'")
    if mipmaps:
        tex.build_mipmaps()  # (moderngl resets the filter here, so set it afterwards)
    tex.filter = (min_f, mag_f)
    return tex


def texture_from_asset(ctx: moderngl.Context, asset):
    """A texture for a session ``TextureAsset`` (``name``, ``kind``, ``data``, ``filter`` in
    ``linear nearest mipmap`` (trilinear with mipmaps), ``wrap`` in ``repeat clamp mirror``).

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from rrcache.gl.context import get_context
    >>> asset = SimpleNamespace(name="u_tex", kind="2d", data=np.zeros((4, 4, 3), np.float32))
    >>> texture_from_asset(get_context(), asset).release()
    """
    return texture_from_array(
        ctx,
        asset.data,
        kind=getattr(asset, "kind", "2d"),
        filter=getattr(asset, "filter", None) or "mipmap",
        wrap=getattr(asset, "wrap", None) or "repeat",
        name=getattr(asset, "name", "<texture>"),
    )
