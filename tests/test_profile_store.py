"""The profile store and the training settings, without GL.

- a store opened with another shader, session, settings or rrcache version is refused, naming the
  file and what differs, with the --out/--fresh hint; ``fresh`` moves it aside as .bak;
- a damaged file, a text file and a foreign SQLite file (no meta, another schema) are refused;
- a write interrupted half-way leaves nothing of it behind;
- settings: bad values are located errors; budget and validate are not part of the key.
"""
from __future__ import annotations

import sqlite3
import warnings
from types import SimpleNamespace

import pytest

from rrcache.errors import RRCacheError
from rrcache.profiles.settings import TrainingSettings, parse_periods
from rrcache.profiles.store import SCHEMA_VERSION, ErrorFrame, ErrorRun, ProfileStore, StoreKey, read_store
from rrcache.selection import CachedNode, Selection

SETTINGS = TrainingSettings(periods=(2, 4, 8), resolution=(32, 24), frames=12, validation_frames=12)


def _key(**over):
    base = dict(shader_hash="a" * 64, session_hash="b" * 64, settings_hash=SETTINGS.key_hash(),
                rrcache_version="0.1.0", settings_json=SETTINGS.key_json())
    base.update(over)
    return StoreKey(**base)


def _run(node="n1", period=2):
    return ErrorRun(node, period, 0.01, 40.0, 0.5, 10, 10, 20, 3, 0.1)


def _frames():
    return [ErrorFrame(i, 0.01 * i, 40.0, 5, 5, 10, 0) for i in range(3)]


def test_round_trip_and_resume_counters(tmp_path):
    path = tmp_path / "profile.sqlite"
    with ProfileStore.open(path, _key()) as store:
        store.begin_run()
        store.add_error_run(_run(), _frames())
        assert store.has_error_run("n1", 2) and not store.has_error_run("n1", 4)
    with ProfileStore.open(path, _key()) as store:
        store.begin_run()
        store.count_skipped(1, 0)
        assert [r.period for r in store.error_runs("n1")] == [2]
        assert [f.frame for f in store.error_frames("n1", 2)] == [0, 1, 2]
        counts = store.counts()
        assert counts["error_runs"] == 1 and counts["error_runs_computed"] == 0 and counts["error_runs_skipped"] == 1
        with pytest.raises(sqlite3.IntegrityError):  # a run is never stored twice
            store.add_error_run(_run(), _frames())
        assert [r["error_runs_computed"] for r in store.run_log()] == [1, 0]
        assert store.meta()["schema_version"] == str(SCHEMA_VERSION)


@pytest.mark.parametrize("field,words", [("shader_hash", "shader"), ("session_hash", "session"),
                                         ("rrcache_version", "rrcache version")])
def test_other_key_is_refused(tmp_path, field, words):
    path = tmp_path / "profile.sqlite"
    ProfileStore.open(path, _key()).close()
    with pytest.raises(RRCacheError) as info:
        ProfileStore.open(path, _key(**{field: "c" * 64}))
    text = str(info.value)
    assert str(path) in text and words in text and "--fresh" in text and "--out" in text


def test_other_settings_name_the_difference(tmp_path):
    path = tmp_path / "profile.sqlite"
    ProfileStore.open(path, _key()).close()
    other = TrainingSettings(periods=(2, 4, 9), resolution=(32, 24), frames=12, validation_frames=12)
    with pytest.raises(RRCacheError, match=r"periods: stored \[2, 4, 8\], now \[2, 4, 9\]"):
        ProfileStore.open(path, _key(settings_hash=other.key_hash(), settings_json=other.key_json()))


def test_fresh_moves_the_old_store_aside(tmp_path):
    path = tmp_path / "profile.sqlite"
    with ProfileStore.open(path, _key()) as store:
        store.add_error_run(_run(), _frames())
    with ProfileStore.open(path, _key(shader_hash="c" * 64), fresh=True) as store:
        assert store.counts()["error_runs"] == 0
    with read_store(tmp_path / "profile.sqlite.bak") as old:
        assert old.counts()["error_runs"] == 1


def test_damaged_file_is_refused(tmp_path, stability_case):
    case = stability_case("damaged store file", "profile store: interruption and damage", "a 4 KiB page in the middle overwritten with 0xa5")
    path = tmp_path / "profile.sqlite"
    with ProfileStore.open(path, _key()) as store:
        for n in range(40):
            store.add_error_run(_run(f"n{n}"), _frames())
        store.conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    data = bytearray(path.read_bytes())
    assert len(data) > 8192
    data[4096:8192] = b"\xa5" * 4096  # wipe a page in the middle
    path.write_bytes(bytes(data))
    with pytest.raises(RRCacheError, match="damaged") as info:
        ProfileStore.open(path, _key())
    case.observe(error=str(info.value).replace(str(tmp_path), "TMP"))
    assert str(path) in str(info.value) and "--fresh" in str(info.value)


def test_text_file_is_refused(tmp_path, stability_case):
    case = stability_case("store file that is text", "profile store: interruption and damage", "'not a database' × 10 lines")
    path = tmp_path / "profile.sqlite"
    path.write_text("not a database\n" * 10)
    with pytest.raises(RRCacheError, match="not an SQLite file") as info:
        ProfileStore.open(path, _key())
    case.observe(error=str(info.value).replace(str(tmp_path), "TMP"))


def test_foreign_sqlite_files_are_refused(tmp_path, stability_case):
    case = stability_case("foreign SQLite store files", "profile store: interruption and damage",
                          "no meta table; a meta table of another schema; schema version 99")
    seen = []
    foreign = tmp_path / "foreign.sqlite"
    with sqlite3.connect(foreign) as conn:
        conn.execute("CREATE TABLE samples (x REAL)")
    with pytest.raises(RRCacheError, match="no meta table") as info:
        ProfileStore.open(foreign, _key())
    seen.append(str(info.value).replace(str(tmp_path), "TMP"))
    other = tmp_path / "other.sqlite"
    with sqlite3.connect(other) as conn:  # coverage.py-like: a meta table with another schema
        conn.execute("CREATE TABLE meta (key TEXT, value TEXT)")
        conn.execute("INSERT INTO meta VALUES ('version', '7.3')")
    with pytest.raises(RRCacheError, match="no schema version") as info:
        ProfileStore.open(other, _key())
    seen.append(str(info.value).replace(str(tmp_path), "TMP"))
    newer = tmp_path / "newer.sqlite"
    ProfileStore.open(newer, _key()).close()
    with sqlite3.connect(newer) as conn:
        conn.execute("UPDATE meta SET value = '99' WHERE key = 'schema_version'")
    with pytest.raises(RRCacheError, match="schema '99'") as info:
        ProfileStore.open(newer, _key())
    seen.append(str(info.value).replace(str(tmp_path), "TMP"))
    case.observe(errors=" / ".join(seen))


def test_interrupted_write_leaves_nothing(tmp_path):
    path = tmp_path / "profile.sqlite"
    with ProfileStore.open(path, _key()) as store:
        def statements():
            yield ("INSERT INTO error_run VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                   ("n1", 2, 0.1, 30.0, 0.5, 1, 1, 2, 3, 0.1, 1))
            raise KeyboardInterrupt
        with pytest.raises(KeyboardInterrupt):
            store._write(statements())
        assert store.counts()["error_runs"] == 0
    with ProfileStore.open(path, _key()) as store:
        assert store.counts()["error_runs"] == 0


@pytest.mark.parametrize("kwargs,match", [
    (dict(periods=(2, 0)), "periods: 0"),
    (dict(periods=(2, 2)), "repeats"),
    (dict(periods=()), "no periods"),
    (dict(resolution=(0, 10)), "resolution"),
    (dict(frames=1), "frames"),
    (dict(timing_frames=0), "timing_frames"),
    (dict(algorithm="four-pass"), "unknown algorithm"),
    (dict(block=3), "block"),
    (dict(refresh="sometimes"), "refresh"),
    (dict(depth_epsilon=2.0), "depth_epsilon"),
    (dict(budget_s=0), "budget_s"),
])
def test_bad_settings_are_located(kwargs, match):
    with pytest.raises(RRCacheError, match=match) as info:
        TrainingSettings(**kwargs)
    assert info.value.where == "settings" and info.value.hint


def test_parse_periods():
    assert parse_periods("8,2, 4") == (2, 4, 8)
    with pytest.raises(RRCacheError, match="--periods") as info:
        parse_periods("2,x")
    assert info.value.hint


def test_key_ignores_budget_and_validate_and_resolves_defaults():
    session = SimpleNamespace(resolution=(64, 48), frames=12, path="s.json")
    a = TrainingSettings(periods=(2, 4, 8)).resolved(session)
    b = TrainingSettings(periods=(2, 4, 8), resolution=(64, 48), frames=12, budget_s=5, validate=False,
                         min_saving=0.3).resolved(session)
    assert a.resolution == (64, 48) and a.frames == 12
    long = TrainingSettings(periods=(2, 4, 8)).resolved(SimpleNamespace(resolution=(64, 48), frames=600, path="s.json"))
    assert long.frames == 150  # the default: 150 frames (all of a session up to that long)
    assert a.key_hash() == b.key_hash()
    assert a.key_hash() != TrainingSettings(periods=(2, 4, 9)).resolved(session).key_hash()
    assert TrainingSettings.from_json(b.to_json()) == b
    with pytest.raises(RRCacheError, match="unknown training settings"):
        TrainingSettings.from_json({**b.to_json(), "octaves": 3})


def test_short_session_warns_and_too_many_frames_fail():
    session = SimpleNamespace(resolution=(64, 48), frames=12, path="s.json")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        TrainingSettings().resolved(session)  # the largest period, 50, exceeds 12 frames
    assert any("steady state" in str(w.message) for w in caught)
    with pytest.raises(RRCacheError, match="the session has 12") as info:
        TrainingSettings(frames=20).resolved(session)
    assert info.value.where == "s.json"


def _selection(label, parts, **measured):
    sel = Selection(parts, 0.02, 3.0, 1.5, label=label, max_error=0.03, algorithm="two-pass")
    return sel.with_measurement(measured.get("error", 0.018), 41.0, 3.1, 4.5, 1.45, 0.8, 12)


def test_validations_keep_the_selection_record(tmp_path):
    """A measured Selection goes into the store and comes back equal: its parts (whatever their
    kind), the algorithm, the predicted and measured figures."""
    rows = [_selection("e1", (CachedNode("n7", 16),)), _selection("e2", (), error=0.0)]
    with ProfileStore.open(tmp_path / "profile.sqlite", _key()) as store:
        for row in rows:
            store.add_validation(row)
        assert store.validations() == rows
        assert store.validations()[0].key == (("cache", "n7", 16),)
        with pytest.raises(ValueError, match="measured"):
            store.add_validation(Selection((CachedNode("n7", 16),), 0.02, 3.0, 1.5, label="e3"))


def test_a_schema_1_store_is_upgraded_in_place(tmp_path):
    """Schema 1 kept a validation's node and period in two columns; opening such a store
    rewrites them as parts and keeps every measurement."""
    path = tmp_path / "profile.sqlite"
    with ProfileStore.open(path, _key()) as store:
        store.add_error_run(_run(), _frames())
    conn = sqlite3.connect(str(path), isolation_level=None)
    conn.execute("DROP TABLE validation")
    conn.execute("CREATE TABLE validation (label TEXT PRIMARY KEY, max_error REAL NOT NULL, node TEXT, "
                 "period INTEGER, predicted_error REAL NOT NULL, predicted_ms REAL NOT NULL, predicted_speedup "
                 "REAL NOT NULL, measured_error REAL NOT NULL, measured_psnr REAL NOT NULL, measured_ms REAL NOT "
                 "NULL, measured_original_ms REAL NOT NULL, measured_speedup REAL NOT NULL, hit_rate REAL NOT "
                 "NULL, frames INTEGER NOT NULL)")
    conn.execute("INSERT INTO validation VALUES ('e1', 0.03, 'n7', 16, 0.02, 3.0, 1.5, 0.018, 41.0, 3.1, 4.5, "
                 "1.45, 0.8, 12)")
    conn.execute("INSERT INTO validation VALUES ('e2', 0.05, NULL, NULL, 0, 4.5, 1, 0, 100, 4.5, 4.5, 1, 0, 0)")
    conn.execute("UPDATE meta SET value = '1' WHERE key = 'schema_version'")
    conn.close()
    with ProfileStore.open(path, _key()) as store:
        assert store.meta()["schema_version"] == str(SCHEMA_VERSION)
        first, second = store.validations()
        assert first.key == (("cache", "n7", 16),) and first.measured_error == 0.018 and first.frames == 12
        assert first.algorithm is None  # schema 1 did not record it
        assert second.parts == () and second.measured_speedup == 1.0
        assert [r.period for r in store.error_runs("n1")] == [2]  # the measurements stay


def _as_schema_2(path) -> None:
    """Make a schema-3 store at ``path`` what schema 2 wrote: no set_run or adaptive_point table
    (the sets in meta('sets')), the amortize_run table from before its history column."""
    conn = sqlite3.connect(str(path))
    conn.executescript("""
        DROP TABLE set_run; DROP TABLE adaptive_point; DROP TABLE amortize_run; DROP TABLE timing_run;
        CREATE TABLE timing_run (node TEXT NOT NULL, period INTEGER NOT NULL, wall_s REAL NOT NULL,
            run_id INTEGER NOT NULL REFERENCES run_log(id), PRIMARY KEY (node, period));
        CREATE TABLE amortize_run (estimator TEXT NOT NULL, kind TEXT NOT NULL, samples INTEGER NOT NULL,
            blend REAL NOT NULL, frame INTEGER NOT NULL, mean_error REAL NOT NULL, psnr REAL NOT NULL,
            hit_rate REAL NOT NULL, hits INTEGER NOT NULL, misses INTEGER NOT NULL, ms REAL NOT NULL,
            original_ms REAL NOT NULL, wall_s REAL NOT NULL, PRIMARY KEY (estimator, kind, samples, blend, frame));
        INSERT INTO amortize_run VALUES ('e1', 'error', 4, 0.6, -1, 0.01, 40.0, 0.8, 80, 20, 0, 0, 0.5);
        INSERT INTO meta(key, value) VALUES ('sets', '[{"nodes": ["n1", "n2"], "periods": [50, 4], "layout": "union",
            "predicted_error": 0.01, "predicted_ms": 2.0, "trained": true, "trained_error": 0.02}]');
        UPDATE meta SET value = '2' WHERE key = 'schema_version';
    """)
    conn.commit()
    conn.close()


def test_a_schema_2_store_is_read_as_it_is_and_upgraded_when_written(tmp_path):
    """One store schema: the amortized runs, the sets and the adaptive points are tables of it. A
    store written by schema 2 (the sets in meta, an amortization table without its history column)
    reads as it is without being changed, and opening it to write upgrades it in one go."""
    path = tmp_path / "profile.sqlite"
    ProfileStore.open(path, _key()).close()
    _as_schema_2(path)
    before = path.read_bytes()
    with read_store(path) as store:
        assert [d["nodes"] for d in store.set_runs()] == [["n1", "n2"]]
        assert [r["history"] for r in store.amortize_rows("e1", "error")] == ["blend"]
        assert store.adaptive_points() == [] and store.amortize_spent_s() == 0.5
    assert path.read_bytes() == before  # reading changed nothing
    with ProfileStore.open(path, _key()) as store:
        assert store.meta()["schema_version"] == str(SCHEMA_VERSION) == "3" and "sets" not in store.meta()
        assert [(d["nodes"], d["trained_error"]) for d in store.set_runs()] == [(["n1", "n2"], 0.02)]
        assert [(r["history"], r["samples"]) for r in store.amortize_rows("e1", "error")] == [("blend", 4)]
        columns = [r[1] for r in store.conn.execute("PRAGMA table_info(amortize_run)")]
        assert "host" in [r[1] for r in store.conn.execute("PRAGMA table_info(timing_run)")]
        assert "history" in columns and store.conn.execute("SELECT COUNT(*) FROM adaptive_point").fetchone() == (0,)
        store.add_set_run({"nodes": ["n1", "n3"], "periods": [8, 8], "trained": False, "note": "x"})
        assert len(store.set_runs()) == 2


def test_every_kind_table_is_in_the_one_schema(tmp_path):
    from rrcache import kinds
    from rrcache.profiles.store import SCHEMA

    with ProfileStore.open(tmp_path / "profile.sqlite", _key()) as store:
        tables = {r[0] for r in store.conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    for kind in kinds.all_kinds():
        for table in ("amortize_run", "set_run", "adaptive_point"):
            if f"TABLE IF NOT EXISTS {table}" in kind.tables:
                assert table in tables and table in SCHEMA, (kind.name, table)
