"""Spending more workers on accuracy: how a profile's default plan grows with its capacity.

In one process a profile's training is cut three ways to fit its budget: few nodes are trained
(9–14 of Marble's 492 in 360 s), on the first 64 frames of the session only, and the error runs
render a window of about a quarter of the frame. Each cut costs accuracy (the error of a cache
grows through a session; a window misses what the rest of the frame does). With ``c`` workers
running error runs, the same wall time buys ``c`` times the run-seconds, and
:func:`plan_for` spends them evenly on two things:

- **coverage** grows by ``g = √c``: first the training frames (``64·g``, up to the whole session,
  spread over it), then what the frame count could not take goes to the error window's area
  (its target cost and its cap, up to the whole frame at the session's resolution);
- **nodes**: the budget of run-seconds grows by ``c / g = √c`` (more nodes trained).

So each doubling of the workers trains √2 more nodes on √2 more of the session. Settings the user
gave (``frames``, ``error_window``) are kept as given; so is the plan of one process
(``c = 1``), whatever the defaults.

>>> p = plan_for(4, session_frames=150)
>>> p.frames, p.window_growth, p.budget_factor
(128, 1.0, 2.0)
>>> p = plan_for(16, session_frames=150)
>>> p.frames, round(p.window_growth, 2), p.budget_factor
(150, 1.71, 4.0)
>>> plan_for(1, session_frames=150).frames
64
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

#: the training frames of one process (TrainingSettings' default)
BASE_FRAMES = 64


@dataclass(frozen=True)
class CapacityPlan:
    """What ``workers`` error-run workers buy (see the module docstring): ``frames``, the default
    training frame count; ``window_growth``, the factor on the error window's target cost and
    area cap; ``budget_factor``, the factor on the node budget's run-seconds."""

    workers: int
    frames: int
    window_growth: float
    budget_factor: float

    def to_json(self) -> dict:
        return {"workers": self.workers, "frames": self.frames, "window_growth": self.window_growth,
                "budget_factor": self.budget_factor}


def plan_for(workers: int, session_frames: int, base_frames: Optional[int] = None) -> CapacityPlan:
    """The plan of ``workers`` error-run workers over a session of ``session_frames`` frames
    (``base_frames``: the frame count of one process, :data:`BASE_FRAMES` by default, never
    more than the session's)."""
    c = max(1, int(workers))
    base = min(int(session_frames), int(base_frames or BASE_FRAMES))
    growth = math.sqrt(c)
    frames = min(int(session_frames), int(round(base * growth)))
    window = max(1.0, growth * base / frames) if frames > 0 else 1.0
    return CapacityPlan(c, frames, float(window), float(c / growth))
