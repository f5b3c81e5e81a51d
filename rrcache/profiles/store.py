"""The profile store: a versioned SQLite file of every training measurement.

In the manner of coverage.py's data file: the schema is one commented string (:data:`SCHEMA`), a
``meta`` table names what the file belongs to, and nothing in a file is trusted before it is
checked. A store is keyed by (shader hash, session hash, settings hash, rrcache version); opening
it with another key is refused with the differences named (use another ``--out``, or ``--fresh``,
which moves the old file aside as ``profile.sqlite.bak``). A damaged file (``PRAGMA
integrity_check``) or a foreign SQLite file (no ``meta`` table, or another schema) is refused too.

Each measurement is committed as soon as it is made, one transaction per (node, period) run, in
WAL journal mode: a run that is killed loses at most the run in flight, and the next run resumes.

>>> store = ProfileStore.open("out/profile.sqlite", key)           # doctest: +SKIP
>>> store.has_error_run("n7", 10)                                  # doctest: +SKIP
False
"""
from __future__ import annotations

import json
import os
import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Optional

from rrcache.atomic import OutputFolder
from rrcache.errors import RRCacheError
from rrcache.files import Refused, open_file
from rrcache.selection import Selection, parts_from_json, parts_to_json

SCHEMA_VERSION = 2
#: the files SQLite keeps beside the store (write-ahead log, shared memory, rollback journal)
_SIDE_FILES = ("-wal", "-shm", "-journal")
#: the store's file name in a profile folder
STORE_NAME = "profile.sqlite"

SCHEMA = """\
-- rrcache profile store; the schema version is in meta('schema_version').
--
-- meta: what the file belongs to. Keys: schema_version, rrcache_version, shader_hash,
--   session_hash, settings_json, settings_hash, created, updated (unix seconds); and, once the
--   first run has chosen them, plan: JSON of the error and timing windows (rrcache.profiler.plan),
--   kept so that a resumed run renders exactly what the first one did.
--   sets: JSON of the sets of cached nodes the set stage trained (rrcache.profiler.sets).
CREATE TABLE meta (
    key TEXT PRIMARY KEY,
    value TEXT NOT NULL
);

-- run_log: one row per `profile` invocation; the counters say what it computed and what it
--   found already stored (a resumed run skips every stored run). status: running, done,
--   interrupted, failed.
CREATE TABLE run_log (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    started REAL NOT NULL,
    finished REAL,
    status TEXT NOT NULL,
    error_runs_computed INTEGER NOT NULL DEFAULT 0,
    error_runs_skipped INTEGER NOT NULL DEFAULT 0,
    timing_runs_computed INTEGER NOT NULL DEFAULT 0,
    timing_runs_skipped INTEGER NOT NULL DEFAULT 0
);

-- reference: the original shader over the training frames at the training resolution
--   (covered pixels per frame); its images are kept in memory only.
CREATE TABLE reference_frame (
    frame INTEGER PRIMARY KEY,
    covered INTEGER NOT NULL
);

-- error_run: one node cached at one refresh period, rendered over the training frames in order
--   from an empty cache. mean_error is the mean over the frames after the first (which has no
--   cache) of each frame's mean RGB L2 error over covered pixels; hit_rate = hits / (hits +
--   misses) over the same frames. wall_s: seconds the run took (counts against the budget).
CREATE TABLE error_run (
    node TEXT NOT NULL,
    period INTEGER NOT NULL,
    mean_error REAL NOT NULL,
    psnr REAL NOT NULL,
    hit_rate REAL NOT NULL,
    hits INTEGER NOT NULL,
    misses INTEGER NOT NULL,
    covered INTEGER NOT NULL,
    frames INTEGER NOT NULL,
    wall_s REAL NOT NULL,
    run_id INTEGER NOT NULL REFERENCES run_log(id),
    PRIMARY KEY (node, period)
);

-- error_frame: the frames of an error run (psnr is capped at 100 dB for identical frames).
CREATE TABLE error_frame (
    node TEXT NOT NULL,
    period INTEGER NOT NULL,
    frame INTEGER NOT NULL,
    mean_error REAL NOT NULL,
    psnr REAL NOT NULL,
    hits INTEGER NOT NULL,
    misses INTEGER NOT NULL,
    covered INTEGER NOT NULL,
    left_out INTEGER NOT NULL,
    PRIMARY KEY (node, period, frame)
);

-- timing_run / timing_frame: one node at one timing period over the L timing frames at the
--   session's full resolution. Each timed frame follows one untimed warm-up frame (the one
--   before it) and is timed right after the original on the same frame (original_ms), so that
--   machine noise touches both alike.
CREATE TABLE timing_run (
    node TEXT NOT NULL,
    period INTEGER NOT NULL,
    wall_s REAL NOT NULL,
    run_id INTEGER NOT NULL REFERENCES run_log(id),
    PRIMARY KEY (node, period)
);
CREATE TABLE timing_frame (
    node TEXT NOT NULL,
    period INTEGER NOT NULL,
    frame INTEGER NOT NULL,
    hits INTEGER NOT NULL,
    misses INTEGER NOT NULL,
    ms REAL NOT NULL,
    original_ms REAL NOT NULL,
    PRIMARY KEY (node, period, frame)
);

-- reference_timing: the original's ms per frame on the timing frames (full resolution),
--   measured once before any node, with the covered pixels M.
CREATE TABLE reference_timing (
    frame INTEGER PRIMARY KEY,
    ms REAL NOT NULL,
    covered INTEGER NOT NULL
);

-- overhead: the cached pipeline's frame time with almost nothing covered (the variant of
--   `node` rendered at a tiny resolution; geometry still processed): median ms over `frames`.
CREATE TABLE overhead (
    id INTEGER PRIMARY KEY CHECK (id = 1),
    node TEXT NOT NULL,
    width INTEGER NOT NULL,
    height INTEGER NOT NULL,
    frames INTEGER NOT NULL,
    ms REAL NOT NULL
);

-- validation: a selection (label e1..e4 at max_error) rendered beside the original at full
--   resolution; predicted figures from the models, measured ones from the render. parts: what is
--   cached, as the JSON list of rrcache.selection.parts_to_json ([] = the original shader:
--   nothing rendered, error 0, speed-up 1); algorithm: the cache algorithm it ran with.
CREATE TABLE validation (
    label TEXT PRIMARY KEY,
    max_error REAL NOT NULL,
    parts TEXT NOT NULL,
    algorithm TEXT,
    predicted_error REAL NOT NULL,
    predicted_ms REAL NOT NULL,
    predicted_speedup REAL NOT NULL,
    measured_error REAL NOT NULL,
    measured_psnr REAL NOT NULL,
    measured_ms REAL NOT NULL,
    measured_original_ms REAL NOT NULL,
    measured_speedup REAL NOT NULL,
    hit_rate REAL NOT NULL,
    frames INTEGER NOT NULL
);
"""

_VALIDATION_COLUMNS = ("label", "max_error", "parts", "algorithm", "predicted_error", "predicted_ms",
                       "predicted_speedup", "measured_error", "measured_psnr", "measured_ms", "measured_original_ms",
                       "measured_speedup", "hit_rate", "frames")

_TABLES = ("meta", "run_log", "reference_frame", "error_run", "error_frame", "timing_run", "timing_frame",
           "reference_timing", "overhead", "validation")


@dataclass(frozen=True)
class StoreKey:
    """What a store belongs to; two stores with different keys never mix measurements."""

    shader_hash: str
    session_hash: str
    settings_hash: str
    rrcache_version: str
    settings_json: str = "{}"

    def compare(self, meta: dict) -> list[str]:
        """The differences against a store's ``meta`` rows, in words (empty: the same key)."""
        names = (("shader_hash", "shader"), ("session_hash", "session"), ("settings_hash", "training settings"),
                 ("rrcache_version", "rrcache version"))
        out = []
        for field_name, words in names:
            mine, theirs = getattr(self, field_name), meta.get(field_name)
            if mine != theirs:
                if field_name == "settings_hash":
                    out.append(f"the {words} differ ({_settings_diff(self.settings_json, meta.get('settings_json'))})")
                elif field_name == "rrcache_version":
                    out.append(f"the {words} differs (stored {theirs}, running {mine})")
                else:
                    out.append(f"the {words} differs (hash stored {str(theirs)[:12]}, now {mine[:12]})")
        return out


def _settings_diff(mine: str, theirs: Optional[str]) -> str:
    try:
        a, b = json.loads(mine), json.loads(theirs or "{}")
    except ValueError:
        return "unreadable stored settings"
    keys = sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))
    return ", ".join(f"{k}: stored {b.get(k)!r}, now {a.get(k)!r}" for k in keys) or "same values, other hash"


@dataclass
class ErrorRun:
    node: str
    period: int
    mean_error: float
    psnr: float
    hit_rate: float
    hits: int
    misses: int
    covered: int
    frames: int
    wall_s: float


@dataclass
class ErrorFrame:
    frame: int
    mean_error: float
    psnr: float
    hits: int
    misses: int
    covered: int
    left_out: int = 0


@dataclass
class TimingFrame:
    frame: int
    hits: int
    misses: int
    ms: float
    original_ms: float


_INF = float("inf")
_REAL, _INT = "number", "integer"
#: the columns a stored row must keep in range: (kind, low, high); None: no bound
_RANGES: dict[str, dict[str, tuple]] = {
    "error_run": {"period": (_INT, 1, None), "mean_error": (_REAL, 0.0, None), "psnr": (_REAL, None, None),
                  "hit_rate": (_REAL, 0.0, 1.0), "hits": (_INT, 0, None), "misses": (_INT, 0, None),
                  "covered": (_INT, 0, None), "frames": (_INT, 0, None), "wall_s": (_REAL, 0.0, None)},
    "error_frame": {"frame": (_INT, 0, None), "mean_error": (_REAL, 0.0, None), "psnr": (_REAL, None, None),
                    "hits": (_INT, 0, None), "misses": (_INT, 0, None), "covered": (_INT, 0, None),
                    "left_out": (_INT, 0, None)},
    "timing_frame": {"period": (_INT, 1, None), "frame": (_INT, 0, None), "hits": (_INT, 0, None),
                     "misses": (_INT, 0, None), "ms": (_REAL, 0.0, None), "original_ms": (_REAL, 0.0, None)},
    "reference_timing": {"frame": (_INT, 0, None), "ms": (_REAL, 0.0, None), "covered": (_INT, 0, None)},
    "overhead": {"width": (_INT, 1, None), "height": (_INT, 1, None), "frames": (_INT, 1, None),
                 "ms": (_REAL, 0.0, None)},
    "validation": {"max_error": (_REAL, 0.0, None), "period": (_INT, 1, None), "predicted_error": (_REAL, 0.0, None),
                   "predicted_ms": (_REAL, 0.0, None), "predicted_speedup": (_REAL, 0.0, None),
                   "measured_error": (_REAL, 0.0, None), "measured_psnr": (_REAL, None, None),
                   "measured_ms": (_REAL, 0.0, None), "measured_original_ms": (_REAL, 0.0, None),
                   "measured_speedup": (_REAL, 0.0, None), "hit_rate": (_REAL, 0.0, 1.0), "frames": (_INT, 0, None)},
}
#: the columns that name a row in an error message
_KEYS = ("node", "period", "frame", "label")


def _out_of_range(value, kind: str, low, high) -> Optional[str]:
    """Why ``value`` does not fit (None: it fits). NULL is allowed only where the schema allows
    it (``validation.node/period``: the original shader)."""
    if value is None:
        return None if kind == _INT else "is missing"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"is not a {kind}"
    if kind == _INT and not isinstance(value, int):
        return "is not an integer"
    if isinstance(value, float) and value != value:
        return "is not a number (NaN)"
    if isinstance(value, float) and value in (_INF, -_INF) and not (low is None and high is None):
        return "is infinite"
    if low is not None and value < low:
        return f"is below {low}"
    if high is not None and value > high:
        return f"is above {high}"
    return None


def _refuse(path: Path, message: str, hint: str) -> RRCacheError:
    return RRCacheError(message, str(path), hint=hint)


_FRESH_HINT = "use another --out folder, or --fresh to move this file aside as profile.sqlite.bak"


class ProfileStore:
    """An open profile store. Use :meth:`open` (checks or creates), then the ``add_*`` methods
    (each one transaction) and the readers. Close with :meth:`close` or a ``with`` block."""

    def __init__(self, path: Path, conn: sqlite3.Connection):
        self.path = path
        self.conn = conn
        self.run_id: Optional[int] = None

    # ------------------------------------------------------------------ opening
    @classmethod
    def open(cls, path: "str | os.PathLike[str]", key: StoreKey, fresh: bool = False) -> "ProfileStore":
        """Open (or create) the store at ``path`` for ``key``.

        ``fresh=True`` moves an existing file aside as ``<name>.bak`` (replacing an older
        ``.bak``) and starts empty. A file with another key, a damaged file and a foreign SQLite
        file raise :class:`RRCacheError` naming the file and the problem.
        """
        path = Path(path)
        # by rrcache.atomic's rule: the store and SQLite's side files must be regular files (a
        # link named profile.sqlite is refused, not followed), reached through the folder's
        # descriptor; --fresh renames only regular files
        sides = [path.name + suffix for suffix in _SIDE_FILES]
        with OutputFolder(path.parent) as folder:
            folder.regular_or_missing(path.name, *sides, path.name + ".bak", *(s + ".bak" for s in sides))
            if fresh and folder.exists(path.name):
                backup = path.name + ".bak"
                folder.rename(path.name, backup)
                for side in sides:
                    if folder.exists(side):
                        folder.rename(side, side.replace(path.name, backup, 1))
            exists = folder.exists(path.name) and os.stat(path.name, dir_fd=folder.fd).st_size > 0
            pinned = folder.proc_path(path.name)
            if exists:
                conn = cls._connect_existing(path, pinned)
                store = cls(path, conn)
                try:
                    if store._is_empty():
                        # a run killed while it created the store (its one transaction never
                        # committed) leaves an SQLite file with no tables: nothing to lose, start it
                        store._create(key)
                    else:
                        store._check(key)
                except BaseException:
                    conn.close()
                    raise
                return store
            try:
                conn = sqlite3.connect(pinned, isolation_level=None)
            except sqlite3.Error as err:
                raise _refuse(path, f"cannot create the profile store: {err}",
                              "free disk space or make the folder writable, then run the same command again") from None
        store = cls(path, conn)
        store._create(key)
        return store

    @staticmethod
    def _connect_existing(path: Path, pinned: Optional[str] = None) -> sqlite3.Connection:
        try:
            with open_file(pinned or path, limit=None) as f:
                header = os.pread(f.fd, 16, 0)
        except Refused as err:
            raise _refuse(path, f"the profile store {err.reason}", _FRESH_HINT) from None
        if header != b"SQLite format 3\x00":
            raise _refuse(path, "not a profile store (not an SQLite file)",
                          "it is damaged or another program's file; " + _FRESH_HINT)
        try:
            conn = sqlite3.connect(pinned or str(path), isolation_level=None)
            rows = conn.execute("PRAGMA integrity_check").fetchall()
        except sqlite3.DatabaseError as err:
            raise _refuse(path, f"the profile store is damaged ({err})", _FRESH_HINT) from None
        if rows != [("ok",)]:
            conn.close()
            detail = "; ".join(str(r[0]) for r in rows[:3])
            raise _refuse(path, f"the profile store is damaged (integrity check: {detail})", _FRESH_HINT)
        return conn

    def _is_empty(self) -> bool:
        try:
            return self.conn.execute("SELECT COUNT(*) FROM sqlite_master").fetchone()[0] == 0
        except sqlite3.DatabaseError:
            return False  # _check reports the damage

    def _create(self, key: StoreKey) -> None:
        conn = self.conn
        try:
            conn.execute("PRAGMA journal_mode=WAL")
            conn.execute("BEGIN")
            for statement in _statements(SCHEMA):
                conn.execute(statement)
            now = repr(time.time())
            meta = {"schema_version": str(SCHEMA_VERSION), "rrcache_version": key.rrcache_version,
                    "shader_hash": key.shader_hash, "session_hash": key.session_hash,
                    "settings_json": key.settings_json, "settings_hash": key.settings_hash,
                    "created": now, "updated": now}
            conn.executemany("INSERT INTO meta(key, value) VALUES (?, ?)", sorted(meta.items()))
            conn.execute("COMMIT")
        except sqlite3.Error as err:
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            raise _refuse(self.path, f"cannot create the profile store: {err}",
                          "free disk space or make the folder writable, then run the same command again") from None

    def _check(self, key: StoreKey) -> None:
        path = self.path
        try:
            tables = {r[0] for r in self.conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        except sqlite3.DatabaseError as err:
            raise _refuse(path, f"the profile store is damaged ({err})", _FRESH_HINT) from None
        if "meta" not in tables:
            raise _refuse(path, "an SQLite file that is not a profile store (no meta table)", _FRESH_HINT)
        try:
            meta = dict(self.conn.execute("SELECT key, value FROM meta"))
        except sqlite3.DatabaseError as err:
            raise _refuse(path, f"an SQLite file that is not a profile store ({err})", _FRESH_HINT) from None
        version = meta.get("schema_version")
        if version in _MIGRATIONS and "validation" in tables:
            _MIGRATIONS[version](self.conn)
            version = str(SCHEMA_VERSION)
        if version != str(SCHEMA_VERSION):
            raise _refuse(path, f"profile store schema {version!r}, this rrcache reads schema {SCHEMA_VERSION}"
                          if version else "an SQLite file that is not a profile store (no schema version)", _FRESH_HINT)
        missing = [t for t in _TABLES if t not in tables]
        if missing:
            raise _refuse(path, f"the profile store lacks the tables {missing}", _FRESH_HINT)
        differences = key.compare(meta)
        if differences:
            raise _refuse(path, "the profile store was made for other inputs: " + "; ".join(differences), _FRESH_HINT)
        self.conn.execute("PRAGMA journal_mode=WAL")

    # ------------------------------------------------------------------ transactions
    def _write(self, statements: Iterable[tuple[str, tuple]]) -> sqlite3.Cursor:
        """Run ``statements`` in one transaction; a failed write (a full disk, a read-only
        folder) rolls back and raises an :class:`RRCacheError`: every earlier run stays stored."""
        conn = self.conn
        cur = None
        try:
            conn.execute("BEGIN IMMEDIATE")
            try:
                for sql, args in statements:
                    cur = conn.execute(sql, args)
                last = cur
                conn.execute("UPDATE meta SET value = ? WHERE key = 'updated'", (repr(time.time()),))
                conn.execute("COMMIT")
            except BaseException:
                if conn.in_transaction:
                    try:
                        conn.execute("ROLLBACK")
                    except sqlite3.Error:
                        pass
                raise
        except sqlite3.IntegrityError:
            raise  # a run stored twice: a bug of the caller, not of the disk
        except sqlite3.Error as err:
            raise _refuse(self.path, f"cannot write the profile store: {err}",
                          "free disk space or make the folder writable; what was stored before is kept, "
                          "and running the same command again resumes") from None
        return last

    def begin_run(self) -> int:
        """Log the start of a ``profile`` invocation; its id tags what it computes."""
        cur = self._write([("INSERT INTO run_log(started, status) VALUES (?, 'running')", (time.time(),))])
        self.run_id = int(cur.lastrowid)
        return self.run_id

    def end_run(self, status: str) -> None:
        """Mark this invocation ``done``, ``interrupted`` or ``failed``."""
        if self.run_id is not None:
            self._write([("UPDATE run_log SET finished = ?, status = ? WHERE id = ?",
                          (time.time(), status, self.run_id))])

    def count_skipped(self, error_runs: int, timing_runs: int) -> None:
        """Record how many stored runs this invocation found and skipped."""
        self._write([("UPDATE run_log SET error_runs_skipped = error_runs_skipped + ?, "
                      "timing_runs_skipped = timing_runs_skipped + ? WHERE id = ?",
                      (error_runs, timing_runs, self._rid()))])

    def _rid(self) -> int:
        if self.run_id is None:
            self.begin_run()
        return self.run_id

    # ------------------------------------------------------------------ writers
    def add_reference(self, covered: dict[int, int]) -> None:
        """The training frames' covered pixels (replaces earlier rows: they are the same)."""
        self._write([("INSERT OR REPLACE INTO reference_frame(frame, covered) VALUES (?, ?)", (int(f), int(c)))
                     for f, c in sorted(covered.items())])

    def add_error_run(self, run: ErrorRun, frames: list[ErrorFrame]) -> None:
        """One error run and its frames, in one transaction."""
        rid = self._rid()
        statements = [("INSERT INTO error_run VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                       (run.node, run.period, run.mean_error, run.psnr, run.hit_rate, run.hits, run.misses,
                        run.covered, run.frames, run.wall_s, rid))]
        statements += [("INSERT INTO error_frame VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                        (run.node, run.period, f.frame, f.mean_error, f.psnr, f.hits, f.misses, f.covered, f.left_out))
                       for f in frames]
        statements.append(("UPDATE run_log SET error_runs_computed = error_runs_computed + 1 WHERE id = ?", (rid,)))
        self._write(statements)

    def add_reference_timing(self, rows: list[tuple[int, float, int]]) -> None:
        """``(frame, ms, covered)`` of the original at full resolution."""
        self._write([("INSERT OR REPLACE INTO reference_timing VALUES (?, ?, ?)", (int(f), float(ms), int(c)))
                     for f, ms, c in rows])

    def add_timing_run(self, node: str, period: int, frames: list[TimingFrame], wall_s: float) -> None:
        """One timing run and its frames, in one transaction."""
        rid = self._rid()
        statements = [("INSERT INTO timing_run VALUES (?, ?, ?, ?)", (node, int(period), float(wall_s), rid))]
        statements += [("INSERT INTO timing_frame VALUES (?, ?, ?, ?, ?, ?, ?)",
                        (node, int(period), f.frame, f.hits, f.misses, f.ms, f.original_ms)) for f in frames]
        statements.append(("UPDATE run_log SET timing_runs_computed = timing_runs_computed + 1 WHERE id = ?", (rid,)))
        self._write(statements)

    def set_overhead(self, node: str, size: tuple[int, int], frames: int, ms: float) -> None:
        self._write([("INSERT OR REPLACE INTO overhead VALUES (1, ?, ?, ?, ?, ?)",
                      (node, int(size[0]), int(size[1]), int(frames), float(ms)))])

    def add_validation(self, sel: Selection) -> None:
        """A measured selection (its ``label`` is the key; a later one replaces it)."""
        if not sel.measured:
            raise ValueError("add_validation needs a measured selection")
        self._write([(f"INSERT OR REPLACE INTO validation({', '.join(_VALIDATION_COLUMNS)}) "
                      f"VALUES ({', '.join('?' * len(_VALIDATION_COLUMNS))})",
                      (sel.label, sel.max_error, json.dumps(parts_to_json(sel.parts)), sel.algorithm,
                       sel.predicted_error, sel.predicted_ms, sel.predicted_speedup, sel.measured_error,
                       # an exact image (PSNR ∞, null in the document) is stored at the cap
                       sel.measured_psnr if sel.measured_psnr is not None else 100.0, sel.measured_ms,
                       sel.measured_original_ms, sel.measured_speedup,
                       sel.hit_rate, sel.frames))])

    # ------------------------------------------------------------------ readers
    def meta(self) -> dict:
        return dict(self.conn.execute("SELECT key, value FROM meta"))

    def plan(self) -> Optional[dict]:
        """The windows the first run chose (``rrcache.profiler.plan.Plan.to_json``), or None."""
        row = self.conn.execute("SELECT value FROM meta WHERE key = 'plan'").fetchone()
        if row is None:
            return None
        try:
            data = json.loads(row[0])
        except ValueError:
            raise _refuse(self.path, "the stored training plan is not JSON", _FRESH_HINT) from None
        if not isinstance(data, dict):
            raise _refuse(self.path, "the stored training plan is not a JSON object", _FRESH_HINT)
        return data

    def set_plan(self, plan: dict) -> None:
        """Keep the windows chosen for this store (once; later runs read :meth:`plan`)."""
        self._write([("INSERT OR REPLACE INTO meta(key, value) VALUES ('plan', ?)", (json.dumps(plan),))])

    def set_meta(self, key: str, value: str) -> None:
        """Keep a stage's own record under ``meta(key)`` (e.g. the trained sets of
        :mod:`rrcache.profiler.sets`); :meth:`meta` reads it back."""
        if key in ("schema_version", "rrcache_version", "shader_hash", "session_hash", "settings_hash",
                   "settings_json", "plan", "updated"):
            raise ValueError(f"meta key {key!r} is the store's own")
        self._write([("INSERT OR REPLACE INTO meta(key, value) VALUES (?, ?)", (key, value))])

    def has_error_run(self, node: str, period: int) -> bool:
        return self.conn.execute("SELECT 1 FROM error_run WHERE node = ? AND period = ?",
                                 (node, int(period))).fetchone() is not None

    def has_timing_run(self, node: str, period: int) -> bool:
        return self.conn.execute("SELECT 1 FROM timing_run WHERE node = ? AND period = ?",
                                 (node, int(period))).fetchone() is not None

    def _rows(self, table: str, sql: str, args: tuple = ()) -> list[tuple]:
        """The rows of ``sql``, each checked against :data:`_RANGES` for ``table``: a stored value
        of the wrong type, not finite or out of its range (a tampered or damaged store) is refused
        with the table, the row and the column, never used."""
        try:
            cur = self.conn.execute(sql, args)
            names = [d[0] for d in cur.description]
            rows = cur.fetchall()
        except sqlite3.DatabaseError as err:
            raise _refuse(self.path, f"the profile store is damaged ({err})", _FRESH_HINT) from None
        ranges = _RANGES[table]
        for row in rows:
            for name, value in zip(names, row):
                rule = ranges.get(name)
                if rule is not None:
                    problem = _out_of_range(value, *rule)
                    if problem:
                        ident = ", ".join(f"{k}={v!r}" for k, v in zip(names, row) if k in _KEYS)
                        raise _refuse(self.path, f"stored row {table}({ident}): {name} = {value!r} {problem}",
                                      "the store was damaged or edited; " + _FRESH_HINT)
        return rows

    def error_runs(self, node: Optional[str] = None) -> list[ErrorRun]:
        sql = "SELECT node, period, mean_error, psnr, hit_rate, hits, misses, covered, frames, wall_s FROM error_run"
        rows = self._rows("error_run", sql + (" WHERE node = ?" if node else "") + " ORDER BY node, period",
                          (node,) if node else ())
        return [ErrorRun(*r) for r in rows]

    def error_frames(self, node: str, period: int) -> list[ErrorFrame]:
        rows = self._rows("error_frame", "SELECT frame, mean_error, psnr, hits, misses, covered, left_out FROM "
                          "error_frame WHERE node = ? AND period = ? ORDER BY frame", (node, int(period)))
        return [ErrorFrame(*r) for r in rows]

    def timing_frames(self, node: str) -> dict[int, list[TimingFrame]]:
        """Per timing period, the timed frames of ``node``."""
        out: dict[int, list[TimingFrame]] = {}
        rows = self._rows("timing_frame", "SELECT period, frame, hits, misses, ms, original_ms FROM timing_frame "
                          "WHERE node = ? ORDER BY period, frame", (node,))
        for period, *rest in rows:
            out.setdefault(int(period), []).append(TimingFrame(*rest))
        return out

    def timed_nodes(self) -> set[str]:
        return {r[0] for r in self.conn.execute("SELECT DISTINCT node FROM timing_run")}

    def reference_timing(self) -> list[tuple[int, float, int]]:
        return [tuple(r) for r in self._rows("reference_timing",
                                             "SELECT frame, ms, covered FROM reference_timing ORDER BY frame")]

    def overhead(self) -> Optional[dict]:
        rows = self._rows("overhead", "SELECT node, width, height, frames, ms FROM overhead WHERE id = 1")
        if not rows:
            return None
        return dict(zip(("node", "width", "height", "frames", "ms"), rows[0]))

    def validations(self) -> list[Selection]:
        """The measured selections, in label order."""
        rows = self._rows("validation", f"SELECT {', '.join(_VALIDATION_COLUMNS)} FROM validation ORDER BY label")
        out = []
        for label, max_error, parts, algorithm, *figures in rows:
            try:
                decoded = parts_from_json(json.loads(parts), f"validation[{label}].parts")
            except ValueError:
                raise _refuse(self.path, f"validation {label!r}: its parts are not JSON", _FRESH_HINT) from None
            except RRCacheError as err:
                raise _refuse(self.path, str(err), _FRESH_HINT) from None
            out.append(Selection(decoded, *figures[:3], label=label, max_error=max_error,
                                 algorithm=algorithm).with_measurement(*figures[3:]))
        return out

    def spent_s(self) -> float:
        """Training seconds stored so far (error and timing runs): what the budget has spent."""
        a = self.conn.execute("SELECT COALESCE(SUM(wall_s), 0) FROM error_run").fetchone()[0]
        b = self.conn.execute("SELECT COALESCE(SUM(wall_s), 0) FROM timing_run").fetchone()[0]
        return float(a) + float(b)

    def counts(self) -> dict:
        """How much is stored: error runs, timing runs, validations, and this invocation's counters."""
        q = lambda sql: int(self.conn.execute(sql).fetchone()[0])  # noqa: E731
        out = {"error_runs": q("SELECT COUNT(*) FROM error_run"),
               "timing_runs": q("SELECT COUNT(*) FROM timing_run"),
               "nodes": q("SELECT COUNT(DISTINCT node) FROM error_run"),
               "validations": q("SELECT COUNT(*) FROM validation")}
        if self.run_id is not None:
            row = self.conn.execute("SELECT error_runs_computed, error_runs_skipped, timing_runs_computed, "
                                    "timing_runs_skipped FROM run_log WHERE id = ?", (self.run_id,)).fetchone()
            out.update(zip(("error_runs_computed", "error_runs_skipped", "timing_runs_computed",
                            "timing_runs_skipped"), row))
        return out

    def run_log(self) -> list[dict]:
        cols = ("id", "started", "finished", "status", "error_runs_computed", "error_runs_skipped",
                "timing_runs_computed", "timing_runs_skipped")
        return [dict(zip(cols, r)) for r in self.conn.execute(f"SELECT {', '.join(cols)} FROM run_log ORDER BY id")]

    def close(self) -> None:
        try:
            self.conn.close()
        except sqlite3.Error:
            pass

    def __enter__(self) -> "ProfileStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _migrate_1(conn: sqlite3.Connection) -> None:
    """Schema 1 → 2 in one transaction: the validation rows' ``node``/``period`` columns become
    ``parts`` (the algorithm was not recorded: NULL)."""
    conn.execute("BEGIN IMMEDIATE")
    try:
        old = conn.execute("SELECT label, max_error, node, period, predicted_error, predicted_ms, predicted_speedup, "
                           "measured_error, measured_psnr, measured_ms, measured_original_ms, measured_speedup, "
                           "hit_rate, frames FROM validation").fetchall()
        conn.execute("DROP TABLE validation")
        table = SCHEMA[SCHEMA.index("CREATE TABLE validation"):]
        conn.execute(table[:table.index(";")])
        for label, max_error, node, period, *figures in old:
            parts = [] if node is None else [{"kind": "cache", "node": node, "period": int(period)}]
            conn.execute(f"INSERT INTO validation({', '.join(_VALIDATION_COLUMNS)}) VALUES "
                         f"({', '.join('?' * len(_VALIDATION_COLUMNS))})",
                         (label, max_error, json.dumps(parts), None, *figures))
        conn.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'", (str(SCHEMA_VERSION),))
        conn.execute("COMMIT")
    except BaseException:
        if conn.in_transaction:
            conn.execute("ROLLBACK")
        raise


#: older schema version -> the function that upgrades a store in place (schema 1 kept a
#: validation's node and period in two columns; schema 2 keeps its parts)
_MIGRATIONS = {"1": _migrate_1}


def _statements(script: str) -> list[str]:
    """The statements of :data:`SCHEMA` (comments dropped)."""
    lines = [line for line in script.splitlines() if not line.lstrip().startswith("--")]
    return [s.strip() for s in "\n".join(lines).split(";") if s.strip()]


def read_store(path: "str | os.PathLike[str]") -> ProfileStore:
    """Open an existing store read-only-ish, without a key check (for reports and tests); a file
    that is not a store raises :class:`RRCacheError`."""
    path = Path(path)
    if not path.exists():
        raise _refuse(path, "no profile store here", "run 'rrcache profile' first")
    with OutputFolder(path.parent, create=False) as folder:
        folder.regular_or_missing(path.name, *(path.name + suffix for suffix in _SIDE_FILES))
        conn = ProfileStore._connect_existing(path, folder.proc_path(path.name))
    store = ProfileStore(path, conn)
    try:
        tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        version = dict(conn.execute("SELECT key, value FROM meta")).get("schema_version") if "meta" in tables else None
        if version in _MIGRATIONS and "validation" in tables:
            _MIGRATIONS[version](conn)
            version = str(SCHEMA_VERSION)
        if version != str(SCHEMA_VERSION):
            raise _refuse(path, "an SQLite file that is not a profile store", _FRESH_HINT)
    except sqlite3.DatabaseError as err:
        conn.close()
        raise _refuse(path, f"the profile store is damaged ({err})", _FRESH_HINT) from None
    except BaseException:
        conn.close()
        raise
    return store
