"""Choosing where the renderer shades next: the priority image dithered under a sample budget, and
predictive sampling on the next camera's occupancy image.

The renderer shades aligned ``k×k`` pixel *blocks* (:class:`~rrcache.kinds.render_cache.RenderCacheSettings`);
everything here works on the block grid (``ceil(W/k) × ceil(H/k)``, flat row-major, GL
orientation) and the budget counts ``k²`` pixels per block, partial blocks at the frame's edge
included, so the pixels shaded never exceed the budget.

- :func:`dither`: error-diffusion dithering of the priority image. The priorities are scaled so
  that they sum to the budget (none above 1: the excess goes to the others), then the
  quantisation error is carried from block to block along a Hilbert curve over the grid
  (Riemersma's error diffusion): a block is chosen where the running sum crosses an integer. The
  curve keeps the error local in both directions, as a 2-D error-diffusion kernel does, and the
  running sum is one ``cumsum`` (a Floyd–Steinberg scan is sequential: a Python loop per pixel).
  The number chosen is the budget rounded down, never more.
- :func:`predicted_requests`: the paper's predictive sampling: one request at the centre of every
  empty pixel of the quarter-resolution occupancy image, decimated to every ``n``-th in scanline
  order when there are more than allowed.

>>> order = hilbert_order(4, 4)
>>> order.tolist()
[0, 1, 5, 4, 8, 12, 13, 9, 10, 14, 15, 11, 7, 6, 2, 3]
>>> chosen = dither(np.ones(16), order, budget=4, phase=0.5)
>>> len(chosen)
4
>>> sorted(chosen.tolist())  # one block in each quadrant
[1, 6, 12, 14]
"""
from __future__ import annotations

import math
from functools import lru_cache
from typing import Optional

import numpy as np


def grid_size(size: tuple[int, int], block: int) -> tuple[int, int]:
    """The block grid of a ``size`` frame: ``(ceil(W/k), ceil(H/k))``."""
    return -(-size[0] // block), -(-size[1] // block)


@lru_cache(maxsize=8)
def hilbert_order(width: int, height: int) -> np.ndarray:
    """The flat indices of a ``width×height`` grid in the order of a Hilbert curve over the
    enclosing power-of-two square (cells outside the grid skipped). Read-only, cached."""
    n = 1 << max(0, math.ceil(math.log2(max(width, height, 1))))
    t = np.arange(n * n, dtype=np.int64)
    x = np.zeros_like(t)
    y = np.zeros_like(t)
    s = 1
    while s < n:
        rx = 1 & (t >> 1)
        ry = 1 & (t ^ rx)
        flip = (ry == 0) & (rx == 1)
        x = np.where(flip, s - 1 - x, x)
        y = np.where(flip, s - 1 - y, y)
        swap = ry == 0
        x, y = np.where(swap, y, x), np.where(swap, x, y)
        x += s * rx
        y += s * ry
        t >>= 2
        s <<= 1
    inside = (x < width) & (y < height)
    order = (y * width + x)[inside]
    order.setflags(write=False)
    return order


def block_priority(priority: np.ndarray, block: int) -> np.ndarray:
    """The summed priority of each ``block×block`` block of an ``H×W`` priority image (flat)."""
    h, w = priority.shape
    if block == 1:
        return priority.reshape(-1).astype(np.float64)
    gw, gh = grid_size((w, h), block)
    padded = np.zeros((gh * block, gw * block), np.float64)
    padded[:h, :w] = priority
    return padded.reshape(gh, block, gw, block).sum(axis=(1, 3)).reshape(-1)


def scaled(priority: np.ndarray, budget: float, excluded: Optional[np.ndarray] = None,
           iterations: int = 64) -> np.ndarray:
    """``priority`` scaled to sum to ``budget`` with no entry above 1 (the excess is spread over the
    others) and 0 at the ``excluded`` indices. Zero everywhere else (nothing asks for samples):
    spread evenly; a budget that covers every entry asking for samples: those get 1 and the rest
    is spread over the others."""
    p = np.maximum(np.asarray(priority, np.float64), 0.0)
    allowed = np.ones(p.size, bool)
    if excluded is not None and len(excluded):
        allowed[excluded] = False
        p[excluded] = 0.0
    n = int(allowed.sum())
    if n == 0 or budget <= 0:
        return np.zeros(p.size)
    if budget >= n:
        return allowed.astype(np.float64)
    asking = p > 0
    wanting = int(asking.sum())
    if budget >= wanting:
        return np.where(asking, 1.0, np.where(allowed, (budget - wanting) / max(1, n - wanting), 0.0))
    p *= budget / p.sum()
    for _ in range(iterations):
        if not (p > 1.0).any():
            break
        full = p >= 1.0
        p[full] = 1.0
        rest = ~full
        p[rest] *= (budget - full.sum()) / p[rest].sum()
    return np.minimum(p, 1.0)


def dither(priority: np.ndarray, order: np.ndarray, budget: int, phase: float = 0.5,
           excluded: Optional[np.ndarray] = None) -> np.ndarray:
    """The blocks chosen (flat indices, in curve order) for a block ``priority`` (flat) and a
    ``budget`` of blocks, never one of ``excluded``; ``phase`` in [0, 1) shifts where the running
    sum crosses integers."""
    budget = int(budget)
    if budget <= 0:
        return np.zeros(0, np.int64)
    p = scaled(priority, budget, excluded)[order]
    crossings = np.floor(np.cumsum(p) + phase)
    chosen = np.diff(crossings, prepend=np.floor(phase)) > 0
    return order[chosen][:budget]


def predicted_requests(occupied: np.ndarray, quarter: tuple[int, int], size: tuple[int, int], block: int,
                       allowed: int) -> np.ndarray:
    """The blocks (flat indices of the block grid, unique) requested for the empty pixels of the
    quarter-resolution occupancy image (flat bool, ``quarter`` = its (w, h)): at most ``allowed``,
    every ``n``-th empty pixel in scanline order when there are more."""
    if allowed <= 0:
        return np.zeros(0, np.int64)
    empty = np.flatnonzero(~occupied)
    if empty.size > allowed:
        step = -(-empty.size // allowed)
        empty = empty[::step][:allowed]
    qw, _qh = quarter
    w, h = size
    col = np.minimum(4 * (empty % qw) + 2, w - 1)
    row = np.minimum(4 * (empty // qw) + 2, h - 1)
    gw, _gh = grid_size(size, block)
    return np.unique((row // block) * gw + col // block)


def blocks_to_pixels(blocks: np.ndarray, size: tuple[int, int], block: int) -> np.ndarray:
    """The flat pixel indices (``row·W + col``) of the chosen blocks, cropped to the frame."""
    w, h = size
    gw, _gh = grid_size(size, block)
    bx, by = blocks % gw, blocks // gw
    dx, dy = np.meshgrid(np.arange(block), np.arange(block))
    cols = (bx[:, None] * block + dx.reshape(1, -1)).reshape(-1)
    rows = (by[:, None] * block + dy.reshape(1, -1)).reshape(-1)
    inside = (cols < w) & (rows < h)
    return rows[inside] * w + cols[inside]
