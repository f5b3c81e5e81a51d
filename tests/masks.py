"""Boolean image-mask helpers shared by the cache tests (not a test module)."""
from __future__ import annotations

import numpy as np


def dilate(m: np.ndarray) -> np.ndarray:
    """``m`` grown by one pixel in the four directions."""
    out = m.copy()
    out[1:] |= m[:-1]
    out[:-1] |= m[1:]
    out[:, 1:] |= m[:, :-1]
    out[:, :-1] |= m[:, 1:]
    return out


def erode(m: np.ndarray) -> np.ndarray:
    """``m`` shrunk by one pixel in the four directions."""
    return ~dilate(~m)
