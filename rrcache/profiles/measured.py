"""Selecting from what was measured (issue 29 item 4; docs/levels.md).

A profile's validation measured some choices beside the original (``Profile.measured``: the
shipped ones and the ones refused at a level, each with its measured PSNR, FLIP, error and
speed-up). :func:`choose` answers a level the way the profile's own levels are answered:

- a measured choice that meets the level (:mod:`rrcache.model.levels`: its quality within the
  measurement's uncertainty, its speed-up clearing the gain worth having) is the answer when no
  unmeasured option is *predicted* faster than it measured;
- the models' choice (their PSNR prediction calibrated by validation, ``Profile.calibration``)
  is the answer otherwise, marked predicted; when validation measured that very choice, its
  measured figures come with it, and when they miss the level the answer is the fastest measured
  choice that meets it (or the original), with a warning naming the miss;
- ``max_flip`` (a FLIP level): FLIP is only measured, so measured choices meeting it answer; with
  none, the PSNR that the profile's measured choices relate to that FLIP (a line through
  log FLIP against PSNR, :func:`flip_psnr`) is asked of the models, marked predicted.

Each answer says which of its figures were measured and which predicted (:class:`Choice`).

>>> flip_psnr([(45.0, 0.01), (35.0, 0.04)], 0.02)
40.0
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from rrcache.model.levels import quality_miss, speed_miss
from rrcache.selection import Selection


@dataclass
class Choice:
    """The answer at a level: ``selection`` (with its measured figures when validation measured
    it), ``source`` (``measured``: its figures were measured; ``predicted``: only predicted),
    ``warnings`` (the asked level not met by what was measured, and what was done), ``note``
    (how the answer was found)."""

    selection: Selection
    source: str
    warnings: list = field(default_factory=list)
    note: str = ""

    @property
    def measured(self) -> bool:
        return self.source == "measured"


def measured_of(prof, sel: Selection) -> Optional[Selection]:
    """The measurement of what ``sel`` caches (``Profile.measured``, then the selections), or None."""
    for m in list(getattr(prof, "measured", None) or []) + list(prof.selections):
        if m.key == sel.key and m.parts and m.measured_error is not None:
            return m
    return None


def _meets(m: Selection, min_gain: float, min_psnr=None, max_error=None, max_flip=None) -> Optional[str]:
    why = quality_miss(m.measured_psnr, float(m.measured_psnr_uncertainty or 0.0), min_psnr, m.measured_error,
                       float(m.measured_error_uncertainty or 0.0), max_error, m.measured_flip,
                       float(m.measured_flip_uncertainty or 0.0), max_flip, exact=m.exact)
    return why or speed_miss(m.speedups or (m.measured_speedup,), min_gain)


def _with_measurement(sel: Selection, m: Selection) -> Selection:
    """``sel`` (the level's labels and predictions) with ``m``'s measured figures."""
    kept = {f: getattr(m, f) for f in ("measured_error", "measured_psnr", "measured_ms", "measured_original_ms",
                                       "measured_speedup", "hit_rate", "frames", "speedups", "measured_noise",
                                       "measured_psnr_uncertainty", "measured_error_uncertainty", "measured_flip",
                                       "measured_flip_uncertainty", "measured_temporal_psnr", "exact",
                                       "visible_artifacts")}
    return sel.replace(**kept)


def _original(prof, **level) -> Selection:
    """The original shader at a level: exact, speed-up 1."""
    return Selection.original(float(prof.original_ms or 0.0), algorithm=prof.algorithm, exact=True,
                              predicted_psnr_uncertainty=0.0, **level)


def flip_psnr(points, max_flip: float) -> Optional[float]:
    """The PSNR (dB) at which measured choices reach mean FLIP ``max_flip``: a least-squares line
    through (PSNR, log FLIP) of ``points`` (at least two with distinct PSNRs and FLIP > 0), None
    without them or when FLIP does not fall as PSNR rises."""
    pts = [(float(p), float(f)) for p, f in points if p is not None and f is not None and f > 0 and math.isfinite(p)]
    if len({p for p, _ in pts}) < 2 or not max_flip > 0:
        return None
    x = np.array([p for p, _ in pts])
    y = np.log(np.array([f for _, f in pts]))
    slope, intercept = np.polyfit(x, y, 1)
    if not slope < 0:
        return None
    return float(round((math.log(max_flip) - intercept) / slope, 6))


def choose(prof, min_psnr: Optional[float] = None, max_error: Optional[float] = None,
           max_flip: Optional[float] = None) -> Choice:
    """The answer at one level (give one of ``min_psnr``, ``max_error``, ``max_flip``; see the
    module docstring)."""
    gain = float(prof.settings.min_gain)
    measured = [m for m in (getattr(prof, "measured", None) or []) if m.parts and m.measured_error is not None]
    level = dict(min_psnr=min_psnr, max_error=max_error, max_flip=max_flip)
    meeting = sorted((m for m in measured if _meets(m, gain, **level) is None),
                     key=lambda m: -float(m.measured_speedup or 0.0))
    best = meeting[0] if meeting else None
    if max_flip is not None:
        if best is not None:
            return Choice(_with_measurement(best, best).replace(max_flip=max_flip, label=None), "measured",
                          note=f"the fastest of the {len(measured)} measured choices with mean FLIP ≤ {max_flip:g}")
        needed = flip_psnr([(m.measured_psnr, m.measured_flip) for m in measured if not m.exact], max_flip)
        if needed is None:
            return Choice(_original(prof, max_flip=max_flip), "measured", [f"no measured choice has mean FLIP ≤ {max_flip:g}, and too few were "
                                                 "measured to relate FLIP to PSNR: the original shader"])
        model = prof.select_psnr(needed).replace(max_flip=max_flip)
        return Choice(model, "predicted", note=f"no measured choice has mean FLIP ≤ {max_flip:g}; the measured "
                                               f"choices relate it to PSNR ≥ {needed:.1f} dB, predicted by the models")
    model = prof.select_psnr(min_psnr) if min_psnr is not None else prof.select(max_error)
    if not model.parts:
        if best is not None:
            return Choice(_with_measurement(best.replace(min_psnr=min_psnr, max_error=max_error, label=None), best),
                          "measured", note="measured to meet the level; the models predicted nothing faster")
        return Choice(model, "measured", note="the original shader (exact)")
    own = measured_of(prof, model)
    if own is not None:
        why = _meets(own, gain, **level)
        if why is None:
            return Choice(_with_measurement(model, own), "measured", note="the models' choice, measured by validation")
        fallback = best.replace(min_psnr=min_psnr, max_error=max_error, label=None) if best is not None else None
        warning = f"the models' choice {model.describe()} was measured and misses the level: {why}"
        if fallback is not None:
            return Choice(_with_measurement(fallback, best), "measured",
                          [warning + f"; the fastest measured choice that meets it instead: {best.describe()}"])
        return Choice(_original(prof, min_psnr=min_psnr, max_error=max_error), "measured",
                      [warning + "; no measured choice meets it: the original shader"])
    if best is not None and float(best.measured_speedup or 0.0) >= float(model.predicted_speedup or 0.0):
        return Choice(_with_measurement(best.replace(min_psnr=min_psnr, max_error=max_error, label=None), best),
                      "measured", note=f"measured faster ({best.measured_speedup:.2f}×) than the models predict of "
                                       f"{model.describe()} ({model.predicted_speedup:.2f}×)")
    return Choice(model, "predicted", note="predicted by the models" + (
        f" (PSNR calibrated by {len(prof.calibrated().points)} validated choices)" if prof.calibrated().points else ""))
