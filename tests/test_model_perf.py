"""The hit-rate model γ(Δn) = μ(1 − 1/Δn), the performance model t = h·t_hit + m·t_miss +
t_overhead (rank deficiency included) and the frame-time prediction (rrcache.model.hitrate,
.performance, .predict)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rrcache.errors import RRCacheError
from rrcache.model import HitRateFit, PerfFit, fit_hit_rate, fit_performance, predict_ms, predict_speedup

PERIODS = np.array([2, 10, 18, 26, 34, 42, 50], dtype=float)
T_HIT, T_MISS, T_OVER = 2e-6, 4e-5, 0.4


def gamma(mu, p):
    return mu * (1 - 1 / np.asarray(p, float))


def frames(coverage, periods, mu=0.9, noise=0.0, seed=0):
    """Timed frames: ``coverage`` pixels each, hit fraction from γ at each period."""
    rng = np.random.default_rng(seed)
    cov = np.asarray(coverage, float)
    g = gamma(mu, periods)
    h = np.round(g * cov)
    m = cov - h
    t = T_OVER + h * T_HIT + m * T_MISS
    return h, m, t * (1 + noise * rng.standard_normal(t.size))


def all_finite(f) -> bool:
    return all(math.isfinite(getattr(f, n)) for n in ("t_hit", "t_miss", "t_overhead", "residual_rms", "cond"))


# ----------------------------------------------------------------------------- hit rate
def test_hit_rate_recovers_mu():
    f = fit_hit_rate(PERIODS, gamma(0.83, PERIODS))
    assert f.quality == "ok" and f.mu == pytest.approx(0.83) and f.r2 == pytest.approx(1.0)
    np.testing.assert_allclose(f.predict(PERIODS), gamma(0.83, PERIODS))
    assert float(f.predict(1)) == 0.0


def test_hit_rate_noisy():
    rng = np.random.default_rng(1)
    p = np.repeat(PERIODS, 20)
    f = fit_hit_rate(p, np.clip(gamma(0.7, p) + 0.02 * rng.standard_normal(p.size), 0, 1))
    assert f.mu == pytest.approx(0.7, abs=0.01) and f.quality == "ok"


def test_hit_rate_static_and_cut_every_frame():
    static = fit_hit_rate(PERIODS, 1 - 1 / PERIODS)
    assert static.quality == "static" and static.mu == pytest.approx(1.0)
    cut = fit_hit_rate(PERIODS, np.zeros(7))
    assert (cut.quality, cut.mu, cut.r2) == ("cut_every_frame", 0.0, 1.0)


def test_hit_rate_nonfinite_clipped_insufficient():
    rates = gamma(0.8, PERIODS)
    rates[1] = np.nan
    f = fit_hit_rate(PERIODS, rates)
    assert f.quality == "nonfinite" and f.dropped == 1 and f.mu == pytest.approx(0.8)
    over = fit_hit_rate([2, 10], [1.5, -0.2])
    assert over.quality == "clipped" and 0.0 <= over.mu <= 1.0
    for p, r in (([], []), ([1, 1], [0.3, 0.4]), ([np.nan], [0.5])):
        f = fit_hit_rate(p, r)
        assert f.quality == "insufficient" and f.mu == 0.0 and math.isfinite(f.r2)


def test_hit_rate_deterministic_and_errors():
    r = gamma(0.6, PERIODS) + 0.01
    assert fit_hit_rate(PERIODS, r) == fit_hit_rate(PERIODS, r)
    with pytest.raises(RRCacheError):
        fit_hit_rate([2, 3], [0.1])
    with pytest.raises(RRCacheError):
        fit_hit_rate(["x"], [0.1])


# ----------------------------------------------------------------------------- performance
def test_performance_recovers_costs_with_varying_coverage():
    rng = np.random.default_rng(2)
    periods = np.repeat([2.0, 8.0, 50.0], 10)
    h, m, t = frames(1e5 * rng.uniform(0.6, 1.0, periods.size), periods)
    f = fit_performance(h, m, t)
    assert f.quality == "ok" and f.rank == 3
    assert f.t_hit == pytest.approx(T_HIT, rel=1e-6)
    assert f.t_miss == pytest.approx(T_MISS, rel=1e-6)
    assert f.t_overhead == pytest.approx(T_OVER, rel=1e-6)


def test_performance_noisy():
    rng = np.random.default_rng(3)
    periods = np.repeat([2.0, 8.0, 50.0], 20)
    h, m, t = frames(1e5 * rng.uniform(0.3, 1.0, periods.size), periods, noise=0.01, seed=4)
    f = fit_performance(h, m, t)
    assert f.quality == "ok"
    assert f.t_miss == pytest.approx(T_MISS, rel=0.05)
    assert f.t_hit == pytest.approx(T_HIT, abs=0.2 * T_MISS)
    assert f.t_overhead == pytest.approx(T_OVER, abs=0.3)


def test_rank_deficient_with_overhead_recovers_costs():
    """h + m constant (the full-screen test scene): the overhead measured separately makes the
    2-unknown system well posed."""
    periods = np.repeat([2.0, 8.0, 50.0], 5)
    h, m, t = frames(np.full(periods.size, 1e5), periods)
    f = fit_performance(h, m, t, overhead_ms=T_OVER)
    assert f.quality == "ok" and f.rank == 2
    assert f.t_hit == pytest.approx(T_HIT, rel=1e-6)
    assert f.t_miss == pytest.approx(T_MISS, rel=1e-6)
    assert f.t_overhead == T_OVER


def test_rank_deficient_without_overhead_predicts_trained_coverage():
    """Without the overhead the solution is the constrained one with t_overhead = 0; its
    predictions at the trained coverage agree with the truth at every hit rate."""
    periods = np.repeat([2.0, 8.0, 50.0], 5)
    h, m, t = frames(np.full(periods.size, 1e5), periods)
    f = fit_performance(h, m, t)
    assert f.quality == "rank_deficient" and f.rank == 2 and f.t_overhead == 0.0
    assert f.t_hit == pytest.approx(T_HIT + T_OVER / 1e5, rel=1e-6)
    assert f.t_miss == pytest.approx(T_MISS + T_OVER / 1e5, rel=1e-6)
    truth = PerfFit(T_HIT, T_MISS, T_OVER, "ok", 3, 0.0)
    np.testing.assert_allclose(predict_ms(f, 0.9, 1e5, np.arange(1, 51)),
                               predict_ms(truth, 0.9, 1e5, np.arange(1, 51)), rtol=1e-9)


def test_collinear_coverage_is_detected():
    """Coverage varying by 1e-5 of itself: numerically full rank but the overhead is not
    determined; it is treated like the rank-deficient case."""
    rng = np.random.default_rng(5)
    periods = np.repeat([2.0, 8.0, 50.0], 5)
    h, m, t = frames(1e5 * (1 + 1e-5 * rng.uniform(-1, 1, periods.size)), periods)
    f = fit_performance(h, m, t)
    assert f.quality == "collinear" and f.cond > 1e3 and f.t_overhead == 0.0
    assert all_finite(f)


def test_noise_makes_overhead_undetermined():
    """Coverage varies by 1% but timings by 3%: the overhead's standard error exceeds a quarter
    frame, so it is not trusted (collinear)."""
    rng = np.random.default_rng(6)
    periods = np.repeat([2.0, 8.0, 50.0], 10)
    h, m, t = frames(1e5 * (1 + 0.01 * rng.uniform(-1, 1, periods.size)), periods, noise=0.03, seed=7)
    f = fit_performance(h, m, t)
    assert f.quality == "collinear" and f.cond < 1e3 and f.t_overhead == 0.0


def test_proportional_hits_and_misses_tie_costs():
    """One hit fraction in every frame: t_hit and t_miss are not separable; they are set equal."""
    cov = np.array([5e4, 8e4, 1e5, 6e4])
    h, m = 0.5 * cov, 0.5 * cov
    t = 0.1 + h * T_HIT + m * T_MISS
    f = fit_performance(h, m, t, overhead_ms=0.1)
    assert f.quality == "rank_deficient" and f.rank == 1
    assert f.t_hit == f.t_miss == pytest.approx((T_HIT + T_MISS) / 2, rel=1e-9)


def test_clamped_when_the_free_solution_is_negative():
    """Data implying a negative overhead: the bound holds it at 0 ("clamped")."""
    rng = np.random.default_rng(8)
    periods = np.repeat([2.0, 8.0, 50.0], 4)
    h, m, _ = frames(1e5 * rng.uniform(0.5, 1.0, periods.size), periods)
    t = h * T_HIT + m * T_MISS - 0.3
    f = fit_performance(h, m, t)
    assert f.quality == "clamped" and f.t_overhead == 0.0
    assert f.t_hit >= 0 and f.t_miss >= 0 and all_finite(f)


def test_too_few_frames():
    f = fit_performance([100, 300], [900, 700], [2.0, 4.0])
    assert f.quality == "insufficient" and f.t_overhead == 0.0
    assert f.t_hit == f.t_miss == pytest.approx(3.0 / 1000)
    g = fit_performance([100], [900], [2.0], overhead_ms=1.0)
    assert g.quality == "insufficient" and g.t_overhead == 1.0 and g.t_hit == pytest.approx(1e-3)
    e = fit_performance([], [], [])
    assert e.quality == "insufficient" and (e.t_hit, e.t_miss, e.t_overhead) == (0.0, 0.0, 0.0)


def test_nonfinite_rows_dropped_and_bad_overhead_ignored():
    rng = np.random.default_rng(9)
    periods = np.repeat([2.0, 8.0, 50.0], 4)
    h, m, t = frames(1e5 * rng.uniform(0.5, 1.0, periods.size), periods)
    h2, t2 = h.copy(), t.copy()
    h2[0], t2[5] = np.nan, -1.0
    f = fit_performance(h2, m, t2)
    assert f.quality == "nonfinite" and f.dropped == 2 and f.n_frames == 10
    assert f.t_miss == pytest.approx(T_MISS, rel=1e-6)
    g = fit_performance(h, m, t, overhead_ms=float("nan"))
    assert g.quality == "overhead_ignored" and g.t_overhead == pytest.approx(T_OVER, rel=1e-6)
    with pytest.raises(RRCacheError):
        fit_performance(h, m, t, overhead_ms="fast")
    with pytest.raises(RRCacheError):
        fit_performance(h, m[:-1], t)


def test_performance_deterministic():
    rng = np.random.default_rng(10)
    periods = np.repeat([2.0, 50.0], 6)
    h, m, t = frames(1e5 * rng.uniform(0.5, 1.0, periods.size), periods, noise=0.02)
    assert fit_performance(h, m, t) == fit_performance(h, m, t)


# ----------------------------------------------------------------------------- prediction
def test_predict_ms_matches_equation_5():
    perf = PerfFit(T_HIT, T_MISS, T_OVER, "ok", 3, 0.0)
    p = np.arange(1, 51)
    g = gamma(0.8, p)
    np.testing.assert_allclose(predict_ms(perf, 0.8, 5e4, p), T_OVER + 5e4 * (g * T_HIT + (1 - g) * T_MISS))
    assert float(predict_ms(perf, 0.8, 5e4, 1)) == pytest.approx(T_OVER + 5e4 * T_MISS)  # all misses
    assert float(predict_ms(perf, 2.0, 5e4, 1e12)) == pytest.approx(T_OVER + 5e4 * T_HIT)  # μ clipped to 1
    with pytest.raises(RRCacheError):
        predict_ms(perf, float("nan"), 5e4, p)
    with pytest.raises(RRCacheError):
        predict_ms(perf, 0.5, -1, p)


def test_predict_speedup():
    np.testing.assert_allclose(predict_speedup(4.0, [2.0, 8.0]), [2.0, 0.5])
    assert float(predict_speedup(1.0, 0.0)) == math.inf


def test_hit_fit_field_names_are_stable():
    """The training loop stores and rebuilds these by field name."""
    assert HitRateFit(0.5, 1.0, "ok").mu == 0.5
    assert PerfFit(1.0, 2.0, 3.0, "ok", 3, 0.0).t_overhead == 3.0
