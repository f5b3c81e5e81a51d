"""The performance model (main paper §4.3, eq. 3): frame time t = h·t_hit + m·t_miss + t_overhead.

Over L timed frames with h hits, m misses (pixels) and time t (ms), the paper solves the
over-constrained system [h m 1]·[t_hit t_miss t_overhead]ᵀ = t by least squares. Here the solve
is bounded (every unknown ≥ 0, ``scipy.optimize.lsq_linear``, method ``bvls``) and made robust:

- **rank deficiency** (DESIGN §3): when every frame covers the same number of pixels, h + m is
  constant and the columns h, m, 1 are linearly dependent: only t_overhead + M·t_miss (and the
  hit/miss difference) are determined. Two ways out:

  * ``overhead_ms`` given (the fixed cost measured separately, e.g. a frame with nothing
    covered): it is subtracted from t and the 2-unknown system [h m]·[t_hit t_miss]ᵀ = t − o is
    solved; t_overhead = ``overhead_ms``. This recovers t_hit and t_miss;
  * otherwise the overhead cannot be told apart from a per-pixel cost: it is fixed at 0 and the
    2-unknown system solved, so its cost is spread over the pixels (the predictions at the
    trained coverage are unchanged, since every solution on the null line (c, c, −M·c) predicts
    the same times there). Quality ``"rank_deficient"``.

- **collinearity**: the columns are scaled to unit max; when the condition number of the scaled
  system exceeds ``COLLINEAR_COND`` (coverage varies by less than about 0.3%), or the overhead's
  least-squares standard error exceeds a quarter of the median frame time (it is then not
  determined by the data), the overhead is fixed at 0 as above: quality ``"collinear"``. If h and
  m are themselves (nearly) proportional (one hit fraction in every frame), t_hit and t_miss are
  not separable: they are set equal (the safe side: no speed-up predicted from hits). When no
  frame covers any pixel (the object off-screen throughout) the time is all overhead:
  t_hit = t_miss = 0, t_overhead = mean(t) (or ``overhead_ms`` when given).
- fewer than 3 usable frames: ``"insufficient"``, t_hit = t_miss = median(t − o)/median(h + m),
  t_overhead = o (``overhead_ms``, or 0).
- a bound became active (the unbounded solution had a negative component): ``"clamped"``.
- rows with NaN/Inf or negative values are dropped (``dropped``, ``"nonfinite"``); an
  ``overhead_ms`` that is NaN/Inf or negative is ignored (``"overhead_ignored"``).

Units: times in ms, counts in pixels; t_hit and t_miss in ms per pixel.

>>> h = [1000, 4000, 7000, 2000]; m = [9000, 6000, 3000, 5000]
>>> t = [0.5 + 1e-4 * a + 1e-3 * b for a, b in zip(h, m)]
>>> f = fit_performance(h, m, t)
>>> round(f.t_hit, 6), round(f.t_miss, 6), round(f.t_overhead, 3), f.quality
(0.0001, 0.001, 0.5, 'ok')
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rrcache.errors import RRCacheError
from rrcache.model.error import _finite, _quiet, _same_length, _vector

#: scaled condition number above which the overhead column is treated as collinear
COLLINEAR_COND = 1e3
#: singular values below this fraction of the largest count as zero (numerical rank)
RANK_RTOL = 1e-10
#: the overhead is "undetermined" when its standard error exceeds this fraction of median(t)
OVERHEAD_SE_FRACTION = 0.25
_PRIORITY = ("insufficient", "nonfinite", "rank_deficient", "collinear", "clamped", "overhead_ignored")


@dataclass(frozen=True)
class PerfFit:
    """Fitted per-node costs: ``t_hit``, ``t_miss`` (ms per pixel, ≥ 0), ``t_overhead`` (ms per
    frame, ≥ 0), ``quality`` (the first of ``flags`` in the order ``insufficient``, ``nonfinite``,
    ``rank_deficient``, ``collinear``, ``clamped``, ``overhead_ignored``; else ``"ok"``),
    ``rank`` (numerical rank of the system as posed: [h m 1], or [h m] when the overhead was
    given), ``residual_rms`` (ms), ``dropped`` (rows dropped), ``n_frames`` (rows used),
    ``cond`` (condition number of the column-scaled system, capped at 1e300).

    >>> f = PerfFit(t_hit=1e-5, t_miss=1e-4, t_overhead=0.2, quality="ok", rank=3, residual_rms=0.0)
    >>> round(f.frame_ms(hits=5000, misses=5000), 3)
    0.75
    """

    t_hit: float
    t_miss: float
    t_overhead: float
    quality: str
    rank: int
    residual_rms: float
    dropped: int = 0
    n_frames: int = 0
    cond: float = 1.0
    flags: str = ""

    def frame_ms(self, hits, misses):
        """Predicted frame time (ms) for ``hits`` and ``misses`` pixels."""
        return float(self.t_overhead) + hits * float(self.t_hit) + misses * float(self.t_miss)


def _svd_info(a: np.ndarray) -> tuple[int, float]:
    """(numerical rank, condition number) of a column-scaled matrix."""
    if a.size == 0:
        return 0, math.inf
    s = np.linalg.svd(a, compute_uv=False)
    if s.size == 0 or s[0] <= 0.0:
        return 0, math.inf
    rank = int(np.count_nonzero(s > s[0] * RANK_RTOL))
    cond = math.inf if s[-1] <= 0.0 or a.shape[0] < a.shape[1] else float(s[0] / s[-1])
    return rank, cond


def _bounded(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, bool]:
    """Least squares with x ≥ 0 on a well-conditioned scaled system; (x, clamped)."""
    from scipy.optimize import lsq_linear

    free, *_ = np.linalg.lstsq(a, b, rcond=None)
    clamped = bool(np.any(free < -1e-9 * max(1.0, float(np.max(np.abs(free))))))
    if not clamped:
        return np.maximum(free, 0.0), False
    res = lsq_linear(a, b, bounds=(0.0, np.inf), method="bvls")
    return np.maximum(np.asarray(res.x, dtype=np.float64), 0.0), True


def _overhead_undetermined(a: np.ndarray, b: np.ndarray, median_t: float) -> bool:
    """Whether the overhead (last column) has a least-squares standard error above
    ``OVERHEAD_SE_FRACTION`` of the median frame time (all in scaled units)."""
    n, k = a.shape
    if n <= k:
        return False
    x, *_ = np.linalg.lstsq(a, b, rcond=None)
    resid = a @ x - b
    sigma2 = float(resid @ resid) / (n - k)
    try:
        cov = np.linalg.inv(a.T @ a)
    except np.linalg.LinAlgError:
        return True
    se = math.sqrt(max(sigma2 * float(cov[-1, -1]), 0.0))
    return se > OVERHEAD_SE_FRACTION * median_t


@_quiet
def fit_performance(hits, misses, times, overhead_ms=None) -> PerfFit:
    """Fit t_hit, t_miss (ms/pixel) and t_overhead (ms) to timed frames (see the module docstring).

    ``hits``, ``misses``: pixels per frame; ``times``: ms per frame; ``overhead_ms``: the
    separately measured fixed cost per frame, or None. Deterministic; never raises for numeric
    input and never returns NaN. RRCacheError when an argument is not numeric or lengths differ.

    Rank-deficient frames (h + m constant) with the overhead measured separately:

    >>> h = [2000, 5000, 8000]; m = [8000, 5000, 2000]
    >>> t = [0.3 + 2e-5 * a + 1e-4 * b for a, b in zip(h, m)]
    >>> f = fit_performance(h, m, t, overhead_ms=0.3)
    >>> round(f.t_hit * 1e5, 6), round(f.t_miss * 1e4, 6), f.quality
    (2.0, 1.0, 'ok')
    >>> fit_performance(h, m, t).quality
    'rank_deficient'
    """
    h = _vector(hits, "hits")
    m = _vector(misses, "misses")
    t = _vector(times, "times")
    _same_length("hits", h, "misses", m)
    _same_length("hits", h, "times", t)
    flags: list[str] = []
    overhead = None
    if overhead_ms is not None:
        try:
            o = float(overhead_ms)
        except (TypeError, ValueError):
            raise RRCacheError(f"overhead_ms must be a number, got {overhead_ms!r}", "model") from None
        if math.isfinite(o) and o >= 0.0:
            overhead = o
        else:
            flags.append("overhead_ignored")
    keep = (np.isfinite(h) & np.isfinite(m) & np.isfinite(t) & (h >= 0.0) & (m >= 0.0) & (t >= 0.0))
    dropped = int(np.count_nonzero(~keep))
    if dropped:
        flags.insert(0, "nonfinite")
    h, m, t = h[keep], m[keep], t[keep]
    n = int(t.size)
    o = 0.0 if overhead is None else overhead
    target = np.maximum(t - o, 0.0) if overhead is not None else t

    def done(th, tm, to, rank, rms, cond):
        quality = next((q for q in _PRIORITY if q in flags), "ok")
        return PerfFit(t_hit=max(_finite(th), 0.0), t_miss=max(_finite(tm), 0.0),
                       t_overhead=max(_finite(to), 0.0),
                       quality=quality, rank=int(rank), residual_rms=abs(_finite(rms)), dropped=dropped,
                       n_frames=n, cond=min(_finite(cond), 1e300) if not math.isinf(cond) else 1e300,
                       flags=",".join(flags))

    cols = [h, m] if overhead is not None else [h, m, np.ones_like(t)]
    a = np.column_stack(cols) if n else np.zeros((0, len(cols)))
    cscale = np.max(np.abs(a), axis=0) if n else np.ones(len(cols))
    cscale = np.where(cscale > 0.0, cscale, 1.0)
    a_s = a / cscale
    tscale = float(np.max(np.abs(target))) if n else 0.0
    tscale = tscale if tscale > 0.0 else 1.0
    b = target / tscale
    rank, cond = _svd_info(a_s)

    def rms_of(x_scaled: np.ndarray) -> float:
        if n == 0:
            return 0.0
        r = a_s @ x_scaled - b
        return math.sqrt(float(r @ r) / n) * tscale

    if n < 3:
        flags.insert(0, "insufficient")
        cover = h + m
        med_c = float(np.median(cover)) if n else 0.0
        per = float(np.median(target)) / med_c if n and med_c > 0.0 else 0.0
        x = np.array([per, per] + ([] if overhead is not None else [0.0]))
        return done(per, per, o, rank, rms_of(x * cscale / tscale), cond)

    k = a_s.shape[1]
    degenerate = rank < k or cond > COLLINEAR_COND
    if overhead is None and not degenerate:
        degenerate = _overhead_undetermined(a_s, b, float(np.median(b)))
    if not degenerate:
        x, clamped = _bounded(a_s, b)
        if clamped:
            flags.append("clamped")
        th, tm = x[0] * tscale / cscale[0], x[1] * tscale / cscale[1]
        to = o if overhead is not None else x[2] * tscale / cscale[2]
        return done(th, tm, to, rank, rms_of(x), cond)

    flags.append("rank_deficient" if rank < k else "collinear")
    # drop the overhead column (if it is an unknown) and try the 2-unknown system
    a2 = a_s[:, :2]
    rank2, cond2 = _svd_info(a2)
    if rank2 == 2 and cond2 <= COLLINEAR_COND:
        x2, clamped = _bounded(a2, b)
        if clamped:
            flags.append("clamped")
        x = np.concatenate([x2, np.zeros(k - 2)])
        return done(x2[0] * tscale / cscale[0], x2[1] * tscale / cscale[1], o, rank, rms_of(x), cond)
    # h and m proportional: one cost per pixel for hits and misses alike
    cover = (h / cscale[0]) * (cscale[0] / max(cscale[0], cscale[1])) + \
        (m / cscale[1]) * (cscale[1] / max(cscale[0], cscale[1]))
    cover_scale = max(cscale[0], cscale[1])  # cover * cover_scale = h + m
    denom = float(cover @ cover)
    if denom <= 0.0 and overhead is None:
        # no pixel covered in any frame: all the time is the fixed cost, t_overhead = mean(t)
        x = np.array([0.0, 0.0, float(np.mean(b))])
        return done(0.0, 0.0, x[2] * tscale / cscale[2], rank, rms_of(x), cond)
    z = max(float(cover @ b) / denom, 0.0) if denom > 0.0 else 0.0  # per-pixel cost, scaled
    per = z * tscale / cover_scale
    x = np.array([z * cscale[0] / cover_scale, z * cscale[1] / cover_scale] + [0.0] * (k - 2))
    return done(per, per, o, rank, rms_of(x), cond)
