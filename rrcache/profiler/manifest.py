"""The list of a shader library to profile: (shader, session) pairs from a manifest or from globs.

A manifest is a JSON or TOML file (by its extension: ``.toml``, else JSON). Paths in it are
relative to the manifest's folder; ``shader`` and ``session`` may each be one path, a glob, or a
list of either, and an entry stands for every shader with every session it names::

    # library.toml
    [settings]                  # TrainingSettings keys, for every entry (optional)
    budget_s = 120

    [[profile]]
    shader = "shaders/marble.glsl"
    session = ["sessions/marble.json", "sessions/*_orbit.json"]

    [[profile]]
    shader = "materials/*.glsl"
    session = "sessions/turntable.json"
    defines = { QUALITY = "2" }  # -D, for this entry's shaders
    include_dirs = ["materials/include"]
    settings = { frames = 48 }   # this entry's own settings (over the manifest's)
    # name = "..."              # the profile folder's name (one shader and one session only)

The JSON form is the same object (``{"settings": {...}, "profile": [{...}, ...]}``; ``profiles``
is accepted for ``profile``) or just the list of entries. Every mistake is an
:class:`~rrcache.errors.RRCacheError` naming the manifest and the key
(``library.toml: profile[2].session: 'sessions/x*.json' matches no file``).

>>> entries_from_globs(["shaders/marble.glsl"], ["sessions/marble.json"])[0].name
'marble-marble'
"""
from __future__ import annotations

import glob
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

from rrcache.errors import RRCacheError

#: a profile folder's name: letters, digits, ``.``, ``_`` and ``-``
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")
#: the keys an entry may have
ENTRY_KEYS = ("shader", "session", "name", "defines", "include_dirs", "vertex", "settings")


@dataclass(frozen=True)
class LibraryEntry:
    """One (shader, session) pair of a library: ``name`` (its profile folder's name), the files,
    the ``-D`` ``defines``, ``include_dirs``, the user's ``vertex`` shader (None: the session's or
    generated) and ``settings``, TrainingSettings keys over the library's."""

    name: str
    shader: str
    session: str
    defines: dict = field(default_factory=dict)
    include_dirs: tuple = ()
    vertex: Optional[str] = None
    settings: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        return {"name": self.name, "shader": self.shader, "session": self.session, "defines": dict(self.defines),
                "include_dirs": list(self.include_dirs), "vertex": self.vertex, "settings": dict(self.settings)}


def default_name(shader, session) -> str:
    """``<shader stem>-<session stem>``, with characters a folder name should not have replaced.

    >>> default_name("a/marble.glsl", "b/orbit 2.json")
    'marble-orbit_2'
    """
    name = f"{Path(shader).stem}-{Path(session).stem}"
    return re.sub(r"[^A-Za-z0-9._-]", "_", name).lstrip(".-_") or "profile"


def read_manifest(path) -> tuple[list[LibraryEntry], dict]:
    """The entries of the manifest at ``path`` and its ``settings`` table (see the module
    docstring)."""
    path = Path(path)
    where = str(path)
    from rrcache.budgets import budget
    from rrcache.files import Refused, read_file

    try:
        text = read_file(path, budget.document_bytes).data.decode("utf-8")
    except Refused as err:
        if err.kind == "missing":
            raise RRCacheError("no such manifest", where, hint="give a JSON or TOML file listing shaders and sessions") from None
        raise RRCacheError(f"cannot read the manifest: it {err.reason}", where, hint="give a UTF-8 JSON or TOML file") from None
    except UnicodeDecodeError as err:
        raise RRCacheError(f"cannot read the manifest ({err})", where, hint="give a UTF-8 JSON or TOML file") from None
    if path.suffix.lower() == ".toml":
        data = _toml(text, where)
    else:
        try:
            data = json.loads(text)
        except ValueError as err:
            raise RRCacheError(f"not valid JSON ({err})", where,
                               hint="a JSON manifest is a list of entries or {\"profile\": [...]}; "
                                    "name a TOML manifest *.toml") from None
    if isinstance(data, list):
        data = {"profile": data}
    if not isinstance(data, dict):
        raise RRCacheError("the manifest is not a table of entries", where, hint="see 'rrcache profile-library --help'")
    unknown = sorted(set(data) - {"profile", "profiles", "settings"})
    if unknown:
        raise RRCacheError(f"unknown key(s) {unknown}", where, hint="the keys are 'settings' and 'profile'")
    if "profile" in data and "profiles" in data:
        raise RRCacheError("both 'profile' and 'profiles' given", where, hint="keep one list of entries")
    key = "profiles" if "profiles" in data else "profile"
    items = data.get(key, [])
    settings = data.get("settings", {})
    if not isinstance(settings, dict):
        raise RRCacheError("'settings' is not a table", where, hint="e.g. settings = { budget_s = 120 }")
    if not isinstance(items, list) or not items:
        raise RRCacheError(f"'{key}' lists no entry", where, hint="add [[profile]] tables with a shader and a session")
    base = path.resolve().parent
    entries: list[LibraryEntry] = []
    for i, item in enumerate(items):
        entries.extend(_entry(item, f"{where}: {key}[{i}]", base))
    check_names(entries, where)
    return entries, dict(settings)


def _toml(text: str, where: str) -> dict:
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise RRCacheError(f"not valid TOML ({err})", where, hint="see 'rrcache profile-library --help'") from None


def _paths(value, where: str, base: Path) -> list[str]:
    """One path, a glob or a list of either → the files (sorted within each glob)."""
    items = value if isinstance(value, list) else [value]
    if not items or not all(isinstance(v, str) and v.strip() for v in items):
        raise RRCacheError("not a path, a glob or a list of them", where, hint='e.g. "shaders/*.glsl"')
    out: list[str] = []
    for item in items:
        pattern = os.path.normpath(item if os.path.isabs(item) else str(base / item))
        if glob.has_magic(item):
            found = sorted(p for p in glob.glob(pattern, recursive=True) if os.path.isfile(p))
            if not found:
                raise RRCacheError(f"{item!r} matches no file", where, hint=f"globs are relative to {base}")
            out.extend(found)
        else:
            if not os.path.isfile(pattern):
                raise RRCacheError(f"{item!r}: no such file", where, hint=f"paths are relative to {base}")
            out.append(pattern)
    return list(dict.fromkeys(out))


def _entry(item, where: str, base: Path) -> list[LibraryEntry]:
    if not isinstance(item, dict):
        raise RRCacheError("an entry is not a table", where, hint='e.g. {"shader": "a.glsl", "session": "s.json"}')
    unknown = sorted(set(item) - set(ENTRY_KEYS))
    if unknown:
        raise RRCacheError(f"unknown key(s) {unknown}", where, hint=f"the keys are {', '.join(ENTRY_KEYS)}")
    for required in ("shader", "session"):
        if required not in item:
            raise RRCacheError(f"no '{required}'", where, hint="every entry names a shader and a session")
    shaders = _paths(item["shader"], f"{where}.shader", base)
    sessions = _paths(item["session"], f"{where}.session", base)
    defines = item.get("defines", {})
    if not isinstance(defines, dict) or not all(isinstance(k, str) and k.isidentifier() for k in defines):
        raise RRCacheError("'defines' is not a table of macro names", f"{where}.defines", hint='e.g. { OCTAVES = "5" }')
    defines = {k: str(v) for k, v in defines.items()}
    dirs = item.get("include_dirs", [])
    if not isinstance(dirs, list) or not all(isinstance(d, str) for d in dirs):
        raise RRCacheError("'include_dirs' is not a list of folders", f"{where}.include_dirs", hint='e.g. ["include"]')
    dirs = tuple(os.path.normpath(d if os.path.isabs(d) else str(base / d)) for d in dirs)
    vertex = item.get("vertex")
    if vertex is not None:
        vertex = _paths(vertex, f"{where}.vertex", base)
        if len(vertex) != 1:
            raise RRCacheError("'vertex' names several files", f"{where}.vertex", hint="give one vertex shader")
        vertex = vertex[0]
    settings = item.get("settings", {})
    if not isinstance(settings, dict):
        raise RRCacheError("'settings' is not a table", f"{where}.settings", hint="e.g. { budget_s = 60 }")
    name = item.get("name")
    if name is not None and (len(shaders) > 1 or len(sessions) > 1):
        raise RRCacheError("'name' given for an entry of several shaders or sessions", f"{where}.name",
                           hint="name only an entry of one shader and one session")
    return [LibraryEntry(name if name is not None else default_name(sh, se), sh, se, defines, dirs, vertex,
                         dict(settings))
            for sh in shaders for se in sessions]


def entries_from_globs(shaders, sessions) -> list[LibraryEntry]:
    """Every shader matched by ``shaders`` with every session matched by ``sessions`` (paths or
    globs, relative to the current folder)."""
    found_shaders = _paths(list(shaders), "--shaders", Path.cwd())
    found_sessions = _paths(list(sessions), "--sessions", Path.cwd())
    entries = [LibraryEntry(default_name(sh, se), os.path.abspath(sh), os.path.abspath(se))
               for sh in found_shaders for se in found_sessions]
    check_names(entries, "--shaders/--sessions")
    return entries


def check_names(entries: list[LibraryEntry], where: str) -> None:
    """Each entry's name must make a folder name and be the only one of its name."""
    seen: dict[str, LibraryEntry] = {}
    for entry in entries:
        if not _NAME.match(entry.name):
            raise RRCacheError(f"{entry.name!r} is not a usable folder name", where,
                               hint="use letters, digits, '.', '_' and '-'")
        if entry.name in seen:
            other = seen[entry.name]
            raise RRCacheError(f"two entries would both be profiled into '{entry.name}' ({other.shader} with "
                               f"{other.session}, and {entry.shader} with {entry.session})", where,
                               hint="give the entries names (name = \"...\")")
        seen[entry.name] = entry
