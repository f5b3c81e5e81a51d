"""Image error metrics (docs/design.md §3, "Models").

- :func:`mean_l2`: the paper's error: mean per-pixel Euclidean distance of RGB between an image
  and the reference, over the covered (shaded) pixels only. Pixels where either image is not
  finite are left out and counted, so one NaN does not poison a whole profile.
- :func:`psnr`: reported beside it, the usual way: whole frame, RGB clamped to [0, 1], peak 1.
- :func:`nonfinite_count`: pixels with a NaN or infinity in any RGB channel.

>>> import numpy as np
>>> a = np.zeros((2, 2, 4), np.float32); b = a.copy(); b[0, 0, :3] = (0.3, 0.4, 0.0)
>>> round(mean_l2(b, a)[0], 6), mean_l2(b, a)[1]
(0.125, 0)
>>> round(psnr(b, a), 3)
16.812
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np


def _rgb(img: np.ndarray, name: str) -> np.ndarray:
    arr = np.asarray(img)
    if arr.ndim != 3 or arr.shape[2] < 3:
        raise ValueError(f"{name} must be an H×W×C image with at least 3 channels, got shape {arr.shape}")
    return arr[..., :3].astype(np.float64)


def _check_same(img: np.ndarray, ref: np.ndarray) -> None:
    if img.shape[:2] != ref.shape[:2]:
        raise ValueError(f"image sizes differ: {img.shape[1]}×{img.shape[0]} and {ref.shape[1]}×{ref.shape[0]}")


def nonfinite_count(img: np.ndarray) -> int:
    """Pixels with a NaN or an infinity in R, G or B.

    >>> import numpy as np
    >>> img = np.zeros((2, 2, 4), np.float32); img[1, 1, 2] = np.inf
    >>> nonfinite_count(img)
    1
    """
    return int((~np.isfinite(_rgb(img, "image")).all(axis=2)).sum())


def mean_l2(img: np.ndarray, ref: np.ndarray, mask: Optional[np.ndarray] = None) -> tuple[float, int]:
    """``(mean RGB L2 distance over the masked pixels, pixels left out as non-finite)``.

    ``mask`` (H×W bool; None: every pixel) selects the covered pixels. The mean is over the masked
    pixels where both images are finite; it is 0.0 when none is left.

    >>> import numpy as np
    >>> ref = np.zeros((1, 2, 3)); img = np.array([[[3.0, 4.0, 0.0], [np.nan, 0, 0]]])
    >>> mean_l2(img, ref)
    (5.0, 1)
    >>> mean_l2(img, ref, np.array([[False, True]]))
    (0.0, 1)
    """
    a, b = _rgb(img, "image"), _rgb(ref, "reference")
    _check_same(a, b)
    if mask is None:
        mask = np.ones(a.shape[:2], dtype=bool)
    mask = np.asarray(mask, dtype=bool)
    if mask.shape != a.shape[:2]:
        raise ValueError(f"mask shape {mask.shape} does not match the image {a.shape[:2]}")
    finite = np.isfinite(a).all(axis=2) & np.isfinite(b).all(axis=2)
    use = mask & finite
    left_out = int((mask & ~finite).sum())
    if not use.any():
        return 0.0, left_out
    dist = np.sqrt(((a[use] - b[use]) ** 2).sum(axis=1))
    return float(dist.mean()), left_out


def clamped_rgb(img: np.ndarray) -> np.ndarray:
    """RGB as displayed: clamped to [0, 1], NaN as 0 and ±inf as 1 or 0 (what :func:`psnr` compares)."""
    return np.clip(np.nan_to_num(_rgb(img, "image"), nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)


def squared_error_map(img: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """H×W: each pixel's squared error of the :func:`clamped_rgb` colours, averaged over RGB (its
    mean is :func:`psnr`'s mean squared error).

    >>> import numpy as np
    >>> squared_error_map(np.full((1, 2, 3), 0.5), np.zeros((1, 2, 3))).tolist()
    [[0.25, 0.25]]
    """
    _check_same(_rgb(img, "image"), _rgb(ref, "reference"))
    return ((clamped_rgb(img) - clamped_rgb(ref)) ** 2).mean(axis=2)


def psnr(img: np.ndarray, ref: np.ndarray) -> float:
    """Peak signal-to-noise ratio in dB over the whole frame, RGB clamped to [0, 1] (NaN counts as
    0); ``inf`` when the clamped images are identical.

    >>> import numpy as np
    >>> psnr(np.zeros((2, 2, 3)), np.zeros((2, 2, 3)))
    inf
    >>> psnr(np.zeros((1, 1, 3)), np.ones((1, 1, 3)))
    0.0
    """
    mse = float(squared_error_map(img, ref).mean())
    if mse == 0.0:
        return math.inf
    return 10.0 * math.log10(1.0 / mse)
