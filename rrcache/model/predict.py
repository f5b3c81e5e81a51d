"""Predicted frame time of a cached variant (main paper eq. 5) and speed-up.

Per pixel r̂(Δn) = γ(Δn)·t_hit + (1 − γ(Δn))·t_miss with γ(Δn) = μ(1 − 1/Δn); per frame
t = t_overhead + M·r̂ for M covered pixels. Δn = 1 refreshes every pixel every frame: γ = 0, all
misses. A miss does all that a hit does and computes the payload besides, so a t_miss fitted
below t_hit (noisy frames) is taken as t_hit.

>>> from rrcache.model.performance import PerfFit
>>> perf = PerfFit(t_hit=1e-5, t_miss=1e-4, t_overhead=0.5, quality="ok", rank=3, residual_rms=0.0)
>>> [round(float(v), 3) for v in predict_ms(perf, mu=0.9, pixels=10000, periods=[1, 10])]
[1.5, 0.771]
>>> float(predict_speedup(1.5, 0.75))
2.0
"""
from __future__ import annotations

import math

import numpy as np

from rrcache.errors import RRCacheError
from rrcache.model.error import _periods, _quiet


def _number(value, name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise RRCacheError(f"{name} must be a number, got {value!r}", "model") from None
    if not math.isfinite(v):
        raise RRCacheError(f"{name} must be finite, got {v}", "model")
    return v


@_quiet
def predict_ms(perf, mu: float, pixels: float, periods) -> np.ndarray:
    """Predicted ms per frame at each of ``periods`` for a node with costs ``perf`` (a
    :class:`~rrcache.model.performance.PerfFit` or anything with ``t_hit``, ``t_miss``,
    ``t_overhead``), hit-rate parameter ``mu`` (clipped to [0, 1]) and ``pixels`` covered pixels
    per frame (same shape as ``periods``). Periods below 1 count as 1. RRCacheError for a
    non-finite ``mu`` or ``pixels`` or a negative ``pixels``.

    >>> from rrcache.model.performance import PerfFit
    >>> perf = PerfFit(2e-5, 1e-4, 0.0, "ok", 3, 0.0)
    >>> predict_ms(perf, 1.0, 1000, [2]).round(6).tolist()
    [0.06]
    """
    mu = min(max(_number(mu, "mu"), 0.0), 1.0)
    pixels = _number(pixels, "pixels")
    if pixels < 0:
        raise RRCacheError(f"pixels must be >= 0, got {pixels}", "model")
    p = np.maximum(_periods(periods), 1.0)
    gamma = mu * (1.0 - 1.0 / p)
    t_hit = float(perf.t_hit)
    t_miss = max(float(perf.t_miss), t_hit)
    return float(perf.t_overhead) + pixels * (gamma * t_hit + (1.0 - gamma) * t_miss)


def predict_speedup(original_ms, predicted_ms):
    """``original_ms / predicted_ms`` elementwise (inf where the prediction is ≤ 0).

    >>> predict_speedup(2.0, [1.0, 4.0, 0.0]).tolist()
    [2.0, 0.5, inf]
    """
    o = np.asarray(original_ms, dtype=np.float64)
    p = np.asarray(predicted_ms, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(p > 0.0, o / np.where(p > 0.0, p, 1.0), np.inf)
