"""What it takes for a measured selection to stand at its level (docs/levels.md).

A level is a promise about what the user gets: a PSNR against the original (``min_psnr``, the
default levels 45, 40, 35, 30 dB), a mean error (``max_error``, ``--levels relative``) or a mean
FLIP (``max_flip``). Validation (:mod:`rrcache.profiler.validate`) renders a choice beside the
original and these pure rules say whether it may ship under that level:

- **quality** (:func:`quality_miss`): the measured figure may miss the level by no more than the
  measurement's own uncertainty. The uncertainty (:func:`batch_uncertainty`) is how much the
  session's mean would move with other frames like these: the steady frames split into
  :data:`BATCHES` consecutive batches, the standard error of the batch means (consecutive frames
  are alike, so batches, not frames, are the independent samples), times the two-sided 95%
  Student-t factor of that many batches (:data:`T95`).
- **speed** (:func:`speed_miss`): the median of the side-by-side repeats (three, by
  validation) reaches the gain worth having (``--min-gain``, 1.1× by default; at least 1.0), and no repeat measured it slower than
  the original (the repeats' spread is the timing's noise: a median above the gain with a repeat
  below 1.0 is not a gain the measurement supports).

Each rule returns None when the selection passes, else the reason in words.

>>> round(batch_uncertainty([40.0] * 20), 3)
0.0
>>> quality_miss(measured_psnr=40.7, psnr_uncertainty=0.3, min_psnr=45.0)
'measured 40.7 ± 0.3 dB, below the level 45 dB'
>>> quality_miss(measured_psnr=44.8, psnr_uncertainty=0.3, min_psnr=45.0) is None
True
>>> speed_miss((0.94, 0.97, 0.92), 1.1)
'measured 0.94× (0.92–0.97): slower than the original in every repeat'
>>> speed_miss((0.978, 1.041, 0.937), 1.1)
'measured 0.98× (0.94–1.04): below the gain worth having (1.10×)'
>>> speed_miss((1.07, 1.12, 0.998), 1.1)
'measured 1.07× (1.00–1.12): below the gain worth having (1.10×)'
>>> speed_miss((1.31, 1.12, 0.998), 1.1)
'measured 1.12× (1.00–1.31): a repeat measured it slower than the original'
>>> speed_miss((1.31, 1.22, 1.4), 1.1) is None
True
"""
from __future__ import annotations

import math
import statistics
from typing import Optional, Sequence

import numpy as np

#: mean FLIP at or above which a measured selection is marked as having visible artifacts
#: (docs/levels.md: a just-noticeable lightness difference on flat grey is 0.06–0.10 of FLIP per
#: pixel, so 0.03 is one over a third to a half of the frame; the SDF material cached at Δn = 4,
#: 6, 9 measured 0.027, 0.039, 0.053: the last two plainly smeared, the first barely)
VISIBLE_FLIP = 0.03

#: consecutive batches the steady frames are split into for the measurement's uncertainty
BATCHES = 10
#: two-sided 95% Student-t factors by degrees of freedom (batches − 1); 1.96 beyond the table
T95 = {1: 12.71, 2: 4.30, 3: 3.18, 4: 2.78, 5: 2.57, 6: 2.45, 7: 2.36, 8: 2.31, 9: 2.26}


def batch_uncertainty(values: Sequence[float], batches: int = BATCHES) -> float:
    """The ± (95%) of the mean of ``values`` (per-frame figures in frame order, the first frame
    already left out): the standard error of :data:`BATCHES` consecutive batch means times the
    Student-t factor. 0 for fewer than two values; with fewer values than batches, one batch per
    value.

    >>> round(batch_uncertainty([40, 42] * 10), 3)     # alternate frames average out in batches
    0.0
    >>> round(batch_uncertainty(list(np.linspace(38, 42, 20))), 2)
    0.91
    """
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], dtype=np.float64)
    if v.size < 2:
        return 0.0
    k = int(min(batches, v.size))
    means = np.array([b.mean() for b in np.array_split(v, k)])
    se = float(np.std(means, ddof=1) / math.sqrt(k))
    return float(T95.get(k - 1, 1.96) * se)


def quality_miss(measured_psnr: Optional[float] = None, psnr_uncertainty: float = 0.0,
                 min_psnr: Optional[float] = None, measured_error: Optional[float] = None,
                 error_uncertainty: float = 0.0, max_error: Optional[float] = None,
                 measured_flip: Optional[float] = None, flip_uncertainty: float = 0.0,
                 max_flip: Optional[float] = None, exact: bool = False) -> Optional[str]:
    """Why a measured selection misses its quality level beyond the measurement's uncertainty,
    or None. The level is whichever of ``min_psnr`` (dB), ``max_flip`` and ``max_error`` is set
    (PSNR first); an exact image (``exact``) meets every level. A figure that was not measured
    meets nothing."""
    if exact:
        return None
    if min_psnr is not None:
        if measured_psnr is None:
            return "no PSNR was measured"
        if measured_psnr + psnr_uncertainty < min_psnr:
            return f"measured {measured_psnr:.1f} ± {psnr_uncertainty:.1f} dB, below the level {min_psnr:g} dB"
    if max_flip is not None:
        if measured_flip is None:
            return "no FLIP was measured"
        if measured_flip - flip_uncertainty > max_flip:
            return f"measured FLIP {measured_flip:.4f} ± {flip_uncertainty:.4f}, above the level {max_flip:g}"
    if min_psnr is None and max_flip is None and max_error is not None:
        if measured_error is None:
            return "no error was measured"
        if measured_error - error_uncertainty > max_error:
            return f"measured error {measured_error:.4g} ± {error_uncertainty:.2g}, above the level {max_error:.4g}"
    return None


def speed_miss(speedups: Sequence[float], min_gain: float) -> Optional[str]:
    """Why measured speed-up repeats do not support shipping (see the module docstring), or None."""
    s = [float(x) for x in speedups if x is not None and math.isfinite(x)]
    if not s:
        return "no speed-up was measured"
    gain = max(1.0, float(min_gain))
    median = statistics.median(s)
    text = f"measured {median:.2f}×" + (f" ({min(s):.2f}–{max(s):.2f})" if len(s) > 1 else "")
    if max(s) < 1.0:
        return f"{text}: slower than the original in every repeat"
    if median < gain:
        return f"{text}: below the gain worth having ({gain:.2f}×)"
    if min(s) < 1.0:
        return f"{text}: a repeat measured it slower than the original"
    return None
