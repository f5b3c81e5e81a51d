"""How far a timing can be trusted: the noise of frame times and the spread of a speed-up.

Speed-ups are ratios of median frame times measured side by side (the original and the variant
alternating frame by frame). Two figures say how much such a number can move:

- :func:`frame_noise`: the noise of a run's frame times, estimated from the original's own
  times: consecutive frames differ little in content, so the spread of their differences is
  mostly the machine's (robust: 1.4826 × the median absolute difference / √2, relative to the
  median time). On a quiet machine it is a few per cent; other work on the machine raises it.
  Above :data:`UNRELIABLE_NOISE` a timing is flagged as unreliable.
- :func:`ratio_interval`: a bootstrap interval of the ratio of medians, resampling the
  (original, variant) frame pairs (seeded, so a run gives the same interval every time it is
  summarised).

>>> round(frame_noise([10.0, 10.2, 9.9, 10.1, 10.0]), 4)
0.021
>>> lo, hi = ratio_interval([10, 11, 10, 12, 10, 11], [5, 5.5, 5, 6, 5, 5.4])
>>> lo <= 2.0 <= hi
True
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

#: relative frame-time noise above which a timing is called unreliable
UNRELIABLE_NOISE = 0.1
BOOTSTRAP = 2000


def frame_noise(times: Sequence[float]) -> float:
    """The relative noise of consecutive frame times (see the module docstring); 0 for fewer
    than three frames."""
    t = np.asarray([v for v in times if v is not None and math.isfinite(v)], dtype=np.float64)
    if t.size < 3 or not np.median(t) > 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(np.diff(t))) / math.sqrt(2.0) / np.median(t))


def ratio_interval(original: Sequence[float], variant: Sequence[float], level: float = 0.95,
                   seed: int = 0) -> tuple[float, float]:
    """A ``level`` bootstrap interval of median(original) / median(variant) over frame pairs."""
    o = np.asarray(original, dtype=np.float64)
    v = np.asarray(variant, dtype=np.float64)
    if o.size == 0 or o.size != v.size:
        return (float("nan"), float("nan"))
    if o.size == 1:
        r = float(o[0] / v[0]) if v[0] > 0 else float("nan")
        return (r, r)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, o.size, size=(BOOTSTRAP, o.size))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.median(o[idx], axis=1) / np.median(v[idx], axis=1)
    ratios = ratios[np.isfinite(ratios)]
    if not ratios.size:
        return (float("nan"), float("nan"))
    tail = (1.0 - level) / 2.0 * 100.0
    return (float(np.percentile(ratios, tail)), float(np.percentile(ratios, 100.0 - tail)))


def load_warning(noise: float) -> str:
    """The warning for a run whose frame-time noise is ``noise`` ('' when it is reliable)."""
    if noise <= UNRELIABLE_NOISE:
        return ""
    return (f"the original's frame times varied by ±{noise:.0%} from frame to frame (over {UNRELIABLE_NOISE:.0%}): "
            "other work on the machine made this timing unreliable; measure again on a quieter machine")
