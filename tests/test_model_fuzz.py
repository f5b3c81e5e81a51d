"""Hypothesis fuzzing of the three fits with random data including NaN, ±Inf, huge, tiny and
negative values: they never raise, never return NaN (every numeric field finite), stay within
their documented ranges and are deterministic. 200 examples per fit (plus 100 for the table
built from fuzzed fits); the whole file runs in a few seconds."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rrcache.model import ModelTable, fit_error, fit_hit_rate, fit_performance, select, thresholds

SPECIAL = [0.0, -0.0, 1.0, -1.0, math.nan, math.inf, -math.inf, 1e308, -1e308, 1e-300, 5e-324, 1e4, -1e4]
number = st.one_of(st.floats(), st.floats(0.0, 1.0), st.floats(-1e6, 1e6), st.sampled_from(SPECIAL))
period = st.one_of(st.integers(1, 60).map(float), st.floats(), st.sampled_from(SPECIAL))
FUZZ = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)

ERROR_QUALITIES = {"ok", "zero", "step", "linear", "poor", "nonfinite", "insufficient", "clipped"}
HIT_QUALITIES = {"ok", "static", "cut_every_frame", "poor", "nonfinite", "insufficient", "clipped"}
PERF_QUALITIES = {"ok", "insufficient", "nonfinite", "rank_deficient", "collinear", "clamped", "overhead_ignored"}


def assert_finite(fit) -> None:
    for f in dataclasses.fields(fit):
        v = getattr(fit, f.name)
        if isinstance(v, (int, float)):
            assert math.isfinite(v), (f.name, fit)


@st.composite
def paired(draw, first=period, second=number, min_size=0, max_size=12):
    n = draw(st.integers(min_size, max_size))
    return draw(st.lists(first, min_size=n, max_size=n)), draw(st.lists(second, min_size=n, max_size=n))


@FUZZ
@given(paired(), st.booleans())
def test_fit_error_never_raises_nor_returns_nan(data, weighted):
    periods, errors = data
    weights = [abs(e) if math.isfinite(e) else 1.0 for e in errors] if weighted else None
    f = fit_error(periods, errors, weights)
    assert_finite(f)
    assert f.quality in ERROR_QUALITIES and f.alpha >= 0 and 1e-4 <= f.lam <= 20 and f.r2 <= 1.0
    assert f == fit_error(periods, errors, weights)
    with np.errstate(over="ignore"):
        assert not np.any(np.isnan(f.predict(np.arange(1, 51))))


@FUZZ
@given(paired())
def test_fit_hit_rate_never_raises_nor_returns_nan(data):
    periods, rates = data
    f = fit_hit_rate(periods, rates)
    assert_finite(f)
    assert f.quality in HIT_QUALITIES and 0.0 <= f.mu <= 1.0 and f.r2 <= 1.0
    assert f == fit_hit_rate(periods, rates)


@st.composite
def timed_frames(draw):
    n = draw(st.integers(0, 12))
    count = st.one_of(st.integers(0, 10**6).map(float), number)
    h = draw(st.lists(count, min_size=n, max_size=n))
    m = draw(st.lists(count, min_size=n, max_size=n))
    t = draw(st.lists(number, min_size=n, max_size=n))
    overhead = draw(st.one_of(st.none(), number))
    return h, m, t, overhead


@FUZZ
@given(timed_frames())
def test_fit_performance_never_raises_nor_returns_nan(data):
    h, m, t, overhead = data
    f = fit_performance(h, m, t, overhead_ms=overhead)
    assert_finite(f)
    assert f.quality in PERF_QUALITIES and min(f.t_hit, f.t_miss, f.t_overhead) >= 0
    assert f == fit_performance(h, m, t, overhead_ms=overhead)


@settings(max_examples=100, deadline=None, derandomize=True)
@given(paired(min_size=1, max_size=8), timed_frames(), st.floats(0.0, 1.0), number)
def test_table_from_fuzzed_fits_selects_without_error(err_data, perf_data, mu, level):
    ef = fit_error(*err_data)
    pf = fit_performance(perf_data[0], perf_data[1], perf_data[2], overhead_ms=perf_data[3])
    with np.errstate(over="ignore"):
        table = ModelTable(["a"], [ef.alpha], [ef.lam], [pf.t_hit], [pf.t_miss], [pf.t_overhead],
                           mu=mu, pixels=1e5, original_ms=3.0)
    if math.isnan(level):
        return
    c = select(table, level)
    assert c.node is None or (c.predicted_error <= level and c.predicted_ms < 3.0)
    assert np.all(np.isfinite(thresholds(table)))
