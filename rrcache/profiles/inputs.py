"""What a profile names outside its folder: the shader and the session it was made from.

A profile folder is input like a session: its ``profile.json`` may have been edited, and a
command run on it (``report``, ``accuracy``, ``select --out``) must not become a way to read the
machine's files. So a file the document names is opened only if it is what the document says:

* the shader: a shader source by its name (:data:`rrcache.glsl.preprocessor.SHADER_EXTENSIONS`),
  read by :mod:`rrcache.files`' rule within the source budget, and shown or parsed only if the
  sha256 of its bytes is the one the profile recorded (``shader_files[0]``); otherwise the error
  says it changed, and nothing of its content;
* the session: a ``.json`` file (loaded by :func:`rrcache.session.load_session`, which reads it by
  the same rule and confines its assets to its own folder);
* the vertex shader, when the profile names one: a shader source by its name.

>>> text = shader_source(load_profile("demo.rrprofile"))    # doctest: +SKIP
"""
from __future__ import annotations

import json
import os

from rrcache.errors import RRCacheError, printable
from rrcache.files import Refused, read_file
from rrcache.glsl.preprocessor import SHADER_EXTENSIONS

_HINT = "profile.json was edited, or the file changed since profiling; run 'rrcache profile' again"


def _named(prof, key: str, path, endings) -> str:
    where = f"{prof._where}: {key}"
    path = os.fspath(path)
    if "\0" in path or os.path.splitext(path)[1].lower() not in endings:
        raise RRCacheError(f"names {printable(path)!r}, which is not a {'session' if key == 'session' else 'shader'} "
                           "file; nothing was read", where, hint=_HINT)
    return path


def shader_source(prof) -> str:
    """The profiled shader's text, when its bytes are the ones profiled (see the module
    docstring); :class:`RRCacheError` otherwise, naming the file and never quoting it."""
    from rrcache.budgets import budget

    path = _named(prof, "shader", prof.shader, SHADER_EXTENSIONS)
    recorded = (prof.shader_files or [{}])[0].get("sha256")
    if not recorded:
        raise RRCacheError("records no hash of the shader's content, so the file it names cannot be checked; "
                           "nothing was read", f"{prof._where}: shader_files", hint=_HINT)
    try:
        got = read_file(path, budget.source_bytes)
    except Refused as err:
        raise RRCacheError(f"cannot read the profiled shader: {'not found' if err.kind == 'missing' else 'it ' + err.reason}",
                           printable(path), hint="put the shader back where the profile names it, or run "
                           "'rrcache profile' again") from None
    if got.sha256 != recorded:
        raise RRCacheError(f"the shader changed since it was profiled: '{printable(path)}' changed (its content is "
                           "not the profiled one, so none of it is shown)", printable(path),
                           hint="run 'rrcache profile' again, or restore the file")
    return got.data.decode("utf-8", "replace")


def session_document(prof) -> dict:
    """The profile's session file as JSON (a ``.json`` file, read by the rule within the
    document budget), for the figures a report shows of it; :class:`RRCacheError` when it is not
    one (nothing of its content is quoted)."""
    from rrcache.budgets import budget

    path = _named(prof, "session", prof.session, (".json",))
    try:
        return json.loads(read_file(path, budget.document_bytes).data)
    except (Refused, ValueError):
        raise RRCacheError("the session the profile names cannot be read as JSON", printable(path),
                           hint=_HINT) from None


def check_inputs(prof) -> None:
    """Before a profile's shader and session are loaded: the shader is the profiled one, the
    session a ``.json`` file and the vertex shader a shader source (see the module docstring)."""
    shader_source(prof)
    _named(prof, "session", prof.session, (".json",))
    if prof.vertex is not None:
        _named(prof, "vertex", prof.vertex, SHADER_EXTENSIONS)


def load_session_of(prof):
    """The profile's session, loaded (after :func:`check_inputs`) and checked to be the one
    profiled (its hash); an error names the file and the place but never quotes a value from it
    (the file may be one a tampered ``profile.json`` named)."""
    from rrcache.errors import SessionError
    from rrcache.session import load_session

    check_inputs(prof)
    try:
        session = load_session(prof.session)
    except SessionError as err:
        raise RRCacheError(f"the session the profile names does not load (at {err.json_path or 'the file'}): it changed "
                           "since profiling, or profile.json was edited; 'rrcache render SHADER SESSION' says why",
                           printable(os.fspath(prof.session)), hint=_HINT) from None
    if prof.session_hash and session.hash != prof.session_hash:
        raise RRCacheError("the session changed since it was profiled (its content or its assets' differ)",
                           printable(os.fspath(prof.session)), hint="run 'rrcache profile' again, or restore it")
    return session
