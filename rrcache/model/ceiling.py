"""The ceiling: the most any cached variant of a shader can gain here (the arithmetic; the
measurement is :func:`rrcache.profiler.ceiling.measure_ceiling`).

A cache cannot render a frame faster than its all-hit frame (:mod:`rrcache.harness.limit`):
every pixel reprojects, the shading after the cached value still runs, and the cache's own work
stays — its extra pass(es) over the geometry, the reprojection fetches, the render targets. So
before anything is trained the profiler measures, on a few frames beside the original, the
all-hit frame of the costliest node to train (the node that leaves the least shading after it)
for each algorithm it may use, and the same two renders at 8×8 pixels (the per-frame cost of the
geometry, which does not grow with the pixels; the fastest of those frames, since other work on
a shared machine only adds time). That splits each side into a fixed cost per frame
and a cost per covered pixel:

    original ≈ O_g + M·o        all-hit cached ≈ L_g + M·l

(M the covered pixels of a full frame, o the shader's cost per covered pixel, l the cache's).
The **ceiling** is original / all-hit at the session's resolution (measured directly on whole
frames; extrapolated with the split when an expensive shader is timed in a window). When it is
below ``min_gain`` no node can reach a gain worth having, and the profiler stops with that
answer, the reason (o against l and the geometry) and what would change it: a shader costing
more per pixel (the cost ``o`` that would reach the gain), a higher resolution (only when
o/l > min_gain: the geometry's share falls as pixels grow), or another renderer (a GPU, where
the cache's passes cost a different share: measured there, not assumed).

**Pruning.** A node whose static cost is a share ``s`` of the costliest node's leaves about
(1 − s)·o per pixel of shading after it, so its best case is about O / (L + (1 − s)·M·o): nodes
whose best case is below ``min_gain`` are not trained.

>>> c = Ceiling("n1", "f(x)", "two-pass", pixels=1000, measured_pixels=1000, original_ms=1.5, limit_ms=1.2,
...             original_fixed_ms=0.5, limit_fixed_ms=0.7, min_gain=1.1)
>>> round(c.speedup, 2), c.reaches, round(c.original_ns_per_pixel), round(c.cache_ns_per_pixel)
(1.25, True, 1000, 500)
>>> round(c.node_speedup(0.5), 3)
0.882
"""
from __future__ import annotations

import math
import statistics
from dataclasses import asdict, dataclass, field
from typing import Optional


#: the gain below which the profiler answers "the original" without training
DEFAULT_MIN_GAIN = 1.1
#: relative noise of the original's repeated frame times above which a measurement is unreliable
UNRELIABLE_NOISE = 0.1


def relative_noise(samples_by_frame: list[list[float]]) -> float:
    """The measurement noise of repeated frame times: per frame the half-range of its repeats
    relative to their median, the median over frames (0 when nothing is repeated).

    >>> relative_noise([[10, 11, 9], [20, 20, 20]])
    0.05
    """
    spreads = [(max(s) - min(s)) / 2 / statistics.median(s) for s in samples_by_frame
               if len(s) > 1 and statistics.median(s) > 0]
    return float(statistics.median(spreads)) if spreads else 0.0


@dataclass
class Ceiling:
    """The measured ceiling (see the module docstring). Times in ms; ``measured_pixels`` the
    covered pixels of the measured renders (the window's when ``windowed``), ``pixels`` a full
    frame's; ``algorithms``: algorithm → its ceiling; ``noise``: the original's relative
    frame-time noise during the measurement."""

    node: str
    node_text: str
    algorithm: str
    pixels: float
    measured_pixels: float
    original_ms: float
    limit_ms: float
    original_fixed_ms: float
    limit_fixed_ms: float
    min_gain: float = DEFAULT_MIN_GAIN
    windowed: bool = False
    algorithms: dict = field(default_factory=dict)
    noise: float = 0.0
    color_format: str = "rgba8"
    frames: list = field(default_factory=list)
    wall_s: float = 0.0

    # ------------------------------------------------------------------ the split
    @property
    def original_ns_per_pixel(self) -> float:
        """o: the shader's cost per covered pixel (ns)."""
        return _per_pixel(self.original_ms, self.original_fixed_ms, self.measured_pixels)

    @property
    def cache_ns_per_pixel(self) -> float:
        """l: the all-hit cached pipeline's cost per covered pixel (ns)."""
        return _per_pixel(self.limit_ms, self.limit_fixed_ms, self.measured_pixels)

    def _frame_ms(self, pixels: float) -> tuple[float, float]:
        o, l = self.original_ns_per_pixel * 1e-6, self.cache_ns_per_pixel * 1e-6
        return self.original_fixed_ms + pixels * o, self.limit_fixed_ms + pixels * l

    @property
    def speedup(self) -> float:
        """The ceiling at the session's resolution: measured on whole frames, else extrapolated."""
        if not self.windowed:
            return self.original_ms / self.limit_ms if self.limit_ms > 0 else math.inf
        original, cached = self._frame_ms(self.pixels)
        return original / cached if cached > 0 else math.inf

    @property
    def reaches(self) -> bool:
        """Whether a gain of ``min_gain`` is within the ceiling."""
        return self.speedup >= self.min_gain

    def node_speedup(self, share: float) -> float:
        """The best case of a node whose static cost is ``share`` of the costliest node's: the
        ceiling with (1 − share) of the shader's per-pixel cost still run at every hit."""
        original, cached = self._frame_ms(self.pixels)
        if not self.windowed:
            original, cached = self.original_ms, self.limit_ms
        rest = (1.0 - min(max(share, 0.0), 1.0)) * self.pixels * self.original_ns_per_pixel * 1e-6
        return original / (cached + rest) if cached + rest > 0 else math.inf

    # ------------------------------------------------------------------ words
    def reason(self) -> str:
        """Why the ceiling is where it is, from the measured split."""
        o, l = self.original_ns_per_pixel, self.cache_ns_per_pixel
        return (f"the shader costs {o:.0f} ns per covered pixel; with every pixel hitting the cache's "
                f"{self.algorithm} pipeline still costs {l:.0f} ns per covered pixel (its passes, reprojection "
                f"fetches and render targets, and the shading left after {self.node}, "
                f"{self.node_text or 'the costliest node'}) plus "
                f"{self.limit_fixed_ms:.2f} ms per frame over the geometry against the original's "
                f"{self.original_fixed_ms:.2f} ms; so at most {self.speedup:.2f}× at "
                f"{self.pixels:,.0f} covered pixels")

    def changes(self) -> list[str]:
        """What would move the ceiling above ``min_gain``."""
        g, o, l = self.min_gain, self.original_ns_per_pixel * 1e-6, self.cache_ns_per_pixel * 1e-6
        m = max(self.pixels, 1.0)
        needed = (g * (self.limit_fixed_ms + m * l) - self.original_fixed_ms) / m
        out = [f"a costlier shader: about {max(needed, 0.0) * 1e6:.0f} ns per covered pixel or more "
               f"(this one costs {o * 1e6:.0f}) would reach {g:.2f}× at this resolution"]
        if l > 0 and o / l > g:
            pixels = (g * self.limit_fixed_ms - self.original_fixed_ms) / (o - g * l)
            scale = math.sqrt(max(pixels, 0.0) / m)
            out.append(f"a higher resolution: the geometry's fixed cost weighs less as pixels grow; about "
                       f"{scale:.1f}× the width and height would reach {g:.2f}× (per pixel the cap is "
                       f"{o / l:.2f}×)")
        else:
            out.append(f"not the resolution: per covered pixel alone the cache costs {l / o if o > 0 else math.inf:.2f} "
                       "of the shader, so no resolution reaches the gain")
        out.append("another renderer: on a GPU the cache's passes cost a different share; "
                   "run 'rrcache profile' there (it measures this, it does not assume it)")
        return out

    def summary(self) -> str:
        """One line: the ceiling and what was measured."""
        alts = ", ".join(f"{a} {s:.2f}×" for a, s in sorted(self.algorithms.items(), key=lambda kv: -kv[1]))
        return (f"{self.speedup:.2f}× (all pixels hitting, {self.algorithm}; measured {alts} on "
                f"{len(self.frames)} frames in {self.wall_s:.1f} s)")

    def to_json(self) -> dict:
        doc = asdict(self)
        doc.update(speedup=self.speedup, reaches=self.reaches, original_ns_per_pixel=self.original_ns_per_pixel,
                   cache_ns_per_pixel=self.cache_ns_per_pixel, reason=self.reason(), changes=self.changes())
        return doc

    @classmethod
    def from_json(cls, data: Optional[dict]) -> Optional["Ceiling"]:
        if not data:
            return None
        names = set(cls.__dataclass_fields__)
        return cls(**{k: (float("nan") if v is None and k.endswith("_ms") else v)
                      for k, v in data.items() if k in names})


def _per_pixel(ms: float, fixed_ms: float, pixels: float) -> float:
    if not pixels > 0:
        return 0.0
    return max(ms - fixed_ms, 0.0) / pixels * 1e6
