"""``load_session(path) -> Session``: read, validate and assemble a session file.

Steps: read and parse the JSON (syntax errors give line and column; duplicate keys, NaN and
Infinity are rejected), check ``rrcache_session`` is 1, validate against ``schema.json``, then
build the camera, light, objects (mesh files and procedural meshes), uniforms and textures.
Meshes are decoded and image headers read here, so every missing or unreadable asset is reported
here as an AssetError naming the session file, the JSON path and the resolved file (an image's
pixels are decoded when a shader first samples it). Mesh, image and include paths are confined
to the session file's folder tree unless the session says ``"allow_outside_paths": true`` or the
command line ``rrcache --allow-outside-paths``. ``Session.hash``
is a sha256 over the canonical JSON and the bytes of every asset file read.

>>> s = load_session("tests/data/sessions/minimal.json")
>>> s.camera_at(0).view.shape
(4, 4)
"""
from __future__ import annotations

import hashlib
import json
import math
import os
from typing import Any

from rrcache.budgets import budget
from rrcache.errors import AssetError, SessionError, printable
from rrcache.files import OpenedFile, Refused, inside, read_file
from rrcache.session import procedural, textures as tex
from rrcache.session.meshes import FORMATS, MeshLoadError, confined_resolver, load_mesh_data
from rrcache.session.model import DEFAULT_FILTER, MeshData, SceneObject, Session, TextureAsset
from rrcache.session.scene import camera_function, light_function, model_function
from rrcache.session.uniforms import BUILTIN_UNIFORMS, uniform_function
from rrcache.session.validation import json_path, validate_document

#: Bumped whenever the meshes or images built from the same files would change.
LOADER_VERSION = 1


class _DuplicateKey(Exception):
    pass


def _pairs(pairs: list) -> dict:
    out = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(key)
        out[key] = value
    return out


def _no_constant(name: str):
    raise ValueError(f"{name} is not a valid JSON number")


def parse_json(text: str, file: str) -> Any:
    """Parse session text; a syntax error becomes SessionError with its line and column."""
    try:
        return json.loads(text, object_pairs_hook=_pairs, parse_constant=_no_constant)
    except json.JSONDecodeError as e:
        err = SessionError(f"invalid JSON at line {e.lineno}, column {e.colno}: {e.msg}", file, None,
                           "check for a missing comma, quote or bracket near that place")
        err.line, err.col = e.lineno, e.colno
        raise err from None
    except _DuplicateKey as e:
        raise SessionError(f"duplicate key {e.args[0]!r}", file, None, "each key may appear once per object") from None
    except (ValueError, RecursionError) as e:
        raise SessionError(f"invalid JSON: {e}", file, None) from None


def _check_text(text: str, file: str, parts: list) -> None:
    """A JSON string may spell a lone UTF-16 surrogate (``"\\ud800"``), which is no character:
    refused here, at its path, rather than failing later when it is written out."""
    for ch in text:
        if "\ud800" <= ch <= "\udfff":
            raise SessionError(f"the text holds a lone surrogate (\\u{ord(ch):04x}), which is not a character",
                               file, json_path(parts) or None, "write the text as plain UTF-8")


def _check_numbers(value: Any, file: str, parts: list) -> None:
    if isinstance(value, str):
        _check_text(value, file, parts)
        return
    if isinstance(value, float) and not math.isfinite(value):
        raise SessionError(f"number {value} is out of range", file, json_path(parts))
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 2 ** 63 - 1:
        raise SessionError("integer is out of range", file, json_path(parts))
    if isinstance(value, dict):
        for k, v in value.items():
            _check_text(k, file, parts + [k])
            _check_numbers(v, file, parts + [k])
    elif isinstance(value, list):
        for k, v in enumerate(value):
            _check_numbers(v, file, parts + [k])


def check_size(doc: dict, file: str) -> None:
    """Refuse a session beyond the budgets before it is validated (validating and building a
    keyframe or an object takes the schema and the scene builders milliseconds each): more JSON
    values than ``budget.session_values`` (``--max-session-values``; counted only up to the
    limit) or more objects than ``budget.session_objects`` (``--max-session-objects``)."""
    objects = doc.get("objects")
    if isinstance(objects, list) and len(objects) > budget.session_objects:
        raise SessionError(f"the session has {len(objects):,} objects, more than the {budget.session_objects:,} "
                           "rrcache loads", file, "objects",
                           "merge meshes into fewer objects, or raise the budget with "
                           "'rrcache --max-session-objects N ...'")
    count, stack = 0, [doc]
    while stack:
        value = stack.pop()
        count += 1
        if count > budget.session_values:
            raise SessionError(f"the session holds more than {budget.session_values:,} JSON values (numbers, "
                               "strings, lists, objects), the most rrcache loads", file, None,
                               "thin the keyframes (the camera and objects are interpolated between them), or "
                               "raise the budget with 'rrcache --max-session-values N ...'")
        if isinstance(value, dict):
            stack.extend(value.values())
        elif isinstance(value, list):
            stack.extend(value)


def check_version(doc: Any, file: str) -> None:
    """The document must be an object with ``"rrcache_session": 1``."""
    if not isinstance(doc, dict):
        raise SessionError(f"a session is a JSON object, got {type(doc).__name__}", file, None,
                           'start the file with {"rrcache_session": 1, ...}')
    if "rrcache_session" not in doc:
        raise SessionError("not an rrcache session: the key 'rrcache_session' is missing", file, None,
                           'add "rrcache_session": 1')
    v = doc["rrcache_session"]
    if isinstance(v, bool) or v != 1:
        raise SessionError(f"unsupported session format version {json.dumps(v)}", file, "rrcache_session",
                           "this rrcache reads version 1")


class _Assets:
    """Opens the asset files by :mod:`rrcache.files`' rule, loads each once and records what was
    read for the hash."""

    def __init__(self, file: str, confine: bool = True):
        self.file = file
        self.base = os.path.dirname(os.path.abspath(file))
        self.root = os.path.realpath(self.base)
        self.confine = confine
        self.files: list[tuple[str, object]] = []  # (path as written, bytes read or the open file)
        self.meshes: dict[str, MeshData] = {}
        self.images: dict[str, OpenedFile] = {}
        self.image_headers: dict[str, tuple[int, int, int]] = {}

    @property
    def roots(self):
        return [self.root] if self.confine else None

    def path(self, written: str, where: str | None = None, what: str = "file") -> str:
        """The path of ``written`` (relative to the session's folder)."""
        if "\0" in written:
            raise AssetError(f"the {what} path holds a NUL character, which no file name can", self.file, where,
                             "write the file's name without control characters")
        return os.path.normpath(os.path.join(self.base, os.path.expanduser(written)))

    def outside(self, written: str, real: str, where: str | None, what: str) -> AssetError:
        return AssetError(f"the {what} {printable(written)!r} resolves to {printable(real)}, outside the "
                          f"session's folder {printable(self.root)}", self.file, where,
                          'paths are confined to the session file\'s folder tree; if you trust the '
                          'session, allow others with "allow_outside_paths": true in it or '
                          "'rrcache --allow-outside-paths ...'")

    def folder(self, written: str, where: str, what: str) -> str:
        """The real path of the folder ``written`` (confined when confinement is on): callers
        keep the real path, so a link changed later cannot move what it names."""
        real = os.path.realpath(self.path(written, where, what))
        if self.confine and not inside(real, [self.root]):
            raise self.outside(written, real, where, what)
        return real

    def text(self, written: str, where: str, what: str, limit: int) -> tuple[str, str]:
        """(path, text) of a small text file the session names (its vertex shader), read by the rule."""
        path = self.path(written, where, what)
        try:
            got = read_file(path, limit, self.roots)
        except Refused as err:
            if err.kind == "outside":
                raise self.outside(written, err.real, where, what) from None
            said = (f"cannot find the {what} {printable(path)}" if err.kind == "missing"
                    else f"cannot read the {what} {printable(path)}: it {err.reason}")
            raise AssetError(said, self.file, where, err.hint or "the path is relative to the session file's folder") from None
        self.files.append((written, got.data))
        try:
            return path, got.data.decode("utf-8-sig")
        except UnicodeDecodeError:
            raise AssetError(f"the {what} {printable(path)} is not UTF-8 text", self.file, where) from None

    def mesh(self, written: str, where: str) -> tuple[MeshData, str]:
        path = self.path(written, where, "mesh")
        if path not in self.meshes:
            ext = os.path.splitext(path)[1].lower()
            try:
                if ext not in FORMATS:
                    load_mesh_data(b"", ext)  # the unsupported-format error, before any file is read
                got = read_file(path, budget.asset_bytes, self.roots,
                                limit_hint="raise it with 'rrcache --max-asset-bytes N ...'")
                self.meshes[path] = load_mesh_data(got.data, ext, confined_resolver(os.path.dirname(path), self.roots))
            except Refused as err:
                if err.kind == "outside":
                    raise self.outside(written, err.real, where, "mesh") from None
                raise AssetError(f"{'mesh file not found' if err.kind == 'missing' else 'the mesh file ' + err.reason}: "
                                 f"{printable(path)}", self.file, where,
                                 err.hint or "mesh paths are relative to the session file's folder") from None
            except MeshLoadError as e:
                raise AssetError(f"{e}: {printable(path)}", self.file, where,
                                 "mesh paths are relative to the session file's folder") from None
            self.files.append((written, got.data))
        return self.meshes[path], path

    def image(self, written: str, where: str):
        """The image's header (width, height, channels) and path; its pixels are decoded later,
        by :meth:`decode`, from the file opened now."""
        path = self.path(written, where, "image")
        try:
            opened = self.images.get(path) or tex.open_image_file(path, self.roots)
            header = tex.read_header(opened)
        except Refused as err:  # confinement: the opened file lies outside
            raise self.outside(written, err.real, where, "image") from None
        except tex.ImageLoadError as e:
            raise AssetError(f"{e}: {printable(path)}", self.file, where,
                             e.hint or "image paths are relative to the session file's folder") from None
        self.images[path] = opened
        self.files.append((written, opened))
        self.image_headers[path] = header
        return header, path

    def decode(self, path: str, where: str):
        try:
            return tex.read_image(self.images[path])
        except tex.ImageLoadError as e:
            raise AssetError(f"{e}: {printable(path)}", self.file, where,
                             e.hint or "image paths are relative to the session file's folder") from None

    def digest(self, doc: dict) -> str:
        """sha256 over the canonical JSON and the bytes of every asset, as they were read (an
        image through the descriptor it was opened with): no path is opened again."""
        h = hashlib.sha256(f"rrcache-session-1 loader-{LOADER_VERSION}\0".encode())
        h.update(json.dumps(doc, sort_keys=True, separators=(",", ":"), ensure_ascii=False).encode())
        for written, content in self.files:
            data = content if isinstance(content, bytes) else content.read(budget.asset_bytes)
            h.update(f"\0{written}\0{len(data)}\0".encode())
            h.update(data)
        return h.hexdigest()


def _objects(doc: dict, file: str, assets: _Assets) -> list[SceneObject]:
    objects, used, suffixes, shapes = [], set(), {}, {}
    for i, spec in enumerate(doc["objects"]):
        base = ["objects", i]
        if "mesh" in spec:
            mesh, source = assets.mesh(spec["mesh"], json_path(base + ["mesh"]))
            default_name = os.path.splitext(os.path.basename(spec["mesh"]))[0] or f"object{i}"
        else:
            proc = spec["procedural"]
            shape = json.dumps(proc, sort_keys=True)  # the same shape twice: one mesh, built once
            if shape not in shapes:
                shapes[shape] = procedural.make_mesh(proc, file, json_path(base + ["procedural"]))
            mesh = shapes[shape]
            source, default_name = f"procedural:{proc['type']}", proc["type"]
        if "name" in spec:
            name = spec["name"]
            if name in used:
                raise SessionError(f"another object is already named {name!r}", file, json_path(base + ["name"]))
        else:
            name, n = default_name, suffixes.get(default_name, 2)
            while name in used:
                name, n = f"{default_name}_{n}", n + 1
            suffixes[default_name] = n  # the next free suffix: naming n objects stays linear
        used.add(name)
        objects.append(SceneObject(name, mesh, model_function(spec.get("keyframes", []), file, i), source,
                                   bool(spec.get("double_sided", False))))
    return objects


def _textures(doc: dict, file: str, assets: _Assets) -> dict[str, TextureAsset]:
    out = {}
    for name in sorted(doc.get("textures", {})):
        spec = doc["textures"][name]
        spec = {"path": spec} if isinstance(spec, str) else spec
        base = ["textures", name]
        where = json_path(base)
        if name in BUILTIN_UNIFORMS:
            raise SessionError(f"{name} is a built-in uniform, not a sampler", file, where)
        if name in doc.get("uniforms", {}):
            raise SessionError(f"{name} is also set in 'uniforms'", file, where, "give each name once")
        kind = spec.get("kind", "cube" if "faces" in spec else "2d")
        if "faces" in spec and kind != "cube":
            raise SessionError("six 'faces' make a cube map; kind must be \"cube\"", file,
                               json_path(base + ["kind"]))
        if "faces" in spec:
            files, wheres, header = [], [], None
            for k, face in enumerate(spec["faces"]):
                wheres.append(json_path(base + ["faces", k]))
                face_header, path = assets.image(face, wheres[-1])
                header = header or face_header
                files.append(path)
            headers = [assets.image_headers[p] for p in files]
            w0, h0, c0 = headers[0]
            if w0 != h0:
                raise AssetError(f"cube faces must be square, face 0 is {w0}×{h0}", file, json_path(base + ["faces"]))
            for k, (w, h, c) in enumerate(headers):
                if (w, h, c) != (w0, h0, c0):
                    raise AssetError(f"cube face {k} is {w}×{h}×{c}, face 0 is {w0}×{h0}×{c0}", file,
                                     json_path(base + ["faces"]))
            loader = _cube_faces_loader(assets, list(files), wheres, file, json_path(base + ["faces"]))
        else:
            at = where if isinstance(doc["textures"][name], str) else json_path(base + ["path"])
            header, path = assets.image(spec["path"], at)
            files = [path]
            if kind == "cube":
                try:
                    size = tex.cube_face_size(header[0], header[1])
                except tex.ImageLoadError as e:
                    raise AssetError(f"{e}: {printable(path)}", file, at) from None
                header = (size, size, header[2])
            loader = _image_loader(assets, path, at, file, kind == "cube")
        out[name] = TextureAsset(name=name, path=files[0], kind=kind, loader=loader, header=header,
                                 filter=spec.get("filter", DEFAULT_FILTER),
                                 wrap=spec.get("wrap", "clamp" if kind == "cube" else "repeat"),
                                 files=tuple(files))
    return out


def _image_loader(assets: _Assets, path: str, at: str, file: str, cube: bool):
    def load():
        data = assets.decode(path, at)
        if cube:
            try:
                data = tex.split_cube_strip(data)
            except tex.ImageLoadError as e:
                raise AssetError(f"{e}: {printable(path)}", file, at) from None
        return data
    return load


def _cube_faces_loader(assets: _Assets, paths: list, wheres: list, file: str, at: str):
    def load():
        faces = [assets.decode(p, w) for p, w in zip(paths, wheres)]
        try:
            return tex.stack_cube_faces(faces)
        except tex.ImageLoadError as e:
            raise AssetError(str(e), file, at) from None
    return load


def _uniforms(doc: dict, file: str):
    functions = {name: uniform_function(name, value, file) for name, value in doc.get("uniforms", {}).items()}
    return lambda frame: {name: f(frame) for name, f in functions.items()}


def load_session(path: str | os.PathLike) -> Session:
    """Load and validate the session file at ``path``.

    Raises SessionError (bad JSON, schema violation, inconsistent values) or AssetError (a mesh
    or image that is missing or unreadable), each naming the file and the JSON path.

    >>> s = load_session("tests/data/sessions/minimal.json")
    >>> s.frames, [o.name for o in s.objects]
    (4, ['torus'])
    """
    file = os.fspath(path)
    try:
        raw = read_file(file, budget.document_bytes).data
    except Refused as err:
        if err.kind == "size":
            raise SessionError(f"the session file {err.reason}", file, None,
                               "raise the budget with 'rrcache --max-document-bytes N ...'") from None
        raise SessionError(f"cannot read the session file: {'not found' if err.kind == 'missing' else 'it ' + err.reason}",
                           file, None, "check the path; a relative one starts from the current folder"
                           if err.kind == "missing" else err.hint) from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise SessionError(f"the session file is not UTF-8 text (byte {e.start})", file, None) from None
    doc = parse_json(text, file)
    check_version(doc, file)
    check_size(doc, file)
    _check_numbers(doc, file, [])
    validate_document(doc, file)
    allow_outside = bool(doc.get("allow_outside_paths", False)) or budget.allow_outside_paths
    assets = _Assets(file, confine=not allow_outside)
    camera = camera_function(doc["camera"], file)
    light = light_function(doc.get("light"), camera, file)
    objects = _objects(doc, file, assets)
    uniforms = _uniforms(doc, file)
    textures = _textures(doc, file, assets)
    vertex = vertex_text = None
    if "vertex" in doc:
        vertex, vertex_text = assets.text(doc["vertex"], "vertex", "vertex shader", budget.source_bytes)
    include_dirs = []
    for k, written in enumerate(doc.get("include_dirs", [])):
        where = json_path(["include_dirs", k])
        folder = assets.folder(written, where, "include folder")
        if not os.path.isdir(folder):
            raise AssetError(f"include folder not found: {printable(assets.path(written, where))}", file, where,
                             "include folders are relative to the session file's folder")
        include_dirs.append(folder)
    return Session(
        path=file, resolution=(int(doc["resolution"][0]), int(doc["resolution"][1])),
        frames=int(doc["frames"]), fps=float(doc.get("fps", 30)), objects=objects, textures=textures,
        hash=assets.digest(doc), name=doc.get("name", ""), description=doc.get("description", ""),
        background=tuple(float(c) for c in doc.get("background", (0.0, 0.0, 0.0, 0.0))), document=doc,
        include_dirs=tuple(include_dirs),
        _camera=camera, _light=light, _uniforms=uniforms, vertex=vertex, vertex_text=vertex_text,
        notes=[f"{path}: {note}" for path, mesh in assets.meshes.items() for note in mesh.notes])
