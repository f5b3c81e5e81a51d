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
        assert f"{first.describe()}: measured {LEVEL - 5.0:.1f}" in row.fallback
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
        assert first.describe() in row.fallback and second.describe() in row.fallback
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
