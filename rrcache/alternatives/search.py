"""Equal-time searches: tune an alternative until its measured speed-up matches a target.

Both searches take the measurement as a function (``measure(x) -> speed-up``, a ratio of median
frame times measured side by side with the original), so the logic is tested with an injected
function and the benches pass a real one.

- :func:`match_scale`: a continuous knob ``s`` in ``[lo, hi]`` whose speed-up falls as ``s``
  grows (dynamic resolution: the shading scale). Starts at ``1/sqrt(target)`` (shading cost
  proportional to the pixel count), then bisects (geometric midpoints) the bracket, stopping
  when the speed-up is within ``rel_tol`` of the target or after ``max_steps`` measurements.
- :func:`first_reaching`: a discrete knob ``k`` in ``1..n`` whose speed-up grows with ``k``
  (simplification: the first k nodes of a ranked list replaced). Binary search for the smallest
  ``k`` reaching the target (within ``rel_tol``); ``n`` itself when none does.

Either returns a :class:`SearchResult`: the chosen value, its speed-up, every step measured and
whether the target was met.

>>> r = match_scale(lambda s: 1.0 / s ** 2, target=4.0)
>>> round(r.value, 3), r.matched, len(r.steps)
(0.5, True, 1)
>>> first_reaching(lambda k: 1.0 + 0.5 * k, target=3.0, n=10).value
4
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

from rrcache.errors import RRCacheError


@dataclass
class SearchResult:
    """``value`` chosen, its ``speedup``, ``target``, ``steps`` [(value, speedup)] in the
    order measured, ``matched`` (within tolerance, or for :func:`first_reaching` at least the
    target less the tolerance)."""

    value: float
    speedup: float
    target: float
    steps: list = field(default_factory=list)
    matched: bool = False


def _check_target(target: float) -> float:
    try:
        t = float(target)
    except (TypeError, ValueError):
        t = float("nan")
    if not math.isfinite(t) or t <= 0:
        raise RRCacheError(f"{target!r} is not a speed-up to match", "equal-time search",
                           hint="the target is the measured speed-up of a selection, a positive ratio")
    return t


def match_scale(measure: Callable[[float], float], target: float, lo: float = 0.1, hi: float = 1.0,
                rel_tol: float = 0.05, max_steps: int = 8) -> SearchResult:
    """The ``s`` in ``[lo, hi]`` whose ``measure(s)`` is closest to ``target`` (see the module
    docstring). Each step is one call of ``measure``."""
    t = _check_target(target)
    if not 0 < lo < hi:
        raise RRCacheError(f"scale bracket [{lo}, {hi}] is empty", "equal-time search", hint="give 0 < lo < hi")
    if max_steps < 1:
        raise RRCacheError(f"max_steps={max_steps}", "equal-time search", hint="give at least one step")
    steps: list[tuple[float, float]] = []
    a, b = lo, hi
    s = min(hi, max(lo, 1.0 / math.sqrt(t)))
    for _ in range(max_steps):
        sp = float(measure(s))
        steps.append((s, sp))
        if math.isfinite(sp) and abs(sp / t - 1.0) <= rel_tol:
            break
        if not math.isfinite(sp) or sp < t:
            b = s  # too slow: shade fewer pixels
        else:
            a = s
        nxt = math.sqrt(a * b)
        if abs(nxt - s) < 1e-4 * s:
            break
        s = nxt
    best_s, best_sp = min(steps, key=lambda p: abs(p[1] / t - 1.0) if math.isfinite(p[1]) else math.inf)
    return SearchResult(best_s, best_sp, t, steps, math.isfinite(best_sp) and abs(best_sp / t - 1.0) <= rel_tol)


def first_reaching(measure: Callable[[int], float], target: float, n: int, rel_tol: float = 0.05) -> SearchResult:
    """The smallest ``k`` in ``1..n`` with ``measure(k) >= target * (1 - rel_tol)`` (binary
    search, assuming the speed-up grows with ``k``); ``n`` when none reaches it."""
    t = _check_target(target)
    if n < 1:
        raise RRCacheError("nothing to search: no candidate", "equal-time search",
                           hint="the shader has no node that can be simplified")
    goal = t * (1.0 - rel_tol)
    steps: list[tuple[int, float]] = []
    seen: dict[int, float] = {}

    def at(k: int) -> float:
        if k not in seen:
            seen[k] = float(measure(k))
            steps.append((k, seen[k]))
        return seen[k]

    if not at(n) >= goal:
        return SearchResult(n, seen[n], t, steps, False)
    lo, hi = 1, n  # invariant: hi reaches the goal
    while lo < hi:
        mid = (lo + hi) // 2
        if at(mid) >= goal:
            hi = mid
        else:
            lo = mid + 1
    return SearchResult(hi, seen[hi], t, steps, True)
