"""Error metrics on known arrays."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rrcache.harness.metrics import mean_l2, nonfinite_count, psnr


def test_mean_l2_over_mask_only():
    ref = np.zeros((2, 2, 4), np.float32)
    img = ref.copy()
    img[0, 0, :3] = (3, 4, 0)        # distance 5
    img[0, 1, :3] = (0, 0, 1)        # distance 1
    img[1, 1, 3] = 9.0               # alpha is ignored
    assert mean_l2(img, ref) == (pytest.approx(1.5), 0)
    mask = np.array([[True, True], [False, False]])
    assert mean_l2(img, ref, mask) == (pytest.approx(3.0), 0)
    assert mean_l2(img, ref, np.zeros((2, 2), bool)) == (0.0, 0)


def test_mean_l2_leaves_out_nonfinite_and_counts_them():
    ref = np.zeros((1, 3, 3))
    img = np.array([[[np.nan, 0, 0], [0, 2, 0], [np.inf, 0, 0]]])
    value, left_out = mean_l2(img, ref)
    assert value == pytest.approx(2.0) and left_out == 2
    ref2 = ref.copy()
    ref2[0, 1, 0] = np.nan           # non-finite in the reference counts too
    assert mean_l2(img, ref2) == (0.0, 3)
    assert mean_l2(img, ref, np.array([[False, True, False]])) == (pytest.approx(2.0), 0)


def test_psnr_known_values():
    a = np.zeros((4, 4, 3))
    assert psnr(a, a) == math.inf
    b = np.full((4, 4, 3), 0.1)
    assert psnr(b, a) == pytest.approx(20.0)
    # clamped to [0, 1]: values above 1 count as 1
    assert psnr(np.full((4, 4, 3), 5.0), np.ones((4, 4, 3))) == math.inf
    assert psnr(np.ones((2, 2, 4)), np.zeros((2, 2, 4))) == pytest.approx(0.0)


def test_nonfinite_count_looks_at_rgb():
    img = np.zeros((2, 3, 4), np.float32)
    img[0, 0, 0] = np.nan
    img[0, 0, 1] = np.inf            # same pixel
    img[1, 2, 2] = -np.inf
    img[1, 1, 3] = np.nan            # alpha: ignored
    assert nonfinite_count(img) == 2


def test_shape_errors():
    with pytest.raises(ValueError, match="sizes differ"):
        mean_l2(np.zeros((2, 2, 3)), np.zeros((3, 2, 3)))
    with pytest.raises(ValueError, match="mask shape"):
        mean_l2(np.zeros((2, 2, 3)), np.zeros((2, 2, 3)), np.zeros((3, 3), bool))
    with pytest.raises(ValueError, match="3 channels"):
        psnr(np.zeros((2, 2)), np.zeros((2, 2)))
