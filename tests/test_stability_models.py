"""The model fits on extreme data, one row of docs/stability.md each (issue 7, part 1).

For every case the same four things are checked and recorded: every numeric field is finite,
the parameters are in their documented ranges (α ≥ 0, λ ∈ [1e-4, 20], μ ∈ [0, 1], times ≥ 0), the
quality flag is the one the model's docstring documents for the case, and the same input fitted
twice gives an identical result; the fitted curve predicts no NaN over Δn = 1..50. The exact
parameter values of the simple cases are tested in test_model_error.py and test_model_perf.py;
here the point is the sweep and the table.
"""
from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

from rrcache.model import fit_error, fit_hit_rate, fit_performance
from rrcache.model.error import LAMBDA_MAX, LAMBDA_MIN
from rrcache.model.performance import _PRIORITY as PERF_PRIORITY

P = np.array([2, 10, 18, 26, 34, 42, 50], dtype=float)
ALL_PERIODS = np.arange(1, 51)


def _ids(cases):
    """ASCII test ids from the case names (pytest escapes anything else)."""
    return [re.sub(r"[^a-z0-9]+", "-", c[0].lower()).strip("-") for c in cases]


def _curve(alpha, lam, periods=P):
    return alpha * (1.0 - np.exp(-lam * (np.asarray(periods, float) - 1.0)))


def _noisy(sigma, seed):
    return np.abs(_curve(0.1, 0.1) + np.random.default_rng(seed).normal(0.0, sigma, P.size))


# name, input description, errors, documented quality
ERROR_CASES = [
    ("all zero", "ε = 0 at every Δn", np.zeros(7), "zero"),
    ("constant (step, λ → ∞)", "ε = 0.04 at every Δn", np.full(7, 0.04), "step"),
    ("linear (λ → 0)", "ε = 0.001 (Δn − 1)", 0.001 * (P - 1), "linear"),
    ("decreasing", "ε from 1.0 down to 0.1", np.linspace(1.0, 0.1, 7), "poor"),
    ("non-monotonic", "ε = 0.1 0.5 0.05 0.6 0.02 0.4 0.1", np.array([0.1, 0.5, 0.05, 0.6, 0.02, 0.4, 0.1]), "poor"),
    ("one non-zero point (first)", "ε = 0.3 at Δn = 2, 0 elsewhere", np.r_[0.3, np.zeros(6)], "poor"),
    ("one non-zero point (middle)", "ε = 0.3 at Δn = 26, 0 elsewhere", np.r_[np.zeros(3), 0.3, np.zeros(3)], "poor"),
    ("one non-zero point (last)", "ε = 0.3 at Δn = 50, 0 elsewhere", np.r_[np.zeros(6), 0.3], "poor"),
    ("NaN and ±Inf measurements", "α=0.2, λ=0.1 with NaN, +Inf, −Inf at 3 of 7 periods",
     np.where([0, 1, 0, 1, 0, 1, 0], [np.nan, np.inf, np.nan, -np.inf, np.nan, np.nan, np.nan], _curve(0.2, 0.1)),
     "nonfinite"),
    ("only NaN", "ε = NaN at every Δn", np.full(7, np.nan), "insufficient"),
    ("HDR values", "α = 1e4, λ = 0.1, 1% noise", _curve(1e4, 0.1) * (1 + 0.01 * np.random.default_rng(1).standard_normal(7)), "ok"),
    ("HDR step", "ε = 1e4 at every Δn", np.full(7, 1e4), "step"),
    ("largest doubles", "ε = 1.7e308 at every Δn", np.full(7, 1.7e308), "step"),
    ("subnormal values", "ε = 5e-324 at every Δn", np.full(7, 5e-324), "step"),
    ("heavy noise", "α=0.1, λ=0.1 plus noise σ = 0.1 (the size of the signal)", _noisy(0.1, 0), "poor"),
    ("negative errors", "α=0.2, λ=0.1 with ε(2) = −0.5", np.r_[-0.5, _curve(0.2, 0.1)[1:]], "clipped"),
]


def _finite_fields(fit) -> dict:
    values = {f.name: getattr(fit, f.name) for f in dataclasses.fields(fit)}
    bad = {k: v for k, v in values.items() if isinstance(v, float) and not math.isfinite(v)}
    assert not bad, f"non-finite fields {bad} in {fit}"
    return values


@pytest.mark.parametrize("name,given,errors,quality", ERROR_CASES, ids=_ids(ERROR_CASES))
def test_error_fit_extreme_data(stability_case, name, given, errors, quality):
    case = stability_case(name, area="error model ε̂(Δn) = α(1 − e^{−λ(Δn−1)})", given=given)
    first, second = fit_error(P, errors), fit_error(P, errors)
    case.observe(alpha=first.alpha, lam=first.lam, r2=first.r2, quality=first.quality, flags=first.flags or "-",
                 deterministic=first == second)
    _finite_fields(first)
    assert first == second
    assert first.alpha >= 0.0 and LAMBDA_MIN <= first.lam <= LAMBDA_MAX and first.r2 <= 1.0
    assert not np.any(np.isnan(first.predict(ALL_PERIODS)))
    assert first.quality == quality, first


def test_error_fit_nonfinite_keeps_the_clean_points(stability_case):
    """Dropping the NaN/Inf points leaves the fit of the remaining points unchanged."""
    y = _curve(0.2, 0.1)
    dirty = y.copy()
    dirty[[1, 3, 5]] = [np.nan, np.inf, -np.inf]
    case = stability_case("NaN/Inf dropped, rest fitted", area="error model ε̂(Δn) = α(1 − e^{−λ(Δn−1)})",
                          given="α=0.2, λ=0.1 exact, 3 of 7 points NaN/±Inf")
    f = fit_error(P, dirty)
    case.observe(alpha=f.alpha, lam=f.lam, dropped=f.dropped, quality=f.quality)
    assert f.dropped == 3 and f.alpha == pytest.approx(0.2, rel=1e-4) and f.lam == pytest.approx(0.1, rel=1e-4)


HIT_CASES = [
    ("hit rate 0 (a cut every frame)", "γ = 0 at every Δn", np.zeros(7), "cut_every_frame", 0.0),
    ("hit rate 1 (static scene)", "γ = 1 − 1/Δn exactly", 1.0 - 1.0 / P, "static", 1.0),
    ("hit rate above 1", "γ = 1 at every Δn (more than the model allows)", np.ones(7), "clipped", 1.0),
    ("hit rate with NaN", "γ = 0.8(1 − 1/Δn), NaN at Δn = 2", np.r_[np.nan, 0.8 * (1 - 1 / P[1:])], "nonfinite", 0.8),
    ("hit rate heavy noise", "γ = 0.8(1 − 1/Δn) + noise σ = 0.3, clipped to [0, 1]",
     np.clip(0.8 * (1 - 1 / P) + np.random.default_rng(1).normal(0, 0.3, 7), 0, 1), "poor", None),
    ("hit rate only Δn = 1", "γ = 0.5 at Δn = 1 only", None, "insufficient", 0.0),
]


@pytest.mark.parametrize("name,given,rates,quality,mu", HIT_CASES, ids=_ids(HIT_CASES))
def test_hit_rate_fit_extreme_data(stability_case, name, given, rates, quality, mu):
    case = stability_case(name, area="hit-rate model γ(Δn) = μ(1 − 1/Δn)", given=given)
    periods = P if rates is not None else np.ones(3)
    rates = rates if rates is not None else np.full(3, 0.5)
    first, second = fit_hit_rate(periods, rates), fit_hit_rate(periods, rates)
    case.observe(mu=first.mu, r2=first.r2, quality=first.quality, flags=first.flags or "-",
                 deterministic=first == second)
    _finite_fields(first)
    assert first == second and 0.0 <= first.mu <= 1.0
    assert not np.any(np.isnan(first.predict(ALL_PERIODS)))
    assert first.quality == quality, first
    if mu is not None:
        assert first.mu == pytest.approx(mu, abs=1e-9)


T_HIT, T_MISS, T_OVER = 2e-6, 4e-5, 0.4
_RNG = np.random.default_rng(2)
_COVER = 1e5 * _RNG.uniform(0.5, 1.0, 12)
_GAMMA = 0.9 * (1 - 1 / np.repeat([2.0, 8.0, 50.0], 4))
_H = np.round(_GAMMA * _COVER)
_M = _COVER - _H
_H_FULL = np.round(_GAMMA * 1e5)
_M_FULL = 1e5 - _H_FULL


def _times(h, m):
    return T_OVER + h * T_HIT + m * T_MISS


PERF_CASES = [
    ("well posed", "12 frames, coverage 50–100%, exact times", _H, _M, _times(_H, _M), None, "ok"),
    ("rank-deficient (h + m constant)", "12 frames all covering 1e5 pixels, no overhead measured",
     _H_FULL, _M_FULL, _times(_H_FULL, _M_FULL), None, "rank_deficient"),
    ("rank-deficient, overhead measured", "h + m = 1e5 every frame, overhead_ms = 0.4",
     _H_FULL, _M_FULL, _times(_H_FULL, _M_FULL), T_OVER, "ok"),
    ("collinear coverage", "coverage varies by 1e-5 of itself",
     np.round(_GAMMA * 1e5 * (1 + 1e-5 * _RNG.uniform(-1, 1, 12))),
     1e5 * (1 + 1e-5 * _RNG.uniform(-1, 1, 12)) - np.round(_GAMMA * 1e5), None, None, "collinear"),
    ("h and m proportional", "hit fraction 0.5 in every frame, overhead given",
     0.5 * _COVER, 0.5 * _COVER, _times(0.5 * _COVER, 0.5 * _COVER), T_OVER, "rank_deficient"),
    ("too few frames", "2 frames", _H[:2], _M[:2], _times(_H[:2], _M[:2]), None, "insufficient"),
    ("no frames", "0 frames", [], [], [], None, "insufficient"),
    ("negative overhead solution", "times 0.3 ms below h·t_hit + m·t_miss", _H, _M, _times(_H, _M) - 0.7, None,
     "clamped"),
    ("negative t_miss solution", "t = 1 + 4e-5 h − 1e-6 m", _H, _M, 1.0 + 4e-5 * _H - 1e-6 * _M, None, "clamped"),
    ("no pixel covered (object off-screen)", "h = m = 0 in every frame, t = 0.5 ms",
     np.zeros(12), np.zeros(12), np.full(12, 0.5), None, "rank_deficient"),
    ("NaN/Inf rows", "12 frames, one hit count NaN, one time +Inf",
     np.r_[np.nan, _H[1:]], _M, np.r_[_times(_H, _M)[:-1], np.inf], None, "nonfinite"),
    ("HDR-sized times", "times × 1e4", _H, _M, 1e4 * _times(_H, _M), None, "ok"),
    ("huge pixel counts", "h, m × 1e200", _H * 1e200, _M * 1e200, _times(_H, _M), None, "ok"),
    ("heavy timing noise", "times × (1 + 0.5 N(0, 1)), clipped at 0", _H, _M,
     np.maximum(_times(_H, _M) * (1 + 0.5 * np.random.default_rng(3).standard_normal(12)), 0.0), None, None),
    ("NaN overhead", "overhead_ms = NaN", _H, _M, _times(_H, _M), math.nan, "overhead_ignored"),
]


@pytest.mark.parametrize("name,given,h,m,t,overhead,quality", PERF_CASES, ids=_ids(PERF_CASES))
def test_performance_fit_extreme_data(stability_case, name, given, h, m, t, overhead, quality):
    case = stability_case(name, area="performance model t = h·t_hit + m·t_miss + t_overhead", given=given)
    if t is None:
        t = _times(np.asarray(h), np.asarray(m))
    first = fit_performance(h, m, t, overhead_ms=overhead)
    second = fit_performance(h, m, t, overhead_ms=overhead)
    case.observe(t_hit=first.t_hit, t_miss=first.t_miss, t_overhead=first.t_overhead, rank=first.rank,
                 quality=first.quality, flags=first.flags or "-", deterministic=first == second)
    _finite_fields(first)
    assert first == second
    assert min(first.t_hit, first.t_miss, first.t_overhead) >= 0.0
    assert first.quality in ("ok",) + PERF_PRIORITY
    if quality is not None:
        assert first.quality == quality, first
    if name.startswith("no pixel"):
        # every frame's time is fixed cost; predicting 0 ms would claim the cache is free
        assert first.t_overhead == pytest.approx(0.5) and first.residual_rms == pytest.approx(0.0, abs=1e-12)
    if name.startswith("rank-deficient, overhead"):
        assert first.t_hit == pytest.approx(T_HIT, rel=1e-6) and first.t_miss == pytest.approx(T_MISS, rel=1e-6)
