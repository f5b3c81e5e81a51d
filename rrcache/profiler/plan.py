"""What the training renders where: the error window, the error frames and the timing window.

**The error window.** A cache's error is mostly resampling blur, and blur depends on the size of
a pixel: measured on Marble (whole noise cached at Δn = 16, 30 frames), the mean error was 0.033 at
160×120, 0.019 at 320×240 and 0.0096 at 640×480. So errors trained at a reduced resolution
overstate what the user will see by 2–3×. Instead the error runs render a *window* of the
full-resolution frame (the scissor test, :mod:`rrcache.gl.window`): the pixels inside are shaded
at full density, the rest are not shaded at all. Measured the same way, the window (a quarter of
the frame) gave 0.0075 against 0.0081 for the whole frame, at about half the time; over the whole
150-frame session Marble's albedo at Δn = 10 and 25 measured 0.0071 and 0.0109 in the quarter
window against 0.0077 and 0.0127 over the frame, the PSNRs within 0.6 dB once the coverage offset
(:func:`rrcache.model.psnr.coverage_offset_db`) is applied.

The window is a quarter of the frame (:data:`MAX_ERROR_FRACTION`), halved (to at least
:data:`MIN_ERROR_FRACTION`) only for shaders whose quarter frame costs more than
:data:`ERROR_TARGET_CPU_MS` of *CPU time* (:func:`error_fraction`). CPU time, not wall time: other
work on a shared machine stretches a frame's wall time many times over (Marble's frame: 45 ms
quiet, 250–530 ms at load 12) but its CPU time little (125–150 ms at load 12), and a window sized
from wall time shrank to 7% of the frame on a loaded machine, without a word. It is placed so
that the objects cover about the share of it they cover of the region validation measures (the
frame, or the timing window): the window then holds the objects' edges, where a cache errs most,
in about the proportion validation sees them. Placed where the objects cover the most, it sat
inside them: on Trashcan a sixteenth of the frame inside the can measured half the error of a
quarter across its edge (0.0031 against 0.0059 at Δn = 2), and the profile predicted 46.7 dB
for a choice validation measured at 37.7.

**The error frames.** Validation measures the whole session from a cold cache at frame 0, so the
error runs do too: every frame of a session of up to ``settings.frames`` frames (default 150, the
length of the paper's sessions). A longer session (or a smaller ``--frames``) is covered by
:func:`error_segments`: segments of consecutive frames spread over it, the first from frame 0,
each later one preceded by 2·Δn frames rendered and not counted, with the runtime's clock set to
the frame number (:func:`restart`), after which the cache holds what it holds there in a run from
frame 0: every block has been refreshed since, on the same frames (:func:`warmup_frames`), and
values resampled across block edges from before the warm-up have faded (one Δn of warm-up left
them 2–6% of the error on the tiny test scene at Δn = 4–16; two, under 0.1%). The frames left out
widen the predicted PSNR's ± by their share (:attr:`Plan.uncovered`; docs/levels.md).

**The timing window.** Shaders so expensive that one full frame costs more than
:data:`TIMING_TARGET_CPU_MS` of CPU time (chess ambient occlusion) are timed and validated in a
window as well, sized to cost about that much; the per-pixel times t_hit and t_miss do not depend
on the window, and the frame time is predicted for the whole frame's covered pixels.

The decision is made once and kept in the profile store (:meth:`~rrcache.profiles.store.ProfileStore.plan`):
a resumed run uses the same windows and frames (a store planned before the error frames were
planned keeps its first ``settings.frames`` frames).

>>> error_fraction(100.0), error_fraction(2800.0)
(0.25, 0.0625)
>>> cov = np.zeros((6, 8)); cov[3:6, 4:8] = 1
>>> place_window(cov, (64, 48), 0.25)
(32, 0, 32, 24)
>>> error_segments(150, 150, 50)
[(0, 150)]
>>> error_segments(600, 150, 50)
[(0, 50), (275, 50), (550, 50)]
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from rrcache.gl.window import Window
from rrcache.harness.segments import WARMUP_PERIODS, run_order, warmup_frames  # noqa: F401 (the plan's rule)

#: the original's time inside the error window, per frame (wall clock: the earlier rule, kept for
#: :func:`fraction_for`'s callers)
ERROR_TARGET_MS = 15.0
#: a full frame costing more than this is timed and validated in a window of about this cost
TIMING_TARGET_MS = 150.0
#: the most CPU time the original may cost inside the error window per frame (Marble's quarter
#: frame: 25–40 ms; chess ambient occlusion's: ~700 ms, so it trains in a sixteenth)
ERROR_TARGET_CPU_MS = 100.0
#: a full frame costing more CPU time than this is timed and validated in a window of about this
#: cost (about 150–200 ms of wall time on two quiet cores)
TIMING_TARGET_CPU_MS = 400.0
#: the default number of error frames: a session of up to this many is covered whole
DEFAULT_ERROR_FRAMES = 150
#: the fewest counted frames of one segment of a session covered in segments, and the most segments
MIN_SEGMENT = 16
MAX_SEGMENTS = 4
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
    time they were chosen from; ``original_cpu_ms`` the full frame's CPU time the windows were
    sized by, ``error_segments`` the error runs' frames as (start, count) segments (None: the
    first ``settings.frames``, a plan made before they were planned) and ``session_frames``."""

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
    original_cpu_ms: Optional[float] = None
    error_segments: Optional[list] = None
    session_frames: Optional[int] = None
    #: how ``algorithm`` was decided (``auto``: the ceiling's limits or a timing beyond its noise)
    algorithm_reason: Optional[str] = None

    def to_json(self) -> dict:
        return {"error_window": list(self.error_window) if self.error_window else None,
                "timing_window": list(self.timing_window) if self.timing_window else None,
                "original_ms": self.original_ms, "algorithm": self.algorithm,
                "algorithm_times": self.algorithm_times, "ceiling": self.ceiling,
                "filter": self.filter, "filter_times": self.filter_times,
                "original_cpu_ms": self.original_cpu_ms,
                "error_segments": [list(s) for s in self.error_segments] if self.error_segments else None,
                "session_frames": self.session_frames, "algorithm_reason": self.algorithm_reason}

    @classmethod
    def from_json(cls, data: dict) -> "Plan":
        ew, tw = data.get("error_window"), data.get("timing_window")
        segments = data.get("error_segments")
        return cls(tuple(int(v) for v in ew) if ew else None, tuple(int(v) for v in tw) if tw else None,
                   float(data.get("original_ms", float("nan"))), data.get("algorithm"),
                   data.get("algorithm_times"), data.get("ceiling"),
                   # a plan that chose its algorithm before the filter existed trained bilinear
                   data.get("filter", "bilinear" if data.get("algorithm") else None), data.get("filter_times"),
                   original_cpu_ms=data.get("original_cpu_ms"),
                   error_segments=[(int(a), int(b)) for a, b in segments] if segments else None,
                   session_frames=data.get("session_frames"), algorithm_reason=data.get("algorithm_reason"))

    def error_frames(self, count: int) -> list[int]:
        """The counted frames of the error runs (``count``: ``settings.frames``, the first frames
        of a plan made before the error frames were planned).

        >>> Plan(None, None, 1.0, error_segments=[(0, 3), (10, 2)]).error_frames(64)
        [0, 1, 2, 10, 11]
        """
        if not self.error_segments:
            return list(range(int(count)))
        return [i for start, n in self.error_segments for i in range(start, start + n)]

    def uncovered(self, count: int, validation_frames: int) -> float:
        """The share of the ``validation_frames`` the error runs did not cover (0: all of them).

        >>> round(Plan(None, None, 1.0, error_segments=[(0, 50), (100, 50)]).uncovered(100, 150), 3)
        0.333
        """
        frames = set(self.error_frames(count))
        if validation_frames <= 0:
            return 0.0
        return 1.0 - len([i for i in range(int(validation_frames)) if i in frames]) / float(validation_frames)

    def describe(self, resolution=None, count: Optional[int] = None) -> str:
        """The error runs' frames and window in words, for the summary and the report.

        >>> Plan((176, 144, 320, 240), None, 1.0, error_segments=[(0, 150)], session_frames=150).describe((640, 480))
        'error runs: frames 0–149 (all 150 of the session) in a 320×240 window (25% of the frame)'
        """
        frames = self.error_frames(count or 0)
        if self.error_segments:
            spans = ", ".join(f"{a}–{a + n - 1}" for a, n in self.error_segments)
        else:
            spans = f"0–{len(frames) - 1}" if frames else "none"
        total = self.session_frames
        if total is not None and len(frames) >= total:
            which = f"frames {spans} (all {total} of the session)"
        else:
            which = f"frames {spans} ({len(frames)}" + (f" of {total})" if total else ")")
        if self.error_window is None:
            return f"error runs: {which} over the whole frame"
        w, h = self.error_window[2], self.error_window[3]
        share = f" ({w * h / (resolution[0] * resolution[1]):.0%} of the frame)" if resolution else ""
        return f"error runs: {which} in a {w}×{h} window{share}"


def error_fraction(original_cpu_ms: float, target_ms: float = ERROR_TARGET_CPU_MS) -> float:
    """The error window's share of the frame for a full frame costing ``original_cpu_ms`` of CPU
    time: :data:`MAX_ERROR_FRACTION`, halved while that share costs more than ``target_ms``, at
    least :data:`MIN_ERROR_FRACTION` (see the module docstring)."""
    fraction = MAX_ERROR_FRACTION
    if not (original_cpu_ms is not None and math.isfinite(original_cpu_ms) and original_cpu_ms > 0):
        return fraction
    while fraction / 2 >= MIN_ERROR_FRACTION and original_cpu_ms * fraction > target_ms:
        fraction /= 2
    return fraction


def error_segments(session_frames: int, count: int, max_period: int) -> list[tuple[int, int]]:
    """The error runs' frames as (start, count) segments: all ``session_frames`` when ``count``
    covers them, else about ``count`` frames in segments spread evenly from frame 0 to the end,
    each at least as long as ``max_period`` (and :data:`MIN_SEGMENT`), at most
    :data:`MAX_SEGMENTS` of them (see the module docstring)."""
    n, count = int(session_frames), max(2, int(count))
    if count >= n:
        return [(0, n)]
    # segments as long as the largest period (each later one costs twice that many frames of
    # warm-up per period), at most MAX_SEGMENTS of them
    k = max(1, min(MAX_SEGMENTS, count // max(MIN_SEGMENT, int(max_period))))
    length = count // k
    starts = [int(round(x)) for x in np.linspace(0, n - length, k)] if k > 1 else [0]
    return [(s, length) for s in starts]


#: the least relative noise assumed of a timing (a quiet machine's frame-to-frame noise)
MIN_TIMING_NOISE = 0.02


def algorithm_by_ceiling(ceilings: dict, noise: float) -> tuple[Optional[str], str]:
    """``--algorithm auto`` from the ceiling's per-algorithm limits (algorithm → all-hit speed-up,
    measured beside the original with relative frame-time ``noise``, the half-range of the
    original's repeated frames: a generous bound on each limit's error, as both limits were
    measured in the same run under the same load): the higher limit when the two are further
    apart than that noise (at least :data:`MIN_TIMING_NOISE`), else None. Returns (algorithm or
    None, why).

    >>> algorithm_by_ceiling({"two-pass": 1.47, "three-pass": 0.85}, 0.40)
    ('two-pass', 'the ceiling: two-pass 1.47× against three-pass 0.85× (73% apart, beyond its noise ±40%)')
    >>> algorithm_by_ceiling({"two-pass": 8.64, "three-pass": 7.06}, 0.26)[0] is None
    True
    """
    ranked = sorted(((float(v), k) for k, v in (ceilings or {}).items() if v and math.isfinite(v)), reverse=True)
    if len(ranked) < 2:
        return None, "the ceiling measured one algorithm"
    (best, name), (second, other) = ranked[0], ranked[1]
    apart = best / second - 1.0 if second > 0 else math.inf
    bound = max(float(noise or 0.0), MIN_TIMING_NOISE)
    words = f"{name} {best:.2f}× against {other} {second:.2f}× ({apart:.0%} apart"
    if apart > bound:
        return name, f"the ceiling: {words}, beyond its noise ±{float(noise or 0.0):.0%})"
    return None, f"the ceiling: {words}, within its noise ±{float(noise or 0.0):.0%})"


def algorithm_by_timing(ratios: dict, fallback: str) -> tuple[str, str]:
    """``--algorithm auto`` from a node's timing (algorithm → its per-frame time ratios to the
    original): the faster median when the medians differ by more than twice the standard error
    of their difference (each median's from its frames' spread, 1.2533·1.4826·MAD/√n), else
    ``fallback`` (the ceiling's higher limit), saying so.

    >>> algorithm_by_timing({"two-pass": [0.30, 0.31, 0.29, 0.30], "three-pass": [0.36, 0.35, 0.37, 0.36]}, "three-pass")[0]
    'two-pass'
    >>> algorithm_by_timing({"two-pass": [0.30, 0.45, 0.22, 0.39], "three-pass": [0.31, 0.40, 0.25, 0.44]}, "three-pass")[0]
    'three-pass'
    """
    stats = {}
    for name, values in ratios.items():
        v = np.asarray([x for x in values if x is not None and math.isfinite(x)], dtype=np.float64)
        if v.size:
            med = float(np.median(v))
            se = 1.2533 * 1.4826 * float(np.median(np.abs(v - med))) / math.sqrt(v.size)
            stats[name] = (med, max(se, MIN_TIMING_NOISE * med / math.sqrt(v.size)))
    if len(stats) < 2:
        return fallback, "one algorithm timed"
    (fast, (m1, s1)), (slow, (m2, s2)) = sorted(stats.items(), key=lambda kv: kv[1][0])[:2]
    bound = 2.0 * math.hypot(s1, s2)
    words = f"{fast} {m1:.3f} against {slow} {m2:.3f} of the original's time"
    if m2 - m1 > bound:
        return fast, f"a timing of the first node: {words}, apart by more than twice their noise (±{bound / 2:.3f})"
    return fallback, (f"{fallback}: neither the ceiling nor a timing of the first node ({words}, within twice "
                      f"their noise ±{bound / 2:.3f}) told them apart; the higher ceiling")


def make_plan(work, session, settings, original_ms: float, renderer_cls) -> Plan:
    """Choose the error and timing windows and the error frames for ``work`` over ``session``:
    the original's CPU time is measured on three frames at full resolution (its fastest), the
    windows sized from it (see the module docstring) and placed over the coverage of the error
    frames. ``original_ms`` is the wall time the timings measured (kept for the record)."""
    full = tuple(int(v) for v in session.resolution)
    at_full = tuple(settings.resolution) == full
    cpu_ms = original_cpu_ms(work, session, settings, renderer_cls)
    error_share = settings.error_window if settings.error_window is not None else error_fraction(cpu_ms)
    timing_share = 1.0 if not cpu_ms > TIMING_TARGET_CPU_MS else max(MIN_FRACTION, TIMING_TARGET_CPU_MS / cpu_ms)
    segments = error_segments(session.frames, settings.frames, max(settings.periods))
    frames = [i for start, n in segments for i in range(start, start + n)]
    need = (at_full and error_share < 1.0) or timing_share < 1.0
    sampled = frames[::max(1, len(frames) // 16)]
    coverage = coverage_map(work.prepared, session, sampled, renderer_cls) / max(1, len(sampled)) if need else None
    timing_window = place_window(coverage, full, timing_share) if timing_share < 1.0 else None
    # the error window covers the object in the share the validated region does (the frame, or
    # the timing window), so that it holds the object's edges, where a cache errs most, in about
    # the proportion validation sees: on Trashcan a sixteenth of the frame inside the object
    # measured half the error of a quarter across its edge (0.0031 against 0.0059 at Δn = 2)
    target = covered_share(coverage, full, timing_window) if coverage is not None else None
    error_window = place_window(coverage, full, error_share, target=target) if at_full and error_share < 1.0 else None
    return Plan(error_window, timing_window, float(original_ms), original_cpu_ms=cpu_ms, error_segments=segments,
                session_frames=int(session.frames))


def original_cpu_ms(work, session, settings, renderer_cls) -> float:
    """The least CPU time (ms, every thread of the process) of the original's full frame over
    three frames spread over the session (its first, middle and last)."""
    full = tuple(int(v) for v in session.resolution)
    last = max(0, int(session.frames) - 1)
    with renderer_cls(work.prepared, session, full, color_format=settings.timing_format) as renderer:
        times = [renderer.render_frame(i).cpu_ms for i in sorted({0, last // 2, last})]
    times = [t for t in times if t is not None and math.isfinite(t) and t > 0]
    return float(min(times)) if times else float("nan")


def fraction_for(original_ms: float, target_ms: float, cap: float, floor: float = MIN_FRACTION) -> float:
    """The share of the frame's area that costs about ``target_ms``, within [``floor``, ``cap``]."""
    if not math.isfinite(original_ms) or original_ms <= 0:
        return cap
    return float(min(cap, max(floor, target_ms / original_ms)))


def place_window(coverage: np.ndarray, size: tuple[int, int], fraction: float,
                 target: Optional[float] = None) -> Optional[Window]:
    """The window of ``fraction`` of the frame ``size`` (w, h) over ``coverage`` (a coarse H'×W'
    map, row 0 = top: the share of the frames covering each pixel), in GL pixel coordinates
    (origin bottom left), sides and origin aligned to :data:`ALIGN`: the one covering the most, or
    with ``target`` the one whose covered share is nearest ``target`` (the share of the region
    validation measures, so that the window holds the object's edges in about the proportion
    that region does; ties: the window nearest the centre). None when the window would be the
    whole frame.

    >>> cov = np.zeros((6, 8)); cov[:, :4] = 1           # the left half covered
    >>> place_window(cov, (64, 48), 0.25), place_window(cov, (64, 48), 0.25, target=0.5)
    ((0, 8, 32, 24), (16, 8, 32, 24))
    """
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
    best, best_xy = -math.inf, (0, 0)
    for y in range(0, h - wh + 1, ALIGN):
        for x in range(0, w - ww + 1, ALIGN):
            x0, x1 = int(round(x * sx)), int(round((x + ww) * sx))
            y0, y1 = int(round(y * sy)), int(round((y + wh) * sy))
            total = sat[y1, x1] - sat[y0, x1] - sat[y1, x0] + sat[y0, x0]
            if target is not None:
                cells = max(1, (x1 - x0) * (y1 - y0))
                total = -abs(total / cells - float(target))
            # ties: the window nearest the centre of the frame
            score = total - 1e-9 * (abs(x + ww / 2 - w / 2) + abs(y + wh / 2 - h / 2))
            if score > best:
                best, best_xy = score, (x, y)
    return (best_xy[0], best_xy[1], ww, wh)


def covered_share(coverage: np.ndarray, size: tuple[int, int], window: Optional[Window] = None) -> float:
    """The share of ``window`` (None: the frame) that ``coverage`` (the coarse map of
    :func:`place_window`) covers.

    >>> cov = np.zeros((6, 8)); cov[:, :4] = 1
    >>> covered_share(cov, (64, 48)), covered_share(cov, (64, 48), (0, 0, 32, 48))
    (0.5, 1.0)
    """
    ch, cw = coverage.shape
    if window is None:
        return float(np.mean(coverage))
    w, h = int(size[0]), int(size[1])
    x, y, ww, wh = window
    x0, x1 = int(round(x * cw / w)), max(int(round(x * cw / w)) + 1, int(round((x + ww) * cw / w)))
    rows = np.asarray(coverage, dtype=np.float64)[::-1]  # row 0 = bottom, as GL
    y0, y1 = int(round(y * ch / h)), max(int(round(y * ch / h)) + 1, int(round((y + wh) * ch / h)))
    return float(np.mean(rows[y0:y1, x0:x1]))


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
