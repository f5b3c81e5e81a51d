"""The profile store: a versioned SQLite file of every training measurement.

In the manner of coverage.py's data file: the schema is one commented string
(:data:`rrcache.profiles.schema.SCHEMA`: the store's own tables and each kind of choice's,
:attr:`rrcache.kinds.base.Kind.tables`, put together there, with the upgrades), a ``meta`` table names what the file belongs to, and nothing in a file is trusted before it
is checked. Opening a store to write upgrades an older schema in place, in one transaction
(schema 1: a validation's node and period in two columns; schema 2: the set stage's record in
``meta('sets')`` and an amortization table made when first written, perhaps without its history
column); reading one (:func:`read_store`) changes nothing.

Only the collector of a profile's runs writes the measurements (:mod:`rrcache.profiler.collect`:
``add_node_result``, ``add_amortize_result``, ``add_set_run``, ``add_adaptive_point`` …). A store is keyed by (shader hash, session hash, settings hash, rrcache version); opening
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
from rrcache.profiles.schema import (StoreKey, _FRESH_HINT, _JSON_META, _KEYS, _MIGRATIONS, _RANGES,  # noqa: F401
                                     _SIDE_FILES, _STORED_RANGES, _TABLES, _TEXT_KEYS,
                                     _VALIDATION_COLUMNS, AMORTIZE_COLUMNS, BASE_SCHEMA, READABLE, SCHEMA,
                                     SCHEMA_VERSION, STORE_NAME, _columns, _count, _kinds_schema, _out_of_range,
                                     _refuse, _set_records, _statements, _table_name, _upgrade)
from rrcache.selection import Selection, parts_from_json, parts_to_json

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
            for statement in _statements(BASE_SCHEMA + _kinds_schema()):
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
        while version in _MIGRATIONS and "validation" in tables:
            version = _upgrade(self.path, self.conn, version)
        if version != str(SCHEMA_VERSION):
            raise _refuse(path, f"profile store schema {version!r}, this rrcache reads schema {SCHEMA_VERSION}"
                          if version else "an SQLite file that is not a profile store (no schema version)", _FRESH_HINT)
        missing = [t for t in _TABLES if t not in tables]
        if missing:
            raise _refuse(path, f"the profile store lacks the tables {missing}", _FRESH_HINT)
        differences = key.compare(meta)
        if differences:
            raise _refuse(path, "the profile store was made for other inputs: " + "; ".join(differences), _FRESH_HINT)
        self.check_stored(meta)
        self.conn.execute("PRAGMA journal_mode=WAL")
        self._kind_tables()

    def _kind_tables(self) -> None:
        """The tables of a kind registered since the store was made (a plug-in), created empty."""
        have = {r[0] for r in self.conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        wanted = [st for st in _statements(_kinds_schema()) if _table_name(st) not in have]
        if wanted:
            self._write([(st, ()) for st in wanted])

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

    def write(self, statements: Iterable[tuple[str, tuple]]) -> None:
        """Run ``statements`` (SQL, arguments) in one transaction: how a kind of choice's
        collector writes its own table (:meth:`rrcache.kinds.base.Kind.collect`); a failed write
        is refused as every write is."""
        self._write(list(statements))

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

    def add_timing_run(self, node: str, period: int, frames: list[TimingFrame], wall_s: float,
                       host: Optional[str] = None) -> None:
        """One timing run and its frames (``host``: the machine that timed it), in one transaction."""
        rid = self._rid()
        statements = [("INSERT INTO timing_run(node, period, wall_s, run_id, host) VALUES (?, ?, ?, ?, ?)",
                       (node, int(period), float(wall_s), rid, host))]
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

    def check_stored(self, meta: Optional[dict] = None) -> None:
        """Every stored row before a run resumes on them: each value of the right type, finite and
        in range (:data:`_RANGES`, :data:`_STORED_RANGES`), the keys of each row named, each error
        run with its frames and each timing run with its frames, the JSON records parsed. A damaged
        or edited store is refused with the table, the row and the column, never used."""
        tables = {r[0] for r in self.conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        for table in sorted(tables & (set(_RANGES) | set(_STORED_RANGES))):
            rules = {**_RANGES.get(table, {}), **_STORED_RANGES.get(table, {})}
            for row in self._rows(table, f"SELECT * FROM {table}", rules=rules):
                pass
            for column in _TEXT_KEYS.get(table, ()):
                bad = self.conn.execute(f"SELECT rowid, {column} FROM {table} WHERE typeof({column}) != 'text' "
                                        f"OR {column} = '' LIMIT 1").fetchone()
                if bad is not None:
                    raise _refuse(self.path, f"stored row {table}(rowid={bad[0]}): {column} = {bad[1]!r} is not a name",
                                  "the store was damaged or edited; " + _FRESH_HINT)
        for node, period, frames in self.conn.execute(
                "SELECT r.node, r.period, r.frames FROM error_run r WHERE r.frames != (SELECT COUNT(*) FROM error_frame f "
                "WHERE f.node = r.node AND f.period = r.period) LIMIT 1"):
            held = self.conn.execute("SELECT COUNT(*) FROM error_frame WHERE node = ? AND period = ?",
                                     (node, period)).fetchone()[0]
            raise _refuse(self.path, f"stored row error_run(node={node!r}, period={period!r}) records {frames} frames, "
                          f"the store holds {held} of them", "the store was damaged or edited; " + _FRESH_HINT)
        for node, period in self.conn.execute(
                "SELECT r.node, r.period FROM timing_run r WHERE NOT EXISTS (SELECT 1 FROM timing_frame f "
                "WHERE f.node = r.node AND f.period = r.period) LIMIT 1"):
            raise _refuse(self.path, f"stored row timing_run(node={node!r}, period={period!r}) has no timed frames",
                          "the store was damaged or edited; " + _FRESH_HINT)
        meta = meta if meta is not None else dict(self.conn.execute("SELECT key, value FROM meta"))
        for key in _JSON_META:
            if key in meta:
                try:
                    json.loads(meta[key])
                except (TypeError, ValueError):
                    raise _refuse(self.path, f"stored meta({key!r}) is not JSON",
                                  "the store was damaged or edited; " + _FRESH_HINT) from None

    def _rows(self, table: str, sql: str, args: tuple = (), rules: Optional[dict] = None) -> list[tuple]:
        """The rows of ``sql``, each checked against :data:`_RANGES` for ``table``: a stored value
        of the wrong type, not finite or out of its range (a tampered or damaged store) is refused
        with the table, the row and the column, never used."""
        try:
            cur = self.conn.execute(sql, args)
            names = [d[0] for d in cur.description]
            rows = cur.fetchall()
        except sqlite3.DatabaseError as err:
            raise _refuse(self.path, f"the profile store is damaged ({err})", _FRESH_HINT) from None
        ranges = rules if rules is not None else _RANGES[table]
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

    # ------------------------------------------------------------------ the kinds' runs
    def add_node_result(self, result) -> None:
        """A node's error or timing run (a :class:`rrcache.runs.RunResult` keyed ``("node", id,
        period)``): the run and its frames, in one transaction."""
        _, node, period = result.spec.key
        rows = result.frames
        if result.spec.measure == "error":
            frames = [ErrorFrame(r.frame, float(r.error), float(r.psnr), _count(r.hits), _count(r.misses),
                                 int(r.covered), int(r.left_out)) for r in rows]
            steady = frames[1:] or frames
            hits, misses = sum(f.hits for f in steady), sum(f.misses for f in steady)
            run = ErrorRun(node, int(period), float(sum(f.mean_error for f in steady) / max(1, len(steady))),
                           float(sum(f.psnr for f in steady) / max(1, len(steady))),
                           hits / (hits + misses) if hits + misses else 0.0, hits, misses,
                           sum(f.covered for f in steady), len(frames), float(result.wall_s))
            self.add_error_run(run, frames)
        else:
            self.add_timing_run(node, int(period), [TimingFrame(r.frame, _count(r.hits), _count(r.misses), float(r.ms),
                                                                float(r.original_ms)) for r in rows],
                                float(result.wall_s), result.host)

    def has_node_run(self, measure: str, node: str, period: int) -> bool:
        return (self.has_error_run if measure == "error" else self.has_timing_run)(node, period)

    def add_amortize_rows(self, rows: list[tuple]) -> None:
        """Rows of ``amortize_run`` (in :data:`AMORTIZE_COLUMNS` order), in one transaction."""
        self._write([(f"INSERT OR REPLACE INTO amortize_run ({', '.join(AMORTIZE_COLUMNS)}) VALUES "
                      f"({', '.join('?' * len(AMORTIZE_COLUMNS))})", tuple(r)) for r in rows])

    def amortize_rows(self, estimator: str, kind: str, history: str = "blend") -> list[dict]:
        """The stored ``amortize_run`` rows of ``estimator`` of ``kind`` (``error`` or ``timing``)
        and ``history`` (``blend``, ``slots``, ``slots/u8``; a schema-2 table without the history
        column has blend rows only)."""
        if not self._has_table("amortize_run"):
            return []
        try:
            if "history" not in _columns(self.conn, "amortize_run"):
                if history != "blend":
                    return []
                cur = self.conn.execute("SELECT *, 'blend' AS history FROM amortize_run WHERE estimator = ? AND "
                                        "kind = ? ORDER BY samples, blend, frame", (estimator, kind))
            else:
                cur = self.conn.execute("SELECT * FROM amortize_run WHERE estimator = ? AND kind = ? AND history = ? "
                                        "ORDER BY samples, blend, frame", (estimator, kind, history))
            names = [d[0] for d in cur.description]
            return [dict(zip(names, r)) for r in cur.fetchall()]
        except sqlite3.DatabaseError as err:
            raise _refuse(self.path, f"the profile store is damaged ({err})", _FRESH_HINT) from None

    def amortize_spent_s(self) -> float:
        """Seconds the stored amortization runs took (they count against the training budget)."""
        if not self._has_table("amortize_run"):
            return 0.0
        return float(self.conn.execute("SELECT COALESCE(SUM(wall_s), 0) FROM amortize_run").fetchone()[0])

    def add_set_run(self, record: dict) -> None:
        """The set stage's record of one set (``nodes``, ``periods``, the prediction and what its
        runs measured: :meth:`rrcache.model.sets.SetOption.to_json`), replacing an earlier one."""
        self._write([("INSERT OR REPLACE INTO set_run(nodes, periods, record) VALUES (?, ?, ?)",
                      (json.dumps(list(record["nodes"])), json.dumps([int(p) for p in record["periods"]]),
                       json.dumps(record)))])

    def set_runs(self) -> list[dict]:
        """The set stage's records (a schema-2 store's from ``meta('sets')``)."""
        if not self._has_table("set_run"):
            return _set_records(self.meta().get("sets"))
        out = []
        for (raw,) in self.conn.execute("SELECT record FROM set_run ORDER BY rowid"):
            out.extend(_set_records(f"[{raw}]"))
        return out

    def add_adaptive_point(self, point, algorithm: str, wall_s: float) -> None:
        """One measured adaptive threshold (:class:`rrcache.profiler.adaptive.AdaptivePoint`)."""
        self._write([("INSERT OR REPLACE INTO adaptive_point VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                      (point.node, int(point.period), float(point.threshold), int(point.fast_period), algorithm,
                       float(point.error), float(point.psnr), float(point.time_ratio), float(point.hit_rate),
                       json.dumps([float(v) for v in point.speedups]), float(wall_s)))])

    def adaptive_points(self, node: Optional[str] = None) -> list[dict]:
        """The stored adaptive points (of ``node``), by node, period and threshold."""
        if not self._has_table("adaptive_point"):
            return []
        cur = self.conn.execute("SELECT * FROM adaptive_point" + (" WHERE node = ?" if node else "")
                                + " ORDER BY node, period, threshold", (node,) if node else ())
        names = [d[0] for d in cur.description]
        rows = [dict(zip(names, r)) for r in cur.fetchall()]
        for r in rows:
            r["speedups"] = tuple(json.loads(r["speedups"]))
        return rows

    def _has_table(self, name: str) -> bool:
        return self.conn.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?",
                                 (name,)).fetchone() is not None

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
        if version == "1" and "validation" in tables:
            version = _upgrade(path, conn, version)
        if version not in READABLE:
            raise _refuse(path, "an SQLite file that is not a profile store", _FRESH_HINT)
    except sqlite3.DatabaseError as err:
        conn.close()
        raise _refuse(path, f"the profile store is damaged ({err})", _FRESH_HINT) from None
    except BaseException:
        conn.close()
        raise
    return store
