"""Amortized sampling in the profiler, end to end on a tiny scene (an icosphere, 64×64, 12 frames,
a shader whose soft lighting sums 8 terms in a loop: estimator e1), real GL and real nlopt fits:

- the estimator is trained: error runs at m = 1, 2, 4 and λ of TRAIN_BLENDS against the original,
  timing runs at each m, the fits in profile.json (which still loads without the key);
- fewer terms per frame cost error (at λ = 0); the nlopt fit follows the runs;
- every level's choice is the faster of the nodes' and the estimator's best admissible option;
- a profile whose estimator is predicted fastest selects an AmortizedLoop: `rrcache select`
  shows and writes it, validation measures it beside the original;
- the slots history (the N/m subset sums kept apart) is trained too, at the m where it fits
  (8 terms of one component: m = 2, 4), with its own fits and options on the same front; a store
  and a document written before it load as blend only (the store resumed adds the slots runs);
  a profile whose slots options are predicted fastest selects one, and its optimized/eN shader
  files are the slots variant's, which renders.
"""
from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from rrcache.model.amortize import TRAIN_BLENDS, admissible
from rrcache.profiler import profile
from rrcache.profiles import TrainingSettings, load_profile
from rrcache.selection import AmortizedLoop

from scene_files import SESSION, WAVE, fragment, write_scene

SHADER = fragment("""void main() {
    vec3 p = v_objectPosition * u_scale;
    vec3 nrm = normalize(v_normal);
    vec3 l = normalize(u_light - v_position.xyz);
    float shade = 0.0;
    for (int i = 0; i < 8; i++) {
        vec3 d = normalize(l + 0.35 * vec3(cos(float(i) * 2.4), sin(float(i) * 2.4), 0.5 * wave(p, 1.0 + float(i))));
        shade += max(dot(nrm, d), 0.0) * (0.6 + 0.4 * wave(p, 2.0 + 0.3 * float(i)));
    }
    fragColor = vec4(vec3(0.9, 0.8, 0.6) * (0.2 + 0.1 * shade), 1.0);
}
""", WAVE)

#: 64×64 at full resolution (the error runs in a window at full pixel density), a 1 s budget:
#: the costliest node and the estimator are trained
SETTINGS = dict(periods=(2, 4, 8), timing_frames=6, timing_periods=(2, 8), min_gain=0.0, budget_s=1.0)


def _scene(folder):
    return write_scene(folder, SHADER, {**SESSION, "resolution": [64, 64]}, "soft.frag")


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    folder = tmp_path_factory.mktemp("amortize")
    shader, session = _scene(folder)
    events = []
    prof = profile(shader, session, folder / "out", TrainingSettings(**SETTINGS, validate=False),
                   progress=events.append)
    return prof, events, folder


def test_the_estimator_is_trained_against_m_and_lambda(trained):
    prof, events, folder = trained
    assert [e.id for e in prof.estimators] == ["e1"]
    est = prof.estimators[0]
    assert est.trained and est.samples == 8 and est.note is None
    assert sorted(set(est.run_samples)) == [1, 2, 4]
    assert sorted(set(est.run_blends)) == sorted(TRAIN_BLENDS)
    assert len(est.errors) == 3 * len(TRAIN_BLENDS)
    assert all(math.isfinite(e) and e > 0 for e in est.errors)
    at_zero = {m: e for m, lam, e in zip(est.run_samples, est.run_blends, est.errors) if lam == 0.0}
    # fewer terms per frame, more error (no blend to hide it)
    assert at_zero[1] > at_zero[2] > at_zero[4]
    # the nlopt fit follows the runs
    model = est.model()
    predicted = model.error.predict(np.array(est.run_samples), np.array(est.run_blends))
    assert est.error_fit["quality"] in ("ok", "poor") and est.error_fit["a"] > 0
    assert np.corrcoef(predicted, est.errors)[0, 1] > 0.8
    # and is held to them: at a run's (m, λ) the model predicts what the run measured
    # (rrcache.model.amortize.AnchoredFit), between them the fit's shape
    assert predicted == pytest.approx(est.errors, rel=1e-9)
    from rrcache.model.amortize import error_fit_from_json

    raw = error_fit_from_json("blend", est.error_fit)
    assert model.error.to_json() == raw.to_json() and model.error.quality == raw.quality
    assert model.error.predict(8, 0.0) == 0.0  # every term each frame: the original
    assert est.timed_samples == [1, 2, 4] and all(ms > 0 for ms in est.timed_ms)
    # more terms evaluated at larger m
    assert est.timed_evaluated[0] < est.timed_evaluated[1] < est.timed_evaluated[2]
    assert 0 < est.hit_rate <= 1 and est.pixels > 100
    assert any(e.stage == "amortize" for e in events)


def test_profile_json_keeps_the_estimators_and_old_documents_load(trained, tmp_path):
    prof, _, folder = trained
    data = json.loads((folder / "out" / "profile.json").read_text())
    assert data["estimators"][0]["id"] == "e1" and data["estimators"][0]["trained"]
    assert load_profile(folder / "out") == prof
    # a document written before amortization was profiled has no "estimators": it loads, with none
    del data["estimators"]
    (tmp_path / "profile.json").write_text(json.dumps(data))
    old = load_profile(tmp_path)
    assert old.estimators == [] and old.amortized_options() == []
    assert old.select_psnr(30).kind in ("cache", "original")
    # a bad value in an estimator is refused with its key path
    data = json.loads((folder / "out" / "profile.json").read_text())
    data["estimators"][0]["errors"][0] = -1
    (tmp_path / "profile.json").write_text(json.dumps(data))
    with pytest.raises(Exception, match=r"estimators\[0\]\.errors\[0\]"):
        load_profile(tmp_path)


def test_each_level_takes_the_faster_of_nodes_and_estimator(trained):
    prof, _, _ = trained
    options = prof.amortized_options()
    assert options and all(isinstance(o.parts[0], AmortizedLoop) for o in options)
    from rrcache.model.psnr import select_min_psnr

    for db in (45.0, 40.0, 35.0, 30.0, 20.0):
        node_choice = select_min_psnr(prof.table, prof.psnr_fits(), db)
        best = admissible(options, prof.original_ms, min_psnr=db)
        choice = prof.select_psnr(db)
        if best and best[0].predicted_ms < node_choice.predicted_ms:
            assert choice.kind == "amortize" and choice.key == best[0].key
        else:
            assert choice.key == node_choice.key


@pytest.fixture(scope="module")
def amortized_wins(trained, tmp_path_factory):
    """The trained profile with the estimator's time per term made tiny: its options are predicted
    far faster than the original and than any node (what a costly estimator gives at full
    resolution), so the choice does not depend on this machine's speed."""
    prof, _, folder = trained
    data = json.loads((folder / "out" / "profile.json").read_text())
    est = data["estimators"][0]
    est["time_fit"]["fixed_ms"] = 0.01 * data["original_ms"]
    est["time_fit"]["t_sample"] = 1e-9
    out = tmp_path_factory.mktemp("wins")
    (out / "profile.json").write_text(json.dumps(data))
    return load_profile(out), folder


def test_select_returns_an_amortized_loop(amortized_wins, tmp_path):
    prof, folder = amortized_wins
    choice = prof.select(1.0)
    assert choice.kind == "amortize" and choice.parts[0].estimator == "e1"
    assert choice.predicted_speedup > 1 and choice.algorithm == prof.algorithm
    # the CLI: JSON, text and the shader files of the choice
    env_cmd = [sys.executable, "-m", "rrcache", "select", str(prof.path), "--max-error", "1"]
    got = subprocess.run(env_cmd + ["--json"], capture_output=True, text=True)
    assert got.returncode == 0, got.stderr
    data = json.loads(got.stdout)
    assert data["kind"] == "amortize" and data["estimator"] == "e1" and data["of"] == 8
    assert data["samples"] == choice.parts[0].samples and data["blend"] == choice.parts[0].blend
    got = subprocess.run(env_cmd + ["--out", str(tmp_path / "opt")], capture_output=True, text=True)
    assert got.returncode == 0, got.stderr
    assert got.stdout.startswith("amortize e1") and "terms per frame" in got.stdout
    manifest = json.loads((tmp_path / "opt" / "manifest.json").read_text())
    assert manifest["algorithm"] == prof.algorithm
    # the PSNR levels choose it too, and front_candidates offers other amortized options
    level = prof.select_psnr(20.0)
    assert level.kind == "amortize" and level.max_error > 0
    assert all(c.key != level.key for c in prof.front_candidates(level))


def test_validation_measures_an_amortized_selection(amortized_wins, tmp_path):
    from rrcache.pipeline import load_for_session
    from rrcache.profiler.validate import validate
    from rrcache.profiles.store import ProfileStore, StoreKey
    from rrcache.session import load_session

    prof, folder = amortized_wins
    session = load_session(folder / "orbit.json")
    work = load_for_session(folder / "soft.frag", session)
    settings = TrainingSettings(**SETTINGS, validation_frames=6).resolved(session)
    key = StoreKey("s" * 64, "t" * 64, settings.key_hash(), "0", settings.key_json())
    choice = prof.select(1.0).replace(label="e4")
    with ProfileStore.open(tmp_path / "v.sqlite", key) as store:
        [row] = validate(work, session, settings, store, [choice], fallback=False)
    assert row.key == choice.key and row.frames == 6 and len(row.speedups) == 3
    # fresh terms every frame at hits: an error against the original, but not a broken image
    assert 0 < row.measured_error < 0.5 and math.isfinite(row.measured_psnr)
    assert 0 < row.hit_rate < 1


def test_the_window_check_measures_an_amortized_choice_for_its_own_family(amortized_wins, tmp_path):
    """rrcache.profiler.window_check: an estimator among the levels' choices gets an error run of
    its own where validation measures; its point is of the estimator family (``est:e1``), equal to
    that run made directly, and moves no cached node's prediction."""
    from rrcache.gl.formats import ERROR_FORMAT
    from rrcache.harness.cached import runtime_spec
    from rrcache.harness.execute import Bench, execute
    from rrcache.pipeline import load_for_session, variant_for_selection
    from rrcache.profiler.validate import Validator
    from rrcache.profiler.window_check import META, check_window
    from rrcache.profiles.store import ProfileStore, StoreKey
    from rrcache.runs import RunSpec
    from rrcache.session import load_session

    prof, folder = amortized_wins
    session = load_session(folder / "orbit.json")
    work = load_for_session(folder / "soft.frag", session)
    settings = TrainingSettings(**SETTINGS, validation_frames=6).resolved(session)
    choice = prof.select_psnr(20.0)
    assert choice.kind == "amortize" and choice.predicted_psnr is not None
    frames = tuple(range(8))
    key = StoreKey("s" * 64, "t" * 64, settings.key_hash(), "0", settings.key_json())
    with ProfileStore.open(tmp_path / "v.sqlite", key) as store:
        validator = Validator(work, session, settings, store, None)
        (point,) = check_window(validator, [choice], frames)
        validator.close()
        assert point["node"] == "est:e1" and point["key"] == f"window check: {choice.describe()}"
        variant, period = variant_for_selection(work, choice)
        spec = runtime_spec(variant, None, period=period, **settings.cache_options())
        with Bench(work, session) as bench:
            direct = execute(RunSpec("error", spec, frames, tuple(session.resolution), None, ERROR_FORMAT), bench)
        assert point["measured"] == pytest.approx(min(direct.steady_psnr, 100.0), abs=1e-9)
        assert validator.calibration.shift("est:e1") == pytest.approx(point["measured"] - point["predicted"])
        assert validator.calibration.shift("n1") == 0.0 and validator.calibration.spread_for("n1") == 0.0
        assert [p["key"] for p in json.loads(store.meta()[META])] == [point["key"]]


def test_the_bench_measures_the_papers_amortized_setting(trained):
    """``rrcache bench`` measures each trained estimator at the paper's setting (N/4 terms per
    frame, λ = 3/5) beside the original and shows it in bench.md."""
    from rrcache.bench.paper import QUICK, SceneResult, _amortized_rows
    from rrcache.bench.paper_report import scene_markdown
    from rrcache.pipeline import load_for_session
    from rrcache.session import load_session

    prof, _, folder = trained
    session = load_session(folder / "orbit.json")
    work = load_for_session(folder / "soft.frag", session)
    # the paper's running blend, and the per-subset slots (4 sums of one float fit the payload)
    row, slots = _amortized_rows(prof, work, session, list(range(6)), QUICK, None)
    assert row.setting == "e1: 2 of 8 per frame, λ=0.6"
    assert slots.setting == "e1: 2 of 8 per frame, λ=0.6, slots" and "slots" in slots.method
    for r in (row, slots):
        assert r.speedup > 0 and 0 < r.mean_error < 0.5 and r.ms > 0 and r.original_ms > 0
    scene = SceneResult("soft", str(folder / "soft.frag"), str(folder / "orbit.json"), (64, 64), 6, 1, 1,
                        amortized=[row, slots])
    text = scene_markdown(scene)
    assert "amortized sampling at the paper's setting" in text and "2 of 8 per frame, λ=0.6, slots" in text
    assert [r["setting"] for r in scene.to_json()["amortized"]] == [row.setting, slots.setting]


def test_the_profile_command_shows_estimators_and_an_amortized_row(amortized_wins):
    """The CLI's summary lines and selections table with an amortized selection in them."""
    from rich.console import Console

    from rrcache.cli.profile import _estimator_lines, _table

    prof, _ = amortized_wins
    [line] = _estimator_lines(prof)
    assert line.startswith("estimator e1 (line 18, 8 terms): amortization trained at m = 1, 2, 4")
    assert "fastest option e1 m=1" in line
    prof.selections = [prof.select(1.0).replace(label="e4")]
    console = Console(record=True, width=200)
    _table(prof).print(console)
    text = console.export_text()
    assert "e1 m=" in text and "/8 λ=" in text


# ---------------------------------------------------------------------------- the slots history
def test_the_slots_history_is_trained_where_it_fits(trained):
    from rrcache.model.amortize import SlotsErrorFit
    from rrcache.selection import slots_fit

    prof, events, _ = trained
    est = prof.estimators[0]
    assert est.components == 1
    slots = est.slots
    assert slots is not None and slots.trained and slots.note is None
    # 8 terms of one component: 4 sums at m = 2, 2 at m = 4; not m = 1 (8 sums)
    assert sorted(set(slots.run_samples)) == [2, 4] and slots.timed_samples == [2, 4]
    assert sorted(set(slots.run_blends)) == sorted(TRAIN_BLENDS)
    assert len(slots.errors) == 2 * len(TRAIN_BLENDS) and all(e > 0 for e in slots.errors)
    assert all(ms > 0 for ms in slots.timed_ms) and 0 < slots.hit_rate <= 1
    assert any("slots" in e.detail for e in events if e.stage == "amortize")
    # the slots are exact on a still image: at λ = 0 their error is the reprojection's alone,
    # below the blend's at the same m (a subset scaled to the whole sum)
    blend0 = {m: e for m, lam, e in zip(est.run_samples, est.run_blends, est.errors) if lam == 0.0}
    slots0 = {m: e for m, lam, e in zip(slots.run_samples, slots.run_blends, slots.errors) if lam == 0.0}
    assert all(slots0[m] < blend0[m] for m in (2, 4)), (slots0, blend0)
    # its own model: one floor per trained m, the lag term shared; the nlopt fit follows the runs
    model = est.model("slots")
    assert model.history == "slots" and isinstance(model.error.fit, SlotsErrorFit)  # held to its runs
    assert list(model.error.samples) == [2, 4] and all(c >= 0 for c in model.error.base) and model.error.b >= 0
    predicted = model.error.predict(np.array(slots.run_samples), np.array(slots.run_blends))
    assert np.corrcoef(predicted, slots.errors)[0, 1] > 0.8
    # its options: only where the slots fit, beside the blend's on the profile's front
    options = prof.amortized_options()
    histories = {(o.parts[0].history, o.parts[0].samples) for o in options}
    assert {m for h, m in histories if h == "slots"} == {2, 4}
    assert {m for h, m in histories if h == "blend"} == {1, 2, 4}
    assert all(slots_fit(8, o.parts[0].samples, 1) is None for o in options if o.parts[0].history == "slots")
    assert all(o.predicted_ms > 0 and o.predicted_error >= 0 for o in options)


def _old_store(path):
    """Rewrite the store at ``path`` as schema 2 wrote it before the history column: its
    amortize_run table without the column (its blend rows only), no set or adaptive tables."""
    import sqlite3

    conn = sqlite3.connect(str(path), isolation_level=None)
    conn.execute("PRAGMA journal_mode=DELETE")
    cols = ("estimator, kind, samples, blend, frame, mean_error, psnr, hit_rate, hits, misses, ms, original_ms, "
            "wall_s")
    rows = conn.execute(f"SELECT {cols} FROM amortize_run WHERE history = 'blend'").fetchall()
    conn.execute("DROP TABLE amortize_run")
    conn.execute("""CREATE TABLE amortize_run (estimator TEXT NOT NULL, kind TEXT NOT NULL,
        samples INTEGER NOT NULL, blend REAL NOT NULL, frame INTEGER NOT NULL, mean_error REAL NOT NULL,
        psnr REAL NOT NULL, hit_rate REAL NOT NULL, hits INTEGER NOT NULL, misses INTEGER NOT NULL,
        ms REAL NOT NULL, original_ms REAL NOT NULL, wall_s REAL NOT NULL,
        PRIMARY KEY (estimator, kind, samples, blend, frame))""")
    conn.executemany(f"INSERT INTO amortize_run ({cols}) VALUES ({', '.join('?' * 13)})", rows)
    conn.execute("DROP TABLE IF EXISTS set_run")
    conn.execute("DROP TABLE IF EXISTS adaptive_point")
    conn.execute("UPDATE meta SET value = '2' WHERE key = 'schema_version'")
    conn.close()
    return rows


def test_a_store_written_before_the_slots_history_opens_and_resumes(trained, tmp_path):
    import shutil

    from rrcache.profiles import amortize as data
    from rrcache.profiles.store import read_store

    prof, _, folder = trained
    out = tmp_path / "out"
    shutil.copytree(folder / "out", out)
    old_rows = _old_store(out / "profile.sqlite")
    assert old_rows
    before = (out / "profile.sqlite").read_bytes()
    store = read_store(out / "profile.sqlite")
    try:
        blend = data.rows(store, "e1", "error") + data.rows(store, "e1", "timing")
        assert len(blend) == len(old_rows) and all(r["history"] == "blend" for r in blend)
        assert data.rows(store, "e1", "error", "slots") == [] and data.rows(store, "e1", "timing", "slots") == []
    finally:
        store.close()
    assert (out / "profile.sqlite").read_bytes() == before  # reading changed nothing
    # resumed: the blend runs are skipped (kept), the slots runs added
    events = []
    shader, session = folder / "soft.frag", folder / "orbit.json"
    again = profile(shader, session, out, TrainingSettings(**SETTINGS, validate=False), progress=events.append)
    details = [e.detail for e in events if e.stage == "amortize"]
    assert details and all("slots" in d for d in details if " m=" in d), details
    est, first = again.estimators[0], prof.estimators[0]
    assert est.errors == first.errors and est.run_samples == first.run_samples
    assert est.slots.trained and sorted(set(est.slots.run_samples)) == [2, 4]
    store = read_store(out / "profile.sqlite")
    try:
        assert len(data.rows(store, "e1", "error")) == len(first.errors)
        assert len(data.rows(store, "e1", "error", "slots")) == len(est.slots.errors)
    finally:
        store.close()


def test_a_document_without_the_slots_loads_as_blend_only(trained, tmp_path):
    prof, _, folder = trained
    data = json.loads((folder / "out" / "profile.json").read_text())
    assert data["estimators"][0]["slots"]["trained"] and data["estimators"][0]["components"] == 1
    for est in data["estimators"]:
        del est["slots"], est["components"]
    (tmp_path / "profile.json").write_text(json.dumps(data))
    old = load_profile(tmp_path)
    assert old.estimators[0].slots is None and old.estimators[0].model("slots") is None
    options = old.amortized_options()
    assert options and {o.parts[0].history for o in options} == {"blend"}
    assert old.select_psnr(30).kind in ("cache", "original", "amortize")

    def refused(change, where):
        doc = json.loads((folder / "out" / "profile.json").read_text())
        change(doc["estimators"][0])
        (tmp_path / "profile.json").write_text(json.dumps(doc))
        with pytest.raises(Exception, match=where):
            load_profile(tmp_path)

    refused(lambda e: e["slots"]["errors"].__setitem__(0, -1), r"estimators\[0\]\.slots\.errors\[0\]")
    refused(lambda e: e["slots"].__setitem__("colour", 1), r"estimators\[0\]\.slots\.colour: unknown key")
    refused(lambda e: e["slots"].__setitem__("trained", "yes"), r"estimators\[0\]\.slots\.trained")
    refused(lambda e: e["slots"]["error_fit"]["base"].__setitem__(0, -0.5),
            r"estimators\[0\]\.slots\.error_fit\.base\[0\]")
    refused(lambda e: e["slots"]["error_fit"].pop("base"), r"estimators\[0\]\.slots\.error_fit\.base: is missing")
    refused(lambda e: e["slots"]["time_fit"].__setitem__("t_sample", None),
            r"estimators\[0\]\.slots\.time_fit\.t_sample")
    refused(lambda e: e["error_fit"].__setitem__("a", -1.0), r"estimators\[0\]\.error_fit\.a")
    refused(lambda e: e["error_fit"].__setitem__("form", "x"), r"estimators\[0\]\.error_fit\.form: unknown key")
    refused(lambda e: e.__setitem__("components", 5), r"estimators\[0\]\.components")


@pytest.fixture(scope="module")
def slots_win(trained, tmp_path_factory):
    """The trained profile with the slots history's time per term made tiny and the blend's
    slow: the slots options are predicted the fastest (so the choice does not depend on this
    machine's speed)."""
    prof, _, folder = trained
    data = json.loads((folder / "out" / "profile.json").read_text())
    est = data["estimators"][0]
    est["time_fit"]["fixed_ms"] = 10.0 * data["original_ms"]
    est["slots"]["time_fit"]["fixed_ms"] = 0.01 * data["original_ms"]
    est["slots"]["time_fit"]["t_sample"] = 1e-9
    out = tmp_path_factory.mktemp("slots_win")
    (out / "profile.json").write_text(json.dumps(data))
    return load_profile(out), folder


def test_select_returns_a_slots_selection_that_compiles_and_renders(slots_win, tmp_path):
    from rrcache.compiler.amortize import instance_amortized
    from rrcache.pipeline import load_for_session
    from rrcache.profiler.run import _write_outputs
    from rrcache.profiler.validate import validate
    from rrcache.profiles.store import ProfileStore, StoreKey
    from rrcache.session import load_session

    prof, folder = slots_win
    choice = prof.select(1.0)
    part = choice.parts[0]
    assert choice.kind == "amortize" and part.history == "slots" and part.samples in (2, 4)
    assert choice.predicted_speedup > 1 and choice.predicted_psnr is not None
    level = prof.select_psnr(20.0)
    assert level.kind == "amortize" and level.parts[0].history == "slots"
    # the CLI: JSON and text say the history; --out writes the slots variant
    cmd = [sys.executable, "-m", "rrcache", "select", str(prof.path), "--max-error", "1"]
    got = subprocess.run(cmd + ["--json"], capture_output=True, text=True)
    assert got.returncode == 0, got.stderr
    doc = json.loads(got.stdout)
    assert doc["history"] == "slots" and doc["phase"] == "frame" and doc["samples"] == part.samples
    got = subprocess.run(cmd + ["--out", str(tmp_path / "opt")], capture_output=True, text=True)
    assert got.returncode == 0, got.stderr
    assert "slots history" in got.stdout
    manifest = json.loads((tmp_path / "opt" / "manifest.json").read_text())
    assert manifest["amortized"]["history"] == "slots" and manifest["amortized"]["samples"] == part.samples
    assert manifest["node"]["components"] == 8 // part.samples
    # the profile's optimized/e1 files are the slots variant's, phase by phase
    session = load_session(folder / "orbit.json")
    work = load_for_session(folder / "soft.frag", session)
    prof.selections = [choice.replace(label="e1")]
    _write_outputs(prof, tmp_path / "prof", work, plots=False)
    written = tmp_path / "prof" / "optimized" / "e1"
    expected = instance_amortized(work.shader, "e1", prof.algorithm, samples=part.samples, blend=part.blend,
                                  history="slots", vertex=work.vertex)
    assert set(expected.passes) == {p.name[:-5] for p in written.glob("*.frag")}
    assert len([k for k in expected.passes if "@" in k]) == (8 // part.samples - 1) * len(
        [k for k in expected.passes if "@" not in k and k + "@1" in expected.passes])
    for key, source in expected.passes.items():
        assert (written / f"{key}.frag").read_text() == source.fragment
    assert json.loads((written / "manifest.json").read_text())["amortized"]["history"] == "slots"
    # it renders: validation measures it beside the original, and beside the blend history at
    # the same (m, λ) it is the closer to the original
    settings = TrainingSettings(**SETTINGS, validation_frames=6).resolved(session)
    key = StoreKey("s" * 64, "t" * 64, settings.key_hash(), "0", settings.key_json())
    blend = choice.replace(parts=(AmortizedLoop("e1", part.samples, part.blend),), label="e2")
    with ProfileStore.open(tmp_path / "v.sqlite", key) as store:
        slots_row, blend_row = validate(work, session, settings, store, [choice.replace(label="e1"), blend],
                                        fallback=False)
    assert slots_row.key == choice.key and slots_row.frames == 6
    assert 0 < slots_row.measured_error < 0.5 and math.isfinite(slots_row.measured_psnr)
    if part.blend == 0.0:
        assert slots_row.measured_error < blend_row.measured_error


def test_the_cli_and_report_show_the_slots_history(slots_win):
    from rich.console import Console

    from rrcache.cli.profile import _estimator_lines, _table
    from rrcache.report.html import _estimators

    prof, _ = slots_win
    [line] = _estimator_lines(prof)
    assert "amortization trained at m = 1, 2, 4" in line and "slots history at m = 2, 4" in line
    prof.selections = [prof.select(1.0).replace(label="e1")]
    console = Console(record=True, width=200)
    _table(prof).print(console)
    assert "slots" in console.export_text()
    table = _estimators(prof)
    assert "<td>slots</td>" in table and "<td>blend</td>" in table and "c<sub>2</sub>" in table


# ---------------------------------------------------------------------------- report and explorer
def _with_selection(prof, choice):
    """A shallow copy of the module's profile whose only selection is ``choice`` (labelled e4)."""
    import copy

    out = copy.copy(prof)
    out.selections = [choice.replace(label="e4")]
    return out


def test_frame_shots_render_an_amortized_selection(amortized_wins):
    """FrameShots renders an amortized choice for real: the run settles its history (the N/m
    cycle and the blend's memory), the cached frame is near the original but not equal to it,
    hits blend and misses evaluate every term, and the payload is the running estimate."""
    from rrcache.profiler.frames import FrameShots
    from rrcache.report.images import HIT_COLOR, MISS_COLOR, settle_frame

    prof, _ = amortized_wins
    choice = prof.select(1.0)
    part = choice.parts[0]
    shots = FrameShots(prof)
    images = shots.selection_images(choice)
    assert images.part == part and images.node is None and images.cached and images.what == part.describe()
    assert list(images.arrays) == ["original", "cached", "error_map", "payload", "hit_map"]
    variant, _ = shots.selection_variant(choice)
    assert images.frame == settle_frame(shots.session.frames, variant.amortized["cycle"], part.blend)
    assert images.frame >= variant.amortized["cycle"]
    assert 0 < images.error < 0.5
    assert np.abs(images.arrays["cached"] - images.arrays["original"]).max() > 0
    hit = np.all(np.isclose(images.arrays["hit_map"], HIT_COLOR), axis=-1).sum()
    miss = np.all(np.isclose(images.arrays["hit_map"], MISS_COLOR), axis=-1).sum()
    assert hit > 0 and miss > 0 and images.hit_rate == pytest.approx(hit / (hit + miss))
    assert images.caption("payload").startswith("running estimate" if part.history == "blend" else "the ")
    assert f"{part.samples} of 8 terms" in images.caption("cached")
    assert images.png("payload")[:4] == b"\x89PNG"
    assert shots.selection_images(choice) is images  # kept, not rendered again


def test_frame_shots_render_a_slots_selection(slots_win):
    from rrcache.profiler.frames import FrameShots

    prof, _ = slots_win
    choice = prof.select(1.0)
    part = choice.parts[0]
    assert part.history == "slots"
    images = FrameShots(prof).selection_images(choice)
    assert "payload" in images.arrays and f"{8 // part.samples} subset sums" in images.caption("payload")
    assert len(images.payload_ranges) == min(3, 8 // part.samples)
    assert 0 < images.error < 0.5


def test_the_report_shows_an_amortized_selections_frames(amortized_wins):
    import base64
    import io
    import re

    from PIL import Image

    from rrcache.profiler.frames import FrameShots
    from rrcache.report.html import report_html

    prof, _ = amortized_wins
    choice = prof.select(1.0)
    shown = _with_selection(prof, choice)
    page = report_html(shown, frames={s.label: FrameShots(prof).selection_images(s) for s in shown.selections})
    block = re.search(r'<div class="sel" id="sel-e4".*?</div></div>', page, re.S).group(0)
    assert 'data-kind="amortize"' in block and "amortize estimator <b>e1</b>" in block
    assert f"λ = {choice.parts[0].blend:g}" in block and "no frames" not in block
    assert re.findall(r'data-image="(\w+)"', block) == ["original", "cached", "error_map", "payload", "hit_map"]
    sources = re.findall(r'<img [^>]*src="([^"]+)"', block)
    assert len(sources) == 5 and all(s.startswith("data:image/png;base64,") for s in sources)
    for src in sources:
        Image.open(io.BytesIO(base64.b64decode(src.split(",", 1)[1]))).verify()
    assert "its history settled" in block and "hit rate" in block


def test_the_explorer_shows_and_measures_an_amortized_choice(amortized_wins):
    from rrcache.explorer import Explorer, measure_choice
    from rrcache.report.explore import default_choice, default_selection, selections_figure, tradeoff_figure

    prof, _ = amortized_wins
    choice = prof.select(1.0)
    prof = _with_selection(prof, choice.replace(max_error=1.0))
    # the first look: the amortized selection; the notebook's node section still gets a node
    assert default_selection(prof).key == choice.key
    node, period = default_choice(prof)
    assert node == prof.trained_nodes[0].id and period >= 1
    ui = Explorer(prof, value=1.0, measure=True)
    assert ui.error is None, ui.status.value
    assert ui.choice.kind == "amortize" and ui.choice.key == choice.key
    assert ui.images.part == choice.parts[0] and len(ui.frames.children) == 5
    summary = ui.summary.value
    assert "amortize estimator <b>e1</b>" in summary and f"λ = {choice.parts[0].blend:g}" in summary
    assert f"<b>{choice.parts[0].samples} of 8</b>" in summary and "blend history" in summary
    # measured beside the original (not stored: the profile never validated it)
    m = ui.measured
    assert m is not None and not m["stored"] and m["frames"] > 0
    assert 0 < m["error"] < 0.5 and m["speedup"] > 0 and 0 < m["hit_rate"] < 1
    assert "<mark" in ui.source.value  # the estimator's loop highlighted
    # a choice the profile measured is returned as stored
    stored = choice.with_measurement(0.01, 40.0, 1.0, 2.0, 2.0, 0.9, 6, (2.0,)).replace(label="e4")
    prof.selections = [stored]
    assert measure_choice(prof, stored, None, ui.shots)["stored"]
    # the tradeoff figure draws the amortized options (reused from the report's plot)
    fig = tradeoff_figure(prof)
    assert "amortized options" in fig.axes[0].get_title()
    assert any(line.get_color() == "darkorange" for line in fig.axes[0].lines)
    # the selections figure shows the amortized selection's frames
    fig = selections_figure(prof, {s.label: ui.shots.selection_images(s) for s in prof.selections})
    assert sum(len(ax.images) for ax in fig.axes) == 5


def test_the_estimator_record_keeps_the_text_as_written():
    """A loop inside a function is found in the inlined program (names like ``_rr_i_3``); the
    profile, its report and the bench show it as the user wrote it, as ``rrcache nodes`` does."""
    from rrcache.analysis.estimators import find_estimators
    from rrcache.glsl.frontend import parse_shader
    from rrcache.profiler.amortize import _record

    shader = parse_shader("#version 330\nin vec2 v_texcoord; out vec4 c;\n"
                          "float soft(vec2 p) { float s = 0.0; for (int i = 0; i < 8; i++) s += sin(p.x * float(i));"
                          " return s; }\nvoid main() { c = vec4(soft(v_texcoord)); }")
    [est] = find_estimators(shader).estimators
    assert "_rr_" in est.text
    assert _record(est).text == "for (int i = 0; i < 8; i++)"


def test_a_malformed_range_pragma_stops_the_profile_before_training(tmp_path):
    """The profiler used to skip the estimators of a shader the analysis refused; a malformed
    pragma is the user's error and is said, at its place, before anything is trained."""
    shader = tmp_path / "bad.frag"
    shader.write_text("#version 330\nin vec2 v_texcoord; out vec4 c;\nvoid main() {\n  float s = 0.0;\n"
                      "  #pragma rrcache estimator range(1, 0)\n"
                      "  for (int i = 0; i < 4; i++) s += sin(v_texcoord.x * float(i));\n  c = vec4(s);\n}\n")
    session = tmp_path / "s.json"
    session.write_text(json.dumps(SESSION))
    run = subprocess.run([sys.executable, "-m", "rrcache", "profile", str(shader), str(session),
                          "--out", str(tmp_path / "out")], capture_output=True, text=True, timeout=300)
    assert run.returncode == 2, run.stderr
    assert f"{shader}:5:" in run.stderr and "range(1, 0)" in run.stderr
    assert not (tmp_path / "out" / "profile.sqlite").exists()


# a term in [0, 1] whatever the inputs (0.5 + 0.5 sin): the analysis proves it, so the slots are
# trained and offered in 8 bits
BOUNDED = SHADER.replace(
    "shade += max(dot(nrm, d), 0.0) * (0.6 + 0.4 * wave(p, 2.0 + 0.3 * float(i)));",
    "shade += 0.5 + 0.5 * sin(dot(d, p) * (2.0 + 0.3 * float(i)));")


def test_slots_of_a_bounded_term_are_trained_and_offered_in_8_bits(tmp_path):
    from rrcache.harness.cached import CachedRenderer
    from rrcache.pipeline import load_for_session, variant_for_selection
    from rrcache.session import load_session

    assert BOUNDED != SHADER
    shader, session = _scene(tmp_path)
    shader.write_text(BOUNDED)
    prof = profile(shader, session, tmp_path / "out", TrainingSettings(**SETTINGS, validate=False))
    est = prof.estimators[0]
    assert est.trained and est.slots.trained and est.slots.payload == "u8"
    assert all(e > 0 for e in est.slots.errors)
    slots = [o for o in prof.amortized_options() if o.parts[0].history == "slots"]
    blend = [o for o in prof.amortized_options() if o.parts[0].history == "blend"]
    assert slots and all(o.parts[0].payload == "u8" for o in slots) and all(o.parts[0].payload == "f4" for o in blend)
    assert "u8" in slots[0].describe()
    # the record's JSON and rrcache select's words name the payload
    from rrcache.cli.select import _history
    from rrcache.selection import parts_from_json, parts_to_json

    assert parts_to_json(slots[0].parts)[0]["payload"] == "u8"
    assert parts_from_json(parts_to_json(slots[0].parts), "parts") == slots[0].parts
    assert "in 8 bits" in _history(slots[0].parts[0])
    # the document keeps it, and the chosen option compiles and runs in 8 bits
    assert load_profile(tmp_path / "out") == prof
    loaded = load_session(session)
    work = load_for_session(str(shader), loaded)
    variant, period = variant_for_selection(work, slots[0])
    assert variant.payload_dtype == "u8"
    with CachedRenderer(variant, loaded, work.prepared, period=period) as cached:
        for index in range(3):
            cached.render_frame(index)
        assert cached.payload_dtype == "u8" and cached.payload_note is None


def test_slots_whose_declared_range_does_not_hold_are_trained_in_floats(tmp_path):
    """The first frames in floats show the values leave the declared range: the slots are
    trained (and offered) in 32 bits, said so, and no 8-bit row is stored."""
    from rrcache.profiles import amortize as data
    from rrcache.profiles.store import read_store

    narrow = BOUNDED.replace("    for (int i = 0; i < 8; i++) {",
                             "    #pragma rrcache estimator range(0.0, 0.1)\n    for (int i = 0; i < 8; i++) {")
    assert narrow != BOUNDED
    shader, session = _scene(tmp_path)
    shader.write_text(narrow)
    events = []
    with pytest.warns(RuntimeWarning, match="outside the range"):
        prof = profile(shader, session, tmp_path / "out", TrainingSettings(**SETTINGS, validate=False),
                       progress=events.append)
    est = prof.estimators[0]
    assert est.slots.trained and est.slots.payload == "f4"
    assert all(o.parts[0].payload == "f4" for o in prof.amortized_options())
    assert any("slots in 32 bits" in e.detail for e in events if e.stage == "amortize")
    store = read_store(tmp_path / "out" / "profile.sqlite")
    assert data.rows(store, "e1", "error", "slots") and not data.rows(store, "e1", "error", "slots/u8")
    # a document that says another payload is refused at its key
    doc = json.loads((tmp_path / "out" / "profile.json").read_text())
    doc["estimators"][0]["slots"]["payload"] = "u4"
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "profile.json").write_text(json.dumps(doc))
    with pytest.raises(Exception, match=r"estimators\[0\]\.slots\.payload"):
        load_profile(tmp_path / "bad")
