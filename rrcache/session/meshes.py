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


def load_mesh_file(path: str) -> MeshData:
    """Load one mesh file into MeshData; raise MeshLoadError with a reason on failure."""
    import trimesh

    ext = os.path.splitext(path)[1].lower()
    if ext not in FORMATS:
        raise MeshLoadError(f"unsupported mesh format {ext or '(none)'!r}; use one of {', '.join(FORMATS)}")
    if not os.path.isfile(path):
        raise MeshLoadError("mesh file not found")
    with _quiet_trimesh() as (records, caught):
        try:
            loaded = trimesh.load(path, process=False)
            parts = [_attributes(p) for p in _parts(loaded)]
        except ImportError as exc:
            raise _missing_package(exc) from None
        except Exception as exc:  # trimesh raises many types on a corrupt file
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
            raise MeshLoadError(f"cannot read mesh: {type(exc).__name__}" + (f": {first}" if first else "")) from None
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
