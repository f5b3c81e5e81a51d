"""The all-hit limit of a cached variant: its frame time when every covered pixel hits, beside
the original's, measured side by side.

A cache never renders faster than its all-hit frame (the frame shown again with nothing moving
and no refresh: every pixel reprojects and only the shading after the cached value runs), so
``original_ms / limit_ms`` bounds the speed-up any refresh period can reach. Both the cache
benchmark (:mod:`rrcache.bench.cache`) and the profiler's ceiling
(:mod:`rrcache.profiler.ceiling`) measure it here.

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
from rrcache.harness.timing import DEFAULT_CLOCK


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
    def fastest_limit_ms(self) -> float:
        """The fastest probe frame's all-hit time (other work on the machine only adds time)."""
        return min(self.cached_ms) if self.cached_ms else float("nan")

    @property
    def fastest_original_ms(self) -> float:
        return min(self.samples) if self.samples else float("nan")

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
                  repeats: int = 5, window=None, color_format: str = "rgba32f",
                  on_frame: Optional[Callable[[int], None]] = None, clock: str = DEFAULT_CLOCK,
                  spec=None, **runtime) -> AllHitLimit:
    """Measure the all-hit limit of ``variant`` beside the original on ``frames`` (see the
    module docstring), at ``resolution`` (default: the session's), inside ``window`` if given,
    both drawing into a ``color_format`` colour target and timed with ``clock``
    (:mod:`rrcache.harness.timing`); ``spec`` or the runtime keywords (``period=`` (default 16),
    ``block=`` …) as for :class:`~rrcache.harness.cached.CachedRenderer`. ``on_frame(index)``
    after each frame."""
    out = AllHitLimit()
    if spec is None:
        runtime.setdefault("period", 16)
    with Renderer(prepared, session, resolution, window=window, color_format=color_format, clock=clock) as original, \
            CachedRenderer(variant, session, prepared, resolution, spec, window=window, color_format=color_format,
                           clock=clock, **runtime) as cached:
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


#: the resolution at which a stage's fixed cost (geometry: vertex processing, set-up, binning,
#: state changes) is measured: almost no pixel is shaded there
FIXED_SIZE = (8, 8)


@dataclass
class StageBreakdown:
    """Where an all-hit frame's time goes, per stage (the GPU waited for after each): ``full``
    stage → median ms at the measured size, ``fixed`` the same at :data:`FIXED_SIZE` (what does
    not grow with the pixels: geometry, state changes), ``pixels`` the covered pixels at the
    measured size; ``frame_ms`` the staged frame's median (clear to queries), ``plain_ms`` the
    same frame without the waits between stages."""

    full: dict = field(default_factory=dict)
    fixed: dict = field(default_factory=dict)
    pixels: float = 0.0
    frame_ms: float = float("nan")
    plain_ms: float = float("nan")

    def per_pixel_ns(self, stage: str) -> float:
        """The part of ``stage`` that grows with the covered pixels, per pixel (ns)."""
        if not self.pixels:
            return float("nan")
        return max(self.full.get(stage, 0.0) - self.fixed.get(stage, 0.0), 0.0) / self.pixels * 1e6

    def to_json(self) -> dict:
        return {"full_ms": self.full, "fixed_ms": self.fixed, "pixels": self.pixels, "frame_ms": self.frame_ms,
                "plain_ms": self.plain_ms, "per_pixel_ns": {k: self.per_pixel_ns(k) for k in self.full}}


def _medians(stages: dict) -> dict:
    return {k: statistics.median(v) for k, v in stages.items()}


def all_hit_breakdown(variant, session, prepared, frames: Sequence[int], resolution=None, repeats: int = 5,
                      period: int = 16, block: int = 4, color_format: str = "rgba32f",
                      on_frame: Optional[Callable[[int], None]] = None) -> tuple[StageBreakdown, StageBreakdown]:
    """(cached, original): the per-stage cost of ``variant``'s all-hit frame and of the
    original's frame, alternating frame by frame as :func:`all_hit_limit` measures, at
    ``resolution`` and at :data:`FIXED_SIZE`. Stages of the cached frame: ``clear``, each pass
    (``reproject``/``payload``/``shade`` or ``hit``/``miss``), ``queries`` (the occlusion
    query results) and ``read-back`` (colour and depth, what the harness reads after a timed
    frame); of the original: ``clear``, ``draw``, ``queries``, ``read-back``."""
    cached_out, original_out = StageBreakdown(), StageBreakdown()
    for size, key in ((resolution, "full"), (FIXED_SIZE, "fixed")):
        cached_stages: dict = {}
        original_stages: dict = {}
        frame_ms, plain_ms, covered = [], [], []
        with Renderer(prepared, session, size, color_format=color_format) as original, \
                CachedRenderer(variant, session, prepared, size, period=period, block=block,
                               color_format=color_format) as cached:
            for index in frames:
                def between():
                    got = original.render_frame(index, stages=original_stages)
                    covered.append(got.covered_pixels)

                frame_ms.append(cached.render_static(index, repeats=repeats, between=between, stages=cached_stages))
                plain_ms.append(cached.render_static(index, repeats=repeats))
                if on_frame is not None:
                    on_frame(int(index))
        setattr(cached_out, key, _medians(cached_stages))
        setattr(original_out, key, _medians(original_stages))
        if key == "full":
            cached_out.pixels = original_out.pixels = statistics.mean(covered) if covered else 0.0
            cached_out.frame_ms, cached_out.plain_ms = statistics.median(frame_ms), statistics.median(plain_ms)
            original_out.frame_ms = sum(original_out.full.get(k, 0.0) for k in ("clear", "draw"))
    return cached_out, original_out
