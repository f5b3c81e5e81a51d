"""The all-hit limit of a cached variant: its frame time when every covered pixel hits, beside
the original's, measured side by side.

A cache never renders faster than its all-hit frame (the frame shown again with nothing moving
and no refresh: every pixel reprojects and only the shading after the cached value runs), so
``original_ms / limit_ms`` bounds the speed-up any refresh period can reach. Both the cache
benchmark (:mod:`rrcache.bench.cache`) and the profiler's ceiling
(:mod:`rrcache.profile.ceiling`) measure it here.

Per probe frame the cached variant renders the frame ``repeats + 2`` times with every pixel
hitting (:meth:`~rrcache.harness.cached.CachedRenderer.render_static`, the first two untimed) and
the original renders the same frame between each two (a limit measured back to back, with the CPU
caches warm from the frame before, came out ~25% faster on Marble than the same frame measured
alternately); the limit is the median over the probe frames of each frame's median.

>>> lim = all_hit_limit(variant, session, prepared, [0, 30, 60])          # doctest: +SKIP
>>> round(lim.speedup, 2), lim.limit_ms < lim.original_ms                   # doctest: +SKIP
(3.4, True)
"""
from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

from rrcache.harness.cached import CachedRenderer
from rrcache.harness.renderer import Renderer


@dataclass
class AllHitLimit:
    """Per probe frame (``frames``): the all-hit cached time (``cached_ms``, the median of the
    repeats), the original's beside it (``original_ms``) and the original's covered pixels
    (``covered``); ``samples`` every original frame time measured (for the noise estimate)."""

    frames: list[int] = field(default_factory=list)
    cached_ms: list[float] = field(default_factory=list)
    original_ms: list[float] = field(default_factory=list)
    covered: list[int] = field(default_factory=list)
    samples: list[float] = field(default_factory=list)

    @property
    def limit_ms(self) -> float:
        return statistics.median(self.cached_ms) if self.cached_ms else float("nan")

    @property
    def original_median_ms(self) -> float:
        return statistics.median(self.original_ms) if self.original_ms else float("nan")

    @property
    def covered_pixels(self) -> float:
        return statistics.mean(self.covered) if self.covered else 0.0

    @property
    def speedup(self) -> float:
        return self.original_median_ms / self.limit_ms if self.limit_ms > 0 else float("nan")


def probe_frames(indices: Sequence[int], count: int = 5) -> list[int]:
    """Up to ``count`` frames spread over ``indices``.

    >>> probe_frames(range(60))
    [0, 12, 24, 36, 48]
    >>> probe_frames([3, 4], 5)
    [3, 4]
    """
    indices = list(indices)
    return indices[:: max(1, len(indices) // count)][:count]


def all_hit_limit(variant, session, prepared, frames: Sequence[int], resolution: Optional[tuple[int, int]] = None,
                  repeats: int = 5, period: int = 16, block: int = 4, refresh: str = "random",
                  depth_epsilon: float = 1e-3, window=None, color_format: str = "rgba32f",
                  on_frame: Optional[Callable[[int], None]] = None) -> AllHitLimit:
    """Measure the all-hit limit of ``variant`` beside the original on ``frames`` (see the
    module docstring), at ``resolution`` (default: the session's), inside ``window`` if given,
    both drawing into a ``color_format`` colour target. ``on_frame(index)`` after each frame."""
    out = AllHitLimit()
    with Renderer(prepared, session, resolution, window=window, color_format=color_format) as original, \
            CachedRenderer(variant, session, prepared, resolution, period=period, block=block, refresh=refresh,
                           depth_epsilon=depth_epsilon, window=window, color_format=color_format) as cached:
        for index in frames:
            times: list[float] = []
            covered: list[int] = []

            def between():
                got = original.render_frame(index)
                times.append(got.ms)
                covered.append(got.covered_pixels)

            out.cached_ms.append(cached.render_static(index, repeats=repeats, between=between))
            out.frames.append(int(index))
            out.original_ms.append(statistics.median(times[2:]))
            out.samples.extend(times[2:])
            out.covered.append(covered[-1])
            if on_frame is not None:
                on_frame(int(index))
    return out
