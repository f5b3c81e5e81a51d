"""Sets of k ≥ 2 cached nodes, each at its own period: their error and time predicted from the
single-node models, the search over the sets built from the single-node Pareto front, and the
choice between a trained set and the single-node choice (pure numpy; the measuring stage is
:mod:`rrcache.profiler.sets`).

**The combination rule.** Per node j of a set S at period Δn_j, from its single-node models
(:class:`~rrcache.model.selection.ModelTable`: ε̂_j, T_j = t_o + M(t_miss_j − γ_j c_j), with
γ_j = μ(1 − 1/Δn_j) and c_j = t_miss_j − t_hit_j, the per-pixel cost a hit saves):

- **time**: ``T_S = T_0 + Σ_j (T_j − T_0) + M Σ_{I feeds O} γ_O · min(c_I, c_O)``. Each node adds
  its own single-node difference from the original ``T_0``: what its hits save *and* its own
  passes and overhead (a single node's frame carries the whole cached pipeline, so the sum
  counts every node's passes; never below the pipeline's fixed cost t_o). Last round's rule
  ``h_O t_O^hit + (1 − h_O) t_I`` left out the second node's two passes and predicted 3.42× for
  a pair measured at 2.00×. When node I feeds node O (inside O's expression, or read by O
  through a variable), O's single-node saving
  already holds I's computation where O hits, so it is taken back once, for I's nearest outer
  node in the set. With the **union layout** (two-pass, one-pass, or three-pass for a shader
  that discards or a node that needs derivatives) llvmpipe's lock-step branches compute every
  node wherever any node misses: every γ_j in the sums is replaced by
  ``γ_U = Π_j γ_j``, the share of pixels where every node hits (independent refresh phases).
- **error**: ``ε_S = Σ_j ε̂_j(Δn_j)``: each node's staleness reaches the colour at most as it does
  alone (a bound when the single models are right; measured 0.81–1.21 of it over eleven Marble
  and Trashcan sets, above it where the single-node models under-predict short periods,
  docs/multinode.md).
- **PSNR**: the PSNR model of the node with the largest error share, at ``ε_S``.

**The search** (:func:`search`): the nodes on or near the single-node Pareto front (within
:data:`NEAR_FRONT` of its time at their error; at most :data:`MAX_FRONT_NODES`); every pair of
them at every period pair Δn ∈ 2..P; a pair *improves* the front where it is predicted at least
``min_gain`` (:data:`MIN_SET_GAIN`; the profiler passes ``−TRAIN_MARGIN``) faster than every
single option (and the original) of no larger error, and faster than the original. Triples only where it pays: the improving
pairs (the :data:`MAX_EXTEND` best) extended by a third such node at each period, kept where they
improve on singles and pairs alike. :func:`pick` chooses the few to train: per level the fastest
admissible set, when predicted faster than the level's single-node choice (by ``min_gain``),
then the best remaining by gain.

>>> import numpy as np
>>> from rrcache.model import ModelTable
>>> t = ModelTable(["a", "b"], alpha=[0.01, 0.01], lam=[0.5, 0.5], t_hit=[0.4, 0.4], t_miss=[1.2, 1.2],
...                t_overhead=[0.1, 0.1], mu=0.9, pixels=1.0, original_ms=1.0)
>>> err, ms = set_prediction(t, [0, 1], [10, 10], feeds=None, layout="per-node")
>>> round(err, 4), round(ms, 3)   # both disjoint: each saves what it saves alone
(0.0198, 0.304)
>>> round(set_prediction(t, [0, 1], [10, 10], feeds={(1, 0)}, layout="per-node")[1], 3)  # b inside a
0.952
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Iterable, Optional

import numpy as np

from rrcache.selection import CachedNode, Selection

#: a set *improves* the front when predicted at least this much faster (as a share of the time)
#: than every single option of no larger error
MIN_SET_GAIN = 0.03
#: the profiler trains a set predicted within this share of the front (``pick``'s and the
#: stage's margin): the time rule measured from 4% optimistic to 2.2× pessimistic over the
#: eleven Marble and Trashcan sets of docs/multinode.md, so a set just behind the predicted
#: front may well be on it
TRAIN_MARGIN = 0.25
#: the distinct nodes of the single-node front a search pairs, fastest first
MAX_FRONT_NODES = 8
#: a node whose best option is within this share of the single-node front's time is paired too
#: (as :data:`TRAIN_MARGIN`: the single-node models' own error reaches the sets)
NEAR_FRONT = 0.25
#: the sets a search keeps (spread over the front with the sets, plus each node set's best)
MAX_OPTIONS = 48
#: the improving pairs a third node is tried with
MAX_EXTEND = 24
#: the sets the profiler trains by default (``rrcache profile --sets N``)
DEFAULT_MAX_SETS = 3
LAYOUTS = ("per-node", "union")


def _rng(minimum=None, maximum=None, default=None, factory=None):
    meta = {"minimum": minimum, "maximum": maximum}
    if factory is not None:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


@dataclass
class SetOption:
    """One set of cached nodes, each at its own period, as ``profile.json`` keeps it (``sets``):
    ``nodes`` and ``periods`` (in the order the variant is compiled), the ``layout`` the
    prediction assumed, the predicted ``predicted_error``, ``predicted_ms``, ``predicted_psnr``
    and ``gain`` (the time of the best single option of no larger error over this set's); when
    ``trained``, what the training measured: ``trained_error`` and ``trained_psnr`` (the
    training frames in the error window, as the single nodes' error runs), ``trained_ms`` (the
    timing frames beside the original, as a share of the original scaled to the profile's
    original time), ``trained_hit_rates`` (per node), ``trained_s``; ``note`` says why a picked
    set was not trained (a nest the compiler refuses, the budget)."""

    nodes: list[str]
    periods: list[int] = _rng(minimum=1, factory=list)
    layout: str = "per-node"
    predicted_error: float = _rng(minimum=0, default=0.0)
    predicted_ms: float = _rng(minimum=0, default=0.0)
    predicted_psnr: Optional[float] = None
    gain: float = _rng(minimum=0, default=1.0)
    trained: bool = False
    trained_error: Optional[float] = _rng(minimum=0)
    trained_psnr: Optional[float] = None
    trained_ms: Optional[float] = _rng(minimum=0)
    trained_hit_rates: list[float] = _rng(minimum=0, maximum=1, factory=list)
    trained_s: Optional[float] = _rng(minimum=0)
    note: Optional[str] = None

    @property
    def key(self) -> tuple:
        return tuple((CachedNode.KIND, n, int(p)) for n, p in zip(self.nodes, self.periods))

    def describe(self) -> str:
        return " + ".join(f"{n} Δn={p}" for n, p in zip(self.nodes, self.periods))

    def to_json(self) -> dict:
        return {f: getattr(self, f) for f in self.__dataclass_fields__}

    @classmethod
    def from_json(cls, data: dict) -> "SetOption":
        return cls(**{k: v for k, v in data.items() if k in cls.__dataclass_fields__})

    def selection(self, original_ms: float, **changes) -> Selection:
        """The :class:`~rrcache.selection.Selection` of this set, with the trained figures as its
        predictions (the predicted ones when not trained)."""
        from rrcache.model.psnr import VISIBLE_DB

        err = self.trained_error if self.trained else self.predicted_error
        ms = self.trained_ms if self.trained else self.predicted_ms
        psnr = self.trained_psnr if self.trained else self.predicted_psnr
        parts = tuple(CachedNode(n, int(p)) for n, p in zip(self.nodes, self.periods))
        speedup = original_ms / ms if ms and ms > 0 else math.inf
        return Selection(parts, float(err), float(ms), float(speedup), predicted_psnr=psnr,
                         predicted_psnr_uncertainty=None, exact=False,
                         visible_artifacts=bool(psnr is not None and psnr < VISIBLE_DB),
                         predicted_speedup_range=(), **changes)


# ---------------------------------------------------------------------- the rule
def _gamma(mu: float, periods) -> np.ndarray:
    p = np.maximum(np.asarray(periods, dtype=np.float64), 1.0)
    return mu * (1.0 - 1.0 / p)


def _saved(table) -> np.ndarray:
    """c_j: the per-pixel cost a hit saves (t_miss − t_hit, as the table clamps it)."""
    return np.maximum(table.t_miss, table.t_hit) - table.t_hit


def _nearest_outer(i: int, members: list[int], feeds) -> Optional[int]:
    """The innermost member that node ``i`` feeds (None when it feeds none)."""
    outers = [j for j in members if j != i and (i, j) in feeds]
    if not outers:
        return None
    return max(outers, key=lambda j: sum((j, m) in feeds for m in outers))


def set_prediction(table, members: list[int], periods: list[int], feeds=None,
                   layout: str = "per-node") -> tuple[float, float]:
    """(ε_S, T_S) of the set of table rows ``members`` at ``periods`` (see the module docstring);
    ``feeds`` holds (i, j) when row i feeds row j (i inside j's computation)."""
    feeds = feeds or set()
    P = table.max_period
    idx = [min(max(int(p), 1), P) - 1 for p in periods]
    err = float(sum(table.E[i, j] for i, j in zip(members, idx)))
    g = _gamma(table.mu, periods)
    if layout == "union":
        g = np.full(len(members), float(np.prod(g)))
    c = _saved(table)
    t0, m = table.original_ms, table.pixels
    ms = t0
    for k, i in enumerate(members):
        # the node's single-node frame at its effective hit share
        single = table.t_overhead[i] + m * (max(table.t_miss[i], table.t_hit[i]) - g[k] * c[i])
        ms += single - t0
    for k, i in enumerate(members):
        o = _nearest_outer(i, members, feeds)
        if o is not None:
            ms += m * g[members.index(o)] * min(c[i], c[o])
    # never below the cached pipeline's fixed cost
    return err, float(max(ms, max(table.t_overhead[i] for i in members)))


# ---------------------------------------------------------------------- the search
class _SingleFront:
    """The fastest single option (or the original) at each error: ``best(e)``."""

    def __init__(self, table):
        e = np.append(table.E[:, 1:].ravel(), 0.0)
        t = np.append(table.T[:, 1:].ravel(), table.original_ms)
        ok = np.isfinite(e) & np.isfinite(t)
        order = np.argsort(e[ok], kind="stable")
        self.e = e[ok][order]
        self.t = np.minimum.accumulate(t[ok][order])

    def best(self, errors) -> np.ndarray:
        pos = np.searchsorted(self.e, np.asarray(errors, dtype=np.float64), side="right") - 1
        return np.where(pos >= 0, self.t[np.maximum(pos, 0)], np.inf)


def front_nodes(table, limit: int = MAX_FRONT_NODES, near: float = NEAR_FRONT) -> list[int]:
    """The rows of the nodes on or near the single-node Pareto front: each node whose best option
    is within ``near`` of the front's time at its error (a node just behind the front, e.g. one
    as good as a front node but disjoint from it, pairs as well as the front's own), those on
    the front first, at most ``limit``."""
    single = _SingleFront(table)
    scores = []
    for i in range(len(table.node_ids)):
        e, t = table.E[i, 1:], table.T[i, 1:]
        ok = np.isfinite(e) & np.isfinite(t) & (t < table.original_ms)
        if not ok.any():
            continue
        ratio = float(np.min(t[ok] / single.best(e[ok])))
        if ratio <= 1.0 + near:
            scores.append((ratio, float(np.min(t[ok])), i))
    return [i for _, _, i in sorted(scores)][:limit]


def _pair_grids(table, a: int, b: int, feeds, layout: str):
    """ε and T over every period pair Δn_a, Δn_b ∈ 2..P (arrays P−1 × P−1)."""
    periods = table.periods[1:].astype(np.float64)
    ga, gb = _gamma(table.mu, periods)[:, None], _gamma(table.mu, periods)[None, :]
    if layout == "union":
        ga = gb = ga * gb
    c = _saved(table)
    t0, m = table.original_ms, table.pixels
    err = table.E[a, 1:][:, None] + table.E[b, 1:][None, :]
    ta = table.t_overhead[a] + m * (max(table.t_miss[a], table.t_hit[a]) - ga * c[a])
    tb = table.t_overhead[b] + m * (max(table.t_miss[b], table.t_hit[b]) - gb * c[b])
    ms = ta + tb - t0
    if (b, a) in feeds:
        ms = ms + m * ga * min(c[a], c[b])
    elif (a, b) in feeds:
        ms = ms + m * gb * min(c[a], c[b])
    ms = np.maximum(ms, max(table.t_overhead[a], table.t_overhead[b]))
    return np.broadcast_to(err, ms.shape), ms


def search(table, psnr_fits=None, feeds=None, layout: str = "per-node", max_nodes: int = 3,
           min_gain: float = MIN_SET_GAIN, limit_nodes: int = MAX_FRONT_NODES) -> list[SetOption]:
    """The sets predicted to improve the single-node front (see the module docstring), best gain
    first, at most one per node set and ``max_nodes`` nodes each (the render targets the driver
    allows; 3 for the union layouts' 8 targets on llvmpipe)."""
    feeds = set(feeds or ())
    rows = front_nodes(table, limit_nodes)
    single = _SingleFront(table)
    periods = table.periods[1:]
    found: list[tuple[float, tuple, tuple, float, float]] = []
    for a, b in itertools.combinations(rows, 2):
        err, ms = _pair_grids(table, a, b, feeds, layout)
        ok = np.isfinite(err) & np.isfinite(ms)
        gain = np.where(ok, single.best(err) / np.where(ms > 0, ms, np.inf), 0.0)
        # only what could be chosen: predicted faster than the original
        good = (gain >= 1.0 / (1.0 - min_gain)) & (ms < table.original_ms)
        for i, j in zip(*np.nonzero(good)):
            found.append((float(gain[i, j]), (a, b), (int(periods[i]), int(periods[j])),
                          float(err[i, j]), float(ms[i, j])))
    if max_nodes >= 3 and found:
        pair_front = _Front([(f[3], f[4]) for f in found])
        for gain, members, pers, _e, _t in sorted(found, reverse=True)[:MAX_EXTEND]:
            for c in rows:
                if c in members:
                    continue
                for p in periods:
                    e3, t3 = set_prediction(table, list(members) + [c], list(pers) + [int(p)], feeds, layout)
                    if not (math.isfinite(e3) and math.isfinite(t3) and t3 > 0):
                        continue
                    best = min(float(single.best([e3])[0]), pair_front.best(e3))
                    if best / t3 >= 1.0 / (1.0 - min_gain) and t3 < table.original_ms:
                        found.append((float(single.best([e3])[0]) / t3, tuple(members) + (c,),
                                      tuple(pers) + (int(p),), e3, t3))
    # the set points on the front of all sets (and the singles), one entry per point
    out, seen = [], set()
    allfront = _Front([(f[3], f[4]) for f in found])
    for gain, members, pers, err, ms in sorted(found, key=lambda f: (f[4], f[3])):
        if ms > allfront.best(err) * (1 + 1e-9):
            continue
        key = (members, pers)
        if key in seen:
            continue
        seen.add(key)
        out.append(SetOption([table.node_ids[i] for i in members], list(pers), layout, err, ms,
                             _set_psnr(table, psnr_fits, members, pers, err), gain))
    if len(out) > MAX_OPTIONS:  # thin along the front, keeping each node set's best
        best = {}
        for o in out:
            if tuple(o.nodes) not in best or o.gain > best[tuple(o.nodes)].gain:
                best[tuple(o.nodes)] = o
        step = len(out) / MAX_OPTIONS
        kept = {id(out[int(k * step)]) for k in range(MAX_OPTIONS)} | {id(o) for o in best.values()}
        out = [o for o in out if id(o) in kept]
    return sorted(out, key=lambda o: -o.gain)


class _Front:
    def __init__(self, points: Iterable[tuple[float, float]]):
        pts = sorted(points)
        self.e = np.array([p[0] for p in pts], dtype=np.float64)
        self.t = np.minimum.accumulate(np.array([p[1] for p in pts], dtype=np.float64)) if pts else np.array([])

    def best(self, error: float) -> float:
        pos = int(np.searchsorted(self.e, error, side="right")) - 1
        return float(self.t[pos]) if pos >= 0 else math.inf


def _set_psnr(table, psnr_fits, members, periods, err) -> Optional[float]:
    if not psnr_fits:
        return None
    shares = [table.E[i, min(int(p), table.max_period) - 1] for i, p in zip(members, periods)]
    dominant = members[int(np.argmax(shares))]
    value = float(psnr_fits[dominant].predict(err)) if err > 0 else math.inf
    return value if math.isfinite(value) else None


def admissible(option: SetOption, max_error: Optional[float] = None, min_psnr: Optional[float] = None,
               trained: bool = False) -> bool:
    """Whether ``option`` meets the level (its trained figures with ``trained``)."""
    err = option.trained_error if trained else option.predicted_error
    psnr = option.trained_psnr if trained else option.predicted_psnr
    if err is None:
        return False
    if min_psnr is not None:
        return psnr is not None and psnr >= min_psnr
    return max_error is not None and err <= max_error


def pick(options: list[SetOption], levels: list[tuple[Optional[float], Optional[float], float]],
         limit: int = DEFAULT_MAX_SETS, min_gain: float = MIN_SET_GAIN) -> list[SetOption]:
    """The few sets to train: per level ``(max_error, min_psnr, single_ms)`` the fastest
    admissible set predicted at least ``min_gain`` faster than the level's single choice, then
    the remaining sets by gain, one per node set, at most ``limit``."""
    chosen: list[SetOption] = []
    for max_error, min_psnr, single_ms in levels:
        ok = [o for o in options if admissible(o, max_error, min_psnr)
              and o.predicted_ms <= single_ms * (1.0 - min_gain)]
        if ok:
            best = min(ok, key=lambda o: o.predicted_ms)
            if best.key not in {c.key for c in chosen}:
                chosen.append(best)
    for o in options:
        if len(chosen) >= limit:
            break
        if tuple(o.nodes) not in {tuple(c.nodes) for c in chosen}:
            chosen.append(o)
    return chosen[:limit]


def better(single: Selection, options: list[SetOption], original_ms: float, max_error: Optional[float] = None,
           min_psnr: Optional[float] = None) -> Optional[SetOption]:
    """The trained set admissible at the level and faster (by its training measurement) than
    ``single`` (the single-node choice, or the original) and the original; None when none is."""
    bar = min(float(single.predicted_ms), float(original_ms)) if single.parts else float(original_ms)
    ok = [o for o in options if o.trained and o.trained_ms is not None and o.trained_ms < bar
          and admissible(o, max_error, min_psnr, trained=True)]
    return min(ok, key=lambda o: o.trained_ms) if ok else None
