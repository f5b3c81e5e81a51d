"""The PSNR model: a cached variant's PSNR against the original, predicted from its error model.

The error model (:mod:`rrcache.model.error`) predicts the mean RGB L2 error ε̂ of a node at any
refresh period; users read image quality in PSNR (dB). The two are measured together in every
training run (the run's mean error and its mean per-frame PSNR), so per node the rule is fitted
to them:

    PSNR̂(node, Δn) = a + b · log10 ε̂(node, Δn)

by least squares over the node's training runs (a and b per node). For a fixed shape of the
error's distribution PSNR = const − 20·log10(RMS) and the RMS is proportional to the mean error,
so b = −20; measured slopes are shallower (about −16 on the demo scene: longer periods spread
the error over more pixels, which raises the mean more than the RMS), hence b is fitted, bounded
to [−40, −5]. With fewer than two distinct errors b = −20 through the mean point. Error 0 (Δn =
1, or a node whose cached value never changes) predicts an exact image (PSNR ∞). ``rms`` is the
fit's residual (dB) over its training runs, floored at :data:`MIN_UNCERTAINTY_DB`. The training
runs' PSNRs are of the error window; a profile shifts ``a`` by :func:`coverage_offset_db` to
predict the PSNR of the frames (or timing window) validation measures.

The uncertainty shown beside a predicted PSNR (:func:`prediction_uncertainty`) is more than that
residual: the PSNR is predicted from the *error model's* ε̂, trained on the first frames of the
session inside an error window, and validated over the whole session. Three terms, added in
quadrature (dB):

- the PSNR rule's residual ``rms`` (above);
- the error model's own error: leaving each training period out, refitting ε̂ on the others and
  predicting it (:func:`loo_db`, the RMS over the periods, through the slope b);
- the error's drift over the session (:func:`frame_spread`): the training frames split into
  :data:`FRAME_BLOCKS` consecutive blocks, the RMS of log10(block mean / mean) at the trained
  period nearest the chosen one, through |b|. On Marble the camera's path makes the error of the
  same cache 2–4× larger on the first 16 training frames than on the last 16, so frames the
  training never saw move the session's mean by about as much; the residual alone (0.25 dB)
  said nothing of that, and validation measured 3–4 dB below the prediction.

>>> round(frame_spread([0.0, 4.0, 4.0, 1.0, 1.0]), 3)   # blocks 4, 4, 1, 1 of mean 2.5: log10 1.6, log10 0.4
0.316

>>> fit = fit_psnr([0.01, 0.0311, 0.0688, 0.1037], [40.5, 32.3, 26.8, 24.3])
>>> round(fit.b, 1), round(float(fit.predict(0.05)), 1), fit.quality
(-16.0, 29.2, 'ok')
>>> float(fit.predict(0.0))
inf
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

#: the physically expected slope (PSNR of an RMS proportional to the mean error), and the bounds
SLOPE = -20.0
SLOPE_BOUNDS = (-40.0, -5.0)
#: the least uncertainty shown beside a predicted PSNR (dB)
MIN_UNCERTAINTY_DB = 0.25
#: the PSNR the harness caps a per-frame PSNR at (identical frames): such runs carry no slope
PSNR_CAP = 100.0
#: below this PSNR a selection shows visible artifacts (dB)
VISIBLE_DB = 30.0
#: the default quality levels (dB), e1 to e4
DEFAULT_LEVELS_DB = (45.0, 40.0, 35.0, 30.0)


@dataclass(frozen=True)
class PsnrFit:
    """``a``, ``b`` of PSNR̂ = a + b·log10 ε̂; ``rms`` the residual (dB), ``n`` the runs used,
    ``quality`` ``ok``, ``fixed_slope`` (b = −20: fewer than two distinct errors) or
    ``no_data``."""

    a: float
    b: float
    rms: float
    n: int
    quality: str

    def predict(self, errors):
        """PSNR̂ (dB) at ``errors`` (inf where the error is 0; nan without data)."""
        e = np.asarray(errors, dtype=np.float64)
        if self.quality == "no_data":
            return np.full(e.shape, np.nan) if e.ndim else float("nan")
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.where(e > 0, self.a + self.b * np.log10(np.where(e > 0, e, 1.0)), np.inf)
        return out if e.ndim else float(out)

    def max_error(self, min_psnr: float) -> float:
        """The largest error whose predicted PSNR is ≥ ``min_psnr``."""
        if self.quality == "no_data":
            return 0.0
        return float(10.0 ** ((min_psnr - self.a) / self.b))

    @property
    def uncertainty(self) -> float:
        return max(self.rms, MIN_UNCERTAINTY_DB)


def fit_psnr(errors, psnrs) -> PsnrFit:
    """Fit the rule of the module docstring to one node's training runs (mean errors and mean
    PSNRs); runs with error ≤ 0, a capped PSNR or non-finite values are left out."""
    e = np.asarray(errors, dtype=np.float64)
    p = np.asarray(psnrs, dtype=np.float64)
    keep = np.isfinite(e) & np.isfinite(p) & (e > 0) & (p < PSNR_CAP)
    e, p = e[keep], p[keep]
    if e.size == 0:
        return PsnrFit(float("nan"), SLOPE, float("nan"), 0, "no_data")
    x = np.log10(e)
    if np.ptp(x) < 1e-6 or e.size < 2:
        a = float(np.mean(p - SLOPE * x))
        return PsnrFit(a, SLOPE, _rms(p - (a + SLOPE * x)), int(e.size), "fixed_slope")
    b, a = np.polyfit(x, p, 1)
    b = float(min(max(b, SLOPE_BOUNDS[0]), SLOPE_BOUNDS[1]))
    a = float(np.mean(p - b * x))
    return PsnrFit(a, b, _rms(p - (a + b * x)), int(e.size), "ok")


#: consecutive blocks the training frames are split into by :func:`frame_spread`
FRAME_BLOCKS = 4


def frame_spread(frame_errors, blocks: int = FRAME_BLOCKS) -> float:
    """How much a training run's mean error depends on which frames it covers: the frames after
    the first (which has no cache) split into ``blocks`` consecutive blocks, the RMS over the
    blocks of log10(block mean / mean of all). 0 with fewer frames than blocks or a zero mean."""
    e = np.asarray(frame_errors, dtype=np.float64)[1:]
    e = e[np.isfinite(e)]
    if e.size < blocks or not np.mean(e) > 0:
        return 0.0
    means = np.array([b.mean() for b in np.array_split(e, blocks)])
    means = np.maximum(means, 1e-12 * float(np.mean(e)))
    return _rms(np.log10(means / float(np.mean(e))))


def loo_db(periods, errors, slope: float) -> float:
    """The error model's leave-one-out error in dB: each training period left out, ε̂ refitted on
    the others (:func:`rrcache.model.error.fit_error`) and compared with the measured error there,
    |slope|·log10(ε̂/ε), RMS over the periods (0 with fewer than three positive errors)."""
    from rrcache.model.error import fit_error

    p = np.asarray(periods, dtype=np.float64)
    e = np.asarray(errors, dtype=np.float64)
    keep = np.isfinite(p) & np.isfinite(e) & (e > 0) & (p > 1)
    p, e = p[keep], e[keep]
    if p.size < 3:
        return 0.0
    out = []
    for j in range(p.size):
        fit = fit_error(np.delete(p, j), np.delete(e, j))
        guess = float(fit.predict(p[j]))
        if guess > 0:
            out.append(abs(slope) * math.log10(guess / e[j]))
    return _rms(np.asarray(out)) if out else 0.0


def prediction_uncertainty(fit: "PsnrFit", loo: float = 0.0, spread: float = 0.0) -> float:
    """The ± (dB) of a predicted PSNR: the rule's residual (:attr:`PsnrFit.uncertainty`), the error
    model's leave-one-out error ``loo`` (dB) and the frames' spread ``spread`` (log10 units, through
    |b|), in quadrature.

    >>> fit = PsnrFit(a=0.0, b=-16.0, rms=0.1, n=7, quality="ok")
    >>> round(prediction_uncertainty(fit, 0.3, 0.2), 2)
    3.22
    """
    terms = (fit.uncertainty, float(loo), abs(fit.b) * float(spread))
    return float(math.sqrt(sum(t * t for t in terms if math.isfinite(t))))


def coverage_offset_db(train_covered: float, train_area: float, check_covered: float, check_area: float) -> float:
    """What to add to a PSNR measured where the object covers ``train_covered`` of
    ``train_area`` pixels to get it where it covers ``check_covered`` of ``check_area``. The
    mean error is over covered pixels, the PSNR over the whole image (uncovered pixels are
    identical), so at the same mean error PSNR changes by 10·log10(f_train / f_check) with f the
    covered fraction: the training's error window sits where the object covers the most (Marble:
    91% of it), the validated frame or timing window less (Marble: 51%, +2.5 dB; the SDF scene:
    67%, +1.7 dB). 0 when a figure is missing.

    >>> round(coverage_offset_db(900, 1000, 500, 1000), 2)
    2.55
    """
    if not (train_covered > 0 and train_area > 0 and check_covered > 0 and check_area > 0):
        return 0.0
    return 10.0 * math.log10((train_covered / train_area) / (check_covered / check_area))


def _rms(r: np.ndarray) -> float:
    return float(math.sqrt(float(np.mean(r * r)))) if r.size else float("nan")


def psnr_grid(table, fits) -> np.ndarray:
    """PSNR̂ over a :class:`~rrcache.model.selection.ModelTable`'s error grid (N × P), one
    :class:`PsnrFit` per node in table order (None: unknown, -inf)."""
    out = np.full(table.E.shape, -np.inf)
    for i, fit in enumerate(fits):
        if fit is not None and fit.quality != "no_data":
            out[i] = fit.predict(np.where(np.isfinite(table.E[i]), table.E[i], np.nan))
    return np.where(np.isnan(out), -np.inf, out)


def select_min_psnr(table, fits, min_psnr: float):
    """The option predicted fastest with PSNR̂ ≥ ``min_psnr`` (what
    :func:`rrcache.model.select` returns; the original when nothing admissible is faster)."""
    grid = psnr_grid(table, fits).ravel()
    cand = np.where(grid >= float(min_psnr), table._t_fast, np.inf)
    if cand.size == 0:
        return table.original()
    idx = int(np.argmin(cand))
    if not math.isfinite(cand[idx]):
        return table.original()
    return table.option(idx)


def predicted_psnr(fit: Optional[PsnrFit], error: float, loo: float = 0.0,
                   spread: float = 0.0) -> tuple[float, float]:
    """(PSNR̂, ± uncertainty) of ``error`` under ``fit`` (inf, 0 for the exact original); the
    uncertainty is :func:`prediction_uncertainty` with ``loo`` and ``spread``."""
    if error is None or not error > 0:
        return math.inf, 0.0
    if fit is None or fit.quality == "no_data":
        return float("nan"), float("nan")
    return float(fit.predict(error)), prediction_uncertainty(fit, loo, spread)


def psnr_text(value: Optional[float], digits: int = 1) -> str:
    """How a PSNR is shown: '∞ (exact)' for an identical image, '–' when unknown.

    >>> psnr_text(float("inf")), psnr_text(41.234), psnr_text(None)
    ('∞ (exact)', '41.2', '–')
    """
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    if math.isinf(value) or value >= PSNR_CAP:
        return "∞ (exact)"
    return f"{value:.{digits}f}"
