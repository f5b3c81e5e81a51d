"""The data a loaded session hands to the harness: plain dataclasses, no file access.

Matrices follow the project convention: numpy ``float64`` 4×4, row-major, column vectors
(``p' = M @ p``); upload to GL as ``M.T.astype("f4").tobytes()``.

Example::

    >>> from rrcache.session import load_session
    >>> s = load_session("tests/data/sessions/minimal.json")
    >>> cam = s.camera_at(0); cam.view.shape, cam.projection(4 / 3).shape
    ((4, 4), (4, 4))
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from rrcache.session.camera import look_at, perspective


@dataclass(eq=False)
class MeshData:
    """A triangle mesh ready for a vertex buffer.

    ``positions`` N×3 float32, ``normals`` N×3 float32 (unit length), ``texcoords`` N×2 float32 or
    None, ``colors`` N×4 float32 in 0..1 or None, ``tangents`` N×4 float32 (xyz unit, w = ±1
    handedness: bitangent = w · cross(normal, tangent)) or None, ``indices`` M×3 uint32 with
    counter-clockwise front faces.

    >>> from rrcache.session.procedural import make_mesh
    >>> m = make_mesh({"type": "box"}); m.face_count
    12
    """

    positions: np.ndarray
    normals: np.ndarray
    indices: np.ndarray
    texcoords: np.ndarray | None = None
    colors: np.ndarray | None = None
    tangents: np.ndarray | None = None
    #: one line per complaint of the mesh file's loader (e.g. a missing texture it names)
    notes: tuple = ()

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def face_count(self) -> int:
        return int(self.indices.shape[0])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned (min, max) corners of the positions, float64."""
        p = self.positions.astype(np.float64)
        return p.min(axis=0), p.max(axis=0)


@dataclass(eq=False)
class Camera:
    """The camera at one frame. ``fov`` is the vertical field of view in degrees.

    >>> c = Camera(np.array([0., 0, 5]), np.zeros(3), np.array([0., 1, 0]), 45.0, 0.1, 100.0)
    >>> (c.view @ [0, 0, 0, 1])[:3].round(6).tolist()
    [0.0, 0.0, -5.0]
    """

    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    fov: float
    near: float
    far: float
    view: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.view = look_at(self.eye, self.target, self.up)

    def projection(self, aspect: float) -> np.ndarray:
        """OpenGL perspective matrix (clip z: near → -1, far → +1) for width/height ``aspect``."""
        return perspective(self.fov, aspect, self.near, self.far)


@dataclass(frozen=True)
class ShadowMap:
    """A session light's shadow map: ``size`` texels square, the light looking at ``target``
    (None: the centre of the scene's bounds) over ``extent`` either side (None: their radius);
    see :mod:`rrcache.session.shadow`."""

    size: int
    target: tuple[float, float, float] | None = None
    extent: float | None = None


@dataclass(eq=False)
class Light:
    """A point light at one frame: world ``position`` and linear RGB ``color`` (float64 3-vectors),
    and its ``shadow_map`` (None when the session asks for none)."""

    position: np.ndarray
    color: np.ndarray
    shadow_map: ShadowMap | None = None


@dataclass(eq=False)
class SceneObject:
    """One object of the scene: its mesh and its animated model matrix (T·R·S).

    >>> from rrcache.session.procedural import make_mesh
    >>> o = SceneObject("box", make_mesh({"type": "box"}), lambda f: np.eye(4))
    >>> o.model_matrix(3).tolist() == np.eye(4).tolist()
    True
    """

    name: str
    mesh: MeshData
    _model: Callable[[int], np.ndarray] = field(repr=False)
    source: str = ""  # the resolved mesh file, or "procedural:<type>"
    double_sided: bool = False  # draw back faces (open meshes); closed meshes cull them

    def model_matrix(self, frame: int) -> np.ndarray:
        """The 4×4 object-to-world matrix at ``frame`` (an int)."""
        return self._model(check_frame(frame))


#: the filter of a session texture that names none (see :class:`TextureAsset`)
DEFAULT_FILTER = "mipmap"


class TextureAsset:
    """An image bound to a sampler uniform.

    ``data`` is float32 H×W×C (``kind == "2d"``) or 6×H×W×C (``"cube"``, faces +X −X +Y −Y +Z −Z),
    with C the file's channel count (1–4). 8/16-bit images are scaled to 0..1; float images are
    kept bit-exact. Row 0 is the image's *top* row: for a 2D texture the harness must flip rows
    (``data[::-1]``) before upload so that texcoord v = 0 samples the image's bottom row as GL
    expects; cube-map faces are uploaded as stored (GL's cube-map convention has row 0 at the top).
    ``filter`` is ``linear|nearest|mipmap``, ``wrap`` ``repeat|clamp|mirror``; a texture given
    without a filter gets :data:`DEFAULT_FILTER` (``mipmap``: mipmaps generated and trilinear
    filtering, as an application sets up a texture its shader samples with an implicit level of
    detail; without mipmaps a minified ``texture()`` lookup aliases). ``path`` is the
    resolved file (the +X face for a cube map given as six files); ``files`` lists every file read.

    The session loader reads only the image headers (size checked against the pixel budget) and
    gives a ``loader``: the pixels are decoded the first time ``data`` is read, so a texture the
    shader never samples is never decoded. ``header`` is the (width, height, channels) of the file.
    """

    def __init__(self, name: str, path: str, kind: str, data: "np.ndarray | None" = None,
                 filter: str = DEFAULT_FILTER, wrap: str = "repeat", files: tuple[str, ...] = (),
                 loader: "Callable[[], np.ndarray] | None" = None,
                 header: "tuple[int, int, int] | None" = None):
        if data is None and loader is None:
            raise ValueError("a TextureAsset needs data or a loader")
        self.name, self.path, self.kind = name, path, kind
        self.filter, self.wrap, self.files = filter, wrap, tuple(files)
        self._data, self._loader, self.header = data, loader, header

    def __repr__(self) -> str:
        return (f"TextureAsset(name={self.name!r}, path={self.path!r}, kind={self.kind!r}, "
                f"loaded={self.loaded}, filter={self.filter!r}, wrap={self.wrap!r})")

    @property
    def loaded(self) -> bool:
        """Whether the pixels have been decoded."""
        return self._data is not None

    @property
    def data(self) -> np.ndarray:
        """The decoded pixels (decoded now if they were not yet)."""
        if self._data is None:
            self._data = self._loader()
        return self._data

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of the image (of one face for a cube map)."""
        if self._data is None and self.header is not None and self.kind == "2d":
            return int(self.header[0]), int(self.header[1])
        h, w = self.data.shape[-3], self.data.shape[-2]
        return int(w), int(h)

    @property
    def channels(self) -> int:
        if self._data is None and self.header is not None:
            return int(self.header[2])
        return int(self.data.shape[-1])


def check_frame(frame: Any) -> int:
    """Accept an int frame number (Python or numpy integer, not bool); raise TypeError otherwise."""
    if isinstance(frame, (bool, np.bool_)) or not isinstance(frame, (int, np.integer)):
        raise TypeError(f"frame must be an int, got {type(frame).__name__} {frame!r}")
    return int(frame)


@dataclass(eq=False)
class Session:
    """A validated session: resolution, frame count, camera and light paths, objects, uniforms
    and textures. Build it with :func:`rrcache.session.load_session`.

    >>> from rrcache.session import load_session
    >>> s = load_session("tests/data/sessions/minimal.json")
    >>> s.resolution, s.frames, s.camera_at(0).fov
    ((64, 48), 4, 45.0)
    """

    path: str
    resolution: tuple[int, int]
    frames: int
    fps: float
    objects: list[SceneObject]
    textures: dict[str, TextureAsset]
    hash: str
    name: str = ""
    description: str = ""
    background: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    document: dict = field(default_factory=dict, repr=False)
    #: the user's vertex shader file (``"vertex"``, resolved), or None for a generated one
    vertex: str | None = None
    #: that file's text, read (by :mod:`rrcache.files`' rule, confined) when the session loaded
    vertex_text: str | None = field(default=None, repr=False)
    #: what loading the session's assets had to say that is not an error (one line each)
    notes: list = field(default_factory=list)
    #: the session's "include_dirs", resolved against its folder (after the command line's -I)
    include_dirs: tuple[str, ...] = ()
    _camera: Callable[[int], Camera] | None = field(default=None, repr=False)
    _light: Callable[[int], Light] | None = field(default=None, repr=False)
    _uniforms: Callable[[int], dict[str, Any]] | None = field(default=None, repr=False)

    @property
    def aspect(self) -> float:
        """width / height of the resolution."""
        return self.resolution[0] / self.resolution[1]

    def time_at(self, frame: int) -> float:
        """Seconds at ``frame`` (``frame / fps``), the value of ``u_time``."""
        return check_frame(frame) / self.fps

    def camera_at(self, frame: int) -> Camera:
        """The :class:`Camera` at ``frame`` (an int; held constant outside the keyframes)."""
        return self._camera(check_frame(frame))

    def light_at(self, frame: int) -> Light:
        """The :class:`Light` at ``frame``."""
        return self._light(check_frame(frame))

    @property
    def shadow_map(self) -> ShadowMap | None:
        """The light's :class:`ShadowMap` settings (None when the session has no shadow map)."""
        return self.light_at(0).shadow_map if self._light is not None else None

    def uniform_values(self, frame: int) -> dict[str, Any]:
        """Session uniforms at ``frame``: name → int, bool, float or numpy array.

        Flat arrays come back 1-D (int64 when every number was a JSON integer, bool when every
        element was a boolean, float64 otherwise); matrices given as nested lists of columns come
        back as a rows×cols float64 matrix (``M[:, j]`` = column ``j``), so upload ``M.T.ravel()``.
        """
        return self._uniforms(check_frame(frame))
