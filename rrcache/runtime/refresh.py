"""Refresh patterns: which pixels are recomputed at a given frame even when the cache hits.

A pixel at window position (x, y) is refreshed at frame ``clock`` when

    (n(x >> s, y >> s) + clock) mod Δn == 0,    k = 2^s the refresh block size,

where ``n`` is the block's phase in [0, Δn) (Sitthi-amorn 2008a eq. 1; Nehab 2007 §5). The shader
tests the equivalent ``n == (−clock) mod Δn`` with the right side a uniform, so it needs no
integer division, and it computes ``n`` from the block coordinates with arithmetic alone, so it
needs no texture: on llvmpipe every texel fetch costs about 5 ns per pixel, and the per-block
offset texture this replaced cost ~0.8 ms of Marble's ~13 ms all-hit frame at 640×480 (measured
side by side, 2026-12-01). One compiled variant still serves every Δn (the period is a uniform).

- ``random`` (Nehab §5.2): ``u`` = the top 24 bits of a 32-bit integer hash of the block
  coordinates and the seed, ``n = min(⌊u · (Δn / 2^24)⌋, Δn − 1)``: every block is refreshed
  exactly once every Δn frames, at a random phase.
- ``tiled`` (Nehab §5.1): ``u`` = the block's raster index + 0.5, ``n = min(⌊u · (Δn / B)⌋,
  Δn − 1)`` with B blocks in all: the screen splits into Δn bands of consecutive blocks,
  refreshed in turn.

The scale ``Δn / 2^24`` or ``Δn / B`` is computed here in float32 and passed as a uniform, so the
shader does one IEEE multiplication and :func:`refresh_phases` reproduces its result bit for
bit (tests compare hit maps pixel for pixel). Blocks are aligned to the target's origin so that,
with k = 4, they coincide with llvmpipe's 4×4 early-depth blocks (docs/design.md §5).
"""
from __future__ import annotations

import numpy as np

REFRESH_MODES = ("random", "tiled")
BLOCK_SIZES = (1, 2, 4, 8)

_MASK = 0xFFFFFFFF

#: the GLSL of the rule; the runtime sets the uniforms (see :func:`refresh_uniforms`)
REFRESH_GLSL = """\
uniform int rr_period;
uniform int rr_refreshPhase;
uniform int rr_blockShift;
uniform bool rr_tiled;
uniform uint rr_seed;
uniform float rr_refreshScale;
uniform int rr_blockColumns;

// the block's rank: its hash (random) or its index (tiled); a period's phases split the ranks
float rr_blockRank() {
    ivec2 b = ivec2(gl_FragCoord.xy) >> rr_blockShift;
    uint x = (uint(b.x) * 0x8da6b343u) ^ (uint(b.y) * 0xd8163841u) ^ rr_seed;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return rr_tiled ? float(b.y * rr_blockColumns + b.x) + 0.5 : float(x >> 8u);
}

bool rr_refreshNow() {
    return min(int(rr_blockRank() * rr_refreshScale), rr_period - 1) == rr_refreshPhase;
}
"""


def check(block: int, mode: str) -> None:
    if block not in BLOCK_SIZES:
        raise ValueError(f"refresh block size must be one of {BLOCK_SIZES}, not {block}")
    if mode not in REFRESH_MODES:
        raise ValueError(f"refresh mode must be one of {REFRESH_MODES}, not {mode!r}")


def block_grid(size: tuple[int, int], block: int) -> tuple[int, int]:
    """Number of refresh blocks (columns, rows) covering a ``size = (width, height)`` target."""
    w, h = size
    return (w + block - 1) // block, (h + block - 1) // block


def seed_word(seed: int) -> int:
    """The 32-bit word the shader mixes into the hash for ``seed``."""
    return (int(seed) * 0x9E3779B9 + 0x7F4A7C15) & _MASK


def refresh_scale(size: tuple[int, int], block: int, mode: str, period: int) -> np.float32:
    """The float32 factor from ``u`` to the phase (``Δn / 2^24`` or ``Δn / B``)."""
    check(block, mode)
    if mode == "random":
        return np.float32(np.float32(period) * np.float32(2.0 ** -24))
    cols, rows = block_grid(size, block)
    return np.float32(period / (cols * rows))


def refresh_uniforms(size: tuple[int, int], block: int, mode: str, seed: int, period: int,
                     clock: int) -> dict:
    """The values of the rule's uniforms at frame ``clock``."""
    return {
        "rr_period": int(period),
        "rr_refreshPhase": int((-clock) % period),
        "rr_blockShift": int(block).bit_length() - 1,
        "rr_tiled": mode == "tiled",
        "rr_seed": seed_word(seed),
        "rr_refreshScale": float(refresh_scale(size, block, mode, period)),
        "rr_blockColumns": block_grid(size, block)[0],
    }


def _hash(bx: np.ndarray, by: np.ndarray, seed: int) -> np.ndarray:
    x = (bx.astype(np.uint64) * 0x8DA6B343 & _MASK) ^ (by.astype(np.uint64) * 0xD8163841 & _MASK) ^ seed_word(seed)
    x ^= x >> 16
    x = x * 0x7FEB352D & _MASK
    x ^= x >> 15
    x = x * 0x846CA68B & _MASK
    x ^= x >> 16
    return x


def refresh_phases(size: tuple[int, int], block: int, mode: str, seed: int, period: int) -> np.ndarray:
    """Each block's phase ``n`` in [0, Δn) as the shader computes it: an int64 array of shape
    (rows, cols), row 0 = window y 0.

    >>> refresh_phases((8, 4), block=4, mode="tiled", seed=0, period=2).tolist()
    [[0, 1]]
    """
    check(block, mode)
    cols, rows = block_grid(size, block)
    by, bx = np.mgrid[0:rows, 0:cols]
    if mode == "random":
        u = (_hash(bx, by, seed) >> 8).astype(np.float32)
    else:
        u = (by * cols + bx).astype(np.float32) + np.float32(0.5)
    scaled = u * refresh_scale(size, block, mode, period)
    return np.minimum(np.floor(scaled).astype(np.int64), period - 1)


def refresh_mask(size: tuple[int, int], block: int, mode: str, seed: int, period: int, clock: int) -> np.ndarray:
    """Boolean (height, width) mask of the pixels refreshed at ``clock`` (row 0 = window y 0),
    the shader's rule exactly (for tests and hit maps)."""
    w, h = size
    blocks = (refresh_phases(size, block, mode, seed, period) + clock) % period == 0
    return np.repeat(np.repeat(blocks, block, axis=0), block, axis=1)[:h, :w]
