"""Training settings of a profile: what is measured, at which resolution, for how long.

:class:`TrainingSettings` is a frozen, JSON-able dataclass. The fields that change what is
*measured* (periods, resolution, frames, timing frames and periods, algorithm, refresh block,
refresh pattern, depth epsilon, validation frames) are hashed into the key of the profile store
(:mod:`rrcache.profiles.store`): a store trained with other settings is refused rather than mixed.
``budget_s`` and ``validate`` only decide how much is done, so they are left out of the key and
may change between a run and its resumption.

The error is measured over ``frames`` frames of the session (default 150: all of a session of
up to 150 frames, as validation measures it; a longer one in segments spread over it,
:func:`rrcache.profiler.plan.error_segments`) at the session's full resolution, inside a window
of the frame chosen from the original's CPU time (:mod:`rrcache.profiler.plan`), or at an
explicit reduced ``resolution`` (errors are then larger: the resampling blur grows with the
pixel size). The times are measured on ``timing_frames`` frames at the session's full
resolution.

>>> s = TrainingSettings(periods=(2, 4, 8), resolution=(32, 24), frames=12)
>>> s.periods, s.to_json()["resolution"]
((2, 4, 8), [32, 24])
>>> TrainingSettings.from_json(s.to_json()) == s
True
>>> TrainingSettings(periods=(0, 4))
Traceback (most recent call last):
    ...
rrcache.errors.RRCacheError: settings: periods: 0 is not a refresh period (hint: give whole numbers from 1 to 1000, e.g. 2,10,18,26,34,42,50)
"""
from __future__ import annotations

import hashlib
import json
import warnings
from dataclasses import asdict, dataclass, fields, replace
from typing import Optional

from rrcache.errors import RRCacheError
from rrcache.gl.formats import COLOR_FORMATS
from rrcache.harness.timing import CLOCKS, DEFAULT_CLOCK
from rrcache.runtime import (ALGORITHMS, BLOCK_SIZES, DEFAULT_BLOCK, DEFAULT_DEPTH_EPSILON, DEFAULT_REFRESH,
                             FILTERS, REFRESH_MODES)

#: the cache algorithms a profile may use; ``auto`` measures which is faster on this machine
ALGORITHM_CHOICES = ("auto",) + tuple(ALGORITHMS)
FILTER_CHOICES = ("auto",) + tuple(FILTERS)
#: what ``auto`` stands for when nothing was measured (no node to time)
DEFAULT_ALGORITHM = "three-pass"

#: the paper's training periods (main paper §4.2)
DEFAULT_PERIODS = (2, 10, 18, 26, 34, 42, 50)
#: the refresh periods at which times are measured: varying Δn varies the hit/miss mix
DEFAULT_TIMING_PERIODS = (2, 8, 50)
#: frames of the error runs when the session has that many (all of a session up to this long,
#: as validation measures; rrcache.profiler.plan)
DEFAULT_TRAINING_FRAMES = 150
#: the fields that do not change a measurement (left out of the store key)
UNKEYED = ("budget_s", "validate", "min_saving", "min_gain", "levels", "max_sets")
#: how the four selection levels are chosen
LEVEL_KINDS = ("psnr", "relative")


def _fail(field_name: str, message: str, hint: str) -> RRCacheError:
    return RRCacheError(f"{field_name}: {message}", "settings", hint=hint)


def _periods(value, name: str, hint: str) -> tuple[int, ...]:
    try:
        items = tuple(value)
    except TypeError:
        raise _fail(name, f"{value!r} is not a list of periods", hint) from None
    if not items:
        raise _fail(name, "no periods given", hint)
    out = []
    for item in items:
        if isinstance(item, bool) or not isinstance(item, int) or not 1 <= item <= 1000:
            raise _fail(name, f"{item!r} is not a refresh period", hint)
        out.append(int(item))
    if len(set(out)) != len(out):
        raise _fail(name, f"{list(out)} repeats a period", hint)
    return tuple(sorted(out))


@dataclass(frozen=True)
class TrainingSettings:
    """What a profile measures (see the module docstring).

    - ``periods``: the refresh periods Δn of the error runs.
    - ``resolution``: (w, h) of the error runs; None: the session's, rendered in a window.
    - ``error_window``: the share of the frame's area the error runs render (1: all of it);
      None: chosen from the original's cost (:mod:`rrcache.profiler.plan`). Only at the
      session's resolution.
    - ``frames``: N frames of the error runs, spread over the session in segments
      (:func:`rrcache.profiler.plan.error_segments`); None: 150 (all of a shorter session).
    - ``timing_frames``: L, the frames timed per node and timing period (spread evenly).
    - ``timing_periods``: the periods at which each node is timed.
    - ``algorithm``, ``block``, ``refresh``, ``depth_epsilon``: the cache's own settings.
      ``algorithm="auto"`` (the default) times the three-pass and two-pass variants of the first
      node to train side by side with the original and keeps the faster for the whole profile
      (:func:`rrcache.profiler.train.choose_algorithm`; the choice is kept in the plan).
    - ``validation_frames``: consecutive frames of each validation render; None: all.
    - ``budget_s``: node training starts no new node once this many seconds are spent.
    - ``validate``: render the four selections against the original after training.
    - ``min_saving``: nodes whose static cost is below this share of the costliest node's are
      not trained (:mod:`rrcache.profiler.order`).
    - ``min_gain``: the least speed-up worth having: when the measured ceiling
      (:mod:`rrcache.profiler.ceiling`) is below it the profile stops before training and answers
      "the original"; nodes whose best case is below it are not trained. 0 measures the ceiling
      but neither stops nor prunes.
    - ``timing_format``: the colour target of every timed run, the original's and the variants'
      alike (``rgba8`` as applications draw; ``rgba16f``, ``rgba32f``); error runs always draw
      into ``rgba32f``.
    - ``levels``: the four selection levels e1..e4: ``psnr`` (predicted PSNR against the original
      ≥ 45, 40, 35, 30 dB) or ``relative`` (the paper's error thresholds, fractions of the
      largest error seen).
    - ``max_sets``: at most this many sets of several cached nodes, each at its own period, are
      trained after the single nodes (:mod:`rrcache.profiler.sets`); 0 trains none.
    - ``clock``: the frame clock of every timed run (:data:`rrcache.harness.timing.CLOCKS`):
      ``wall`` (the default; wall time around ``ctx.finish()``) or ``gl-timer`` (GL timer
      queries, for real GPUs). Keyed (another clock measures other times), except at its
      default, so stores trained before the clock was recorded keep their key.
    - ``filter``: the cache's hit test and payload reconstruction; ``auto`` (the default)
      measures ``bilinear`` against ``plane`` on the first node to train and keeps ``plane``
      where it was faster at about the same PSNR (:mod:`rrcache.profiler.filters`; the choice is
      kept in the plan).
    - ``measure_terms``: before training, order the terms of every sum whose weights do not fold
      by what caching each alone costs in error (:mod:`rrcache.profiler.terms`, kept in the
      store and in ``Profile.term_scores``); off by default.
    """

    periods: tuple[int, ...] = DEFAULT_PERIODS
    resolution: Optional[tuple[int, int]] = None
    error_window: Optional[float] = None
    frames: Optional[int] = None
    timing_frames: int = 8
    timing_periods: tuple[int, ...] = DEFAULT_TIMING_PERIODS
    algorithm: str = "auto"
    block: int = DEFAULT_BLOCK
    refresh: str = DEFAULT_REFRESH
    depth_epsilon: float = DEFAULT_DEPTH_EPSILON
    validation_frames: Optional[int] = None
    budget_s: float = 360.0
    validate: bool = True
    min_saving: float = 0.1
    min_gain: float = 1.1
    timing_format: str = "rgba8"
    levels: str = "psnr"
    #: the sets of cached nodes (k >= 2) the set stage trains at most (rrcache.profiler.sets); 0: none
    max_sets: int = 3
    #: the frame clock of the timed runs (rrcache.harness.timing.CLOCKS)
    clock: str = DEFAULT_CLOCK
    #: the cache's hit test and payload reconstruction: ``auto`` measures ``bilinear`` against
    #: ``plane`` on the first node (rrcache.profiler.filters), or one of rrcache.runtime.glsl.FILTERS
    filter: str = "auto"
    #: order the terms of sums whose weights do not fold by a short measurement of each term
    #: (rrcache.profiler.terms) before training; node ids then refer to that order
    measure_terms: bool = False

    def cache_options(self) -> dict:
        """The cache's run-time parameters besides the period, as the keyword arguments of
        :class:`rrcache.runtime.CacheRuntime` (and of the harness that wraps it)."""
        return {"block": self.block, "refresh": self.refresh, "depth_epsilon": self.depth_epsilon}

    @property
    def fixed_algorithm(self) -> str:
        """The algorithm these settings name without measuring: ``algorithm``, or
        :data:`DEFAULT_ALGORITHM` for ``auto``."""
        return DEFAULT_ALGORITHM if self.algorithm == "auto" else self.algorithm

    def __post_init__(self):
        hint = "give whole numbers from 1 to 1000, e.g. 2,10,18,26,34,42,50"
        object.__setattr__(self, "periods", _periods(self.periods, "periods", hint))
        object.__setattr__(self, "timing_periods", _periods(self.timing_periods, "timing_periods", "e.g. 2,8,50"))
        if self.resolution is not None:
            try:
                w, h = (int(v) for v in self.resolution)
            except (TypeError, ValueError):
                raise _fail("resolution", f"{self.resolution!r} is not (width, height)", "e.g. 160x120") from None
            if w < 1 or h < 1 or w > 16384 or h > 16384:
                raise _fail("resolution", f"{w}x{h} is not a usable size", "e.g. 160x120")
            object.__setattr__(self, "resolution", (w, h))
        for name, low in (("frames", 2), ("timing_frames", 1), ("validation_frames", 2)):
            value = getattr(self, name)
            if value is None and name != "timing_frames":
                continue
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise _fail(name, f"{value!r} is not a frame count", f"give a whole number >= {low}")
        if self.algorithm not in ALGORITHM_CHOICES:
            raise _fail("algorithm", f"unknown algorithm {self.algorithm!r}", f"one of {', '.join(ALGORITHM_CHOICES)}")
        if self.block not in BLOCK_SIZES:
            raise _fail("block", f"{self.block!r} is not a refresh block size",
                        f"one of {', '.join(str(b) for b in BLOCK_SIZES)}")
        if self.refresh not in REFRESH_MODES:
            raise _fail("refresh", f"unknown refresh pattern {self.refresh!r}", f"one of {', '.join(REFRESH_MODES)}")
        if not (isinstance(self.depth_epsilon, (int, float)) and 0 < self.depth_epsilon < 1):
            raise _fail("depth_epsilon", f"{self.depth_epsilon!r} is not in (0, 1)", "the default is 0.001")
        object.__setattr__(self, "depth_epsilon", float(self.depth_epsilon))
        if self.error_window is not None:
            if isinstance(self.error_window, bool) or not isinstance(self.error_window, (int, float)) \
                    or not 0 < self.error_window <= 1:
                raise _fail("error_window", f"{self.error_window!r} is not a share of the frame in (0, 1]",
                            "e.g. 0.25 for a quarter of the frame, 1 for all of it")
            object.__setattr__(self, "error_window", float(self.error_window))
        if isinstance(self.min_saving, bool) or not isinstance(self.min_saving, (int, float)) \
                or not 0 <= self.min_saving < 1:
            raise _fail("min_saving", f"{self.min_saving!r} is not a share in [0, 1)", "the default is 0.1")
        object.__setattr__(self, "min_saving", float(self.min_saving))
        if isinstance(self.min_gain, bool) or not isinstance(self.min_gain, (int, float)) \
                or not 0 <= self.min_gain < 100:
            raise _fail("min_gain", f"{self.min_gain!r} is not a speed-up in [0, 100)", "the default is 1.1")
        object.__setattr__(self, "min_gain", float(self.min_gain))
        if isinstance(self.max_sets, bool) or not isinstance(self.max_sets, int) or not 0 <= self.max_sets <= 64:
            raise _fail("max_sets", f"{self.max_sets!r} is not a count of sets in [0, 64]", "the default is 3; 0 trains none")
        if self.levels not in LEVEL_KINDS:
            raise _fail("levels", f"unknown levels {self.levels!r}", f"one of {', '.join(LEVEL_KINDS)}")
        if self.clock not in CLOCKS:
            raise _fail("clock", f"unknown frame clock {self.clock!r}", f"one of {', '.join(sorted(CLOCKS))}")
        if self.filter not in FILTER_CHOICES:
            raise _fail("filter", f"unknown filter {self.filter!r}", f"one of {', '.join(FILTER_CHOICES)}")
        if self.timing_format not in COLOR_FORMATS:
            raise _fail("timing_format", f"unknown colour format {self.timing_format!r}",
                        f"one of {', '.join(COLOR_FORMATS)}")
        if isinstance(self.budget_s, bool) or not isinstance(self.budget_s, (int, float)) \
                or not 0 < self.budget_s < float("inf"):
            raise _fail("budget_s", f"{self.budget_s!r} is not a positive, finite number of seconds", "e.g. 480")
        object.__setattr__(self, "budget_s", float(self.budget_s))

    # ------------------------------------------------------------------ JSON
    def to_json(self) -> dict:
        """A JSON-able dict (tuples become lists)."""
        out = asdict(self)
        for key, value in out.items():
            if isinstance(value, tuple):
                out[key] = list(value)
        return out

    @classmethod
    def from_json(cls, data: dict, where: str = "settings") -> "TrainingSettings":
        """The settings from :meth:`to_json`'s dict; unknown keys are an error."""
        if not isinstance(data, dict):
            raise RRCacheError("the training settings are not a JSON object", where,
                               hint="the profile file is damaged; run the profile again")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise RRCacheError(f"unknown training settings {unknown}", where,
                               hint="this profile was written by another rrcache version")
        kwargs = dict(data)
        for key in ("periods", "timing_periods", "resolution"):
            if isinstance(kwargs.get(key), list):
                kwargs[key] = tuple(kwargs[key])
        return cls(**kwargs)

    # ------------------------------------------------------------------ resolved against a session
    def resolved(self, session) -> "TrainingSettings":
        """These settings with the session's defaults filled in (resolution, frames, validation
        frames), so that leaving a default and writing it out give the same store key. Warns
        (``UserWarning``) when the error runs have fewer frames than the largest period: the
        cache then never reaches its steady state and the largest periods' errors are low.

        >>> from types import SimpleNamespace
        >>> s = TrainingSettings(periods=(2, 4)).resolved(SimpleNamespace(resolution=(640, 480), frames=30, path="s.json"))
        >>> s.resolution, s.frames, s.validation_frames
        ((640, 480), 30, 30)
        """
        where = str(getattr(session, "path", "session"))
        resolution = self.resolution
        if resolution is None:
            resolution = tuple(int(v) for v in session.resolution)
        frames = self.frames if self.frames is not None else min(DEFAULT_TRAINING_FRAMES, int(session.frames))
        if frames > session.frames:
            raise RRCacheError(f"asked for {frames} training frames; the session has {session.frames}", where,
                               hint=f"use --frames {session.frames} or fewer")
        validation = self.validation_frames if self.validation_frames is not None else int(session.frames)
        validation = min(validation, int(session.frames))
        if int(session.frames) < 2:
            raise RRCacheError("a session of one frame cannot train a cache", where,
                               hint="give the session at least as many frames as the largest period")
        if frames <= max(self.periods):
            warnings.warn(f"{frames} training frames do not reach the steady state of period {max(self.periods)}: "
                          "the cache needs at least as many consecutive frames as the largest period",
                          UserWarning, stacklevel=2)
        return replace(self, resolution=resolution, frames=frames, validation_frames=max(2, validation),
                       timing_frames=min(self.timing_frames, int(session.frames) - 1))

    def key_json(self) -> str:
        """The canonical JSON of the keyed fields (everything but :data:`UNKEYED`)."""
        data = {k: v for k, v in self.to_json().items() if k not in UNKEYED}
        if data.get("clock") == DEFAULT_CLOCK:  # as stores written before the clock was a setting
            del data["clock"]
        if data.get("filter") == "auto":  # the default keys as before it existed: older stores resume
            del data["filter"]
        if not data.get("measure_terms"):
            data.pop("measure_terms", None)
        return json.dumps(data, sort_keys=True, separators=(",", ":"))

    def key_hash(self) -> str:
        """sha256 of :meth:`key_json` (use on :meth:`resolved` settings)."""
        return hashlib.sha256(self.key_json().encode()).hexdigest()


def parse_periods(text: str, option: str = "--periods") -> tuple[int, ...]:
    """``"2,10,18"`` → ``(2, 10, 18)``; anything else raises :class:`RRCacheError`.

    >>> parse_periods("2, 4,8")
    (2, 4, 8)
    """
    try:
        values = tuple(int(part) for part in text.split(",") if part.strip())
    except ValueError:
        raise RRCacheError(f"{text!r} is not a comma-separated list of whole numbers", option,
                           hint="e.g. 2,10,18,26,34,42,50") from None
    return _periods(values, option, "e.g. 2,10,18,26,34,42,50")
