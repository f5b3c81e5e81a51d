"""Kind ``render-cache``: the render cache of Walter, Drettakis and Greenberg 2002 (forward
reprojection of shaded points; :mod:`rrcache.alternatives.render_cache`, docs/render_cache.md).

It is an alternative to compare at equal time, **not a choice the profiler makes**: it has no
compiled variant (:meth:`RenderCacheKind.spec` and :meth:`RenderCacheKind.compile` refuse), no
training and no store tables, and nothing selects it. Its part is :class:`RenderCacheSettings`,
the frozen record of every knob (the share of the pixels shaded per frame first), with its JSON
and checks, so a measured render cache can stand in a :class:`~rrcache.selection.Selection`
beside the cached choices (the bench's equal-time table) and be described by the registry.

The defaults are the paper's where it gives one (the 7×7 and 3×3 filters, up to half the budget
on predicted samples, ages in [0, 255] reaching 128 when the ring overwrites them) and a measured
choice where it does not (docs/render_cache.md: the sample block, the cache size, the z-buffer).

>>> RenderCacheSettings(samples=0.05).checked().pixel_budget(640 * 480)
15360
>>> RenderCacheSettings(samples=1.5).checked()
Traceback (most recent call last):
...
rrcache.errors.RRCacheError: render cache: samples=1.5 is not a share of the pixels (hint: give 0 < F <= 1, e.g. 0.03 for 3% of the pixels per frame)
>>> from rrcache import kinds
>>> part = RenderCacheSettings(samples=0.03)
>>> kinds.kind_of((part,)).name, kinds.parts_from_json(kinds.parts_to_json((part,)), "parts") == (part,)
('render-cache', True)
>>> part.describe()
'render cache: 3% of the pixels per frame in 2×2 blocks'
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import ClassVar

from rrcache.errors import RRCacheError
from rrcache.kinds.base import Kind, only

#: sample blocks the renderer shades as one request (k×k pixels, aligned)
BLOCKS = (1, 2, 4)


@dataclass(frozen=True)
class RenderCacheSettings:
    """What the render cache does per frame (see :mod:`rrcache.alternatives.render_cache`).

    - ``samples``: share of the pixels the renderer may shade per frame (the budget, 0 < F ≤ 1);
    - ``points_per_pixel``: the point cache's fixed size as a multiple of the pixel count;
    - ``block``: the renderer shades aligned ``block``×``block`` pixel blocks (1: single pixels, as a
      ray tracer; 2: the quads a rasteriser shades together); the budget counts every pixel of a block;
    - ``predict``: predictive sampling on the next camera; ``predict_share`` of the budget at most;
    - ``cull``: the depth-cull tolerance (a point farther than ``1 + cull`` times its 3×3 mean depth goes);
    - ``min_points``: the 3×3 filter needs at least this many points, else the 7×7 prefilter fills;
    - ``smooth``: the 3×3 filter also smooths pixels that hold a point (off: they show their point);
    - ``invisible_rate``: a point not visible this frame ages this many times faster;
    - ``change_threshold``/``change_penalty``: a new sample differing from the displayed colour at its
      pixel by more than the threshold (RGB L2) adds the penalty to the ages of the points around it;
    - ``tiled``: bucket-sort the projected points into ``tile``×``tile`` tiles before the z-buffer;
    - ``seed``: the dither's phase per frame.

    It is the part of a render-cache choice (JSON tag ``render-cache``).
    """

    KIND: ClassVar[str] = "render-cache"

    samples: float = 0.03
    points_per_pixel: float = 1.0
    block: int = 2
    predict: bool = True
    predict_share: float = 0.5
    cull: float = 0.1
    min_points: int = 1
    smooth: bool = False
    invisible_rate: float = 4.0
    change_threshold: float = 0.1
    change_penalty: float = 64.0
    tiled: bool = False
    tile: int = 32
    seed: int = 0

    def checked(self) -> "RenderCacheSettings":
        """``self`` when every knob is in range, else an :class:`RRCacheError` naming it."""
        def bad(name, hint):
            raise RRCacheError(f"{name}={getattr(self, name)!r} {hint[0]}", "render cache", hint=hint[1])

        def number(v) -> bool:
            return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)

        if not (number(self.samples) and 0 < self.samples <= 1):
            bad("samples", ("is not a share of the pixels", "give 0 < F <= 1, e.g. 0.03 for 3% of the pixels per frame"))
        if not (number(self.points_per_pixel) and 0 < self.points_per_pixel <= 64):
            bad("points_per_pixel", ("is not a cache size", "give a multiple of the pixel count in (0, 64]"))
        if self.block not in BLOCKS:
            bad("block", ("is not a sample block", f"give one of {', '.join(map(str, BLOCKS))}"))
        if not (number(self.predict_share) and 0 <= self.predict_share <= 1):
            bad("predict_share", ("is not a share of the budget", "give a value in [0, 1]"))
        if not (number(self.cull) and self.cull >= 0):
            bad("cull", ("is not a depth tolerance", "give a relative tolerance >= 0, e.g. 0.1"))
        if not (isinstance(self.min_points, int) and 1 <= self.min_points <= 9):
            bad("min_points", ("is not a 3×3 point count", "give an integer in 1..9"))
        if not (number(self.invisible_rate) and self.invisible_rate >= 1):
            bad("invisible_rate", ("is not an ageing rate", "give a factor >= 1"))
        for name in ("change_threshold", "change_penalty"):
            if not (number(getattr(self, name)) and getattr(self, name) >= 0):
                bad(name, ("is negative or not a number", "give a value >= 0"))
        if not (isinstance(self.tile, int) and 4 <= self.tile <= 1024):
            bad("tile", ("is not a tile size", "give an integer in 4..1024"))
        return self

    def pixel_budget(self, pixels: int) -> int:
        """The pixels the renderer may shade per frame: ``floor(samples · pixels)``, at least one block."""
        return max(self.block * self.block, int(math.floor(self.samples * pixels)))

    def capacity(self, pixels: int) -> int:
        """The point cache's size for a frame of ``pixels`` pixels."""
        return max(1, int(round(self.points_per_pixel * pixels)))

    def to_json(self) -> dict:
        return asdict(self)

    # ---------------------------------------------------------------- as a part
    def key(self) -> tuple:
        return (self.KIND,) + tuple(asdict(self).values())

    def describe(self) -> str:
        return f"render cache: {self.samples * 100:.3g}% of the pixels per frame in {self.block}×{self.block} blocks"

    @classmethod
    def from_json(cls, data: dict, where: str) -> "RenderCacheSettings":
        names = tuple(f.name for f in fields(cls))
        only(data, ("kind",) + names, where)
        values = {k: v for k, v in data.items() if k != "kind"}
        for name, value in values.items():
            default = getattr(cls(), name)
            if isinstance(default, bool) != isinstance(value, bool) or not isinstance(value, (int, float)):
                raise RRCacheError(f"must be {'true or false' if isinstance(default, bool) else 'a number'}",
                                   f"{where}.{name}")
        try:
            return cls(**values).checked()
        except RRCacheError as err:
            raise RRCacheError(err.message, where, hint=err.hint) from None


class RenderCacheKind(Kind):
    """The render cache as a kind of choice that is never chosen (see the module docstring)."""

    name = "render-cache"
    part = RenderCacheSettings
    title = "the render cache (Walter et al. 2002), an alternative to compare"
    one_node = False
    has_frames = True
    marker = "P"

    def _refuse(self):
        return RRCacheError("the render cache is an alternative to compare, not a compiled cache", "selection",
                            hint="render it with rrcache.alternatives.render_cache.RenderCacheRenderer, or "
                                 "'rrcache render SHADER SESSION --method render-cache --samples F'")

    def spec(self, parts, algorithm, filter=None, **runtime):
        raise self._refuse()

    def compile(self, work, spec):
        raise self._refuse()

    def training(self, subject, settings, algorithm=None, filter=None) -> list:
        return []

    def cells(self, selection, profile=None, texts: bool = False) -> tuple[str, str]:
        return self.describe(selection.parts), "–"

    def summary(self, selection, profile=None) -> dict:
        return {"kind": self.name, "describe": self.describe(selection.parts), **selection.parts[0].to_json()}

    def shown_frame(self, selection, variant, frames: int) -> int:
        return min(int(frames) - 1, 30)  # after a second of a 30 fps session: the cache has filled


KIND = RenderCacheKind()
