"""Image reconstruction from the projected points (the paper's Fig. 1, after the z-buffer).

Arrays are ``H×W`` (GL orientation); colours are *planar* (``3×H×W`` float32: one plane per
channel, which numpy filters about twice as fast as ``H×W×3``), with zero padding at the
frame's edges (an edge pixel simply has fewer neighbours).

- :func:`depth_cull`: the 3×3 depth-cull heuristic of the original render cache: a point whose
  depth is more than ``1 + tolerance`` times the mean depth of the points in its 3×3 neighbourhood
  (itself included) is taken to be a hidden surface showing through a gap, and removed. Points
  the renderer shaded for this very frame (``exempt``) stay: the renderer resolved their
  visibility at that pixel.
- :func:`weighted3`: the 3×3 interpolation/smoothing filter (weights ``[1 2 1] ⊗ [1 2 1]``).
- :func:`box7`: the 7×7 uniform prefilter, computed only over the rows that need it.
- :func:`reconstruct`: the image: a pixel holding a point shows it (or, with ``smooth``, the 3×3
  weighted mean around it); a pixel without one takes the 3×3 weighted mean of the points around
  it when it finds at least ``min_points``, else the 7×7 uniform mean (the prefilter, used only
  where the 3×3 filter finds too few points), else keeps the previous frame's colour (the
  paper's choice for a pixel with nothing near). It also returns the paper's priority image:
  a pixel's point's age / 255, and 1 where the pixel has no point.

>>> import numpy as np
>>> depth = np.full((3, 3), 2.0, np.float32); depth[1, 1] = 9.0
>>> keep = depth_cull(depth, np.ones((3, 3), bool), 0.1)
>>> bool(keep[1, 1]), bool(keep[0, 0])
(False, True)
>>> weighted3(np.pad(np.ones((1, 1), np.float32), 1)).tolist()
[[1.0, 2.0, 1.0], [2.0, 4.0, 2.0], [1.0, 2.0, 1.0]]
"""
from __future__ import annotations

from typing import Callable, Optional

import numpy as np

#: the 3×3 interpolation/smoothing weights (the paper's Fig. 3); the 7×7 prefilter is uniform
WEIGHTS_3X3 = np.outer([1.0, 2.0, 1.0], [1.0, 2.0, 1.0])


def _pad(a: np.ndarray) -> np.ndarray:
    """``a`` (``H×W`` or planes ``C×H×W``) with one zero row and column on every side."""
    out = np.zeros(a.shape[:-2] + (a.shape[-2] + 2, a.shape[-1] + 2), a.dtype)
    out[..., 1:-1, 1:-1] = a
    return out


def box3(a: np.ndarray) -> np.ndarray:
    """The 3×3 sums of ``a`` (``H×W`` or planes ``C×H×W``), zero outside the frame."""
    p = _pad(a)
    rows = p[..., :-2, :] + p[..., 1:-1, :]
    rows += p[..., 2:, :]
    out = rows[..., :-2] + rows[..., 1:-1]
    out += rows[..., 2:]
    return out


def weighted3(a: np.ndarray) -> np.ndarray:
    """The ``[1 2 1] ⊗ [1 2 1]`` sums of ``a`` (``H×W`` or planes ``C×H×W``), zero outside the frame."""
    p = _pad(a)
    rows = p[..., 1:-1, :] + p[..., 1:-1, :]
    rows += p[..., :-2, :]
    rows += p[..., 2:, :]
    out = rows[..., 1:-1] + rows[..., 1:-1]
    out += rows[..., :-2]
    out += rows[..., 2:]
    return out


def _sum7(p: np.ndarray, axis: int, n: int) -> np.ndarray:
    """The sums of 7 consecutive entries along ``axis`` of ``p`` (padded by 3 on both sides)."""
    def part(k):
        return p[..., k:k + n, :] if axis == -2 else p[..., k:k + n]
    out = part(0) + part(1)
    for k in range(2, 7):
        out += part(k)
    return out


def box7(a: np.ndarray, rows: Optional[np.ndarray] = None) -> tuple[np.ndarray, int]:
    """The 7×7 sums of ``a`` (``H×W`` or planes ``C×H×W``) at the rows ``rows.min() ..
    rows.max()`` (all rows when None), zero outside the frame: ``(sums, first row)``. Shifted
    adds along each axis (measured faster here than running sums or scipy's filters)."""
    h, w = a.shape[-2:]
    lo, hi = (0, h) if rows is None or not len(rows) else (int(rows.min()), int(rows.max()) + 1)
    top, bottom = max(0, lo - 3), min(h, hi + 3)
    band = a[..., top:bottom, :]
    p = np.zeros(band.shape[:-1] + (w + 6,), np.float32)
    p[..., 3:-3] = band
    horizontal = _sum7(p, -1, w)
    q = np.zeros(band.shape[:-2] + (hi - lo + 6, w), np.float32)
    # rows lo-3 .. hi+2 of the image (zero beyond its edges), from the band's rows top .. bottom-1
    q[..., top - (lo - 3):top - (lo - 3) + (bottom - top), :] = horizontal
    return _sum7(q, -2, hi - lo), lo


def depth_cull(depth: np.ndarray, has_point: np.ndarray, tolerance: float,
               exempt: Optional[np.ndarray] = None) -> np.ndarray:
    """Which points survive the depth cull (see the module docstring): ``H×W`` bool."""
    v = has_point.astype(np.float32)
    d = np.where(has_point, depth, np.float32(0.0)).astype(np.float32)
    total, count = box3(d), box3(v)
    keep = has_point & (d * count <= (1.0 + tolerance) * total)
    if exempt is not None:
        keep |= exempt & has_point
    return keep


def _gather7(a: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """The 7×7 sums of planes ``a`` (``C×H×W``) at the pixels ``(rows, cols)`` only: ``C×n``."""
    p = np.zeros(a.shape[:-2] + (a.shape[-2] + 6, a.shape[-1] + 6), a.dtype)
    p[..., 3:-3, 3:-3] = a
    out = np.zeros(a.shape[:-2] + (len(rows),), np.float32)
    for dy in range(7):
        for dx in range(7):
            out += p[..., rows + dy, cols + dx]
    return out


#: below this share of the pixels needing it, the prefilter sums each pixel's 49 neighbours
#: directly; above, it filters the band of rows that holds them
SPARSE_PREFILTER = 0.01


def reconstruct(colors: np.ndarray, keep: np.ndarray, ages: np.ndarray, previous: np.ndarray,
                min_points: int = 1, smooth: bool = False,
                clock: Optional[Callable[[str], None]] = None) -> tuple[np.ndarray, np.ndarray, dict]:
    """The image and priority from the surviving points.

    ``colors`` ``3×H×W`` (the surviving point's colour where ``keep``, zero elsewhere), ``ages``
    ``H×W`` (its age), ``previous`` the last displayed image (``3×H×W``). Returns ``(image 3×H×W,
    priority H×W, counts)``, counts being how many pixels each filter filled (``point``,
    ``interpolated``, ``prefiltered``, ``empty``: kept from the previous frame). ``clock(stage)``
    (optional) is called when the interpolation (with the priority image) and the prefilter are
    done."""
    v = keep.astype(np.float32)
    stack = np.empty((4,) + keep.shape, np.float32)
    stack[:3] = colors
    stack[3] = v
    w3 = weighted3(stack)
    found = w3[3] > 0 if min_points <= 1 else box3(v) >= min_points
    use3 = found if smooth else found & ~keep
    need7 = ~found & ~keep
    # the image as a blend (measured 2-3× faster here than masked copies): the interpolated colour
    # where the 3×3 filter is used, plus the point's colour where there is one (``colors`` is zero
    # elsewhere), then the previous frame's colour where neither filled the pixel
    weight = np.maximum(w3[3], np.float32(1e-30))
    image = np.divide(w3[:3], weight, out=w3[:3])
    image *= use3.astype(np.float32)
    if not smooth:
        image += colors
    np.copyto(image, previous, where=need7 if not smooth else ~found)
    priority = ages * np.float32(1.0 / 255.0)
    np.copyto(priority, np.float32(1.0), where=~keep)
    if clock is not None:
        clock("interpolate")
    rows, cols = np.nonzero(need7)
    prefiltered = 0
    if len(rows) and len(rows) <= SPARSE_PREFILTER * keep.size:
        sums = _gather7(stack, rows, cols)
        fill = sums[3] > 0
        image[:, rows[fill], cols[fill]] = sums[:3, fill] / sums[3, fill]
        prefiltered = int(fill.sum())
    elif len(rows):
        sums, first = box7(stack, rows)
        band = need7[first:first + sums.shape[1]] & (sums[3] > 0)
        np.divide(sums[:3], np.maximum(sums[3], np.float32(1e-30)), out=sums[:3])
        np.copyto(image[:, first:first + sums.shape[1]], sums[:3], where=band)
        prefiltered = int(np.count_nonzero(band))
    if clock is not None:
        clock("prefilter")
    counts = {"point": 0 if smooth else int(np.count_nonzero(keep)), "interpolated": int(np.count_nonzero(use3)),
              "prefiltered": prefiltered, "empty": len(rows) - prefiltered}
    return image, priority, counts
