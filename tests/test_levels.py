"""A level means what it says (docs/levels.md), on the tiny scene of ``test_profile`` (renders are
real: 64×48, 6 validation frames):

- a validation that measures a choice 5 dB under its level (faked on top of the real render) tries
  the next candidate, which stands; the CLI table marks it (``met, try 2``, ``↩``) and the profile
  keeps what was refused and why;
- when every candidate misses, the original stands for the level, saying what was tried; with
  ``fallback=False`` the miss is shipped and marked ``MISSED``;
- a choice whose repeats do not clear the gain worth having is refused (the fBm case of issue 29);
- the calibration learns from the miss: the next candidate is one the calibrated model predicts
  above the level with margin;
- FLIP and the temporal error are measured on the real rendered frames of a validation.
"""
from __future__ import annotations

import copy

import pytest

from rrcache.profiler import profile
from rrcache.profiles import TrainingSettings
from rrcache.selection import CachedNode, Selection
from scene_files import SETTINGS, write_scene

LEVEL = 40.0


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    folder = tmp_path_factory.mktemp("levels")
    shader, session = write_scene(folder)
    prof = profile(shader, session, folder / "out", TrainingSettings(**SETTINGS, validate=False), plots=False)
    return prof, folder


def _setup(trained, tmp_path):
    from rrcache.pipeline import load_for_session
    from rrcache.profiles.store import ProfileStore, StoreKey
    from rrcache.session import load_session

    prof, folder = trained
    session = load_session(folder / "orbit.json")
    work = load_for_session(folder / "noise.frag", session)
    settings = TrainingSettings(**SETTINGS, validation_frames=6).resolved(session)
    key = StoreKey("s" * 64, "t" * 64, settings.key_hash(), "0", settings.key_json())
    return prof, work, session, settings, ProfileStore.open(tmp_path / "v.sqlite", key)


def _option(node, period, predicted_psnr, ms=1.0):
    return Selection((CachedNode(node.id, period, node.text),), 0.01, ms, 2.0, label="e1", min_psnr=LEVEL, max_error=0.02,
                     predicted_psnr=predicted_psnr, predicted_psnr_uncertainty=0.5, algorithm="three-pass")


def _fake(monkeypatch, psnr_by_period, speedup=2.0, speedups=None):
    """Every validation render is real; then each frame's PSNR is set to ``psnr_by_period[Δn]``
    and the variant's frame time to the original's / ``speedup`` (per repeat from ``speedups``),
    so that the outcome does not depend on this machine or its load. (Validation's renders are
    compare runs: :func:`rrcache.harness.cached.compare` is what the executor calls.)"""
    import rrcache.harness.cached as cached_module

    real = cached_module.compare
    calls = {"timing": 0}

    def fake(variant, session, prepared, frames, spec, color_format="rgba32f", **kwargs):
        result = real(variant, session, prepared, frames, spec, color_format=color_format, **kwargs)
        if color_format == "rgba32f":
            for f in result.frames:
                f.psnr = psnr_by_period[spec.period]
        else:
            gain = speedups[calls["timing"] % len(speedups)] if speedups else speedup
            calls["timing"] += 1
            for f in result.frames:
                f.ms = f.original_ms / gain
        return result

    monkeypatch.setattr(cached_module, "compare", fake)


def _table_text(prof, rows) -> str:
    from rich.console import Console

    from rrcache.cli.profile import _table

    shown = copy.copy(prof)
    shown.selections = rows
    console = Console(record=True, width=220)
    _table(shown).print(console)  # a TextTable (rrcache.cli.tables), printed as the CLI does
    return console.export_text()


def test_a_validation_5_db_under_the_level_tries_the_next_candidate(trained, tmp_path, monkeypatch, gl_ctx):
    from rrcache.profiler.validate import Validator

    prof, work, session, settings, store = _setup(trained, tmp_path)
    node = prof.trained_nodes[0]
    first, second = _option(node, 8, LEVEL + 0.2, ms=1.0), _option(node, 2, LEVEL + 8.0, ms=1.5)
    _fake(monkeypatch, {8: LEVEL - 5.0, 2: LEVEL + 3.0})
    asked = []

    def candidates(choice):
        asked.append(choice.key)
        return [second]

    with store:
        validator = Validator(work, session, settings, store, candidates=candidates)
        [row] = validator.run([first])
        assert asked == [first.key]
        # the next candidate was measured and stands; what was refused, and why, is kept
        assert row.key == second.key and row.level_met and row.tries == 2
        assert row.measured_psnr == pytest.approx(LEVEL + 3.0)
        assert f"{node.id} ({node.text[:20]}" in row.fallback and f"Δn=8: measured {LEVEL - 5.0:.1f}" in row.fallback
        assert f"below the level {LEVEL:g} dB" in row.fallback and "candidate 2" in row.fallback
        labels = sorted(r.label for r in store.validations())
        assert labels == ["e1", "e1~1"]
        # the calibration learned the 5 dB miss (predicted 40.2, measured 35.0) and the second
        # candidate was chosen with that shift applied (48 − 5.2 = 42.8 ≥ 40 + the margin); its
        # own point (48 against 43) joins the calibration after it
        assert row.calibration_db == pytest.approx(-5.2) and row.predicted_psnr == pytest.approx(LEVEL + 2.8)
        assert validator.calibration.shift(node.id) == pytest.approx(-5.1)
    text = _table_text(prof, [row])
    assert "met, try 2" in text and "↩" in text and f"{LEVEL + 3.0:.1f}" in text


def test_when_every_candidate_misses_the_original_stands(trained, tmp_path, monkeypatch, gl_ctx):
    from rrcache.profiler.validate import Validator, validate

    prof, work, session, settings, store = _setup(trained, tmp_path)
    node = prof.trained_nodes[0]
    first, second = _option(node, 8, LEVEL + 0.2), _option(node, 2, LEVEL + 9.0, ms=1.5)
    _fake(monkeypatch, {8: LEVEL - 5.0, 2: LEVEL - 4.0})
    with store:
        [row] = Validator(work, session, settings, store, candidates=lambda c: [second]).run([first])
        assert not row.parts and row.exact and row.level_met and row.tries == 2
        assert "Δn=8: measured" in row.fallback and "Δn=2: measured" in row.fallback
        assert row.fallback.endswith("so the original shader stands")
        assert "original (2 tried)" in _table_text(prof, [row])
        # told not to fall back, validation ships the miss and marks it
        [kept] = validate(work, session, settings, store, [first], fallback=False)
        assert kept.key == first.key and kept.level_met is False and "below the level" in kept.level_note
        assert "MISSED" in _table_text(prof, [kept])


def test_a_speed_up_within_the_noise_does_not_ship(trained, tmp_path, monkeypatch, gl_ctx):
    """Issue 29's fBm: a 0.98× median (repeats 0.978, 1.041, 0.937) is not a gain."""
    from rrcache.profiler.validate import Validator

    prof, work, session, settings, store = _setup(trained, tmp_path)
    node = prof.trained_nodes[0]
    _fake(monkeypatch, {8: LEVEL + 5.0}, speedups=(0.978, 1.041, 0.937))
    with store:
        [row] = Validator(work, session, settings, store, candidates=lambda c: []).run([_option(node, 8, LEVEL + 6)])
    assert not row.parts and "below the gain worth having" in row.fallback and row.tries == 1


def test_flip_and_the_temporal_error_on_real_frames(trained, tmp_path, gl_ctx):
    """Measured on the real renders of a validation (nothing faked): FLIP is in (0, 1) for a
    cached node at Δn = 8 and 0 where every pixel is recomputed (Δn = 1); the frame-to-frame
    changes differ from the original's only where the cache lags."""
    from rrcache.profiler.validate import validate

    prof, work, session, settings, store = _setup(trained, tmp_path)
    node = prof.trained_nodes[0]
    with store:
        lagging, exact = validate(work, session, settings, store,
                                  [_option(node, 8, 30.0).replace(label="e1"),
                                   _option(node, 1, 90.0).replace(label="e2")], fallback=False)
    assert 0.0 < lagging.measured_flip < 1.0 and lagging.measured_flip_uncertainty is not None
    assert lagging.measured_temporal_psnr is not None and lagging.measured_temporal_psnr < 100.0
    assert lagging.measured_psnr_uncertainty is not None and lagging.measured_psnr_uncertainty >= 0.0
    assert exact.exact and exact.measured_flip == 0.0 and exact.measured_temporal_psnr is None


def test_a_screen_space_shader_is_answered_with_its_files(tmp_path):
    """Every input gets an answer (issue 29 item 7): a shader whose every value is a function of
    gl_FragCoord (The Book of Shaders' clouds) exits 0 with "keep the original" and why, and
    writes profile.json, report.html and the original's manifest; select answers the original."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    from test_cli_profile import _env as _cli_env

    def _env():  # this checkout's rrcache in the child
        return dict(_cli_env(), PYTHONPATH=str(Path(__file__).resolve().parents[1]))

    shader = Path(__file__).parent / "data" / "shaders" / "clouds_fragcoord.frag"
    _, session = write_scene(tmp_path)
    out = tmp_path / "clouds.rrprofile"
    run = subprocess.run([sys.executable, "-m", "rrcache", "profile", str(shader), str(session), "--out", str(out),
                          "--quiet"], capture_output=True, text=True, env=_env(), timeout=300)
    assert run.returncode == 0, run.stderr
    answer = "keep the original shader: every value it computes per pixel depends on the screen position"
    assert answer in run.stdout and "why:" in run.stdout and "gl_FragCoord" in run.stdout
    data = json.loads((out / "profile.json").read_text())
    assert data["verdict"]["choice"] == "original" and data["verdict"]["answer"].startswith(answer)
    assert "screen" in data["verdict"]["reason"] and data["selections"] == []
    report = (out / "report.html").read_text()
    assert answer in report and "what would change it" in report
    assert json.loads((out / "optimized" / "original" / "manifest.json").read_text())["node"] is None
    chosen = subprocess.run([sys.executable, "-m", "rrcache", "select", str(out), "--min-psnr", "40", "--json"],
                            capture_output=True, text=True, env=_env(), timeout=120)
    assert chosen.returncode == 0, chosen.stderr
    assert json.loads(chosen.stdout)["node"] is None


def _measured(node, period, psnr, speedups=(2.0, 2.1, 1.9), flip=0.02):
    return _option(node, period, psnr + 1.0).with_measurement(0.01, psnr, 1.0, 2.0, sorted(speedups)[1], 0.8, 12,
                                                             speedups).replace(
        measured_psnr_uncertainty=0.2, measured_flip=flip, measured_flip_uncertainty=0.001, label="e2")


def test_select_prefers_what_was_measured(trained, tmp_path, monkeypatch):
    """rrcache select answers from validation's measurements where the profile has them, says
    which figures were measured, and warns when the models' choice was measured below the level."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    from rrcache.profiles import load_profile
    from rrcache.profiles.measured import choose

    prof, folder = trained
    prof = load_profile(folder / "out")
    a, b = prof.trained_nodes[:2]
    good, bad = _measured(a, 4, LEVEL + 2.0), _measured(b, 8, LEVEL - 5.0, speedups=(3.0, 3.1, 2.9))
    prof.measured = [good, bad]
    # the models choose b at Δn = 8 (predicted above the level), which validation measured 5 dB under
    model = _option(b, 8, LEVEL + 1.0).replace(predicted_speedup=3.0)
    monkeypatch.setattr(prof, "select_psnr", lambda level: model)
    answer = choose(prof, min_psnr=LEVEL)
    assert answer.source == "measured" and answer.selection.key == good.key
    assert answer.selection.measured_psnr == LEVEL + 2.0 and answer.selection.measured_speedup == 2.0
    assert len(answer.warnings) == 1 and "measured and misses the level" in answer.warnings[0]
    assert f"{LEVEL - 5.0:.1f}" in answer.warnings[0] and good.describe() in answer.warnings[0]
    # a level the measured choices cannot tell about: the models' prediction, said to be one
    monkeypatch.setattr(prof, "select_psnr", lambda level: _option(a, 2, LEVEL + 9.0).replace(predicted_speedup=5.0))
    answer = choose(prof, min_psnr=LEVEL + 8.0)
    assert answer.source == "predicted" and answer.selection.measured_error is None and not answer.warnings
    # FLIP: a measured level only; the measured choice that meets it
    assert choose(prof, max_flip=0.03).selection.key in (good.key, bad.key)
    # through the command: profile.json keeps the measured choices; each figure says which it is
    monkeypatch.undo()
    prof.measured = [good]
    out = tmp_path / "measured.rrprofile"
    prof.write(out)
    env = dict(__import__("os").environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))
    run = subprocess.run([sys.executable, "-m", "rrcache", "select", str(out), "--min-psnr", str(LEVEL), "--json"],
                         capture_output=True, text=True, env=env, timeout=120)
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    assert data["source"] == "measured" and data["node"] == a.id and data["period"] == 4
    assert data["measured_psnr"] == LEVEL + 2.0 and data["measured_flip"] == 0.02
    text = subprocess.run([sys.executable, "-m", "rrcache", "select", str(out), "--min-psnr", str(LEVEL)],
                          capture_output=True, text=True, env=env, timeout=120).stdout
    assert f"measured PSNR {LEVEL + 2.0:.1f} ± 0.2 dB" in text and "measured 2.00×" in text


def test_a_flip_level_is_answered_from_the_measured_choices(trained, tmp_path):
    """rrcache profile --max-flip: the measured choices that meet the FLIP level (and the gain)
    answer it first; a level none meets is asked of the models at the PSNR the measured choices
    relate to it (here: the original)."""
    from rrcache.profiler.validate import Validator, flip_level

    prof, work, session, settings, store = _setup(trained, tmp_path)
    a, b = prof.trained_nodes[:2]
    soft = _measured(a, 4, 44.0, flip=0.012, speedups=(2.0, 2.1, 1.9))
    rough = _measured(b, 8, 35.0, flip=0.045, speedups=(3.0, 3.1, 2.9))
    with store:
        validator = Validator(work, session, settings, store)
        validator.measured = {soft.key: soft, rough.key: rough}
        met = flip_level(prof, validator, 0.03)
        assert met.key == soft.key and met.label == "flip" and met.max_flip == 0.03 and met.level_met
        assert met.min_psnr is None and met.measured_flip == 0.012
        strict = flip_level(prof, validator, 0.001)
        assert not strict.parts and strict.label == "flip" and strict.max_flip == 0.001


def test_the_calibration_borrows_only_a_shift_its_family_agrees_on():
    """The validated points of many_lights' default profile at 7af0467 (docs/levels.md), in the
    order they were measured: a cached node 5.5 dB under its prediction, then an amortized
    estimator 10.6 dB over it. The estimator has no point of its own and is of another family:
    it is predicted by its model alone (the node's shift had put it 16.2 dB off); the second
    cached node borrows the first's; once cached nodes disagree in sign nothing is borrowed."""
    from rrcache.model.calibration import Calibration, prediction_errors, replay

    cal = (Calibration().add("n3839", 71.74, 66.21, "n3839 Δn=50").add("est:e1", 47.98, 58.62, "e1 m=16")
           .add("est:e1", 43.33, 49.02, "e1 m=8").add("n10886", 39.15, 36.53, "n10886 Δn=2"))
    again = [(c, m) for _, c, m in replay(cal)]
    assert again[1] == (47.98, 58.62)  # the estimator: the models alone
    assert again[2][0] == pytest.approx(43.33 + 10.64)  # its own point's shift
    assert again[3][0] == pytest.approx(39.15 - 5.53)  # the cached node's
    assert prediction_errors(again)["worst"] == pytest.approx(10.64)
    disagree = cal.add("n20", 40.0, 42.0)
    assert disagree.shift("n99") == 0.0 and disagree.shift("n20") == pytest.approx(2.0)
    assert cal.add("n3839", 71.74, 66.0, "n3839 Δn=50").points[0].measured == 66.0  # replaced in its place
