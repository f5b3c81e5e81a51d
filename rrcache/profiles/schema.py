"""The profile store's schema: one commented string, the store's own tables and each kind of
choice's (:attr:`rrcache.kinds.base.Kind.tables`) put together here; the ranges a stored value
must keep; and the upgrades of older schemas (:mod:`rrcache.profiles.store` opens, checks, reads
and writes the file).
"""
from __future__ import annotations

import json
import sqlite3
from pathlib import Path
from typing import Optional

from dataclasses import dataclass

from rrcache import kinds
from rrcache.errors import RRCacheError

SCHEMA_VERSION = 3
#: the schema versions :func:`read_store` reads as they are
READABLE = ("2", "3")
#: the files SQLite keeps beside the store (write-ahead log, shared memory, rollback journal)
_SIDE_FILES = ("-wal", "-shm", "-journal")
#: the store's file name in a profile folder
STORE_NAME = "profile.sqlite"

BASE_SCHEMA = """\
-- rrcache profile store; the schema version is in meta('schema_version').
--
-- meta: what the file belongs to. Keys: schema_version, rrcache_version, shader_hash,
--   session_hash, settings_json, settings_hash, created, updated (unix seconds); and, once the
--   first run has chosen them, plan: JSON of the error and timing windows (rrcache.profiler.plan),
--   kept so that a resumed run renders exactly what the first one did.
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
--   machine noise touches both alike. host: the machine that timed it (NULL: the profiling
--   process itself).
CREATE TABLE timing_run (
    node TEXT NOT NULL,
    period INTEGER NOT NULL,
    wall_s REAL NOT NULL,
    run_id INTEGER NOT NULL REFERENCES run_log(id),
    host TEXT,
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


def _kinds_schema() -> str:
    """The tables each kind of choice keeps (rrcache.kinds), in the registry's order."""
    return "".join(k.tables for k in kinds.all_kinds() if k.tables)


#: the whole schema: the store's own tables and the kinds' (amortized runs, sets, adaptive points)
SCHEMA = BASE_SCHEMA + _kinds_schema()

#: the columns of an amortize_run row (rrcache.kinds.amortize), in the order add_amortize_rows takes
AMORTIZE_COLUMNS = ("estimator", "history", "kind", "samples", "blend", "frame", "mean_error", "psnr", "hit_rate",
                    "hits", "misses", "ms", "original_ms", "wall_s")

_VALIDATION_COLUMNS = ("label", "max_error", "parts", "algorithm", "predicted_error", "predicted_ms",
                       "predicted_speedup", "measured_error", "measured_psnr", "measured_ms", "measured_original_ms",
                       "measured_speedup", "hit_rate", "frames")

_TABLES = ("meta", "run_log", "reference_frame", "error_run", "error_frame", "timing_run", "timing_frame",
           "reference_timing", "overhead", "validation")


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
#: what :meth:`ProfileStore.check_stored` checks besides :data:`_RANGES` when a run resumes on a
#: store: the tables of no reader's range check, and the columns that key a run
_STORED_RANGES: dict[str, dict[str, tuple]] = {
    "reference_frame": {"frame": (_INT, 0, None), "covered": (_INT, 0, None)},
    "timing_run": {"period": (_INT, 1, None), "wall_s": (_REAL, 0.0, None)},
    "amortize_run": {"samples": (_INT, 1, None), "blend": (_REAL, 0.0, 1.0), "frame": (_INT, -1, None),
                     "mean_error": (_REAL, 0.0, None), "psnr": (_REAL, None, None), "hit_rate": (_REAL, 0.0, 1.0),
                     "hits": (_INT, 0, None), "misses": (_INT, 0, None), "ms": (_REAL, 0.0, None),
                     "original_ms": (_REAL, 0.0, None), "wall_s": (_REAL, 0.0, None)},
}
#: the text columns that name what a row is about (never empty)
_TEXT_KEYS = {"error_run": ("node",), "error_frame": ("node",), "timing_run": ("node",), "timing_frame": ("node",),
              "overhead": ("node",), "validation": ("label", "parts"), "amortize_run": ("estimator", "kind")}
#: the meta keys that hold JSON (a store's own records of the run)
_JSON_META = ("plan", "sets", "validation_figures")
#: the columns that name a row in an error message
_KEYS = ("node", "period", "frame", "label", "estimator", "samples")


def _out_of_range(value, kind: str, low, high) -> Optional[str]:
    """Why ``value`` does not fit (None: it fits). NULL is allowed only where the schema allows
    it (``validation.node/period``: the original shader)."""
    if value is None:
        return None if kind == _INT else "is missing"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"is not {'an' if kind[0] in 'aeiou' else 'a'} {kind}"
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


def _count(value) -> int:
    """A hit or miss count as stored (an algorithm that cannot count them: 0)."""
    return int(value) if value is not None else 0


def _migrate_1(conn: sqlite3.Connection) -> None:
    """Schema 1 → 2: the validation rows' ``node``/``period`` columns become ``parts`` (the
    algorithm was not recorded: NULL)."""
    old = conn.execute("SELECT label, max_error, node, period, predicted_error, predicted_ms, predicted_speedup, "
                       "measured_error, measured_psnr, measured_ms, measured_original_ms, measured_speedup, "
                       "hit_rate, frames FROM validation").fetchall()
    conn.execute("DROP TABLE validation")
    table = BASE_SCHEMA[BASE_SCHEMA.index("CREATE TABLE validation"):]
    conn.execute(table[:table.index(";")])
    for label, max_error, node, period, *figures in old:
        parts = [] if node is None else [{"kind": "cache", "node": node, "period": int(period)}]
        conn.execute(f"INSERT INTO validation({', '.join(_VALIDATION_COLUMNS)}) VALUES "
                     f"({', '.join('?' * len(_VALIDATION_COLUMNS))})",
                     (label, max_error, json.dumps(parts), None, *figures))
    conn.execute("UPDATE meta SET value = '2' WHERE key = 'schema_version'")


def _migrate_2(conn: sqlite3.Connection) -> None:
    """Schema 2 → 3 in one transaction: the kinds' tables made (``amortize_run`` from before the
    slots history rebuilt with its ``history`` column, its rows ``blend``), the set stage's
    record moved from ``meta('sets')`` into ``set_run``, and ``timing_run`` given its ``host``."""
    if "host" not in _columns(conn, "timing_run"):
        conn.execute("ALTER TABLE timing_run ADD COLUMN host TEXT")
    tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    if "amortize_run" in tables and "history" not in _columns(conn, "amortize_run"):
        conn.execute("ALTER TABLE amortize_run RENAME TO amortize_run_old")
        tables.discard("amortize_run")
    for statement in _statements(_kinds_schema()):
        conn.execute(statement)
    if "amortize_run_old" in {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}:
        old = [c for c in AMORTIZE_COLUMNS if c != "history"]
        conn.execute(f"INSERT INTO amortize_run ({', '.join(old)}, history) "
                     f"SELECT {', '.join(old)}, 'blend' FROM amortize_run_old")
        conn.execute("DROP TABLE amortize_run_old")
    row = conn.execute("SELECT value FROM meta WHERE key = 'sets'").fetchone()
    for record in _set_records(row[0] if row else None):
        conn.execute("INSERT OR REPLACE INTO set_run(nodes, periods, record) VALUES (?, ?, ?)",
                     (json.dumps(record["nodes"]), json.dumps(record["periods"]), json.dumps(record)))
    conn.execute("DELETE FROM meta WHERE key = 'sets'")
    conn.execute("UPDATE meta SET value = '3' WHERE key = 'schema_version'")


def _set_records(raw) -> list[dict]:
    """The set stage's records of a ``meta('sets')`` value (schema 2; what is not one is dropped)."""
    try:
        data = json.loads(raw) if raw else []
    except ValueError:
        return []
    return [d for d in data if isinstance(d, dict) and "nodes" in d and "periods" in d] if isinstance(data, list) else []


def _columns(conn: sqlite3.Connection, table: str) -> list[str]:
    return [r[1] for r in conn.execute(f"PRAGMA table_info({table})").fetchall()]


def _table_name(statement: str) -> str:
    words = statement.replace("(", " ").split()
    return words[words.index("TABLE") + (4 if words[words.index("TABLE") + 1] == "IF" else 1)]


#: older schema version -> the function that upgrades a store in place to the next version
#: (schema 1 kept a validation's node and period in two columns; schema 2 kept the sets in meta
#: and made the amortization table when first written)
_MIGRATIONS = {"1": _migrate_1, "2": _migrate_2}


def _upgrade(path: Path, conn: sqlite3.Connection, version: str) -> str:
    """Run the upgrade from ``version`` in one transaction; its version after. A store that cannot
    be written (a full disk) is refused with what to do; the file is left as it was."""
    try:
        conn.execute("BEGIN IMMEDIATE")
        try:
            _MIGRATIONS[version](conn)
            conn.execute("COMMIT")
        except BaseException:
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            raise
    except sqlite3.Error as err:
        raise _refuse(path, f"cannot upgrade the profile store from schema {version}: {err}",
                      "free some disk space or make the folder writable, then run the profile again") from None
    return str(int(version) + 1)


def _statements(script: str) -> list[str]:
    """The statements of :data:`SCHEMA` (comments dropped)."""
    lines = [line for line in script.splitlines() if not line.lstrip().startswith("--")]
    return [s.strip() for s in "\n".join(lines).split(";") if s.strip()]


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
