"""The hit-rate model (main paper §4.3, eq. 4): γ(Δn) = μ (1 − 1/Δn).

One μ per shader and session (the hit rate does not depend on what is cached), fitted to every
node's measured hit rates at once. The model is linear in μ, so the least-squares fit is closed
form: with g = 1 − 1/Δn, μ = Σ r g / Σ g², clipped to [0, 1].

>>> fit = fit_hit_rate([2, 10, 50], [0.45, 0.81, 0.882])
>>> round(fit.mu, 3), fit.quality
(0.9, 'ok')
>>> fit.predict([1, 2]).round(3).tolist()
[0.0, 0.45]
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rrcache.model.error import _finite, _periods, _quiet, _r2, _same_length, _vector

#: μ above this is flagged ``"static"`` (nearly every pixel is a hit until refreshed)
STATIC_MU = 0.99
#: μ below this is flagged ``"cut_every_frame"`` (nearly nothing survives from frame to frame)
CUT_MU = 0.01
#: R² below this is flagged ``"poor"``
POOR_R2 = 0.9
_PRIORITY = ("insufficient", "nonfinite", "clipped", "cut_every_frame", "static", "poor")


@dataclass(frozen=True)
class HitRateFit:
    """A fitted hit-rate model γ(Δn) = μ (1 − 1/Δn).

    ``mu`` in [0, 1]; ``r2`` (≤ 1; 1 when the data have no spread and are fitted exactly);
    ``dropped``: points with a NaN/Inf period or rate, or a period < 1. ``quality`` is the first of
    ``flags`` in the order ``insufficient`` (no usable point with Δn > 1: μ = 0, which predicts no
    hits, the safe side), ``nonfinite`` (``dropped`` > 0), ``clipped`` (a rate outside [0, 1] was
    clipped into it, or μ was), ``cut_every_frame`` (μ < 0.01), ``static`` (μ > 0.99), ``poor``
    (R² < 0.9); ``"ok"`` when there is none.

    >>> HitRateFit(mu=0.8, r2=1.0, quality="ok").predict([1, 5]).round(3).tolist()
    [0.0, 0.64]
    """

    mu: float
    r2: float
    quality: str
    dropped: int = 0
    n_points: int = 0
    flags: str = ""

    @_quiet
    def predict(self, periods) -> np.ndarray:
        """γ at ``periods`` (scalar or array, same shape out; periods below 1 count as 1: no hits).

        >>> float(HitRateFit(1.0, 1.0, "static").predict(4))
        0.75
        """
        p = np.maximum(_periods(periods), 1.0)
        return float(self.mu) * (1.0 - 1.0 / p)


@_quiet
def fit_hit_rate(periods, rates) -> HitRateFit:
    """Fit μ of γ(Δn) = μ(1 − 1/Δn) to measured hit ``rates`` (fractions in [0, 1]) at
    ``periods``.

    Closed-form least squares, deterministic; never raises for numeric input and never returns
    NaN. RRCacheError when an argument is not numeric or the lengths differ.

    >>> fit_hit_rate([2, 2, 10], [0.0, 0.0, 0.0]).quality
    'cut_every_frame'
    >>> fit_hit_rate([1, 1], [0.5, 0.4]).quality
    'insufficient'
    """
    p = _vector(periods, "periods")
    r = _vector(rates, "rates")
    _same_length("periods", p, "rates", r)
    flags: list[str] = []
    keep = np.isfinite(p) & np.isfinite(r) & (p >= 1.0)
    dropped = int(np.count_nonzero(~keep))
    if dropped:
        flags.append("nonfinite")
    p, r = p[keep], r[keep]
    if np.any((r < 0.0) | (r > 1.0)):
        flags.append("clipped")
        r = np.clip(r, 0.0, 1.0)
    g = 1.0 - 1.0 / p
    den = float(np.sum(g * g))
    n = int(p.size)
    if den <= 1e-300:
        flags.insert(0, "insufficient")
        r2 = 1.0 if n == 0 else _finite(_r2(float(np.sum(r * r)), r, np.ones(n)))
        return HitRateFit(mu=0.0, r2=r2,
                          quality=_first(flags), dropped=dropped, n_points=n, flags=",".join(flags))
    mu = float(np.sum(r * g)) / den
    if mu > 1.0 or mu < 0.0:  # cannot happen for rates in [0, 1]; kept for safety
        if "clipped" not in flags:
            flags.append("clipped")
        mu = min(max(mu, 0.0), 1.0)
    resid = mu * g - r
    r2 = _r2(float(np.sum(resid * resid)), r, np.ones(n))
    if mu < CUT_MU:
        flags.append("cut_every_frame")
    elif mu > STATIC_MU:
        flags.append("static")
    if r2 < POOR_R2:
        flags.append("poor")
    return HitRateFit(mu=_finite(mu), r2=min(_finite(r2), 1.0), quality=_first(flags), dropped=dropped,
                      n_points=n, flags=",".join(flags))


def _first(flags: list[str]) -> str:
    for name in _PRIORITY:
        if name in flags:
            return name
    return "ok"
