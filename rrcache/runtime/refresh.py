"""Refresh patterns: which pixels are recomputed at a given frame even when the cache hits.

A pixel at window position (x, y) is refreshed at frame ``clock`` when

    (floor(h(x // k, y // k) * Δn) + clock) mod Δn == 0

where ``h`` is a per-block value in [0, 1) stored in a small float texture and ``k`` the refresh
block size (Sitthi-amorn 2008a eq. 1; Nehab 2007 §5). Storing ``h`` in [0, 1) rather than an
integer in [0, Δn) lets one texture serve every refresh period (the period is a uniform, so one
compiled variant serves every Δn): ``floor(h * Δn)`` is uniform on [0, Δn) for random ``h``.

- ``random``: ``h`` is uniform random per block (Nehab §5.2). Every block is refreshed exactly
  once every Δn frames, at a random phase.
- ``tiled``: ``h`` is the block's raster index divided by the number of blocks (Nehab §5.1), so
  ``floor(h * Δn)`` splits the screen into Δn bands of consecutive block rows, refreshed in turn.

Blocks are aligned to the window origin so that, with k = 4, they coincide with llvmpipe's 4×4
early-depth blocks (DESIGN.md §5).
"""
from __future__ import annotations

import numpy as np

REFRESH_MODES = ("random", "tiled")
BLOCK_SIZES = (1, 2, 4, 8)


def block_grid(size: tuple[int, int], block: int) -> tuple[int, int]:
    """Number of refresh blocks (columns, rows) covering a ``size = (width, height)`` viewport."""
    w, h = size
    return (w + block - 1) // block, (h + block - 1) // block


def refresh_offsets(size: tuple[int, int], block: int = 4, mode: str = "random", seed: int = 0) -> np.ndarray:
    """The per-block ``h`` values as a float32 array of shape (rows, cols), row 0 = window y 0.

    >>> refresh_offsets((8, 4), block=4, mode="tiled").tolist()
    [[0.25, 0.75]]
    """
    if block not in BLOCK_SIZES:
        raise ValueError(f"refresh block size must be one of {BLOCK_SIZES}, not {block}")
    cols, rows = block_grid(size, block)
    if mode == "random":
        return np.random.default_rng(seed).random((rows, cols), dtype=np.float64).astype(np.float32)
    if mode == "tiled":
        index = np.arange(rows * cols, dtype=np.float64).reshape(rows, cols)
        return ((index + 0.5) / (rows * cols)).astype(np.float32)
    raise ValueError(f"refresh mode must be one of {REFRESH_MODES}, not {mode!r}")


def refresh_mask(offsets: np.ndarray, size: tuple[int, int], block: int, period: int, clock: int) -> np.ndarray:
    """Boolean (height, width) mask of the pixels refreshed at ``clock`` (the same rule as the GLSL,
    evaluated in float32 like the shader, for tests and hit maps).
    """
    w, h = size
    phase = np.floor(offsets.astype(np.float32) * np.float32(period)).astype(np.int64)
    refresh_blocks = (phase + clock) % period == 0
    return np.repeat(np.repeat(refresh_blocks, block, axis=0), block, axis=1)[:h, :w]
