"""The models of amortized sampling (Nehab et al. 2007 §6): an estimator's error against the
original at (m, λ), its frame time per evaluated sample, and the options they predict.

An estimator (:mod:`rrcache.analysis.estimators`) sums ``N`` terms. Its amortized variant
(:mod:`rrcache.compiler.amortize`) evaluates ``m`` of them per frame at a hit, scaled to the full
sum, and blends that with the reprojected running estimate by λ; a miss evaluates all ``N``.

**Error** (mean RGB L2 against the original, as the cached nodes' error runs measure):

    ε̂(m, λ) = a · sqrt(s(m) · (1 − λ)/(1 + λ)) + b · sqrt(λ/(1 − λ)),    s(m) = (N − m) / (m (N − 1))

The first term is the paper's: ``s(m)`` is the variance of an m-of-N subset scaled to the full
sum relative to one sample's (sampling without replacement: 1 at m = 1, 0 at m = N), and the
blend keeps (1 − λ)/(1 + λ) of it; the error is a standard deviation, hence the square root.
The second is the history's lag and resampling blur: the blended estimate is λ/(1 − λ) frames
old on average and reprojected every frame; a value that drifts by independent steps each frame
is off by a standard deviation growing as the square root of that age. Both coefficients are
≥ 0, fitted per estimator by nlopt's Nelder–Mead on the squared residuals. ε̂(N, 0) = 0: the
original. Why this form, from measurements (README, "Amortized sampling"; m × λ grids of 25 runs
against the original): the paper's term alone fits the temple's 16-tap PCF (320×240, 40 frames;
R² 0.94: the error at m = 1 falls from 0.0137 at λ = 0 to 0.0030 at λ = 0.9) but not Trashcan's
glossy rows (160×120, 30 frames; R² < 0: there the error *grows* with λ, to 0.066 at λ = 0.9
for every m, the reflections lagging the orbiting camera). Of the lag terms tried with it,
b·λ/(1−λ), b·λ and b·sqrt(λ/(1−λ)), the last fitted best on both (R² 0.96 and 0.91 against
0.96 and 0.70, 0.95 and 0.80).

**Error of the slots history** (``history="slots"``: the N/m subset sums kept apart in the
payload, each blended with its own reprojected value by λ at its phase):

    ε̂(m, λ) = sqrt(c_m² + b² · λ/(1 − λ))

No noise term: the slots are exact on a still image whatever λ (after one cycle every slot holds
its own subset's sum), so the error against the original is all reprojection and motion. ``c_m``
is the floor at λ = 0 (the N/m − 1 slots not recomputed this frame are 1..N/m − 1 frames old and
resampled every frame); it is one coefficient per m, because the measurements follow no law in
m: on the temple with ``PCF_SAMPLES=12`` the error at λ = 0 is 0.0028 at m = 3, 0.0037 at m = 4
and 0.0024 at m = 6 (the subsets of a stratified pattern differ in shape, not only in size). That
costs nothing in prediction: the slots fit at few m (one component: N/m = 2, 3 or 4) and the
profiler trains every one of them, so the options are only at trained m. The second term is the
blend model's lag term, added in quadrature: a slot blended by λ is λ/(1 − λ) cycles older on
average and each slot's drift is an independent error of variance growing with its age
(``b ≥ 0`` shared by the m). Why this form, from measurements (m × λ grids, λ = 0, 0.3, 0.6,
0.8, 0.9, 320×240, 40 frames, least squares on the error; docs/amortize_model_grid.json): R² 0.95
(temple, N = 16, m = 4, 8) and 0.91 (N = 12, m = 3, 4, 6) over each grid, and 0.90 and 0.87 on
the runs left out when fitted on λ = 0, 0.6, 0.9 only; the blend form fitted to the slots runs
gave 0.90 and 0.65, c_m + b·sqrt(λ/(1−λ)) 0.94 and 0.84, the age of the slots in frames
(N/m·λ/(1−λ)) in place of λ/(1−λ) 0.97 and 0.89 (0.93 and 0.86 held out), and one floor for
every m (a·sqrt((N/m − 1)·m/N)) 0.96 and 0.79. The error grows with λ (0.0016 at λ = 0 to 0.0034
at λ = 0.9, N = 16, m = 4): the best slots option is usually λ = 0.

**Time**: a frame costs ``c + t_s · S`` where ``S = P (h m + (1 − h) N)`` is the number of terms
evaluated over the frame's ``P`` covered pixels at hit rate ``h`` (least squares over the timed
frames, each taken relative to the original timed beside it; ``t_s`` ≥ 0, ms per evaluated
term). λ costs nothing.

>>> fit = fit_amortized_error([1, 1, 4, 4, 16], [0.0, 0.6, 0.0, 0.6, 0.6], [0.02, 0.01, 0.01, 0.005, 0.001], 16)
>>> fit.quality, bool(fit.predict(16, 0.0) == 0.0)
('ok', True)
>>> t = fit_amortized_time([1000, 4000, 16000], [1.5, 2.4, 6.0])
>>> round(t.t_sample * 1e4, 2), round(t.fixed_ms, 2)
(3.0, 1.2)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from rrcache.errors import RRCacheError
from rrcache.selection import AmortizedLoop, Selection, slots_fit, slots_samples

#: the blends the options are predicted at (the paper's 3/5 and 7/9 among them)
BLEND_GRID = (0.0, 0.2, 0.4, 0.5, 0.6, 0.7, 7.0 / 9.0, 0.85, 0.9)
#: the blends an estimator's error runs measure
TRAIN_BLENDS = (0.0, 0.6, 0.85)
#: at most this many sample counts m are trained per estimator
TRAIN_SAMPLES = 3


def sample_counts(total: int) -> list[int]:
    """The m an estimator of ``total`` terms is offered at: the proper divisors of N (each index
    used every N/m frames by a stratified subset) when there are two or more, else 1..N−1.

    >>> sample_counts(16), sample_counts(5), sample_counts(1)
    ([1, 2, 4, 8], [1, 2, 3, 4], [])
    """
    n = int(total)
    if n < 2:
        return []
    divisors = [d for d in range(1, n) if n % d == 0]
    return divisors if len(divisors) >= 2 else list(range(1, n))


def training_samples(total: int, history: str = "blend", components: int = 1) -> list[int]:
    """The m the error and timing runs measure: for ``blend`` the smallest, the middle and the
    largest of :func:`sample_counts` (at most :data:`TRAIN_SAMPLES`); for ``slots`` every m where
    the N/m sums of ``components`` components fit (:func:`rrcache.selection.slots_samples`: at
    most three, N/m = 2, 3 or 4 for one component), the only m it is offered at.

    >>> training_samples(16), training_samples(5), training_samples(2)
    ([1, 4, 8], [1, 3, 4], [1])
    >>> training_samples(16, "slots"), training_samples(16, "slots", 2), training_samples(5, "slots")
    ([4, 8], [8], [])
    """
    if history == "slots":
        return slots_samples(total, components)
    counts = sample_counts(total)
    if len(counts) <= TRAIN_SAMPLES:
        return counts
    return sorted({counts[0], counts[len(counts) // 2], counts[-1]})


def variance_factor(samples, total: int):
    """``s(m)`` of the module docstring (0 at m = N).

    >>> float(variance_factor(1, 16)), float(variance_factor(16, 16)), round(float(variance_factor(4, 16)), 3)
    (1.0, 0.0, 0.2)
    """
    m = np.asarray(samples, dtype=np.float64)
    n = float(total)
    if n < 2:
        return np.zeros_like(m)
    return np.clip((n - m) / (m * (n - 1.0)), 0.0, None)


def _terms(samples, blends, total: int) -> tuple[np.ndarray, np.ndarray]:
    lam = np.clip(np.asarray(blends, dtype=np.float64), 0.0, 0.999)
    noise = np.sqrt(variance_factor(samples, total) * (1.0 - lam) / (1.0 + lam))
    lag = np.sqrt(lam / (1.0 - lam))
    return noise, lag


@dataclass(frozen=True)
class AmortizeErrorFit:
    """ε̂(m, λ) = ``a``·sqrt(s(m)(1−λ)/(1+λ)) + ``b``·sqrt(λ/(1−λ)) for an estimator of ``total``
    terms; ``r2``, ``rms`` over the ``n`` runs; ``quality`` ``ok``, ``poor`` (R² < 0.8),
    ``insufficient`` (fewer than two runs) or ``zero``."""

    a: float
    b: float
    total: int
    r2: float
    rms: float
    n: int
    quality: str

    def predict(self, samples, blend):
        noise, lag = _terms(samples, blend, self.total)
        out = self.a * noise + self.b * lag
        return float(out) if np.ndim(out) == 0 else out

    def to_json(self) -> dict:
        return {"a": self.a, "b": self.b, "total": self.total, "r2": self.r2, "rms": self.rms, "n": self.n,
                "quality": self.quality}


def fit_amortized_error(samples: Sequence[int], blends: Sequence[float], errors: Sequence[float],
                        total: int) -> AmortizeErrorFit:
    """Fit the error model (module docstring) to error runs at (``samples[i]``, ``blends[i]``)
    with mean errors ``errors[i]`` (non-finite runs left out); nlopt's Nelder–Mead over (a, b) ≥ 0
    on the errors divided by their largest. Never returns NaN."""
    import nlopt

    m = np.asarray(samples, dtype=np.float64)
    lam = np.asarray(blends, dtype=np.float64)
    e = np.asarray(errors, dtype=np.float64)
    if not (m.shape == lam.shape == e.shape):
        raise RRCacheError("samples, blends and errors must have one value per run", "amortization model")
    keep = np.isfinite(m) & np.isfinite(lam) & np.isfinite(e) & (m >= 1) & (lam >= 0) & (lam < 1)
    m, lam, e = m[keep], lam[keep], np.maximum(e[keep], 0.0)
    n = int(e.size)
    if n == 0:
        return AmortizeErrorFit(0.0, 0.0, int(total), 1.0, 0.0, 0, "insufficient")
    scale = float(e.max())
    if scale <= 0:
        return AmortizeErrorFit(0.0, 0.0, int(total), 1.0, 0.0, n, "zero")
    noise, lag = _terms(m, lam, total)
    y = e / scale

    def sse(v, grad=None):
        r = v[0] * noise + v[1] * lag - y
        return float(np.dot(r, r))

    # start: the best of a few closed-form least-squares points with one coefficient or both
    starts = [np.array([float(np.dot(noise, y) / max(np.dot(noise, noise), 1e-300)), 0.0]),
              np.array([0.0, float(np.dot(lag, y) / max(np.dot(lag, lag), 1e-300))])]
    both, *_ = np.linalg.lstsq(np.stack([noise, lag], axis=1), y, rcond=None)
    starts.append(np.maximum(both, 0.0))
    start = min(starts, key=sse)
    opt = nlopt.opt(nlopt.LN_NELDERMEAD, 2)
    opt.set_min_objective(sse)
    opt.set_lower_bounds([0.0, 0.0])
    opt.set_upper_bounds([1e6, 1e6])
    opt.set_xtol_rel(1e-10)
    opt.set_ftol_abs(1e-16)
    opt.set_maxeval(4000)
    opt.set_initial_step([max(0.1 * start[0], 1e-3), max(0.1 * start[1], 1e-3)])
    try:
        v = opt.optimize(np.clip(start, 0.0, 1e6))
        if sse(v) > sse(start) or not np.all(np.isfinite(v)):
            v = start
    except (RuntimeError, ValueError, nlopt.RoundoffLimited):
        v = start
    a, b = float(v[0]) * scale, float(v[1]) * scale
    pred = a * noise + b * lag
    res = pred - e
    ss_res = float(np.dot(res, res))
    ss_tot = float(np.dot(e - e.mean(), e - e.mean()))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else 1.0
    quality = "insufficient" if n < 2 else ("poor" if r2 < 0.8 else "ok")
    return AmortizeErrorFit(a, b, int(total), float(min(r2, 1.0)), math.sqrt(ss_res / n), n, quality)


def _lag_squared(blends) -> np.ndarray:
    lam = np.clip(np.asarray(blends, dtype=np.float64), 0.0, 0.999)
    return lam / (1.0 - lam)


@dataclass(frozen=True)
class SlotsErrorFit:
    """ε̂(m, λ) = sqrt(c_m² + ``b``²·λ/(1−λ)) (module docstring, the slots history) with the
    floors c_m ``base`` at the m of ``samples`` (NaN at any other m: the profiler trains every
    m the slots fit); ``r2``, ``rms`` over the ``n`` runs; ``quality`` ``ok``, ``poor`` (R² <
    0.8), ``insufficient`` (no more runs than coefficients) or ``zero``.

    >>> fit = fit_slots_error([4, 4, 4, 8, 8, 8], [0, 0.6, 0.85] * 2, [0.0016, 0.0021, 0.0030, 0.0015, 0.0016, 0.0025], 16)
    >>> fit.samples, fit.quality, round(float(fit.predict(4, 0.0)), 4), bool(np.isnan(fit.predict(2, 0.0)))
    ((4, 8), 'ok', 0.0017, True)
    """

    samples: tuple
    base: tuple
    b: float
    total: int
    r2: float
    rms: float
    n: int
    quality: str

    def predict(self, samples, blend):
        m = np.asarray(samples, dtype=np.float64)
        floor = np.full(np.broadcast_shapes(m.shape, np.shape(blend)), np.nan)
        for k, c in zip(self.samples, self.base):
            floor = np.where(np.broadcast_to(m, floor.shape) == k, c, floor)
        out = np.sqrt(floor * floor + self.b * self.b * _lag_squared(blend))
        return float(out) if np.ndim(out) == 0 else out

    def to_json(self) -> dict:
        return {"samples": [int(m) for m in self.samples], "base": [float(c) for c in self.base], "b": self.b,
                "total": self.total, "r2": self.r2, "rms": self.rms, "n": self.n, "quality": self.quality}


def fit_slots_error(samples: Sequence[int], blends: Sequence[float], errors: Sequence[float],
                    total: int) -> SlotsErrorFit:
    """Fit the slots history's error model (module docstring) to error runs at (``samples[i]``,
    ``blends[i]``) with mean errors ``errors[i]`` (non-finite runs left out): nlopt's
    Nelder–Mead over (b, c_m...) ≥ 0 on the errors divided by their largest, from the best of a
    few closed-form starts. Never returns NaN."""
    import nlopt

    m = np.asarray(samples, dtype=np.float64)
    lam = np.asarray(blends, dtype=np.float64)
    e = np.asarray(errors, dtype=np.float64)
    if not (m.shape == lam.shape == e.shape):
        raise RRCacheError("samples, blends and errors must have one value per run", "amortization model")
    keep = np.isfinite(m) & np.isfinite(lam) & np.isfinite(e) & (m >= 1) & (lam >= 0) & (lam < 1)
    m, lam, e = m[keep].astype(np.int64), lam[keep], np.maximum(e[keep], 0.0)
    ms = tuple(int(v) for v in sorted(set(m.tolist())))
    n = int(e.size)
    if n == 0:
        return SlotsErrorFit((), (), 0.0, int(total), 1.0, 0.0, 0, "insufficient")
    scale = float(e.max())
    if scale <= 0:
        return SlotsErrorFit(ms, tuple(0.0 for _ in ms), 0.0, int(total), 1.0, 0.0, n, "zero")
    y = e / scale
    x = _lag_squared(lam)
    which = np.array([ms.index(int(v)) for v in m])

    def model(v):
        c = np.asarray(v[1:])[which]
        return np.sqrt(c * c + v[0] * v[0] * x)

    def sse(v, grad=None):
        r = model(v) - y
        return float(np.dot(r, r))

    # starts: each m's smallest-λ run as its floor with b from the rest on the squares; the
    # linear least squares of the squares (floors² and b² clipped at 0); b = 0 with each m's mean
    floors = np.array([y[which == k][np.argmin(lam[which == k])] for k in range(len(ms))])
    rest = y * y - floors[which] ** 2
    b2 = float(np.dot(x, rest) / np.dot(x, x)) if np.dot(x, x) > 0 else 0.0
    starts = [np.concatenate([[math.sqrt(max(b2, 0.0))], floors]),
              np.concatenate([[0.0], [float(y[which == k].mean()) for k in range(len(ms))]])]
    design = np.concatenate([x[:, None], (which[:, None] == np.arange(len(ms))[None, :]).astype(np.float64)], axis=1)
    sq, *_ = np.linalg.lstsq(design, y * y, rcond=None)
    starts.append(np.sqrt(np.maximum(sq, 0.0)))
    start = min(starts, key=sse)
    opt = nlopt.opt(nlopt.LN_NELDERMEAD, 1 + len(ms))
    opt.set_min_objective(sse)
    opt.set_lower_bounds([0.0] * (1 + len(ms)))
    opt.set_upper_bounds([1e6] * (1 + len(ms)))
    opt.set_xtol_rel(1e-10)
    opt.set_ftol_abs(1e-16)
    opt.set_maxeval(8000)
    opt.set_initial_step([max(0.1 * v, 1e-3) for v in start])
    try:
        v = opt.optimize(np.clip(start, 0.0, 1e6))
        if sse(v) > sse(start) or not np.all(np.isfinite(v)):
            v = start
    except (RuntimeError, ValueError, nlopt.RoundoffLimited):
        v = start
    v = np.asarray(v, dtype=np.float64)
    pred = model(v) * scale
    res = pred - e
    ss_res = float(np.dot(res, res))
    ss_tot = float(np.dot(e - e.mean(), e - e.mean()))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else 1.0
    quality = "insufficient" if n <= len(ms) else ("poor" if r2 < 0.8 else "ok")
    return SlotsErrorFit(ms, tuple(float(c) * scale for c in v[1:]), float(v[0]) * scale, int(total),
                         float(min(r2, 1.0)), math.sqrt(ss_res / n), n, quality)


def fit_error(history: str, samples, blends, errors, total: int):
    """The error model of ``history`` (``blend``: :func:`fit_amortized_error`; ``slots``:
    :func:`fit_slots_error`) fitted to its runs."""
    if history == "slots":
        return fit_slots_error(samples, blends, errors, total)
    return fit_amortized_error(samples, blends, errors, total)


@dataclass(frozen=True)
class AnchoredFit:
    """An estimator's error ``fit`` held to its own error runs: ε̂ × the run's measured/predicted
    ratio, interpolated in log between the runs (over λ at a trained m, then over log m between
    trained m; held constant past the ends). At a run's (m, λ) it predicts what that run
    measured; elsewhere the fit's shape carries the nearest runs' ratio.

    Why: the fits are least squares on the error, so the small errors of many samples and a high
    blend weigh nothing in them, while a level reads them in dB. On many_lights (N = 32, runs at
    m = 1, 4, 16 × λ = 0, 0.6, 0.85) the fit was within 15% of the m = 1 runs and 3.6× over the
    m = 16, λ = 0.85 run (11 dB), and validation measured `e1 m=16 λ=0.9` 10.6 dB over its
    prediction (docs/levels.md). Everything else (``quality``, ``total``, ``samples``, ...) is the
    fit's.

    >>> fit = fit_amortized_error([1, 1, 4, 4], [0.0, 0.6, 0.0, 0.6], [0.02, 0.01, 0.01, 0.001], 16)
    >>> held = anchored(fit, [1, 1, 4, 4], [0.0, 0.6, 0.0, 0.6], [0.02, 0.01, 0.01, 0.001])
    >>> round(held.predict(4, 0.6), 6), round(held.predict(4, 0.9) / fit.predict(4, 0.9), 3), held.predict(16, 0.0)
    (0.001, 0.226, 0.0)
    >>> held.quality == fit.quality
    True
    """

    fit: object
    anchor_samples: tuple  # the m of the runs
    anchor_ratios: tuple  # per m of anchor_samples: ((λ, log measured/predicted), ...) by λ

    def __getattr__(self, name):  # only what the dataclass does not hold: the fit's
        if name.startswith("__") or name in ("fit", "anchor_samples", "anchor_ratios"):
            raise AttributeError(name)
        return getattr(self.fit, name)

    def _log_ratio(self, m: float, lam: float) -> float:
        at = [float(np.interp(lam, [p[0] for p in row], [p[1] for p in row])) for row in self.anchor_ratios]
        if len(at) == 1:
            return at[0]
        return float(np.interp(math.log(max(m, 1e-9)), [math.log(k) for k in self.anchor_samples], at))

    def predict(self, samples, blend):
        base = self.fit.predict(samples, blend)
        m, lam = np.broadcast_arrays(np.asarray(samples, dtype=np.float64), np.asarray(blend, dtype=np.float64))
        factor = np.array([math.exp(self._log_ratio(float(a), float(b))) for a, b in zip(m.ravel(), lam.ravel())])
        out = np.asarray(base, dtype=np.float64) * factor.reshape(m.shape)
        return float(out) if np.ndim(out) == 0 else out

    def to_json(self) -> dict:
        return self.fit.to_json()


def anchored(fit, samples: Sequence[int], blends: Sequence[float], errors: Sequence[float]):
    """``fit`` held to the runs (``samples[i]``, ``blends[i]``, ``errors[i]``)
    (:class:`AnchoredFit`); ``fit`` itself where no run has a finite error > 0 and a prediction
    > 0 to compare it with."""
    by_m: dict[int, dict] = {}
    for m, lam, e in zip(samples, blends, errors):
        if not (e is not None and math.isfinite(float(e)) and float(e) > 0):
            continue
        pred = float(fit.predict(int(m), float(lam)))
        if not (math.isfinite(pred) and pred > 0):
            continue
        by_m.setdefault(int(m), {}).setdefault(float(lam), []).append(math.log(float(e) / pred))
    if not by_m:
        return fit
    ms = tuple(sorted(by_m))  # runs repeated at one (m, λ): their mean ratio
    return AnchoredFit(fit, ms, tuple(tuple((lam, float(np.mean(r))) for lam, r in sorted(by_m[m].items()))
                                      for m in ms))


def error_fit_from_json(history: str, data: dict):
    """The error fit of ``history`` from its ``error_fit`` record (what ``to_json`` wrote)."""
    if history == "slots":
        return SlotsErrorFit(tuple(int(m) for m in data["samples"]), tuple(float(c) for c in data["base"]),
                             float(data["b"]), int(data["total"]), float(data["r2"]), float(data["rms"]),
                             int(data["n"]), str(data["quality"]))
    return AmortizeErrorFit(**{k: data[k] for k in ("a", "b", "total", "r2", "rms", "n", "quality")})


@dataclass(frozen=True)
class AmortizeTimeFit:
    """Frame time = ``fixed_ms`` + ``t_sample`` · (terms evaluated over the frame); ``rms``
    the residual (ms) over ``n`` timed frames; ``quality`` ``ok`` or ``insufficient`` (fewer than
    two distinct term counts: ``t_sample`` from the line through the origin)."""

    fixed_ms: float
    t_sample: float
    rms: float
    n: int
    quality: str

    def frame_ms(self, evaluated):
        return self.fixed_ms + self.t_sample * np.asarray(evaluated, dtype=np.float64)


def fit_amortized_time(evaluated: Sequence[float], ms: Sequence[float]) -> AmortizeTimeFit:
    """Least squares of ``ms`` on the terms ``evaluated`` per frame, both coefficients ≥ 0."""
    x = np.asarray(evaluated, dtype=np.float64)
    y = np.asarray(ms, dtype=np.float64)
    keep = np.isfinite(x) & np.isfinite(y) & (x >= 0) & (y >= 0)
    x, y = x[keep], y[keep]
    n = int(x.size)
    if n == 0:
        return AmortizeTimeFit(0.0, 0.0, 0.0, 0, "insufficient")
    if np.ptp(x) <= 0:
        slope = float(y.mean() / x.mean()) if x.mean() > 0 else 0.0
        return AmortizeTimeFit(0.0, slope, float(np.sqrt(np.mean((slope * x - y) ** 2))), n, "insufficient")
    slope, fixed = np.polyfit(x, y, 1)
    if fixed < 0:  # through the origin
        fixed, slope = 0.0, float(np.dot(x, y) / np.dot(x, x))
    if slope < 0:
        fixed, slope = float(y.mean()), 0.0
    res = fixed + slope * x - y
    return AmortizeTimeFit(float(fixed), float(slope), float(np.sqrt(np.mean(res * res))), n, "ok")


@dataclass(frozen=True)
class AmortizeModel:
    """One trained estimator's models for one history: ``estimator`` id, ``total`` N,
    ``error`` (:class:`AmortizeErrorFit` for ``blend``, :class:`SlotsErrorFit` for ``slots``) and
    ``time`` fits, ``hit_rate`` h (the timing runs'), ``pixels`` P (mean covered pixels per
    frame), ``psnr`` (a :class:`~rrcache.model.psnr.PsnrFit` or None), ``text`` (the loop),
    ``history``, ``components`` (the accumulators' payload components; None: not recorded),
    ``payload`` (the payload format its runs used, which its options compile with)."""

    estimator: str
    total: int
    error: object
    time: AmortizeTimeFit
    hit_rate: float
    pixels: float
    psnr: object = None
    text: Optional[str] = None
    history: str = "blend"
    components: Optional[int] = None
    payload: str = "f4"

    def sample_counts(self) -> list[int]:
        """The m this history is offered at: :func:`sample_counts` for ``blend``; for ``slots``
        the trained m where the slots fit (:func:`rrcache.selection.slots_fit`)."""
        if self.history != "slots":
            return sample_counts(self.total)
        trained = [int(m) for m in getattr(self.error, "samples", ())]
        if self.components is None:
            return trained
        return [m for m in trained if slots_fit(self.total, m, self.components) is None]

    def evaluated(self, samples) -> np.ndarray:
        h = min(max(self.hit_rate, 0.0), 1.0)
        return self.pixels * (h * np.asarray(samples, dtype=np.float64) + (1.0 - h) * self.total)

    def options(self, original_ms: float) -> list[Selection]:
        """Every (m, λ) of :meth:`sample_counts` × :data:`BLEND_GRID` as a predicted
        :class:`Selection` (one :class:`AmortizedLoop` part of this history)."""
        out = []
        for m in self.sample_counts():
            ms = float(self.time.frame_ms(self.evaluated(m)))
            for lam in BLEND_GRID:
                err = max(float(self.error.predict(m, lam)), 0.0)
                sel = Selection((AmortizedLoop(self.estimator, int(m), float(round(lam, 6)), self.history,
                                               text=self.text, payload=self.payload),),
                                err, ms, float(original_ms) / ms if ms > 0 else math.inf)
                if self.psnr is not None:
                    sel = sel.replace(predicted_psnr=float(self.psnr.predict(err)) if err > 0 else None)
                out.append(sel)
        return out


def admissible(options: Sequence[Selection], original_ms: float, max_error: Optional[float] = None,
               min_psnr: Optional[float] = None) -> list[Selection]:
    """The options predicted faster than the original within the level (error ≤ ``max_error``,
    or predicted PSNR ≥ ``min_psnr``), fastest first.

    >>> s = Selection((AmortizedLoop("e1", 4, 0.6),), 0.01, 2.0, 2.0)
    >>> [x.predicted_ms for x in admissible([s], 4.0, max_error=0.02)], admissible([s], 4.0, max_error=0.001)
    ([2.0], [])
    """
    out = []
    for s in options:
        if not s.predicted_ms < original_ms:
            continue
        if max_error is not None and not s.predicted_error <= max_error:
            continue
        if min_psnr is not None and not (s.predicted_psnr is not None and s.predicted_psnr >= min_psnr):
            continue
        out.append(s)
    return sorted(out, key=lambda s: (s.predicted_ms, s.predicted_error))


def front(options: Sequence[Selection]) -> list[Selection]:
    """The options on the lower-left error-against-time frontier, fastest first."""
    best = math.inf
    out = []
    for s in sorted(options, key=lambda s: (s.predicted_ms, s.predicted_error)):
        if s.predicted_error < best:
            out.append(s)
            best = s.predicted_error
    return out
