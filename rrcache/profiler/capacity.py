"""Spending more workers on accuracy: how a profile's default plan grows with its capacity.

In one process a profile's training is cut to fit its budget: few nodes are trained (9–14 of
Marble's 492 in 360 s) on the first 64 frames of the session. Each cut costs accuracy (the
error of a cache grows through a session; an untrained node cannot be chosen). With ``c``
workers running error runs the same wall time buys about ``c`` times the run-seconds, and
:func:`plan_for` spends them on both cuts:

- the **training frames** grow by ``√c``: ``64·√c``, up to the whole session;
- the **node budget** (run-seconds; ``TrainingSettings.budget_s`` stays the wall-clock budget
  the user gives) grows by the rest, ``c / (frames growth)``: at least ``√c``, and more once the
  frames reach the whole session.

So each doubling of the workers trains about √2 more nodes on √2 more of the session. A frame
count the user gave (``frames``) is kept as given; in one process (``c = 1``) nothing changes.
Which frames are trained (spread over the session) and the error window are the plan's
(:mod:`rrcache.profiler.plan`).

>>> p = plan_for(4, session_frames=150)
>>> p.frames, p.budget_factor
(128, 2.0)
>>> p = plan_for(16, session_frames=150)
>>> p.frames, round(p.budget_factor, 2)
(150, 6.83)
>>> plan_for(1, session_frames=150).frames, plan_for(1, session_frames=150).budget_factor
(64, 1.0)
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
    training frame count, and ``budget_factor``, the factor on the node budget's run-seconds."""

    workers: int
    frames: int
    budget_factor: float

    def to_json(self) -> dict:
        return {"workers": self.workers, "frames": self.frames, "budget_factor": self.budget_factor}


def plan_for(workers: int, session_frames: int, base_frames: Optional[int] = None) -> CapacityPlan:
    """The plan of ``workers`` error-run workers over a session of ``session_frames`` frames
    (``base_frames``: the frame count of one process, :data:`BASE_FRAMES` by default, never
    more than the session's)."""
    c = max(1, int(workers))
    base = min(int(session_frames), int(base_frames or BASE_FRAMES))
    frames = min(int(session_frames), int(round(base * math.sqrt(c))))
    return CapacityPlan(c, frames, float(c * base / frames) if frames > 0 else float(c))


def scaled(settings, session, workers: int):
    """``settings`` for a profile whose error runs have ``workers`` workers: the default frame
    count and the budget grown as :func:`plan_for` says (a frame count given is kept, and its
    share of the capacity goes to the budget); returns (settings, plan)."""
    from dataclasses import replace

    plan = plan_for(workers, int(session.frames))
    if plan.workers == 1:
        return settings, plan
    frames = settings.frames if settings.frames is not None else plan.frames
    base = min(int(session.frames), BASE_FRAMES)
    factor = plan.workers * base / max(1, frames) if settings.frames is None else float(plan.workers)
    plan = CapacityPlan(plan.workers, frames, max(1.0, factor))
    return replace(settings, frames=frames, budget_s=settings.budget_s * plan.budget_factor), plan
