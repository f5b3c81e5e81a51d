"""Perceptual and temporal measures of a cached variant against the original (docs/levels.md).

PSNR counts every channel difference alike; a reprojection cache's errors are smears, lags and
blurred detail, which people see more or less than their squared size says. Two measures are
taken beside PSNR on the frames validation renders:

- :func:`flip_mean`: NVIDIA's FLIP (Andersson et al. 2020, the ``flip-evaluator`` package), the
  per-pixel difference a person perceives when flipping between the two images, for standard
  viewing (67 pixels per degree), pooled to its mean over the frame as its authors recommend for
  a single number. 0 is identical; the visible-artifact threshold is
  :data:`rrcache.model.levels.VISIBLE_FLIP` (justified in docs/levels.md).
- the **temporal error** (:class:`FrameQuality`): the PSNR of the frame-to-frame *changes*:
  (cached_t − cached_{t−1}) against (original_t − original_{t−1}), over the whole frame, peak 1.
  A constant offset does not change it; a value that lags behind the surface, a highlight that
  sticks, a shadow that smears, does.

The images are the harness's linear float frames, row 0 on top, taken as display values in
[0, 1] (clamped; what an 8-bit target would show), so FLIP reads them as sRGB-encoded LDR.

>>> import numpy as np
>>> a = np.full((32, 32, 4), 0.5, np.float32); b = a.copy(); b[8:24, 8:24, :3] = 0.6
>>> 0.0 < flip_mean(b, a) < 0.2, flip_mean(a, a)
(True, 0.0)
>>> q = FrameQuality(flip_frames={2})
>>> for i, shift in enumerate((0.0, 0.01, 0.02)):
...     q.add(i, a + shift, a + 2 * shift)
>>> round(q.temporal_psnr, 1), len(q.flips)
(40.0, 1)
"""
from __future__ import annotations

import math
from typing import Iterable, Optional

import numpy as np

#: frames of a validation on which FLIP is computed (spread over the steady frames): about a
#: third of a second each at 640×480 on this machine's CPU
FLIP_FRAMES = 10


def _display(img: np.ndarray) -> np.ndarray:
    rgb = np.asarray(img, dtype=np.float32)[..., :3]
    return np.ascontiguousarray(np.clip(np.nan_to_num(rgb, nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0))


def flip_mean(image: np.ndarray, reference: np.ndarray) -> float:
    """Mean FLIP of ``image`` against ``reference`` (H×W×C, C ≥ 3; see the module docstring)."""
    import flip_evaluator

    a, b = _display(reference), _display(image)
    if a.shape != b.shape:
        raise ValueError(f"image sizes differ: {b.shape[1]}×{b.shape[0]} and {a.shape[1]}×{a.shape[0]}")
    if np.array_equal(a, b):
        return 0.0
    _, mean, _ = flip_evaluator.evaluate(a, b, "LDR", inputsRGB=True, applyMagma=False, computeMeanError=True)
    return float(mean)


def flip_frame_indices(frames: Iterable[int], count: int = FLIP_FRAMES) -> list[int]:
    """``count`` of ``frames`` spread evenly over them, the first left out (it has no cache).

    >>> flip_frame_indices(range(150), 4)
    [1, 50, 100, 149]
    """
    steady = list(frames)[1:]
    if len(steady) <= count:
        return steady
    return [steady[int(round(i))] for i in np.linspace(0, len(steady) - 1, count)]


class FrameQuality:
    """Accumulates FLIP (on ``flip_frames``) and the temporal error (on every consecutive pair
    after the first frame) as frames arrive in order through :meth:`add`."""

    def __init__(self, flip_frames: Iterable[int] = ()):
        self.flip_frames = set(int(i) for i in flip_frames)
        self.flips: list[float] = []
        self.temporal_mse: list[float] = []
        self._previous: Optional[tuple[int, np.ndarray, np.ndarray]] = None
        self._first: Optional[int] = None

    def add(self, index: int, image: np.ndarray, reference: np.ndarray) -> None:
        """Frame ``index`` (cached ``image``, original ``reference``)."""
        img, ref = _display(image), _display(reference)
        if self._first is None:
            self._first = index
        if index in self.flip_frames:
            self.flips.append(flip_mean(img, ref))
        if self._previous is not None and self._previous[0] == index - 1 and self._previous[0] != self._first:
            _, prev_img, prev_ref = self._previous
            d = (img - prev_img) - (ref - prev_ref)
            self.temporal_mse.append(float(np.mean(d.astype(np.float64) ** 2)))
        self._previous = (index, img, ref)

    @property
    def flip(self) -> Optional[float]:
        """Mean FLIP over the FLIP frames (None when none was rendered)."""
        return float(np.mean(self.flips)) if self.flips else None

    @property
    def temporal_psnr(self) -> Optional[float]:
        """PSNR (dB, peak 1) of the frame-to-frame changes over the pairs (None without a pair;
        inf when they match exactly)."""
        if not self.temporal_mse:
            return None
        mse = float(np.mean(self.temporal_mse))
        return math.inf if mse <= 0 else float(10.0 * math.log10(1.0 / mse))
