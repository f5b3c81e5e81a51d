"""Mesh files (OBJ, PLY, STL, GLB/GLTF, OFF) → MeshData, through trimesh.

Files are loaded without trimesh's vertex merging, so UV seams and flat-shaded STL facets are
kept as written; a scene (GLB/GLTF, multi-object OBJ) is flattened into one mesh with every
node's transform applied. Normals come from the file when present, otherwise area-weighted
vertex normals are computed. Texcoords and vertex colours are kept when the file has them
(for every part of a flattened scene); tangents are computed when there are texcoords.

trimesh's own log records, warnings and tracebacks never reach the user: a load that fails
becomes a :class:`MeshLoadError` (one line: the reason, and for an optional package trimesh needs
for this file, which one to install); a load that succeeds with complaints (a PLY or OBJ naming a
texture image that is missing: rrcache does not use mesh textures) keeps one line per complaint
in ``MeshData.notes``, which the session's notes carry to the user.

>>> m = load_mesh_file("tests/data/sessions/meshes/tetra.obj")
>>> m.face_count
4
"""
from __future__ import annotations

import contextlib
import logging
import os
import warnings

import numpy as np

from rrcache.session.model import MeshData
from rrcache.session.tangents import compute_tangents, vertex_normals

FORMATS = (".obj", ".ply", ".stl", ".glb", ".gltf", ".off")


class MeshLoadError(Exception):
    """Raised by :func:`load_mesh_file`; the loader turns it into an AssetError with the JSON path."""


#: module trimesh imports for some files -> the package that provides it (declared in pyproject)
_OPTIONAL_PACKAGES = {"charset_normalizer": "charset-normalizer", "PIL": "pillow", "chardet": "charset-normalizer",
                      "networkx": "networkx", "lxml": "lxml", "scipy": "scipy"}


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__(logging.WARNING)
        self.records: list[logging.LogRecord] = []

    def emit(self, record):
        self.records.append(record)


@contextlib.contextmanager
def _quiet_trimesh():
    """Collect trimesh's log records (WARNING and above) and Python warnings instead of letting
    them print; yields (records, warnings)."""
    logger = logging.getLogger("trimesh")
    handler = _Collect()
    saved = logger.handlers[:], logger.propagate, logger.level
    logger.handlers, logger.propagate = [handler], False
    if logger.level == logging.NOTSET or logger.level > logging.WARNING:
        logger.setLevel(logging.WARNING)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield handler.records, caught
        finally:
            logger.handlers, logger.propagate = saved[0], saved[1]
            logger.setLevel(saved[2])


def _note(record: logging.LogRecord) -> str:
    """One line for a trimesh log record."""
    message = record.getMessage().strip().splitlines()[0] if record.getMessage().strip() else "warning"
    exc = record.exc_info[1] if record.exc_info else None
    if isinstance(exc, FileNotFoundError) and "image" in message.lower():
        return f"the mesh names a texture image that is missing ({exc}); ignored (rrcache does not use mesh textures)"
    if exc is not None:
        return f"{message.rstrip('!.')}: {type(exc).__name__}: {exc}"
    return message


def _missing_package(exc: ImportError) -> MeshLoadError:
    name = (exc.name or "").split(".")[0] or str(exc)
    package = _OPTIONAL_PACKAGES.get(name, name)
    return MeshLoadError(f"reading this file needs the Python package '{package}' (an optional dependency "
                         f"of trimesh), which is not installed; install it: pip install {package}")


def _parts(loaded):
    import trimesh

    if isinstance(loaded, trimesh.Trimesh):
        return [loaded]
    if isinstance(loaded, trimesh.Scene):
        parts = []
        for node in loaded.graph.nodes_geometry:
            transform, name = loaded.graph[node]
            geom = loaded.geometry.get(name)
            if isinstance(geom, trimesh.Trimesh) and len(geom.faces):
                g = geom.copy()
                g.apply_transform(transform)
                parts.append(g)
        return parts
    return []


def _attributes(mesh) -> dict:
    v = np.asarray(mesh.vertices, dtype=np.float64)
    f = np.asarray(mesh.faces, dtype=np.int64)
    out = {"positions": v, "indices": f, "texcoords": None, "colors": None}
    # trimesh keeps normals read from the file in its cache; otherwise it would compute them
    from_file = "vertex_normals" in getattr(getattr(mesh, "_cache", None), "cache", {})
    out["normals"] = np.asarray(mesh.vertex_normals, dtype=np.float64) if from_file else None
    visual = mesh.visual
    kind = getattr(visual, "kind", None)
    uv = getattr(visual, "uv", None) if kind == "texture" else None
    if uv is not None and len(uv) == len(v):
        out["texcoords"] = np.asarray(uv, dtype=np.float64)[:, :2]
    if kind == "vertex":
        colors = np.asarray(visual.vertex_colors)
        if colors.shape[0] == len(v):
            scale = 255.0 if colors.dtype == np.uint8 or colors.max() > 1.0 else 1.0
            c = colors.astype(np.float64) / scale
            if c.shape[1] == 3:
                c = np.concatenate([c, np.ones((len(c), 1))], 1)
            out["colors"] = c
    return out


class _ConfinedResolver:
    """trimesh's resolver for the files a mesh names (an OBJ's material library, a glTF's
    buffers): each read by :mod:`rrcache.files`' rule, inside ``roots`` (None: anywhere) and the
    asset budget; a refused one reads as missing, as trimesh expects."""

    def __init__(self, folder: str, roots):
        self.parent, self.roots = folder, roots

    def get(self, name: str) -> bytes:
        from rrcache.budgets import budget
        from rrcache.files import Refused, read_file

        path = os.path.normpath(os.path.join(self.parent, str(name)))
        try:
            return read_file(path, budget.asset_bytes, self.roots).data
        except Refused as err:
            raise FileNotFoundError(f"{name}: {err.reason}") from None

    def __getitem__(self, name: str) -> bytes:
        return self.get(name)

    def namespaced(self, namespace: str) -> "_ConfinedResolver":
        return _ConfinedResolver(os.path.join(self.parent, namespace), self.roots)

    def keys(self):
        return []

    def write(self, name, data):
        raise OSError("rrcache writes nothing beside a mesh")


def confined_resolver(folder: str, roots=None) -> _ConfinedResolver:
    """The resolver of the files a mesh in ``folder`` names (see :class:`_ConfinedResolver`)."""
    return _ConfinedResolver(folder, roots)


def load_mesh_file(path: str, roots=None) -> MeshData:
    """Load one mesh file into MeshData, read by :mod:`rrcache.files`' rule (a regular file
    within ``rrcache --max-asset-bytes``; inside ``roots`` when given); raise MeshLoadError with a
    reason on failure."""
    from rrcache.budgets import budget
    from rrcache.files import Refused, read_file

    ext = os.path.splitext(path)[1].lower()
    if ext not in FORMATS:
        raise MeshLoadError(f"unsupported mesh format {ext or '(none)'!r}; use one of {', '.join(FORMATS)}")
    try:
        data = read_file(path, budget.asset_bytes, roots,
                         limit_hint="raise it with 'rrcache --max-asset-bytes N ...'").data
    except Refused as err:
        raise MeshLoadError("mesh file not found" if err.kind == "missing" else f"the mesh file {err.reason}")
    return load_mesh_data(data, ext, confined_resolver(os.path.dirname(path), roots))


def load_mesh_data(data: bytes, ext: str, resolver=None) -> MeshData:
    """The mesh held in ``data`` (the bytes of a file of format ``ext``); the files it names
    (materials, buffers) come through ``resolver``. Raises MeshLoadError."""
    import io

    import trimesh

    if ext not in FORMATS:
        raise MeshLoadError(f"unsupported mesh format {ext or '(none)'!r}; use one of {', '.join(FORMATS)}")
    check_header(data, ext)
    with _quiet_trimesh() as (records, caught):
        try:
            loaded = trimesh.load(io.BytesIO(data), file_type=ext.lstrip("."), process=False, resolver=resolver)
            parts = [_attributes(p) for p in _parts(loaded)]
        except ImportError as exc:
            raise _missing_package(exc) from None
        except Exception as exc:  # trimesh raises many types on a corrupt file
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
            raise MeshLoadError(f"cannot read mesh: {type(exc).__name__}" + (f": {first}" if first else "")) from None
    for p in parts:
        _check_part(p, data, ext)
    for record in records:
        inner = record.exc_info[1] if record.exc_info else None
        if isinstance(inner, ImportError) and not parts:
            raise _missing_package(inner)
    notes = []
    for line in [_note(r) for r in records] + [str(w.message).strip().splitlines()[0] for w in caught
                                               if str(w.message).strip()]:
        if line not in notes:
            notes.append(line)
    if not parts:
        raise MeshLoadError("the file holds no triangles")
    positions = np.concatenate([p["positions"] for p in parts])
    offsets = np.cumsum([0] + [len(p["positions"]) for p in parts[:-1]])
    indices = np.concatenate([p["indices"] + o for p, o in zip(parts, offsets)])
    if not np.all(np.isfinite(positions)):
        raise MeshLoadError("the file has non-finite vertex positions")
    normals = []
    for p in parts:
        n = p["normals"]
        if n is None or n.shape != p["positions"].shape or not np.all(np.isfinite(n)):
            n = vertex_normals(p["positions"], p["indices"])
        normals.append(n)
    normals = np.concatenate(normals).astype(np.float64)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(length > 1e-20, normals / np.maximum(length, 1e-300), [0.0, 0.0, 1.0])
    texcoords = (np.concatenate([p["texcoords"] for p in parts])
                 if all(p["texcoords"] is not None for p in parts) else None)
    colors = (np.concatenate([p["colors"] for p in parts])
              if all(p["colors"] is not None for p in parts) else None)
    tangents = compute_tangents(positions, normals, texcoords, indices) if texcoords is not None else None
    return MeshData(positions=positions.astype(np.float32), normals=normals.astype(np.float32),
                    indices=indices.astype(np.uint32),
                    texcoords=None if texcoords is None else texcoords.astype(np.float32),
                    colors=None if colors is None else colors.astype(np.float32), tangents=tangents,
                    notes=tuple(notes))


def _check_part(part: dict, data: bytes, ext: str) -> None:
    """A loaded part has three coordinates per vertex and triangles that index its vertices
    (an OBJ line ``v 0 0`` gave trimesh two-coordinate vertices)."""
    v, f = part["positions"], part["indices"]
    if v.ndim != 2 or v.shape[1] != 3:
        where = ""
        if ext == ".obj":
            for number, line in enumerate(data.decode("utf-8", "replace").splitlines(), 1):
                words = line.split()
                if words and words[0] == "v" and len(words) < 4:
                    where = f" (line {number}: 'v' with {len(words) - 1} coordinate{'s' if len(words) != 2 else ''})"
                    break
        raise MeshLoadError(f"the vertices have {v.shape[1] if v.ndim == 2 else 0} coordinates, a mesh needs 3 "
                            f"(x y z){where}")
    if f.ndim != 2 or f.shape[1] != 3 or (f.size and (f.min() < 0 or f.max() >= len(v))):
        raise MeshLoadError("the faces are not triangles of the file's vertices")


#: the fewest bytes one value takes in a binary PLY (by type name), and in ASCII (a digit and a
#: separator)
_PLY_SIZES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2, "int16": 2, "uint16": 2,
              "int": 4, "uint": 4, "int32": 4, "uint32": 4, "float": 4, "float32": 4, "double": 8, "float64": 8}
_ASCII_VALUE = 2


def check_header(data: bytes, ext: str) -> None:
    """Refuse a PLY or OFF whose header declares more vertices and faces than the file's bytes
    can hold (a few hundred bytes claiming 10⁹ vertices), before any array is made for them.

    >>> check_header(b"OFF\\n1000000000 1 0\\n0 0 0\\n", ".off")
    Traceback (most recent call last):
    ...
    rrcache.session.meshes.MeshLoadError: the OFF header declares 1,000,000,000 vertices and 1 faces, which need at least 6,000,000,008 bytes; the file has 25
    """
    if ext == ".ply":
        _check_ply(data)
    elif ext == ".off":
        _check_off(data)


def _claim(what: str, counts: dict, need: int, have: int) -> None:
    if need > have:
        said = " and ".join(f"{n:,} {name}" for name, n in counts.items())
        raise MeshLoadError(f"the {what} header declares {said}, which need at least {need:,} bytes; "
                            f"the file has {have:,}")


def _check_ply(data: bytes) -> None:
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        return  # trimesh says what is wrong with it
    body = len(data) - data.find(b"\n", end) - 1
    binary, elements = True, []
    for line in data[:end].decode("ascii", "replace").splitlines():
        words = line.split()
        if len(words) >= 2 and words[0] == "format":
            binary = words[1] != "ascii"
        elif len(words) >= 3 and words[0] == "element" and words[2].isdigit():
            elements.append([words[1], int(words[2]), 0])
        elif len(words) >= 3 and words[0] == "property" and elements:
            if words[1] == "list" and len(words) >= 4:  # at least the count of each list
                elements[-1][2] += _PLY_SIZES.get(words[2], 1) if binary else _ASCII_VALUE
            else:
                elements[-1][2] += _PLY_SIZES.get(words[1], 1) if binary else _ASCII_VALUE
    need = sum(count * size for _, count, size in elements)
    plural = {"vertex": "vertices", "face": "faces"}
    _claim("PLY", {plural.get(name, f"'{name}' elements"): count for name, count, _ in elements}, need, body)


def _check_off(data: bytes) -> None:
    words = data[:4096].split()
    if not words or not words[0].endswith(b"OFF"):
        return
    numbers = [w for w in words[1:4] if w.isdigit()]
    if len(numbers) < 2:
        return
    vertices, faces = int(numbers[0]), int(numbers[1])
    # "x y z\n" and "3 a b c\n": three and four values of at least two bytes each
    _claim("OFF", {"vertices": vertices, "faces": faces}, vertices * 3 * _ASCII_VALUE + faces * 4 * _ASCII_VALUE,
           len(data))
