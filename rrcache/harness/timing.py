"""The frame clock every timed site uses, and how far a timing can be trusted: the noise of frame
times and the spread of a speed-up.

**Clocks.** A :class:`FrameClock` times one frame's GL work: :meth:`~FrameClock.start` before the
frame's first command, :meth:`~FrameClock.stop` after its last (the frame's ms; ``cpu_ms`` the
process CPU time over the same span), :meth:`~FrameClock.mark` a stage boundary inside it
(diagnostics: the GPU is waited for, so a staged frame is slower). Two clocks, picked by name
(:data:`CLOCKS`, :func:`make_clock`; ``rrcache profile --clock``, recorded in the profile's
settings), in the manner of moderngl-window's ``timers/``:

- ``wall`` (:class:`WallClock`, the default): ``ctx.finish()``, then ``time.perf_counter()``
  around the commands and a second ``ctx.finish()``. The only one that means anything on a
  software rasterizer (llvmpipe runs the draws on the CPU; its timer queries say little).
- ``gl-timer`` (:class:`GLTimerClock`): a GL ``TIME_ELAPSED`` query around the commands, the
  GPU's own time for them, for real GPUs where the driver's queue makes wall time blur frames.

>>> from types import SimpleNamespace
>>> clock = WallClock(SimpleNamespace(finish=lambda: None))
>>> clock.start(); ms = clock.stop()
>>> ms >= 0.0, clock.cpu_ms >= 0.0, sorted(CLOCKS)
(True, True, ['gl-timer', 'wall'])

Speed-ups are ratios of median frame times measured side by side (the original and the variant
alternating frame by frame). Two figures say how much such a number can move:

- :func:`frame_noise`: the noise of a run's frame times, estimated from the original's own
  times: consecutive frames differ little in content, so the spread of their differences is
  mostly the machine's (robust: 1.4826 × the median absolute difference / √2, relative to the
  median time). On a quiet machine it is a few per cent; other work on the machine raises it.
  Above :data:`UNRELIABLE_NOISE` a timing is flagged as unreliable.
- :func:`ratio_interval`: a bootstrap interval of the ratio of medians, resampling the
  (original, variant) frame pairs (seeded, so a run gives the same interval every time it is
  summarised).

>>> round(frame_noise([10.0, 10.2, 9.9, 10.1, 10.0]), 4)
0.021
>>> lo, hi = ratio_interval([10, 11, 10, 12, 10, 11], [5, 5.5, 5, 6, 5, 5.4])
>>> lo <= 2.0 <= hi
True
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod
import time
from typing import ClassVar, Sequence

import numpy as np

#: the clock a frame is timed with unless one is chosen
DEFAULT_CLOCK = "wall"


class FrameClock(ABC):
    """Times one frame (see the module docstring). Subclasses set :attr:`name` and implement
    :meth:`_begin` and :meth:`_end` (the frame's ms)."""

    name: ClassVar[str] = ""

    def __init__(self, ctx):
        self.ctx = ctx
        self.cpu_ms = float("nan")
        self._cpu = 0.0
        #: wall-clock seconds (``perf_counter``) at the last start and stop: the stage marks' origin
        self.started = self.end = 0.0

    def start(self) -> None:
        """Before the frame's first GL command: the GPU is idle when timing starts."""
        self.ctx.finish()
        self._cpu = time.process_time()
        self.started = time.perf_counter()
        self._begin()

    def stop(self) -> float:
        """After the frame's last GL command: the frame's ms (and :attr:`cpu_ms`)."""
        ms = self._end()
        self.cpu_ms = (time.process_time() - self._cpu) * 1000.0
        return ms

    def mark(self) -> float:
        """A stage boundary (seconds on the wall clock, the GPU waited for): the stage
        breakdowns of ``rrcache bench-cache --breakdown`` subtract consecutive marks."""
        self.ctx.finish()
        return time.perf_counter()

    @abstractmethod
    def _begin(self) -> None:
        """Start the frame's measurement (after :meth:`start`'s wall-clock mark)."""

    @abstractmethod
    def _end(self) -> float:
        """End it: the frame's ms."""


class WallClock(FrameClock):
    """``perf_counter()`` between two ``ctx.finish()`` calls."""

    name = "wall"

    def _begin(self) -> None:
        pass

    def _end(self) -> float:
        self.ctx.finish()
        self.end = time.perf_counter()
        return (self.end - self.started) * 1000.0


class GLTimerClock(FrameClock):
    """A GL ``TIME_ELAPSED`` query around the frame's commands (the GPU's time for them)."""

    name = "gl-timer"

    def __init__(self, ctx):
        super().__init__(ctx)
        self._query = ctx.query(time=True)

    def _begin(self) -> None:
        self._query.__enter__()

    def _end(self) -> float:
        self._query.__exit__(None, None, None)
        self.ctx.finish()
        self.end = time.perf_counter()
        return float(self._query.elapsed) / 1e6


#: clock name -> class: the one place a clock is declared
CLOCKS: dict[str, type] = {WallClock.name: WallClock, GLTimerClock.name: GLTimerClock}


def make_clock(name: str, ctx) -> FrameClock:
    """The clock called ``name`` (:data:`CLOCKS`) on ``ctx``; ValueError naming the known ones."""
    try:
        cls = CLOCKS[name or DEFAULT_CLOCK]
    except KeyError:
        raise ValueError(f"clock must be one of {', '.join(sorted(CLOCKS))}, not {name!r}") from None
    return cls(ctx)

#: relative frame-time noise above which a timing is called unreliable
UNRELIABLE_NOISE = 0.1
BOOTSTRAP = 2000


def frame_noise(times: Sequence[float]) -> float:
    """The relative noise of consecutive frame times (see the module docstring); 0 for fewer
    than three frames."""
    t = np.asarray([v for v in times if v is not None and math.isfinite(v)], dtype=np.float64)
    if t.size < 3 or not np.median(t) > 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(np.diff(t))) / math.sqrt(2.0) / np.median(t))


def ratio_interval(original: Sequence[float], variant: Sequence[float], level: float = 0.95,
                   seed: int = 0) -> tuple[float, float]:
    """A ``level`` bootstrap interval of median(original) / median(variant) over frame pairs."""
    o = np.asarray(original, dtype=np.float64)
    v = np.asarray(variant, dtype=np.float64)
    if o.size == 0 or o.size != v.size:
        return (float("nan"), float("nan"))
    if o.size == 1:
        r = float(o[0] / v[0]) if v[0] > 0 else float("nan")
        return (r, r)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, o.size, size=(BOOTSTRAP, o.size))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.median(o[idx], axis=1) / np.median(v[idx], axis=1)
    ratios = ratios[np.isfinite(ratios)]
    if not ratios.size:
        return (float("nan"), float("nan"))
    tail = (1.0 - level) / 2.0 * 100.0
    return (float(np.percentile(ratios, tail)), float(np.percentile(ratios, 100.0 - tail)))


def load_warning(noise: float) -> str:
    """The warning for a run whose frame-time noise is ``noise`` ('' when it is reliable)."""
    if noise <= UNRELIABLE_NOISE:
        return ""
    return (f"the original's frame times varied by ±{noise:.0%} from frame to frame (over {UNRELIABLE_NOISE:.0%}): "
            "other work on the machine made this timing unreliable; measure again on a quieter machine")
