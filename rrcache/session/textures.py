"""Image files → float32 arrays through OpenImageIO (PNG, JPEG, EXR, HDR, TIFF, ...).

The session loader reads each image's header when the session loads (:func:`read_header`: a
missing or unreadable file is reported then, and an image of more pixels than the budget,
``rrcache --max-texture-pixels``, is refused before anything is decoded); the pixels are decoded
when a shader samples the texture. OpenImageIO's codecs (libpng...) print their own warnings on
the process's stderr: they are silenced, and the error comes through OpenImageIO's error API. 8/16-bit integer images are scaled to 0..1; float and half images are kept
exactly (float data textures are used as arrays of records). Row 0 of the result is the
image's top row (see :class:`rrcache.session.model.TextureAsset` for how to upload it).
A cube map is six files (+X −X +Y −Y +Z −Z) of equal square size, or one image holding the six
faces side by side (a 6:1 horizontal strip) or stacked (a 1:6 vertical strip) in that order, or
one of the cross layouts glslViewer (and cmft, CubeMapGen) read (see :func:`split_cube_cross`).

>>> read_image("tests/data/sessions/textures/checker.png").shape
(4, 4, 3)
"""
from __future__ import annotations


import numpy as np

from rrcache.budgets import budget
from rrcache.errors import printable
from rrcache.files import OpenedFile, Refused, open_file
from rrcache.stdio import quiet_stderr


class ImageLoadError(Exception):
    """Raised by the readers; the loader turns it into an AssetError with the JSON path (and
    ``hint``, when the reader has one)."""

    def __init__(self, message: str, hint=None):
        super().__init__(message)
        self.hint = hint


def _clean(text: str) -> str:
    return printable(" ".join(str(text).split()))[:300]


def open_image_file(path: str, roots=None) -> OpenedFile:
    """The image file ``path`` opened by :mod:`rrcache.files`' rule (a regular file within
    ``rrcache --max-asset-bytes``, inside ``roots`` when given); ImageLoadError saying what it is
    otherwise (a FIFO or a device as such, not as "not found")."""
    try:
        return open_file(path, budget.asset_bytes, roots, limit_hint="raise it with 'rrcache --max-asset-bytes N ...'")
    except Refused as err:
        if err.kind == "missing":
            raise ImageLoadError("image file not found" if "NUL" not in err.reason else err.reason) from None
        if err.kind == "outside":
            raise
        raise ImageLoadError(f"the image file {err.reason}", err.hint) from None


def _open(source: "str | OpenedFile"):
    """An open ImageInput for ``source`` (a path, or a file opened by :func:`open_image_file`,
    read through its descriptor) and its spec, the size checked against the pixel budget."""
    import OpenImageIO as oiio

    opened = source if isinstance(source, OpenedFile) else open_image_file(source)
    try:
        with quiet_stderr():
            inp = oiio.ImageInput.open(opened.library_path)
    finally:
        if opened is not source:
            opened.close()
    if inp is None:
        raise ImageLoadError(f"cannot read image: {_clean(oiio.geterror()) or 'unknown format'}")
    spec = inp.spec()
    pixels = int(spec.width) * int(spec.height) * max(1, int(spec.depth))
    if spec.width < 1 or spec.height < 1:
        inp.close()
        raise ImageLoadError("the image is empty")
    if pixels > budget.image_pixels:
        inp.close()
        raise ImageLoadError(f"the image declares {spec.width}×{spec.height} pixels ({pixels:,}), more than the "
                             f"texture budget of {budget.image_pixels:,} pixels; nothing was decoded "
                             f"(hint: shrink the image, or raise the budget with "
                             f"'rrcache --max-texture-pixels N ...')")
    return inp, spec


def read_header(path: "str | OpenedFile") -> tuple[int, int, int]:
    """(width, height, channels) of the image ``path`` from its header, nothing decoded; raises
    :class:`ImageLoadError` for a missing or unreadable file or one beyond the pixel budget."""
    inp, spec = _open(path)
    inp.close()
    return int(spec.width), int(spec.height), int(spec.nchannels)


def read_image(path: "str | OpenedFile") -> np.ndarray:
    """Decode the first subimage of ``path`` into float32 H×W×C (row 0 = top row)."""
    import OpenImageIO as oiio

    inp, spec = _open(path)
    try:
        with quiet_stderr():
            data = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        err = _clean(inp.geterror())
    finally:
        inp.close()
    if data is None or err:
        raise ImageLoadError(f"cannot decode image: {err or 'read failed'}")
    data = np.asarray(data, dtype=np.float32)
    if data.ndim == 2:
        data = data[:, :, None]
    if data.ndim == 4:  # a volume image: keep the first slice
        data = data[0]
    if data.shape[0] < 1 or data.shape[1] < 1:
        raise ImageLoadError("the image is empty")
    return np.ascontiguousarray(data)


def cube_face_size(width: int, height: int) -> int:
    """The face size of a single-file cube map of ``width``×``height`` pixels (a strip or a
    cross, as :func:`split_cube_strip` reads it), from the header alone; ImageLoadError otherwise.

    >>> cube_face_size(8, 6)
    2
    """
    w, h = int(width), int(height)
    if w == 6 * h or h == 6 * w:
        return min(w, h)
    if w * 3 == h * 4 and w % 4 == 0:
        return w // 4
    if w * 4 == h * 3 and w % 3 == 0:
        return w // 3
    raise ImageLoadError(f"a single-file cube map must be a 6:1 or 1:6 strip or a 4:3 or 3:4 cross of "
                         f"square faces, got {w}×{h}")


def split_cube_strip(image: np.ndarray) -> np.ndarray:
    """A 6:1 horizontal or 1:6 vertical strip (or a cross, :func:`split_cube_cross`) → 6×S×S×C
    faces.

    >>> split_cube_strip(np.zeros((2, 12, 3), np.float32)).shape
    (6, 2, 2, 3)
    """
    h, w = image.shape[:2]
    cube_face_size(w, h)  # refuses any other shape
    if w == 6 * h:
        return np.ascontiguousarray(np.stack([image[:, k * h:(k + 1) * h] for k in range(6)]))
    if h == 6 * w:
        return np.ascontiguousarray(np.stack([image[k * w:(k + 1) * w] for k in range(6)]))
    return split_cube_cross(image)


def split_cube_cross(image: np.ndarray) -> np.ndarray:
    """A horizontal (4:3) or vertical (3:4) cross → 6×S×S×C faces (+X −X +Y −Y +Z −Z).

    The unfolded cube seen from inside, +Z in the middle (rows from the top)::

        horizontal cross        vertical cross
            .  +Y  .   .            .  +Y  .
           −X  +Z  +X  −Z          −X  +Z  +X
            .  −Y  .   .            .  −Y  .
                                    .  −Z  .    (upside down: rotated 180°)

    Each face comes out as it would in a strip; the vertical cross' −Z is turned back (glslViewer
    flips it horizontally and vertically too).

    >>> split_cube_cross(np.zeros((6, 8, 3), np.float32)).shape
    (6, 2, 2, 3)
    """
    h, w = image.shape[:2]
    if w * 3 == h * 4 and w % 4 == 0:
        s = w // 4
        cells = {0: (1, 2), 1: (1, 0), 2: (0, 1), 3: (2, 1), 4: (1, 1), 5: (1, 3)}  # face: (row, col)
        rotate = ()
    elif w * 4 == h * 3 and w % 3 == 0:
        s = w // 3
        cells = {0: (1, 2), 1: (1, 0), 2: (0, 1), 3: (2, 1), 4: (1, 1), 5: (3, 1)}
        rotate = (5,)
    else:
        raise ImageLoadError(f"a cube-map cross is 4:3 (horizontal) or 3:4 (vertical) with square faces, "
                             f"got {w}×{h}")
    faces = []
    for k in range(6):
        r, c = cells[k]
        face = image[r * s:(r + 1) * s, c * s:(c + 1) * s]
        faces.append(face[::-1, ::-1] if k in rotate else face)
    return np.ascontiguousarray(np.stack(faces))


def stack_cube_faces(faces: list[np.ndarray]) -> np.ndarray:
    """Six decoded faces → 6×S×S×C; raises ImageLoadError naming the face index on a mismatch."""
    first = faces[0].shape
    if first[0] != first[1]:
        raise ImageLoadError(f"cube faces must be square, face 0 is {first[1]}×{first[0]}", )
    for k, f in enumerate(faces):
        if f.shape != first:
            raise ImageLoadError(f"cube face {k} is {f.shape[1]}×{f.shape[0]}×{f.shape[2]}, "
                                 f"face 0 is {first[1]}×{first[0]}×{first[2]}")
    return np.ascontiguousarray(np.stack(faces))
