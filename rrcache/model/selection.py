"""Selection (main paper §4.5): the (node, Δn ≤ 50) predicted fastest within an error threshold.

A :class:`ModelTable` holds the fitted models of N nodes as arrays and precomputes, once, the
predicted error grid E[N, P] (eq. 2) and frame-time grid T[N, P] (eq. 5) over Δn = 1..P
(P = ``max_period``, 50 as in the paper, where the gains of longer periods have flattened out).
:func:`select` is then a masked argmin over those grids — a few tens of microseconds for 200
nodes × 50 periods (:func:`selection_benchmark`), so a threshold slider can re-select at once.
The original shader competes as the option (error 0, ``original_ms``): a node is chosen only
when it is predicted strictly faster than the original. A choice is the record
:class:`rrcache.selection.Selection` (one ``CachedNode(node, period)`` part, or none for the
original), the same record the store, ``profile.json``, the report and the bench carry.

>>> table = synthetic_table(20, seed=1)
>>> choice = select(table, max_error=0.05)
>>> choice.predicted_error <= 0.05 and choice.predicted_ms <= table.original_ms
True
>>> select(table, max_error=0.0).node is None or select(table, 0.0).period == 1
True
"""
from __future__ import annotations

import math
import statistics
import time
from typing import NamedTuple, Optional

import numpy as np

from rrcache.errors import RRCacheError
from rrcache.model.error import _quiet
from rrcache.selection import CachedNode, Selection

#: the paper's clip on the refresh period
MAX_PERIOD = 50
#: ε1 (see :func:`thresholds`): this quantile of the non-zero predicted errors of fast options
LOW_QUANTILE = 0.05
#: ε1 is at most ε_k divided by this
MIN_SPREAD = 10.0


class FrontPoint(NamedTuple):
    """One point of :func:`pareto_front`: a tuple ``(predicted_ms, predicted_error, node,
    period)``; node and period None for the original shader."""

    predicted_ms: float
    predicted_error: float
    node: Optional[str]
    period: Optional[int]


def _scalar(value, name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise RRCacheError(f"{name} must be a number, got {value!r}", "model table") from None
    if not math.isfinite(v):
        raise RRCacheError(f"{name} must be finite, got {v}", "model table",
                           hint="the profile lacks this measurement; run 'rrcache profile' again")
    return v


def _array(values, n: Optional[int], name: str) -> np.ndarray:
    try:
        a = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise RRCacheError(f"{name} must be numbers ({err})", "model table") from None
    if a.ndim != 1 or (n is not None and a.size != n):
        raise RRCacheError(f"{name} must be a vector of {n} values, got shape {a.shape}", "model table")
    return a


class ModelTable:
    """The fitted models of N nodes, with the predicted grids precomputed.

    Arrays (length N): ``alpha``, ``lam`` (error model), ``t_hit``, ``t_miss`` (ms per pixel),
    ``t_overhead`` (ms); scalars ``mu`` (hit rate, clipped to [0, 1]), ``pixels`` (mean covered
    pixels per frame), ``original_ms`` (the original shader's frame time), ``max_period``;
    ``node_ids`` (list). Derived: ``periods`` (1..max_period), ``E`` and ``T`` (N × P: predicted
    error and ms per frame). A node with a non-finite or negative parameter (e.g. a fit missing
    from a profile) is never selected (its E and T rows are +inf). RRCacheError when lengths
    differ or ``mu``, ``pixels``, ``original_ms`` are not finite (``pixels``, ``original_ms`` ≥ 0).

    >>> t = ModelTable(["a"], alpha=[0.1], lam=[0.2], t_hit=[1e-6], t_miss=[1e-4], t_overhead=[0.1],
    ...                mu=0.9, pixels=10000, original_ms=0.9)
    >>> t.E.shape, float(t.E[0, 0]), round(float(t.T[0, 0]), 3)
    ((1, 50), 0.0, 1.1)
    """

    def __init__(self, node_ids, alpha, lam, t_hit, t_miss, t_overhead, mu, pixels, original_ms,
                 max_period: int = MAX_PERIOD):
        self.node_ids = [str(n) for n in node_ids]
        n = len(self.node_ids)
        self.alpha = _array(alpha, n, "alpha")
        self.lam = _array(lam, n, "lam")
        self.t_hit = _array(t_hit, n, "t_hit")
        self.t_miss = _array(t_miss, n, "t_miss")
        self.t_overhead = _array(t_overhead, n, "t_overhead")
        self.mu = min(max(_scalar(mu, "mu"), 0.0), 1.0)
        self.pixels = _scalar(pixels, "pixels")
        self.original_ms = _scalar(original_ms, "original_ms")
        if self.pixels < 0 or self.original_ms < 0:
            raise RRCacheError("pixels and original_ms must be >= 0", "model table")
        try:
            self.max_period = int(max_period)
        except (TypeError, ValueError):
            raise RRCacheError(f"max_period must be a whole number, got {max_period!r}",
                               "model table") from None
        if self.max_period < 1:
            raise RRCacheError(f"max_period must be >= 1, got {max_period}", "model table")
        self.periods = np.arange(1, self.max_period + 1)
        params = np.stack([self.alpha, self.lam, self.t_hit, self.t_miss, self.t_overhead])
        self.valid = np.all(np.isfinite(params) & (params >= 0.0), axis=0)
        p = self.periods[None, :].astype(np.float64)
        # a miss does all a hit does and computes the payload besides: a fit on noisy frames
        # that puts t_miss below t_hit would predict refreshing to be a gain (as predict_ms)
        t_miss = np.maximum(self.t_miss, self.t_hit)
        with np.errstate(all="ignore"):
            err = self.alpha[:, None] * -np.expm1(-self.lam[:, None] * (p - 1.0))
            gamma = self.mu * (1.0 - 1.0 / p)
            ms = self.t_overhead[:, None] + self.pixels * (gamma * self.t_hit[:, None]
                                                           + (1.0 - gamma) * t_miss[:, None])
        ok = self.valid[:, None] & np.isfinite(err) & np.isfinite(ms)
        self.E = np.where(ok, err, np.inf)
        self.T = np.where(ok, ms, np.inf)
        self.E.setflags(write=False)
        self.T.setflags(write=False)
        # flat views for selection: options not faster than the original are +inf from the start,
        # and so is Δn = 1: refreshed every frame, the cache recomputes every pixel and adds its
        # own passes, so it is never faster than the original, whatever a fit predicts
        self._e_flat = self.E.ravel()
        fast = np.where(self.T < self.original_ms, self.T, np.inf)
        fast[:, 0] = np.inf
        self._t_fast = fast.ravel()

    @classmethod
    def from_fits(cls, node_ids, error_fits, perf_fits, hit_fit, pixels, original_ms,
                  max_period: int = MAX_PERIOD) -> "ModelTable":
        """Build from per-node :class:`ErrorFit` and :class:`PerfFit` lists (same order as
        ``node_ids``; None entries make the node unselectable), a :class:`HitRateFit` (or a
        plain μ), ``pixels`` and ``original_ms``.

        >>> from rrcache.model import ErrorFit, PerfFit, HitRateFit
        >>> t = ModelTable.from_fits(["n1"], [ErrorFit(0.1, 0.2, 1.0, 0.0, 7, "ok")],
        ...                          [PerfFit(1e-6, 1e-4, 0.1, "ok", 3, 0.0)], HitRateFit(0.9, 1.0, "ok"),
        ...                          pixels=10000, original_ms=0.9)
        >>> select(t, 0.1).node
        'n1'
        """
        ids = list(node_ids)
        ef, pf = list(error_fits), list(perf_fits)
        if not (len(ids) == len(ef) == len(pf)):
            raise RRCacheError(f"{len(ids)} node ids, {len(ef)} error fits and {len(pf)} "
                               "performance fits",
                               "model table", hint="give one fit of each kind per node")
        nan = float("nan")

        def get(fit, name):
            v = getattr(fit, name, nan) if fit is not None else nan
            return nan if v is None else v

        mu = getattr(hit_fit, "mu", hit_fit)
        if mu is None:
            raise RRCacheError("no hit-rate fit", "model table", hint="train at least one node")
        return cls(ids, [get(f, "alpha") for f in ef], [get(f, "lam") for f in ef],
                   [get(f, "t_hit") for f in pf], [get(f, "t_miss") for f in pf],
                   [get(f, "t_overhead") for f in pf], mu, pixels, original_ms, max_period)

    def __len__(self) -> int:
        return len(self.node_ids)

    def __repr__(self) -> str:
        return (f"ModelTable({len(self)} nodes, periods 1..{self.max_period}, mu={self.mu:.3f}, "
                f"pixels={self.pixels:.0f}, original_ms={self.original_ms:.4g})")

    def option(self, index: int) -> Selection:
        """The :class:`Selection` of flat grid index ``index`` (node-major, then period)."""
        i, j = divmod(int(index), self.max_period)
        ms = float(self.T[i, j])
        return Selection((CachedNode(self.node_ids[i], int(self.periods[j])),), float(self.E[i, j]), ms,
                         self.original_ms / ms if ms > 0 else math.inf)

    def original(self) -> Selection:
        """The original shader as a :class:`Selection` (error 0, speed-up 1)."""
        return Selection.original(self.original_ms)


def select(table: ModelTable, max_error: float) -> Selection:
    """The option with the least predicted time whose predicted error is ≤ ``max_error``, or the
    original shader (``node=None``) when no admissible option is predicted strictly faster than
    it. Ties go to the first node in table order, then the shorter period. RRCacheError for a
    NaN or non-numeric threshold; a negative one admits nothing.

    >>> t = synthetic_table(5, seed=0)
    >>> fastest = select(t, float("inf"))
    >>> fastest.predicted_ms == float(t.T.min()) or fastest.node is None
    True
    """
    try:
        level = float(max_error)
    except (TypeError, ValueError):
        raise RRCacheError(f"{max_error!r} is not an error threshold", "max_error") from None
    if math.isnan(level):
        raise RRCacheError("the error threshold is NaN", "max_error", hint="give a number >= 0")
    if table._t_fast.size == 0:
        return table.original()
    cand = np.where(table._e_flat <= level, table._t_fast, np.inf)
    idx = int(np.argmin(cand))
    if not math.isfinite(cand[idx]):
        return table.original()
    return table.option(idx)


@_quiet
def pareto_front(table: ModelTable) -> list[FrontPoint]:
    """The lower-left frontier of every (predicted ms, predicted error) point, the original shader
    (original_ms, 0) included: sorted by time, each point strictly lower in error than every
    faster one. Items are :class:`FrontPoint` tuples ``(ms, error, node, period)``.

    >>> front = pareto_front(synthetic_table(30, seed=2))
    >>> all(a.predicted_ms <= b.predicted_ms and a.predicted_error > b.predicted_error
    ...     for a, b in zip(front, front[1:]))
    True
    """
    ms = np.append(table.T.ravel(), table.original_ms)
    err = np.append(table.E.ravel(), 0.0)
    finite = np.flatnonzero(np.isfinite(ms) & np.isfinite(err))
    order = finite[np.lexsort((err[finite], ms[finite]))]
    e_sorted = err[order]
    best_before = np.concatenate([[np.inf], np.minimum.accumulate(e_sorted)[:-1]])
    keep = order[e_sorted < best_before]
    last = ms.size - 1
    out = []
    for k in keep:
        if k == last:
            out.append(FrontPoint(float(table.original_ms), 0.0, None, None))
        else:
            i, j = divmod(int(k), table.max_period)
            out.append(FrontPoint(float(ms[k]), float(err[k]), table.node_ids[i], int(table.periods[j])))
    return out


@_quiet
def thresholds(table: ModelTable, k: int = 4) -> np.ndarray:
    """``k`` ascending error thresholds spread like the paper's ε1…ε4 (Fig. 7–9).

    Rule: among the options predicted faster than the original, ε_k is the predicted error of
    the fastest option — the level from which it becomes admissible (in the paper the final
    colour, cached at a long period); every larger threshold would select the same. ε1 is the
    5% quantile of their non-zero predicted errors ("nearly invisible"), but at most ε_k/10 so
    that the thresholds span at least a decade; those in between are spaced geometrically. When
    the fastest option has error 0 (Δn = 1), ε_k is the largest non-zero error of the fast
    options instead. When no option is faster than the original, the same is done over every
    option with ε_k the largest predicted error; when every predicted error is 0, all
    thresholds are 0.

    >>> th = thresholds(synthetic_table(50, seed=3))
    >>> len(th), bool(np.all(np.diff(th) > 0))
    (4, True)
    """
    try:
        k = int(k)
    except (TypeError, ValueError):
        raise RRCacheError(f"k must be a whole number, got {k!r}", "thresholds") from None
    if k < 1:
        raise RRCacheError(f"k must be >= 1, got {k}", "thresholds")
    e, t = table.E.ravel(), table._t_fast
    fast = np.isfinite(e) & np.isfinite(t)
    pool = e[fast & (e > 0)]
    if pool.size:
        fastest = int(np.argmin(np.where(fast, t, np.inf)))
        top = float(e[fastest])
    else:
        pool = e[np.isfinite(e) & (e > 0)]
        if not pool.size:
            return np.zeros(k)
        top = float(pool.max())
    if top <= 0.0:  # the fastest option is exact (Δn = 1): spread over the errors there are
        top = float(pool.max())
    low = min(float(np.quantile(pool, LOW_QUANTILE)), top / MIN_SPREAD)
    if k == 1 or not low > 0.0:  # (ε_k/10 underflows only for subnormal errors)
        return np.full(k, top)
    out = np.geomspace(low, top, k)
    out[-1] = top  # exactly the fastest option's error, so that it is admissible there
    return out


def synthetic_table(n_nodes: int = 200, seed: int = 0, max_period: int = MAX_PERIOD) -> ModelTable:
    """A random but plausible :class:`ModelTable` (for benchmarks, tests and examples): α in
    [1e-3, 0.3] (log-uniform), λ in [0.01, 2], t_miss in [1, 1.5]× the original per-pixel cost
    (a miss computes everything and fills the cache: Δn = 1 is never faster), t_hit in
    [0.05, 0.9]× it, overhead 0.1 ms, μ = 0.9, 1e5 pixels, original 4 ms.

    >>> len(synthetic_table(7))
    7
    """
    rng = np.random.default_rng(seed)
    pixels, original_ms = 1e5, 4.0
    per_px = (original_ms - 0.1) / pixels
    return ModelTable([f"n{i}" for i in range(n_nodes)],
                      alpha=10 ** rng.uniform(-3, math.log10(0.3), n_nodes),
                      lam=rng.uniform(0.01, 2.0, n_nodes),
                      t_hit=per_px * rng.uniform(0.05, 0.9, n_nodes),
                      t_miss=per_px * rng.uniform(1.0, 1.5, n_nodes),
                      t_overhead=np.full(n_nodes, 0.1), mu=0.9, pixels=pixels, original_ms=original_ms,
                      max_period=max_period)


def selection_benchmark(n_nodes: int = 200, repeats: int = 200, seed: int = 0) -> float:
    """Median seconds of one :func:`select` call on a :func:`synthetic_table` of ``n_nodes`` ×
    50 periods, over ``repeats`` thresholds spread log-uniformly over the table's errors.

    >>> selection_benchmark(20, repeats=5) > 0
    True
    """
    table = synthetic_table(n_nodes, seed)
    rng = np.random.default_rng(seed + 1)
    levels = 10 ** rng.uniform(-4, 0, max(int(repeats), 1))
    times = []
    for level in levels:
        start = time.perf_counter()
        select(table, float(level))
        times.append(time.perf_counter() - start)
    return float(statistics.median(times))
