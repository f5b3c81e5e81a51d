"""The error model (main paper §4.2, eq. 2): ε̂(Δn) = α (1 − e^{−λ (Δn − 1)}), ε̂(1) = 0.

α is the level the error saturates at, λ how fast it gets there. Both are fitted per node to the
mean per-pixel error measured at a few training periods (the paper uses Δn = 2, 10, …, 50) by a
downhill-simplex search (nlopt's Nelder–Mead) on the (weighted) sum of squared residuals.

How the fit is made robust, so that it never raises and never returns NaN for numeric input:

- points whose period or error (or weight) is NaN/Inf, or whose period is < 1, are dropped
  (``dropped`` counts them, flag ``"nonfinite"``); negative errors are clipped to 0 (flag
  ``"clipped"``), negative weights to 0;
- the errors are divided by their maximum before optimising, so 1e-9 and 1e4 fit alike
  (scale invariance), and α is recovered afterwards;
- the search runs over (α/max, log λ) with nlopt bounds α ≥ 0, λ ∈ [``LAMBDA_MIN``,
  ``LAMBDA_MAX``]; its start is the best of a closed-form two-point estimate (α from the largest
  measurement, λ = −ln(1 − ε₁/α)/(Δn₁ − 1) from the first trained period) and a fixed grid of λ
  with α solved in closed form, so the result is deterministic;
- degenerate data get a documented fallback (see :class:`ErrorFit`).

>>> fit = fit_error([2, 10, 18, 26, 34, 42, 50], [0.02, 0.11, 0.15, 0.17, 0.18, 0.185, 0.19])
>>> fit.quality, round(fit.alpha, 2)
('ok', 0.19)
>>> float(fit.predict(1))
0.0
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from rrcache.errors import RRCacheError

#: bounds on λ (per frame of refresh period)
LAMBDA_MIN = 1e-4
LAMBDA_MAX = 20.0
#: R² below this is flagged ``"poor"``
POOR_R2 = 0.9
#: the largest magnitude a fitted number is allowed (keeps every field finite)
_BIG = 1.7e308
#: λ·(Δn₁ − 1) above this: the curve is within 0.1% of α at the first trained period ("step")
_STEP_EXPONENT = math.log(1000.0)
#: flag priority: the first flag present becomes ``quality``
_PRIORITY = ("insufficient", "nonfinite", "clipped", "zero", "poor", "step", "linear")


def _quiet(func):
    """Run ``func`` with numpy's floating-point warnings off: overflow to ±inf and underflow to
    0 are expected with extreme inputs and every result is made finite explicitly."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with np.errstate(all="ignore"):
            return func(*args, **kwargs)
    return wrapper


def _vector(values, name: str) -> np.ndarray:
    """``values`` as a 1-D float64 array (a scalar becomes one element); RRCacheError if it is not
    numeric."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise RRCacheError(f"{name} must be numbers ({err})", "model",
                           hint="pass a list or array of floats") from None
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise RRCacheError(f"{name} must be one-dimensional, got shape {arr.shape}", "model")
    return arr


def _periods(periods) -> np.ndarray:
    """``periods`` as a float64 array of the same shape (a scalar gives a 0-d array)."""
    try:
        return np.asarray(periods, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise RRCacheError(f"periods must be numbers ({err})", "model") from None


def _same_length(name_a: str, a: np.ndarray, name_b: str, b: np.ndarray) -> None:
    if a.shape != b.shape:
        raise RRCacheError(f"{name_a} and {name_b} differ in length ({a.size} and {b.size})", "model",
                           hint="give one value per measurement")


def _finite(x: float) -> float:
    """``x`` clipped into [−1.7e308, 1.7e308], NaN → 0 (every fitted number stays finite)."""
    x = float(x)
    if math.isnan(x):
        return 0.0
    return min(max(x, -_BIG), _BIG)


def _quality(flags: list[str]) -> str:
    for name in _PRIORITY:
        if name in flags:
            return name
    return "ok"


@dataclass(frozen=True)
class ErrorFit:
    """A fitted error model ε̂(Δn) = α (1 − e^{−λ (Δn − 1)}).

    - ``alpha`` (≥ 0, in the units of the errors), ``lam`` (in [1e-4, 20]), ``r2`` (weighted
      coefficient of determination, ≤ 1; 1 when the data have no spread and are fitted exactly),
      ``rmse`` (weighted, in error units), ``n_points`` (points used), ``dropped`` (points dropped
      as NaN/Inf or with a period < 1).
    - ``quality``: the first of ``flags`` in the order ``insufficient``, ``nonfinite``,
      ``clipped``, ``zero``, ``poor``, ``step``, ``linear``; ``"ok"`` when there is none.
      ``flags`` lists every condition found, comma-separated:

      - ``insufficient``: fewer than 2 usable points (α = the largest usable error or 0, λ = 1), or
        fewer than 2 distinct periods > 1 (λ = 1, α solved by least squares for λ = 1);
      - ``nonfinite``: ``dropped`` > 0;
      - ``clipped``: some errors were negative and were taken as 0;
      - ``zero``: every error is 0 (α = 0, λ = 1, R² = 1);
      - ``poor``: R² < 0.9;
      - ``step``: the error saturates at the first trained period (λ(Δn₁ − 1) > ln 1000); λ is then
        set to its upper bound 20 and α re-solved;
      - ``linear``: λ sits at its lower bound 1e-4: no curvature within the trained range.

    >>> f = ErrorFit(alpha=0.2, lam=0.1, r2=1.0, rmse=0.0, n_points=7, quality="ok")
    >>> [round(float(v), 4) for v in f.predict([1, 2, 50])]
    [0.0, 0.019, 0.1985]
    """

    alpha: float
    lam: float
    r2: float
    rmse: float
    n_points: int
    quality: str
    dropped: int = 0
    flags: str = ""

    @_quiet
    def predict(self, periods) -> np.ndarray:
        """ε̂ at ``periods`` (scalar or array, same shape out; periods below 1 count as 1, i.e.
        error 0).

        >>> ErrorFit(0.5, 1.0, 1.0, 0.0, 3, "ok").predict(1).tolist()
        0.0
        """
        x = np.maximum(_periods(periods) - 1.0, 0.0)
        return float(self.alpha) * -np.expm1(-float(self.lam) * x)


def _alpha_for(lam: float, x: np.ndarray, y: np.ndarray, w: np.ndarray) -> float:
    """The least-squares α ≥ 0 for a fixed λ (closed form)."""
    g = -np.expm1(-lam * x)
    den = float(np.sum(w * g * g))
    if den <= 0.0:
        return 0.0
    return max(float(np.sum(w * y * g)) / den, 0.0)


def _sse(alpha: float, lam: float, x, y, w) -> float:
    r = alpha * -np.expm1(-lam * x) - y
    return float(np.sum(w * r * r))


def _r2(sse: float, y: np.ndarray, w: np.ndarray) -> float:
    sw = float(np.sum(w))
    if sw <= 0.0:
        return 1.0
    mean = float(np.sum(w * y)) / sw
    sst = float(np.sum(w * (y - mean) ** 2))
    tiny = 1e-24 * max(float(np.sum(w * y * y)), 1e-300)
    if sst <= tiny:
        return 1.0 if sse <= 1e-12 * max(float(np.sum(w * y * y)), 1e-300) else 0.0
    return max(1.0 - sse / sst, -_BIG)


def _minimise(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """Nelder–Mead (nlopt) over (a, log λ) for normalised data (max y = 1); returns (a, λ)."""
    import nlopt

    lo, hi = math.log(LAMBDA_MIN), math.log(LAMBDA_MAX)
    # candidate starts: closed-form two-point estimate, then a λ grid with α in closed form
    starts = []
    a0 = float(np.max(y))
    pos = x > 0
    x1 = float(np.min(x[pos]))
    y1 = float(np.max(y[x == x1]))
    ratio = min(y1 / (a0 * 1.001), 0.999999)
    lam0 = -math.log1p(-ratio) / x1 if ratio > 0 else LAMBDA_MIN
    lam0 = min(max(lam0, LAMBDA_MIN), LAMBDA_MAX)
    starts.append((a0, lam0))
    for u in np.linspace(lo, hi, 49):
        lam = float(math.exp(u))
        starts.append((_alpha_for(lam, x, y, w), lam))
    a_start, lam_start = min(starts, key=lambda s: _sse(s[0], s[1], x, y, w))

    # α bound: the LS α never exceeds max y / min g for any λ in range
    g_min = float(-np.expm1(-LAMBDA_MIN * x1))
    a_max = min(max(1.0 / max(g_min, 1e-300), 1.0) * 2.0, 1e12)

    def objective(v, grad):
        return _sse(float(v[0]), math.exp(float(v[1])), x, y, w)

    opt = nlopt.opt(nlopt.LN_NELDERMEAD, 2)
    opt.set_min_objective(objective)
    opt.set_lower_bounds([0.0, lo])
    opt.set_upper_bounds([a_max, hi])
    opt.set_xtol_rel(1e-10)
    opt.set_ftol_abs(1e-16)
    opt.set_maxeval(4000)
    start = np.array([min(max(a_start, 0.0), a_max), min(max(math.log(lam_start), lo), hi)])
    opt.set_initial_step([max(0.1 * start[0], 1e-3), 0.5])
    try:
        v = opt.optimize(start)
        a, lam = float(v[0]), math.exp(float(v[1]))
        if not (math.isfinite(a) and math.isfinite(lam)):
            raise ValueError("non-finite result")
    except (nlopt.RoundoffLimited, ValueError, RuntimeError):
        a, lam = float(start[0]), math.exp(float(start[1]))
    if _sse(a, lam, x, y, w) > _sse(a_start, lam_start, x, y, w):
        a, lam = a_start, lam_start
    # polish α for the found λ (exact for fixed λ; never worse)
    a_ls = _alpha_for(lam, x, y, w)
    if _sse(a_ls, lam, x, y, w) <= _sse(a, lam, x, y, w):
        a = a_ls
    return a, min(max(lam, LAMBDA_MIN), LAMBDA_MAX)


@_quiet
def fit_error(periods, errors, weights=None) -> ErrorFit:
    """Fit ε̂(Δn) = α (1 − e^{−λ(Δn−1)}) to measured mean errors at refresh ``periods``.

    ``weights`` (optional, one per point, ≥ 0) weight the squared residuals, e.g. by the number
    of shaded pixels. Deterministic; never raises for numeric input and never returns NaN (see
    :class:`ErrorFit` for what each degenerate case gives). RRCacheError when an argument is not
    numeric or the lengths differ.

    >>> f = fit_error([2, 10, 18, 26, 34, 42, 50], [0.0] * 7)
    >>> f.quality, f.alpha, f.r2
    ('zero', 0.0, 1.0)
    >>> fit_error([2, 10, float("nan")], [0.1, 0.3, 0.2]).dropped
    1
    """
    p = _vector(periods, "periods")
    e = _vector(errors, "errors")
    _same_length("periods", p, "errors", e)
    if weights is None:
        wt = np.ones_like(p)
    else:
        wt = _vector(weights, "weights")
        _same_length("periods", p, "weights", wt)
    flags: list[str] = []
    keep = np.isfinite(p) & np.isfinite(e) & np.isfinite(wt) & (p >= 1.0)
    dropped = int(np.count_nonzero(~keep))
    if dropped:
        flags.append("nonfinite")
    x, y, w = p[keep] - 1.0, e[keep], np.maximum(wt[keep], 0.0)
    if np.any(y < 0):
        flags.append("clipped")
        y = np.maximum(y, 0.0)
    used = w > 0
    x, y, w = x[used], y[used], w[used]
    n = int(x.size)

    def done(alpha, lam, r2, rmse):
        return ErrorFit(alpha=_finite(alpha), lam=_finite(lam), r2=min(_finite(r2), 1.0),
                        rmse=abs(_finite(rmse)), n_points=n, quality=_quality(flags), dropped=dropped,
                        flags=",".join(flags))

    if n < 2:
        flags.insert(0, "insufficient")
        alpha = float(np.max(y)) if n else 0.0
        rmse = float(np.sqrt(_sse(alpha, 1.0, x, y, w) / np.sum(w))) if n else 0.0
        return done(alpha, 1.0, 1.0 if n == 0 else _r2(_sse(alpha, 1.0, x, y, w), y, w), rmse)
    scale = float(np.max(y))
    if scale <= 0.0:
        flags.append("zero")
        return done(0.0, 1.0, 1.0, 0.0)
    yn = y / scale
    sw = float(np.sum(w))
    wn = w / sw  # weights normalised: scale-invariant objective
    if np.unique(x[x > 0]).size < 2:
        flags.insert(0, "insufficient")
        a = _alpha_for(1.0, x, yn, wn)
        sse = _sse(a, 1.0, x, yn, wn)
        return done(a * scale, 1.0, _r2(sse, yn, wn), math.sqrt(sse) * scale)

    a, lam = _minimise(x, yn, wn)
    x1 = float(np.min(x[x > 0]))
    if lam * x1 > _STEP_EXPONENT:
        flags.append("step")
        lam = LAMBDA_MAX
        a = _alpha_for(lam, x, yn, wn)
    elif lam <= LAMBDA_MIN * 1.01:
        flags.append("linear")
    sse = _sse(a, lam, x, yn, wn)
    r2 = _r2(sse, yn, wn)
    if r2 < POOR_R2:
        flags.append("poor")
    return done(a * scale, lam, r2, math.sqrt(sse) * scale)


def fit_errors(periods, matrix, weights=None) -> list[ErrorFit]:
    """:func:`fit_error` for many nodes: ``matrix[i, j]`` is node i's error at ``periods[j]``.

    >>> fits = fit_errors([2, 10, 50], [[0.1, 0.5, 0.6], [0.0, 0.0, 0.0]])
    >>> [f.quality for f in fits]
    ['ok', 'zero']
    """
    p = _vector(periods, "periods")
    try:
        m = np.asarray(matrix, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise RRCacheError(f"errors must be numbers ({err})", "model") from None
    if m.ndim == 1:
        m = m.reshape(1, -1)
    if m.ndim != 2 or (m.size and m.shape[1] != p.size):
        raise RRCacheError(f"the error matrix must be nodes × {p.size} periods, got shape {m.shape}",
                           "model")
    return [fit_error(p, row, weights) for row in m]
