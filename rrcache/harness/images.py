"""Writing rendered frames as image files through OpenImageIO.

EXR keeps the float32 RGBA values bit-exact; PNG (and other 8-bit formats) clamp to [0, 1] and
quantise, with straight (unassociated) alpha, since shaders write straight colour.

>>> import os, tempfile
>>> import numpy as np
>>> path = os.path.join(tempfile.mkdtemp(), "frame.exr")
>>> write_image(path, np.full((4, 4, 4), 0.25, np.float32))
>>> os.path.getsize(path) > 0
True
"""
from __future__ import annotations

import os

import numpy as np

from rrcache import atomic
from rrcache.errors import AssetError, printable
from rrcache.stdio import quiet_stderr

_FLOAT_FORMATS = (".exr", ".hdr", ".tif", ".tiff")


def write_image(path: str | os.PathLike, image: np.ndarray) -> None:
    """Write an H×W×C float image (row 0 = top) to ``path``; the extension picks the format.

    EXR/HDR/TIFF are written as 32-bit float, anything else as 8 bits per channel. Raises
    :class:`AssetError` when OpenImageIO cannot write the file.
    """
    import OpenImageIO as oiio

    path = os.fspath(path)
    pixels = np.ascontiguousarray(np.asarray(image, dtype=np.float32))
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    h, w, c = pixels.shape
    is_float = path.lower().endswith(_FLOAT_FORMATS)
    if not is_float:
        pixels = np.clip(np.nan_to_num(pixels, nan=0.0), 0.0, 1.0)
    spec = oiio.ImageSpec(w, h, c, oiio.FLOAT if is_float else oiio.UINT8)
    if c == 4:
        spec.attribute("oiio:UnassociatedAlpha", 1)
    out = oiio.ImageOutput.create(path)
    if out is None:
        raise AssetError(f"cannot write an image: {oiio.geterror()}", path,
                         hint="use a .exr or .png file name")
    # written beside, read back, then renamed: a full disk leaves no empty or truncated image
    # (OpenImageIO's codecs do not always report a failed write)
    with atomic.via_file(path) as tmp:
        with quiet_stderr():
            ok = out.open(tmp, spec) and out.write_image(pixels)
            message = out.geterror()
            out.close()
            check = oiio.ImageInput.open(tmp) if ok else None
            if check is not None:
                ok = check.read_image(0, 0, 0, c, oiio.FLOAT) is not None and not check.geterror()
                check.close()
            else:
                ok = False
        if not ok:
            raise AssetError(f"cannot write the image: {printable(message) or 'it did not read back whole (is the disk full?)'}",
                             path, hint="check that the folder is writable and the disk has room")
