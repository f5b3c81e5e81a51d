"""Selection over the model grids (rrcache.model.selection): against a brute-force loop, the
original shader when nothing beats it, monotonic in the threshold, the Pareto front and the
e1..e4 thresholds."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rrcache.errors import RRCacheError
from rrcache.model import (ErrorFit, HitRateFit, ModelTable, PerfFit, pareto_front, predict_ms, select,
                           selection_benchmark, synthetic_table, thresholds)


def brute_force(table: ModelTable, max_error: float):
    """The paper's rule written as a plain loop over nodes and periods, from the raw parameters;
    Δn = 1 (every pixel refreshed every frame) is never a gain and never chosen."""
    best = (table.original_ms, None, None)
    for i, node in enumerate(table.node_ids):
        a, lam = table.alpha[i], table.lam[i]
        perf = PerfFit(table.t_hit[i], table.t_miss[i], table.t_overhead[i], "ok", 3, 0.0)
        for p in range(2, table.max_period + 1):
            err = a * (1 - math.exp(-lam * (p - 1)))
            ms = float(predict_ms(perf, table.mu, table.pixels, p))
            if err <= max_error and ms < best[0]:
                best = (ms, node, p)
    return best


def random_table(seed: int, n: int = 40) -> ModelTable:
    rng = np.random.default_rng(seed)
    px = 1e5
    return ModelTable([f"n{i}" for i in range(n)], alpha=10 ** rng.uniform(-3, 0, n), lam=rng.uniform(0.005, 3, n),
                      t_hit=rng.uniform(0, 3e-5, n), t_miss=rng.uniform(1e-5, 8e-5, n),
                      t_overhead=rng.uniform(0, 0.5, n), mu=rng.uniform(0.3, 1.0), pixels=px,
                      original_ms=float(rng.uniform(1.5, 5.0)))


@pytest.mark.parametrize("seed", range(8))
def test_select_matches_brute_force(seed):
    table = random_table(seed)
    for level in [0.0, 1e-4, 1e-3, 0.01, 0.05, 0.2, 1.0, math.inf]:
        got = select(table, level)
        ms, node, period = brute_force(table, level)
        assert (got.node, got.period) == (node, period), level
        assert got.predicted_ms == pytest.approx(ms, rel=1e-12)
        assert got.predicted_error <= level
        assert got.predicted_speedup == pytest.approx(table.original_ms / ms)


def test_original_when_nothing_is_faster():
    n = 10
    table = ModelTable([f"n{i}" for i in range(n)], alpha=np.full(n, 0.1), lam=np.full(n, 0.2),
                       t_hit=np.full(n, 5e-5), t_miss=np.full(n, 6e-5), t_overhead=np.full(n, 0.1),
                       mu=0.9, pixels=1e5, original_ms=4.0)  # best case 0.1 + 1e5·5.1e-5 > 4
    for level in (0.0, 0.05, math.inf):
        c = select(table, level)
        assert (c.node, c.period, c.predicted_error, c.predicted_ms, c.predicted_speedup) == (None, None, 0.0, 4.0, 1.0)


def test_original_for_a_negative_threshold_and_an_empty_table():
    assert select(synthetic_table(10), -1.0).node is None
    empty = ModelTable([], [], [], [], [], [], mu=0.9, pixels=1e5, original_ms=3.0)
    assert select(empty, 1.0).node is None and pareto_front(empty)[0].node is None
    assert list(thresholds(empty)) == [0.0] * 4


@pytest.mark.parametrize("seed", range(4))
def test_monotonic_in_threshold(seed):
    table = random_table(seed + 100, n=60)
    levels = np.concatenate([[0.0], np.geomspace(1e-5, 2.0, 80), [math.inf]])
    times = [select(table, float(lv)).predicted_ms for lv in levels]
    assert all(b <= a for a, b in zip(times, times[1:]))


def test_unusable_nodes_are_never_selected():
    table = synthetic_table(20, seed=4)
    fast = select(table, math.inf).node
    idx = table.node_ids.index(fast)
    lam = table.lam.copy()
    lam[idx] = np.nan  # e.g. a fit read back from a profile as null
    broken = ModelTable(table.node_ids, table.alpha, lam, table.t_hit, table.t_miss, table.t_overhead,
                        table.mu, table.pixels, table.original_ms)
    assert select(broken, math.inf).node != fast
    assert not broken.valid[idx] and np.all(np.isinf(broken.T[idx]))


def test_from_fits_and_none_entries():
    e = [ErrorFit(0.1, 0.2, 1.0, 0.0, 7, "ok"), None]
    p = [PerfFit(1e-6, 1e-4, 0.1, "ok", 3, 0.0), PerfFit(0.0, 0.0, 0.0, "ok", 3, 0.0)]
    t = ModelTable.from_fits(["a", "b"], e, p, HitRateFit(0.9, 1.0, "ok"), pixels=1e4, original_ms=0.9)
    assert select(t, math.inf).node == "a"  # b would be free but has no error model
    assert ModelTable.from_fits(["a"], e[:1], p[:1], 0.9, 1e4, 0.9).mu == 0.9
    with pytest.raises(RRCacheError):
        ModelTable.from_fits(["a", "b"], e, p[:1], 0.9, 1e4, 0.9)


@pytest.mark.parametrize("kwargs", [
    {"original_ms": float("nan")}, {"pixels": float("inf")}, {"mu": None}, {"pixels": -1.0},
    {"max_period": 0}, {"alpha": [0.1, 0.2]},
])
def test_bad_tables_raise_project_errors(kwargs):
    args = dict(node_ids=["a"], alpha=[0.1], lam=[0.1], t_hit=[1e-6], t_miss=[1e-5], t_overhead=[0.1],
                mu=0.9, pixels=1e5, original_ms=2.0)
    args.update(kwargs)
    with pytest.raises(RRCacheError):
        ModelTable(**args)


def test_bad_thresholds_raise_project_errors():
    table = synthetic_table(5)
    for bad in (float("nan"), "tight", None):
        with pytest.raises(RRCacheError):
            select(table, bad)
    with pytest.raises(RRCacheError):
        thresholds(table, 0)


@pytest.mark.parametrize("seed", range(4))
def test_pareto_front_against_brute_force(seed):
    table = random_table(seed + 200, n=15)
    front = pareto_front(table)
    points = [(float(table.T[i, j]), float(table.E[i, j]), table.node_ids[i], j + 1)
              for i in range(len(table)) for j in range(table.max_period)] + [(table.original_ms, 0.0, None, None)]

    def dominated(pt):
        return any((q[0] <= pt[0] and q[1] <= pt[1]) and (q[0] < pt[0] or q[1] < pt[1]) for q in points)

    expected = {(p[2], p[3]) for p in points if not dominated(p)}
    assert {(f.node, f.period) for f in front} == expected
    assert all(a.predicted_ms <= b.predicted_ms and a.predicted_error > b.predicted_error
               for a, b in zip(front, front[1:]))
    assert front[-1].predicted_error == 0.0  # the original or a Δn = 1 option ends it
    assert front[0] == (front[0].predicted_ms, front[0].predicted_error, front[0].node, front[0].period)


@pytest.mark.parametrize("seed", range(4))
def test_thresholds_span_invisible_to_fastest(seed):
    table = random_table(seed + 300)
    th = thresholds(table, 4)
    assert th.shape == (4,) and np.all(np.diff(th) > 0) and th[0] > 0
    ratios = th[1:] / th[:-1]
    np.testing.assert_allclose(ratios, ratios[0])  # geometric spacing
    fastest = select(table, math.inf)
    assert select(table, th[-1]).predicted_ms == fastest.predicted_ms
    choices = [select(table, float(x)) for x in th]
    assert all(b.predicted_ms <= a.predicted_ms for a, b in zip(choices, choices[1:]))
    assert len(thresholds(table, 1)) == 1 and thresholds(table, 1)[0] == th[-1]


def test_benchmark_returns_a_number():
    s = selection_benchmark(n_nodes=50, repeats=10)
    assert math.isfinite(s) and s > 0
