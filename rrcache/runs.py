"""The unit of measurement: one :class:`RunSpec` → one :class:`RunResult`.

A run renders one variant (a :class:`~rrcache.runtime.spec.VariantSpec`, whole) or the original
over some frames of the session and measures it, as one of :data:`MEASURES`:

- ``reference``: the original alone over ``frames`` in the error format (its images stay with the
  executor for the error runs that follow; the rows say each frame's covered pixels);
- ``error``: the variant from an empty cache over ``frames`` in order, each frame against the
  original's: mean RGB L2 over covered pixels, PSNR (capped at :data:`PSNR_CAP`), hits, misses,
  covered pixels and the covered pixels the error left out;
- ``timing``: per frame f the original renders f (timed), the variant f − 1 from an empty cache
  (untimed) and f (timed), so every timed frame is a steady frame beside its original; with no
  variant, the original alone, timed;
- ``overhead``: per frame f the variant renders f − 1 from an empty cache and f timed, alone;
- ``compare``: the variant and the original alternating frame by frame
  (:func:`rrcache.harness.cached.compare`): each frame's error and both times; with
  ``flip_frames`` the FLIP of those frames and with ``temporal`` the temporal error
  (:mod:`rrcache.harness.perceptual`), as validation measures them.

Runs are plain records (strings, numbers, tuples: they pickle, hash and compare), so a trainer
plans a list of them, an executor runs them anywhere the shader and session are loaded
(:func:`rrcache.harness.execute.execute`, the one function that does; in process
:class:`~rrcache.harness.execute.LocalExecutor`), and only the collector writes what they measured
into the store (:mod:`rrcache.profiler.collect`). ``timed`` says which runs measure time: a
distributed executor keeps those alone on a host. ``key`` is what the collector files a result
under (the kind's: :meth:`rrcache.kinds.base.Kind.training`), ``label`` the progress's words.

>>> from rrcache.runtime.spec import VariantSpec
>>> run = RunSpec("error", VariantSpec("cache", ("n12",), periods=(8,)), frames=(0, 1, 2), resolution=(64, 48))
>>> run.timed, run.cost, RunSpec("timing", None, (1, 5), (64, 48)).cost
(False, 3, 2)
>>> RunResult(run, (FrameRow(0, 0.5, 20.0, 10, 90, 100), FrameRow(1, 0.1, 30.0, 80, 20, 100))).steady_error
0.1
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

from rrcache.gl.formats import ERROR_FORMAT
from rrcache.runtime.spec import VariantSpec

#: what a run measures (see the module docstring)
MEASURES = ("reference", "error", "timing", "overhead", "compare")
#: the measures whose result is a time (a distributed executor keeps them alone on a host)
TIMED = ("timing", "overhead", "compare")
#: the PSNR of an identical frame, as stored
PSNR_CAP = 100.0


@dataclass(frozen=True)
class RunSpec:
    """One run (see the module docstring): ``measure`` of ``variant`` (None: the original) over
    ``frames`` at ``resolution``, inside ``window`` (x, y, w, h) when given, drawn into
    ``color_format`` and timed with ``clock`` (:mod:`rrcache.harness.timing`). ``strict_payload``:
    stop after the first frame when the cache cannot keep the payload the variant asks for (a 16-
    or 8-bit payload whose values do not fit), rather than measuring it in 32 bits. A ``compare``
    run also measures FLIP on ``flip_frames`` and, with ``temporal``, the temporal error."""

    measure: str
    variant: Optional[VariantSpec]
    frames: tuple
    resolution: tuple
    window: Optional[tuple] = None
    color_format: str = ERROR_FORMAT
    clock: str = "wall"
    key: tuple = ()
    label: str = ""
    strict_payload: bool = False
    flip_frames: tuple = ()
    temporal: bool = False

    def __post_init__(self):
        if self.measure not in MEASURES:
            raise ValueError(f"measure must be one of {MEASURES}, not {self.measure!r}")
        if self.variant is None and self.measure not in ("reference", "timing"):
            raise ValueError(f"a {self.measure} run needs a variant")
        if (self.flip_frames or self.temporal) and self.measure != "compare":
            raise ValueError(f"FLIP and the temporal error are measured in compare runs, not {self.measure} runs")
        object.__setattr__(self, "frames", tuple(int(f) for f in self.frames))
        object.__setattr__(self, "flip_frames", tuple(int(f) for f in self.flip_frames))
        object.__setattr__(self, "resolution", tuple(int(v) for v in self.resolution))
        if self.window is not None:
            object.__setattr__(self, "window", tuple(int(v) for v in self.window))

    @property
    def timed(self) -> bool:
        """Whether the run measures time (see :data:`TIMED`)."""
        return self.measure in TIMED

    @property
    def cost(self) -> int:
        """Frames it renders, as the progress counts them: a timing run beside the original three
        per frame (the original, the warm-up and the timed frame), the original alone one."""
        per = {"reference": 1, "error": 1, "overhead": 1, "compare": 2,
               "timing": 3 if self.variant is not None else 1}[self.measure]
        return per * len(self.frames)


@dataclass(frozen=True)
class FrameRow:
    """One measured frame: ``error`` (mean RGB L2 over covered pixels), ``psnr`` (dB, capped),
    ``hits``/``misses`` (None where the algorithm cannot count them), ``covered`` pixels,
    ``left_out`` (covered pixels the error left out: not finite), ``ms`` (the variant's, or the
    original's in a run of the original alone) and ``original_ms`` (the original's beside it)."""

    frame: int
    error: float = 0.0
    psnr: float = PSNR_CAP
    hits: Optional[int] = None
    misses: Optional[int] = None
    covered: int = 0
    left_out: int = 0
    ms: float = math.nan
    original_ms: float = math.nan


@dataclass(frozen=True)
class RunResult:
    """What one run measured: its ``spec``, one :class:`FrameRow` per frame rendered, ``wall_s``
    (seconds it took, ``setup_s`` of them compiling, linking and allocating), the ``payload`` the
    cache kept (``f4`` when a narrower one did not fit), ``notes`` (what the renderers said),
    ``complete`` (False when ``strict_payload`` stopped it), and where and when it ran: ``host``
    (the machine's name; None in this process), ``started``/``finished`` (Unix seconds). A
    ``compare`` run asked for them has ``flips`` (the FLIP of each of ``spec.flip_frames`` rendered,
    in order) and ``temporal_psnr`` (dB; inf when the changes match exactly, None without a pair)."""

    spec: RunSpec
    frames: tuple = ()
    wall_s: float = 0.0
    setup_s: float = 0.0
    payload: Optional[str] = None
    notes: tuple = ()
    complete: bool = True
    host: Optional[str] = None
    started: Optional[float] = None
    finished: Optional[float] = None
    flips: tuple = ()
    temporal_psnr: Optional[float] = None

    @property
    def steady(self) -> tuple:
        """The frames after the first (which has no cache), or every frame when there is one."""
        return self.frames[1:] or self.frames

    @property
    def steady_error(self) -> float:
        """The mean error of the steady frames."""
        rows = self.steady
        return float(sum(r.error for r in rows) / len(rows)) if rows else 0.0

    @property
    def steady_psnr(self) -> float:
        """The mean PSNR (capped) of the steady frames."""
        rows = self.steady
        return float(sum(min(r.psnr, PSNR_CAP) for r in rows) / len(rows)) if rows else PSNR_CAP

    @property
    def hit_rate(self) -> float:
        """Hits over hits and misses of the steady frames (NaN where nothing could count them)."""
        rows = [r for r in self.steady if r.hits is not None and r.misses is not None]
        if not rows:
            return math.nan
        hits, total = sum(r.hits for r in rows), sum(r.hits + r.misses for r in rows)
        return hits / total if total else 0.0

    @property
    def ms(self) -> float:
        """The median frame time of the steady frames."""
        return _median([r.ms for r in self.steady])

    @property
    def original_ms(self) -> float:
        """The median frame time of the original beside the steady frames."""
        return _median([r.original_ms for r in self.steady])


def _median(values) -> float:
    import statistics

    return float(statistics.median(values)) if values else math.nan
