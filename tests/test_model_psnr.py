"""The PSNR model (rrcache.model.psnr): PSNR̂ = a + b·log10 ε̂ per node, fitted to the node's
training runs, and selection by a least PSNR.

- on the runs of a real profile (the tests' tiny scene) each node's fit leaves under 0.5 dB of
  residual, and leaving one training period out predicts it within 1.5 dB;
- degenerate inputs (no run, one error, capped PSNRs) give the documented fallbacks;
- ``select_min_psnr`` returns the fastest option whose predicted PSNR meets the level, and the
  original when none is faster.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from scene_files import SETTINGS, write_scene

from rrcache.model import ErrorFit, HitRateFit, ModelTable, PerfFit
from rrcache.model.psnr import PSNR_CAP, fit_psnr, psnr_grid, psnr_text, select_min_psnr
from rrcache.profiler import profile
from rrcache.profiles import TrainingSettings


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    folder = tmp_path_factory.mktemp("psnr")
    shader, session = write_scene(folder)
    return profile(shader, session, folder / "out", TrainingSettings(**SETTINGS, validate=False), plots=False)


def test_rule_fits_and_predicts_held_out_training_runs(trained):
    nodes = [n for n in trained.trained_nodes if any(e > 0 for e in n.errors)]
    assert nodes
    for n in nodes:
        fit = fit_psnr(n.errors, n.psnrs)
        assert fit.quality == "ok" and fit.rms < 0.5 and -40 <= fit.b <= -5, (n.id, fit)
        for i in range(len(n.errors)):
            held = fit_psnr(np.delete(n.errors, i), np.delete(n.psnrs, i))
            assert abs(held.predict(n.errors[i]) - n.psnrs[i]) < 1.5, (n.id, i)


def test_fallbacks():
    assert fit_psnr([], []).quality == "no_data" and math.isnan(fit_psnr([], []).predict(0.1))
    one = fit_psnr([0.01], [40.0])
    assert one.quality == "fixed_slope" and one.b == -20.0 and math.isclose(one.predict(0.01), 40.0)
    assert math.isclose(one.predict(0.1), 20.0)
    capped = fit_psnr([0.0, 0.01, 0.02], [PSNR_CAP, 40.0, 35.0])
    assert capped.n == 2 and math.isinf(capped.predict(0.0))
    assert math.isclose(capped.predict(capped.max_error(37.5)), 37.5)
    assert psnr_text(math.inf) == "∞ (exact)" and psnr_text(PSNR_CAP) == "∞ (exact)" and psnr_text(33.33) == "33.3"


def test_select_min_psnr():
    # two nodes: n0 fast and coarse, n1 slower and fine; both faster than the original at Δn > 1
    errors = [ErrorFit(0.1, 0.3, 1.0, 0.0, 7, "ok"), ErrorFit(0.005, 0.3, 1.0, 0.0, 7, "ok")]
    perfs = [PerfFit(1e-6, 1e-4, 0.1, "ok", 3, 0.0), PerfFit(5e-6, 1e-4, 0.1, "ok", 3, 0.0)]
    table = ModelTable.from_fits(["n0", "n1"], errors, perfs, HitRateFit(0.95, 1.0, "ok"), 10000, 2.0)
    fits = [fit_psnr([0.01, 0.1], [40.0, 20.0]), fit_psnr([0.001, 0.005], [50.0, 36.0])]
    grid = psnr_grid(table, fits)
    assert grid.shape == table.E.shape and math.isinf(grid[0, 0])
    low = select_min_psnr(table, fits, 15.0)
    assert low.node == "n0"  # the fastest admits anything at 15 dB
    high = select_min_psnr(table, fits, 37.0)
    assert high.node == "n1" and fits[1].predict(high.predicted_error) >= 37.0
    assert select_min_psnr(table, fits, 200.0).node is None


def test_profile_keeps_frame_spreads_and_widens_the_psnr_uncertainty(trained):
    from rrcache.model.psnr import frame_spread

    nodes = [n for n in trained.trained_nodes if any(e > 0 for e in n.errors)]
    assert nodes
    for n in nodes:
        assert len(n.frame_spreads) == len(n.periods) and all(s >= 0 for s in n.frame_spreads)
    assert any(s > 0 for n in nodes for s in n.frame_spreads)
    for choice in trained.threshold_selections():
        if choice.parts and choice.predicted_error > 0:
            i = [n.id for n in trained.trained_nodes].index(choice.node)
            fit = trained.psnr_fits()[i]
            assert choice.predicted_psnr_uncertainty >= fit.uncertainty
    assert frame_spread([0.0, 0.1, 0.1, 0.1, 0.1]) == 0.0
