"""Profiling a shader library: one profile folder per (shader, session) pair and a summary.

:func:`profile_library` profiles each :class:`~rrcache.profiler.manifest.LibraryEntry` into
``<out>/<name>/`` with :func:`rrcache.profiler.run.profile` and keeps the summary
(:mod:`rrcache.report.library`) up to date after each one:

- ``library.json``: the rows (and, for a failure, its message), rewritten whole after each entry;
- ``library.csv`` and ``index.html`` (each name links the profile's ``report.html``).

A failure of one entry (a shader that does not compile, a session that does not load, a bug)
is recorded in its row and the rest are profiled. Run again with the same entries, the library
resumes: an entry whose ``profile.json`` is current (the same shader files, session, settings,
defines) is taken as it is, any other resumes from its store, every stored run skipped. One
process at a time writes a library folder (``library.lock``, as :mod:`rrcache.profiler.lock`).

>>> rows = profile_library(entries_from_globs(["shaders/*.glsl"], ["sessions/orbit.json"]), "lib")  # doctest: +SKIP
"""
from __future__ import annotations

import json
import time
import traceback
from pathlib import Path
from typing import Callable, Optional

from rrcache.atomic import write_text
from rrcache.errors import RRCacheError
from rrcache.jsonable import finite_json
from rrcache.profiler.lock import StoreLock
from rrcache.profiler.manifest import LibraryEntry
from rrcache.profiles.settings import TrainingSettings
from rrcache.report.library import failed_row, profile_row, write_summary

LIBRARY_JSON = "library.json"
LIBRARY_LOCK = "library.lock"
LIBRARY_VERSION = 1


def entry_settings(base: Optional[TrainingSettings], *overrides: dict, where: str = "settings") -> TrainingSettings:
    """``base`` (default settings when None) with each dict of TrainingSettings keys laid over it
    in turn; an unknown key or a bad value is an :class:`RRCacheError` naming ``where``."""
    data = (base or TrainingSettings()).to_json()
    for more in overrides:
        data.update(more or {})
    return TrainingSettings.from_json(data, where)


def _sha256(path: str) -> Optional[str]:
    from rrcache.budgets import budget
    from rrcache.files import Refused, read_file

    try:  # by rrcache.files' rule: a FIFO or a sparse giant is no shader
        return read_file(path, budget.source_bytes).sha256
    except Refused:
        return None


def stale_reason(prof, entry: LibraryEntry, settings: TrainingSettings,
                 workers: int = 1) -> tuple[Optional[str], bool]:
    """Why the finished profile ``prof`` is not the profile of ``entry`` with ``settings`` now,
    and whether it must start over: (None, False) when it is current; (reason, True) when a
    shader file, the session, a keyed setting, the defines or the vertex shader differ (its store
    holds another shader's runs); (reason, False) when only settings that change no measurement
    (the budget, validation, the levels) differ, so that it resumes from its store. ``workers``:
    the error-run workers it would be profiled with now (:mod:`rrcache.profiler.capacity`)."""
    from rrcache.session import load_session

    if not prof.shader_files:
        return "the profile records no shader files", True
    for record in prof.shader_files:
        path = record.get("path", "")
        if not path.startswith("<") and _sha256(path) != record.get("sha256"):
            return f"{path} changed", True
    if Path(prof.shader_files[0]["path"]).resolve() != Path(entry.shader).resolve():
        return "another shader", True
    session = load_session(entry.session)
    if session.hash != prof.session_hash:
        return "the session changed", True
    if any(prof.defines.get(k) != v for k, v in entry.defines.items()):
        return "other defines", True
    vertex = entry.vertex if entry.vertex is not None else getattr(session, "vertex", None)
    if (vertex is None) != (prof.vertex is None):
        return "another vertex shader", True
    if vertex is not None:
        from rrcache.pipeline import all_include_dirs, load_user_vertex

        user = load_user_vertex(vertex, session, prof.defines, all_include_dirs(entry.include_dirs, session))
        if user.hash != prof.vertex_hash:
            return "the vertex shader changed", True
    from rrcache.profiler.capacity import scaled

    resolved = scaled(settings, session, workers)[0].resolved(session)
    if resolved.key_json() != prof.settings.key_json():
        return "settings that change the measurements differ", True
    if resolved.to_json() != prof.settings.to_json():
        return "other settings", False
    return None, False


def read_rows(folder) -> dict[str, dict]:
    """The rows of ``library.json`` in ``folder`` by name (none when it is missing or unreadable:
    every entry is then checked against its own profile folder)."""
    from rrcache.budgets import budget
    from rrcache.files import Refused, read_file

    path = Path(folder) / LIBRARY_JSON
    try:
        try:
            data = json.loads(read_file(path, budget.document_bytes).data.decode("utf-8"))
        except Refused:
            return {}
        return {row["name"]: row for row in data.get("rows", []) if isinstance(row, dict) and "name" in row}
    except (OSError, ValueError, AttributeError, TypeError, KeyError):
        return {}


def _write(folder: Path, rows: list[dict], entries: list[LibraryEntry]) -> None:
    doc = {"rrcache_library": LIBRARY_VERSION, "rows": rows, "entries": [e.to_json() for e in entries]}
    write_text(folder / LIBRARY_JSON, json.dumps(finite_json(doc), indent=1) + "\n")
    write_summary([{k: v for k, v in r.items() if k != "traceback"} for r in rows], folder)


def profile_library(entries: list[LibraryEntry], out_dir, settings: Optional[TrainingSettings] = None,
                    manifest_settings: Optional[dict] = None, progress=None,
                    announce: Optional[Callable[[str], None]] = None, fresh: bool = False,
                    plots: bool = True, cluster=None) -> list[dict]:
    """Profile every entry into ``out_dir`` (see the module docstring) and return the summary's
    rows, in the entries' order. ``settings`` are the library's (the command line's),
    ``manifest_settings`` the manifest's keys over them; each entry's own ``settings`` come
    last. ``progress`` receives each profile's progress events, ``announce`` a line as each
    entry starts and ends. ``fresh`` starts every profile over (each store moved aside).
    ``cluster`` (:mod:`rrcache.cluster`) makes the profiles' runs (None: in this process). A ``KeyboardInterrupt``
    records the entry in flight as interrupted, writes the summary and propagates."""
    from rrcache.profiler.run import profile
    from rrcache.profiles.document import JSON_NAME, load_profile

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise RRCacheError("the output path is a file, not a folder", str(out), hint="give a folder with --out")
    say = announce or (lambda text: None)
    lock = StoreLock.acquire(out / LIBRARY_LOCK)
    try:
        earlier = read_rows(out)
        rows = [earlier.get(e.name) or failed_row(e.name, e.shader, e.session, "not profiled yet", None,
                                                   status="pending") for e in entries]
        for i, entry in enumerate(entries):
            folder = out / entry.name
            tag = f"[{i + 1}/{len(entries)}] {entry.name}"
            started = time.perf_counter()
            try:
                chosen = entry_settings(settings, manifest_settings, entry.settings, where=f"{entry.name}: settings")
                prof, why, restart = None, "no finished profile", fresh
                if not fresh and (folder / JSON_NAME).exists():
                    try:
                        done = load_profile(folder)
                        why, restart = stale_reason(done, entry, chosen, cluster.capacity if cluster else 1)
                        prof = done if why is None else None
                    except RRCacheError as err:
                        why = f"its profile.json is not readable ({err})"
                if prof is not None:
                    say(f"{tag}: current, kept ({folder / JSON_NAME})")
                    wall = prof.precompute_s
                else:
                    say(f"{tag}: profiling {entry.shader} over {entry.session} ({why}"
                        f"{'; starting over' if restart and not fresh else ''})")
                    prof = profile(entry.shader, entry.session, folder, chosen, entry.defines, progress, fresh=restart,
                                   plots=plots, include_dirs=entry.include_dirs, vertex=entry.vertex,
                                   executor=cluster)
                    wall = prof.precompute_s if prof.precompute_s is not None else time.perf_counter() - started
                report = folder / "report.html"
                row = profile_row(prof, entry.name, entry.name, f"{entry.name}/report.html" if report.exists() else None,
                                  wall)
                say(f"{tag}: {row['verdict']} ({wall or 0.0:.0f} s)")
            except KeyboardInterrupt:
                rows[i] = failed_row(entry.name, entry.shader, entry.session, "interrupted; run again to resume",
                                     time.perf_counter() - started, status="interrupted",
                                     folder=entry.name if folder.exists() else None)
                _write(out, rows, entries)
                raise
            except RRCacheError as err:
                row = failed_row(entry.name, entry.shader, entry.session, str(err), time.perf_counter() - started,
                                 folder=entry.name if folder.exists() else None)
                say(f"{tag}: failed: {err}")
            except Exception as err:  # a bug met on this shader: reported, and the rest profiled
                row = failed_row(entry.name, entry.shader, entry.session, f"{type(err).__name__}: {err}",
                                 time.perf_counter() - started, folder=entry.name if folder.exists() else None)
                row["traceback"] = traceback.format_exc()
                say(f"{tag}: failed: {type(err).__name__}: {err} (the traceback is in {out / LIBRARY_JSON})")
            rows[i] = row
            _write(out, rows, entries)
        return rows
    finally:
        lock.release()
