"""The paper's scenes for ``rrcache bench`` (Marble, Trashcan, chess; and the temple's PCF shadows), and sessions scaled down for quick runs.

:data:`PAPER_SCENES` names them (main paper §5: Marble, Trashcan, chess ambient occlusion);
:func:`resolve_scenes` turns ``--scenes`` entries (a name, or ``SHADER:SESSION`` for any other
scene) into :class:`Scene` objects with checked paths. :func:`scaled_session` writes a copy of
a session at another resolution and frame count (asset paths made absolute so the copy loads
from anywhere), which is how a quick bench shrinks the work: the profiler times at the
session's own resolution.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from rrcache import atomic
from rrcache.errors import RRCacheError
from rrcache.files import Refused, inside, read_file

#: name -> (shader, session), relative to the repository root
PAPER_SCENES = {
    "marble": ("shaders/marble.glsl", "sessions/marble.json"),
    "trashcan": ("shaders/trashcan.glsl", "sessions/trashcan.json"),
    "chess": ("shaders/ambient_occlusion.glsl", "sessions/chess.json"),
    # the fourth scene (Nehab et al. 2007 §7.3): 16-tap PCF shadows, where amortized sampling competes
    "temple": ("shaders/pcf_shadows.glsl", "sessions/temple.json"),
}


@dataclass(frozen=True)
class Scene:
    name: str
    shader: str
    session: str


def default_root() -> Path:
    """The folder holding ``shaders/`` and ``sessions/``: the source checkout of this package,
    else the current folder."""
    here = Path(__file__).resolve().parents[2]
    return here if (here / "shaders").is_dir() else Path.cwd()


def resolve_scenes(spec: str, root: Optional[Path] = None) -> list[Scene]:
    """``"marble,chess"`` or ``"marble,my.frag:my.json"`` → scenes with existing files.

    >>> [s.name for s in resolve_scenes("marble,chess")]
    ['marble', 'chess']
    """
    root = Path(root) if root is not None else default_root()
    scenes = []
    for entry in (e.strip() for e in spec.split(",")):
        if not entry:
            continue
        if entry in PAPER_SCENES:
            shader, session = (root / p for p in PAPER_SCENES[entry])
            name = entry
        elif ":" in entry:
            shader_text, session_text = entry.split(":", 1)
            shader, session = Path(shader_text), Path(session_text)
            name = shader.stem
        else:
            raise RRCacheError(f"unknown scene {entry!r}", "--scenes",
                               hint=f"give {', '.join(PAPER_SCENES)} or SHADER:SESSION")
        for path in (shader, session):
            if not path.is_file():
                raise RRCacheError(f"scene {name!r}: no such file", str(path),
                                   hint="run from the repository (shaders/ and sessions/) or give SHADER:SESSION")
        if any(s.name == name for s in scenes):
            raise RRCacheError(f"scene {name!r} is given twice", "--scenes", hint="name each scene once")
        scenes.append(Scene(name, str(shader), str(session)))
    if not scenes:
        raise RRCacheError("no scene given", "--scenes", hint=f"e.g. {','.join(PAPER_SCENES)}")
    return scenes


def _absolute(doc: dict, base: Path) -> list[str]:
    """Make the session's file paths absolute (resolved against ``base``); returns them."""
    fixed: list[str] = []

    def fix(path: str) -> str:
        p = Path(path).expanduser()
        fixed.append(str(p if p.is_absolute() else (base / p).resolve()))
        return fixed[-1]

    if isinstance(doc.get("vertex"), str):
        doc["vertex"] = fix(doc["vertex"])
    if isinstance(doc.get("include_dirs"), list):
        doc["include_dirs"] = [fix(d) if isinstance(d, str) else d for d in doc["include_dirs"]]

    for obj in doc.get("objects", []):
        if isinstance(obj, dict) and isinstance(obj.get("mesh"), str):
            obj["mesh"] = fix(obj["mesh"])
    textures = doc.get("textures", {})
    for name, spec in list(textures.items()):
        if isinstance(spec, str):
            textures[name] = fix(spec)
        elif isinstance(spec, dict):
            if isinstance(spec.get("path"), str):
                spec["path"] = fix(spec["path"])
            if isinstance(spec.get("faces"), list):
                spec["faces"] = [fix(f) if isinstance(f, str) else f for f in spec["faces"]]
    return fixed


def scaled_session(session_path, out_path, resolution: tuple[int, int], frames: int) -> Path:
    """Write ``session_path`` at ``resolution`` with its first ``frames`` frames to ``out_path``
    (rewritten only when the content changes, so a profile keyed on it resumes)."""
    source = Path(session_path)
    try:
        doc = json.loads(read_file(source, None).data)
    except Refused as err:
        raise RRCacheError(f"cannot read the session: it {err.reason}", str(source), hint="give a session JSON file") from None
    except ValueError as err:
        raise RRCacheError(f"cannot read the session ({err})", str(source), hint="give a session JSON file") from None
    if not isinstance(doc, dict):
        raise RRCacheError("not a session (no JSON object)", str(source), hint="give a session JSON file")
    doc["resolution"] = [int(resolution[0]), int(resolution[1])]
    doc["frames"] = int(frames)
    folder = source.resolve().parent
    paths = _absolute(doc, folder)
    if not doc.get("allow_outside_paths"):
        # the copy lives elsewhere: its paths are the original's, confined to the original's folder
        root = os.path.realpath(folder)
        outside = [p for p in paths if not inside(os.path.realpath(p), [root])]
        if outside:
            raise RRCacheError(f"the session names {outside[0]}, outside its folder {root}", str(source),
                               hint='paths are confined to the session file\'s folder tree; if you trust the '
                                    'session, say "allow_outside_paths": true in it')
        doc["allow_outside_paths"] = True
    out = Path(out_path)
    text = json.dumps(doc, indent=2) + "\n"
    try:
        same = read_file(out, limit=len(text.encode("utf-8"))).data == text.encode("utf-8")
    except Refused:
        same = False
    if not same:
        atomic.write_text(out, text)
    return out
