"""What the training renders where: the error window and the timing window.

A cache's error is mostly resampling blur, and blur depends on the size of a pixel: measured on
Marble (whole noise cached at Δn = 16, 30 frames), the mean error was 0.033 at 160×120, 0.019 at
320×240 and 0.0096 at 640×480. So errors trained at a reduced resolution overstate what the user
will see by 2–3×. Instead the error runs render a *window* of the full-resolution frame (the
scissor test, :mod:`rrcache.gl.window`): the pixels inside are shaded at full density, the rest
are not shaded at all. Measured the same way, the window (a quarter of the frame) gave 0.0075
against 0.0081 for the whole frame, at about half the time.

The window's area is chosen from the original's measured frame time (the fastest of the timing
frames: other work on a shared machine only ever adds time) so that the original costs
about :data:`ERROR_TARGET_MS` inside it (at most a quarter of the frame, at least
:data:`MIN_ERROR_FRACTION`: on chess a 1/64 window, 80×64 pixels of flat board, measured errors
5–25× below what the selections showed over the frame), and it is
placed where the session's objects cover the most pixels over the training frames. Shaders so
expensive that one full frame costs more than :data:`TIMING_TARGET_MS` (chess ambient occlusion:
1.4 s; Marble costs 45 ms) are timed and validated in a window as well, sized to cost about that much; the per-pixel
times t_hit and t_miss do not depend on the window, and the frame time is predicted for the
whole frame's covered pixels.

The decision depends on a timing, so it is made once and kept in the profile store
(:meth:`~rrcache.profiles.store.ProfileStore.plan`): a resumed run uses the same windows.

>>> fraction_for(45.0, ERROR_TARGET_MS, 0.25), fraction_for(1400.0, ERROR_TARGET_MS, 0.25, MIN_ERROR_FRACTION)
(0.25, 0.0625)
>>> cov = np.zeros((6, 8)); cov[3:6, 4:8] = 1
>>> place_window(cov, (64, 48), 0.25)
(32, 0, 32, 24)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from rrcache.gl.window import Window

#: the original's time inside the error window, per frame
ERROR_TARGET_MS = 15.0
#: a full frame costing more than this is timed and validated in a window of about this cost
TIMING_TARGET_MS = 150.0
#: the largest error window (a quarter of the frame), the smallest, and the smallest window of
#: any kind
MAX_ERROR_FRACTION = 0.25
MIN_ERROR_FRACTION = 1.0 / 16.0
MIN_FRACTION = 1.0 / 64.0
#: the coverage map is rendered at the session's resolution divided by this
COVERAGE_SCALE = 8
#: window sides are multiples of this (the largest refresh block), and so are their origins
ALIGN = 8


@dataclass
class Plan:
    """The windows of one profile: ``error_window`` (None: the whole frame at the training
    resolution), ``timing_window`` (None: whole frames), and ``original_ms``, the full-frame
    time they were chosen from."""

    error_window: Optional[Window]
    timing_window: Optional[Window]
    original_ms: float
    #: the cache algorithm of the profile (``auto`` settings: the faster one measured, see
    #: :func:`rrcache.profiler.train.choose_algorithm`), and the median time of each candidate
    #: as a fraction of the original's
    algorithm: Optional[str] = None
    algorithm_times: Optional[dict] = None
    #: the measured ceiling (:class:`rrcache.model.ceiling.Ceiling` as JSON), once measured
    ceiling: Optional[dict] = None
    #: the cache filter of the profile (``auto`` settings: :mod:`rrcache.profiler.filters`) and
    #: what each candidate measured; None in plans made before the choice existed (bilinear)
    filter: Optional[str] = None
    filter_times: Optional[dict] = None

    def to_json(self) -> dict:
        return {"error_window": list(self.error_window) if self.error_window else None,
                "timing_window": list(self.timing_window) if self.timing_window else None,
                "original_ms": self.original_ms, "algorithm": self.algorithm,
                "algorithm_times": self.algorithm_times, "ceiling": self.ceiling,
                "filter": self.filter, "filter_times": self.filter_times}

    @classmethod
    def from_json(cls, data: dict) -> "Plan":
        ew, tw = data.get("error_window"), data.get("timing_window")
        return cls(tuple(int(v) for v in ew) if ew else None, tuple(int(v) for v in tw) if tw else None,
                   float(data.get("original_ms", float("nan"))), data.get("algorithm"),
                   data.get("algorithm_times"), data.get("ceiling"),
                   # a plan that chose its algorithm before the filter existed trained bilinear
                   data.get("filter", "bilinear" if data.get("algorithm") else None), data.get("filter_times"))


def fraction_for(original_ms: float, target_ms: float, cap: float, floor: float = MIN_FRACTION) -> float:
    """The share of the frame's area that costs about ``target_ms``, within [``floor``, ``cap``]."""
    if not math.isfinite(original_ms) or original_ms <= 0:
        return cap
    return float(min(cap, max(floor, target_ms / original_ms)))


def place_window(coverage: np.ndarray, size: tuple[int, int], fraction: float) -> Optional[Window]:
    """The window of ``fraction`` of the frame ``size`` (w, h) covering the most of
    ``coverage`` (a coarse H'×W' map, row 0 = top, e.g. covered frames per pixel), in GL pixel
    coordinates (origin bottom left), sides and origin aligned to :data:`ALIGN`. None when the
    window would be the whole frame."""
    w, h = int(size[0]), int(size[1])
    if fraction >= 1.0:
        return None
    side = math.sqrt(fraction)
    ww = max(ALIGN, int(round(w * side / ALIGN)) * ALIGN)
    wh = max(ALIGN, int(round(h * side / ALIGN)) * ALIGN)
    if ww >= w and wh >= h:
        return None
    ww, wh = min(ww, w), min(wh, h)
    ch, cw = coverage.shape
    sx, sy = cw / w, ch / h
    # summed-area table of the coarse map (row 0 = bottom, as GL)
    grid = np.asarray(coverage, dtype=np.float64)[::-1]
    sat = np.zeros((ch + 1, cw + 1))
    sat[1:, 1:] = grid.cumsum(0).cumsum(1)
    best, best_xy = -1.0, (0, 0)
    for y in range(0, h - wh + 1, ALIGN):
        for x in range(0, w - ww + 1, ALIGN):
            x0, x1 = int(round(x * sx)), int(round((x + ww) * sx))
            y0, y1 = int(round(y * sy)), int(round((y + wh) * sy))
            total = sat[y1, x1] - sat[y0, x1] - sat[y1, x0] + sat[y0, x0]
            # ties: the window nearest the centre of the frame
            score = total - 1e-9 * (abs(x + ww / 2 - w / 2) + abs(y + wh / 2 - h / 2))
            if score > best:
                best, best_xy = score, (x, y)
    return (best_xy[0], best_xy[1], ww, wh)


def coverage_map(prepared, session, frames, renderer_cls) -> np.ndarray:
    """How many of ``frames`` cover each pixel of a coarse render (the session's resolution
    divided by :data:`COVERAGE_SCALE`), row 0 = top."""
    w, h = session.resolution
    size = (max(1, w // COVERAGE_SCALE), max(1, h // COVERAGE_SCALE))
    total = np.zeros((size[1], size[0]))
    with renderer_cls(prepared, session, size) as coarse:
        for index in frames:
            total += coarse.render_frame(index).mask
    return total
