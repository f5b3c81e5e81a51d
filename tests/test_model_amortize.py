"""The amortized-sampling models (rrcache.model.amortize) with real nlopt fits: the slots
history's error model against the measured grids kept in docs/ (the figures its docstring cites),
its fit on data it generated, and the options each history offers."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rrcache.model.amortize import (AmortizeModel, AmortizeTimeFit, SlotsErrorFit, error_fit_from_json,
                                    fit_amortized_error, fit_error, fit_slots_error)
from rrcache.selection import slots_fit

GRID = Path(__file__).resolve().parent.parent / "docs" / "amortize_model_grid.json"


def _grid(name):
    errors = json.loads(GRID.read_text())[name]["errors"]
    m = [int(k.split(",")[0]) for k in errors]
    lam = [float(k.split(",")[1]) for k in errors]
    return m, lam, list(errors.values())


@pytest.mark.parametrize("name, total, r2", [("temple_slots", 16, 0.95), ("temple12_slots", 12, 0.91)])
def test_the_slots_form_fits_the_measured_grids_better_than_the_blend_form(name, total, r2):
    m, lam, e = _grid(name)
    slots = fit_slots_error(m, lam, e, total)
    blend = fit_amortized_error(m, lam, e, total)
    assert slots.quality == "ok" and round(slots.r2, 2) == r2  # the module docstring's figures
    assert slots.r2 > blend.r2
    # fitted on λ = 0, 0.6, 0.9 (three blends per m, as the profiler trains), it predicts the rest
    keep = [x in (0.0, 0.6, 0.9) for x in lam]
    part = fit_slots_error([a for a, k in zip(m, keep) if k], [a for a, k in zip(lam, keep) if k],
                           [a for a, k in zip(e, keep) if k], total)
    rest = np.array([not k for k in keep])
    y, p = np.array(e)[rest], part.predict(np.array(m)[rest], np.array(lam)[rest])
    assert 1 - np.sum((y - p) ** 2) / np.sum((y - y.mean()) ** 2) > 0.85


def test_the_slots_fit_recovers_the_coefficients_it_was_made_with():
    true = SlotsErrorFit((3, 4, 6), (0.003, 0.0045, 0.002), 0.0012, 12, 1.0, 0.0, 9, "ok")
    m = [3, 3, 3, 4, 4, 4, 6, 6, 6]
    lam = [0.0, 0.6, 0.85] * 3
    fit = fit_slots_error(m, lam, true.predict(np.array(m), np.array(lam)), 12)
    assert fit.samples == (3, 4, 6) and fit.quality == "ok" and fit.r2 > 0.999
    assert np.allclose(fit.base, true.base, rtol=1e-3) and fit.b == pytest.approx(true.b, rel=1e-3)
    # round trip through the document's record
    assert error_fit_from_json("slots", fit.to_json()) == fit
    assert fit_error("blend", m, lam, list(fit.predict(np.array(m), np.array(lam))), 12).__class__.__name__ \
        == "AmortizeErrorFit"


def test_the_slots_fit_on_too_little_or_nothing():
    assert fit_slots_error([], [], [], 16).quality == "insufficient"
    one = fit_slots_error([4, 8], [0.0, 0.0], [0.002, 0.001], 16)
    assert one.quality == "insufficient" and one.base == pytest.approx((0.002, 0.001))
    zero = fit_slots_error([4, 4], [0.0, 0.6], [0.0, 0.0], 16)
    assert zero.quality == "zero" and zero.predict(4, 0.6) == 0.0
    nan = fit_slots_error([4, 4, 4], [0.0, 0.6, 0.85], [0.002, float("nan"), 0.003], 16)
    assert nan.n == 2 and np.isfinite(nan.b)


def test_each_history_offers_its_own_m():
    time = AmortizeTimeFit(0.5, 1e-5, 0.0, 3, "ok")
    slots = SlotsErrorFit((2, 4, 8), (0.003, 0.002, 0.001), 0.001, 16, 0.9, 0.0, 9, "ok")
    model = AmortizeModel("e1", 16, slots, time, 0.9, 1000.0, history="slots", components=1)
    # m = 2 was (somehow) fitted but 8 sums do not fit a payload: not offered
    assert model.sample_counts() == [4, 8]
    options = model.options(2.0)
    assert {o.parts[0].samples for o in options} == {4, 8}
    assert all(o.parts[0].history == "slots" and slots_fit(16, o.parts[0].samples, 1) is None for o in options)
    # two components: only m = 8 (2 sums of 2)
    assert AmortizeModel("e1", 16, slots, time, 0.9, 1000.0, history="slots", components=2).sample_counts() == [8]
    blend = AmortizeModel("e1", 16, fit_amortized_error([1, 4], [0.0, 0.6], [0.02, 0.01], 16), time, 0.9, 1000.0)
    assert blend.sample_counts() == [1, 2, 4, 8] and {o.parts[0].history for o in blend.options(2.0)} == {"blend"}
