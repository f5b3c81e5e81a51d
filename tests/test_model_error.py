"""The error model ε̂(Δn) = α(1 − e^{−λ(Δn−1)}) (rrcache.model.error): recovery of known
parameters and every degenerate case with its documented outcome."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rrcache.errors import RRCacheError
from rrcache.model import ErrorFit, fit_error, fit_errors
from rrcache.model.error import LAMBDA_MAX, LAMBDA_MIN

PERIODS = np.array([2, 10, 18, 26, 34, 42, 50], dtype=float)


def curve(alpha, lam, periods=PERIODS):
    return alpha * (1.0 - np.exp(-lam * (np.asarray(periods, float) - 1.0)))


def finite_fit(f: ErrorFit) -> None:
    for name in ("alpha", "lam", "r2", "rmse"):
        assert math.isfinite(getattr(f, name)), (name, f)
    assert f.alpha >= 0 and LAMBDA_MIN <= f.lam <= LAMBDA_MAX and f.r2 <= 1.0 and f.rmse >= 0


@pytest.mark.parametrize("alpha,lam", [(0.2, 0.1), (0.05, 0.5), (3e4, 0.02), (1e-9, 1.5), (0.5, 0.003)])
def test_recovers_noise_free_parameters(alpha, lam):
    f = fit_error(PERIODS, curve(alpha, lam))
    assert f.quality == "ok", f
    assert f.alpha == pytest.approx(alpha, rel=1e-4)
    assert f.lam == pytest.approx(lam, rel=1e-4)
    assert f.r2 == pytest.approx(1.0, abs=1e-9)
    assert f.n_points == 7 and f.dropped == 0


def test_recovers_noisy_parameters():
    rng = np.random.default_rng(7)
    periods = np.repeat(PERIODS, 5)  # five sessions' worth of measurements per period
    y = curve(0.2, 0.12, periods) * (1 + 0.05 * rng.standard_normal(periods.size))
    f = fit_error(periods, y)
    assert f.quality == "ok"
    assert f.alpha == pytest.approx(0.2, rel=0.05)
    assert f.lam == pytest.approx(0.12, rel=0.2)
    assert f.r2 > 0.95


def test_predict_is_zero_at_period_one_and_keeps_shape():
    f = fit_error(PERIODS, curve(0.3, 0.2))
    assert float(f.predict(1)) == 0.0
    assert f.predict(np.arange(1, 51)).shape == (50,)
    assert f.predict(np.ones((2, 3)) * 5).shape == (2, 3)
    assert np.all(np.diff(f.predict(np.arange(1, 51))) >= 0)
    assert float(f.predict(0.5)) == 0.0  # periods below 1 count as 1


def test_scale_invariance():
    y = curve(0.07, 0.3) + np.array([0.001, -0.002, 0.0015, 0.0, -0.001, 0.002, 0.0])
    small, big = fit_error(PERIODS, y), fit_error(PERIODS, y * 1e4)
    assert big.alpha == pytest.approx(small.alpha * 1e4, rel=1e-6)
    assert big.lam == pytest.approx(small.lam, rel=1e-6)
    assert big.r2 == pytest.approx(small.r2, abs=1e-9)


def test_huge_values_stay_finite():
    f = fit_error(PERIODS, np.full(7, 1e308))
    finite_fit(f)
    assert f.alpha == pytest.approx(1e308, rel=1e-6)
    assert f.quality == "step"


def test_all_zero_errors():
    f = fit_error(PERIODS, np.zeros(7))
    assert (f.quality, f.alpha, f.lam, f.r2) == ("zero", 0.0, 1.0, 1.0)
    assert np.all(f.predict(PERIODS) == 0)


def test_step_saturates_at_first_period():
    """Error already at its level at Δn = 2: λ goes to the upper bound ("step")."""
    f = fit_error(PERIODS, np.full(7, 0.04))
    assert f.quality == "step" and f.lam == LAMBDA_MAX
    assert f.alpha == pytest.approx(0.04, rel=1e-6)
    assert f.r2 == pytest.approx(1.0)


def test_linear_data_hits_lower_bound():
    f = fit_error(PERIODS, 0.001 * (PERIODS - 1))
    assert f.quality == "linear" and f.lam == pytest.approx(LAMBDA_MIN, rel=0.02)
    np.testing.assert_allclose(f.predict(PERIODS), 0.001 * (PERIODS - 1), rtol=0.01)


def test_poor_fit_on_non_monotonic_data():
    f = fit_error(PERIODS, [0.1, 0.5, 0.05, 0.6, 0.02, 0.4, 0.1])
    finite_fit(f)
    assert f.quality == "poor" and f.r2 < 0.9


def test_decreasing_data():
    """Errors that fall with Δn do not fit the model: a finite flat fit flagged poor."""
    f = fit_error(PERIODS, [1.0, 0.8, 0.5, 0.4, 0.3, 0.2, 0.1])
    finite_fit(f)
    assert f.quality == "poor"
    assert "step" in f.flags.split(",")
    assert f.alpha == pytest.approx(np.mean([1.0, 0.8, 0.5, 0.4, 0.3, 0.2, 0.1]), rel=1e-3)


def test_nonfinite_points_are_dropped():
    y = curve(0.2, 0.1)
    bad_y = y.copy()
    bad_y[2] = np.nan
    bad_p = PERIODS.copy()
    bad_p[4] = np.inf
    f = fit_error(bad_p, bad_y)
    ref = fit_error(np.delete(PERIODS, [2, 4]), np.delete(y, [2, 4]))
    assert f.quality == "nonfinite" and f.dropped == 2 and f.n_points == 5
    assert f.alpha == pytest.approx(ref.alpha) and f.lam == pytest.approx(ref.lam)
    assert f.alpha == pytest.approx(0.2, rel=1e-4)


def test_periods_below_one_are_dropped():
    f = fit_error([0, -3, 2, 10, 50], [0.5, 0.5] + list(curve(0.2, 0.1, [2, 10, 50])))
    assert f.dropped == 2 and f.quality == "nonfinite"
    assert f.alpha == pytest.approx(0.2, rel=1e-4)


def test_negative_errors_are_clipped():
    y = curve(0.2, 0.1)
    y[0] = -0.5
    f = fit_error(PERIODS, y)
    finite_fit(f)
    assert f.quality == "clipped"
    ref_y = y.copy()
    ref_y[0] = 0.0
    ref = fit_error(PERIODS, ref_y)  # the same data with the negative value taken as 0
    assert (f.alpha, f.lam, f.r2) == (ref.alpha, ref.lam, ref.r2)


def test_insufficient_data():
    empty = fit_error([], [])
    assert (empty.quality, empty.alpha, empty.lam, empty.n_points) == ("insufficient", 0.0, 1.0, 0)
    single = fit_error([10], [0.3])
    assert (single.quality, single.alpha, single.lam) == ("insufficient", 0.3, 1.0)
    only_nan = fit_error([2, 10], [np.nan, np.inf])
    assert only_nan.quality == "insufficient" and only_nan.dropped == 2 and only_nan.alpha == 0.0
    # two points at one period: λ not identifiable; λ = 1 and α by least squares
    same = fit_error([10, 10], [0.2, 0.4])
    assert same.quality == "insufficient" and same.lam == 1.0
    assert same.alpha * (1 - math.exp(-9)) == pytest.approx(0.3)


def test_weights_suppress_an_outlier():
    y = curve(0.2, 0.1)
    y[3] = 5.0
    w = np.ones(7)
    w[3] = 0.0
    f = fit_error(PERIODS, y, weights=w)
    assert f.quality == "ok" and f.n_points == 6
    assert f.alpha == pytest.approx(0.2, rel=1e-4)


def test_deterministic():
    rng = np.random.default_rng(3)
    y = curve(0.1, 0.2) + 0.01 * rng.standard_normal(7)
    assert fit_error(PERIODS, y) == fit_error(PERIODS, y)


def test_fit_errors_many_nodes():
    m = np.stack([curve(0.2, 0.1), np.zeros(7), curve(0.05, 0.8)])
    fits = fit_errors(PERIODS, m)
    assert [f.quality for f in fits] == ["ok", "zero", "ok"]
    assert fits[2].lam == pytest.approx(0.8, rel=1e-4)
    assert len(fit_errors(PERIODS, curve(0.2, 0.1))) == 1


@pytest.mark.parametrize("call", [
    lambda: fit_error([2, 10], [0.1]),
    lambda: fit_error([2, 10], ["a", "b"]),
    lambda: fit_error([[2, 10]], [[0.1, 0.2]]),
    lambda: fit_error([2, 10], [0.1, 0.2], weights=[1.0]),
    lambda: fit_errors([2, 10], np.zeros((3, 4))),
    lambda: ErrorFit(0.1, 0.1, 1.0, 0.0, 2, "ok").predict("x"),
])
def test_bad_shapes_raise_project_errors(call):
    with pytest.raises(RRCacheError):
        call()


def test_fit_uses_nlopt_nelder_mead(monkeypatch):
    """The paper's downhill simplex: the search is nlopt's LN_NELDERMEAD."""
    import nlopt

    used = []
    real = nlopt.opt

    def spy(algorithm, n):
        used.append((algorithm, n))
        return real(algorithm, n)

    monkeypatch.setattr(nlopt, "opt", spy)
    f = fit_error(PERIODS, curve(0.2, 0.1))
    assert used == [(nlopt.LN_NELDERMEAD, 2)] and f.quality == "ok"


def test_short_training_periods():
    """The training loop's small settings (Δn = 2, 4, 8) still recover the curve."""
    f = fit_error([2, 4, 8], curve(0.05, 0.4, [2, 4, 8]))
    assert f.quality == "ok" and f.lam == pytest.approx(0.4, rel=1e-4)
