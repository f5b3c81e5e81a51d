"""What the profiler tells its caller while it works: :class:`ProgressEvent`."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


@dataclass
class ProgressEvent:
    """Sent to the ``progress`` callback: ``stage`` (``reference``, ``error``, ``timing``,
    ``overhead``, ``check`` (the window check), ``validate``, ``sets``, ``amortize``, ``adaptive``), frames rendered ``done`` of ``total`` planned (the plan shrinks
    when the budget stops the training), and a short ``detail`` (node and period)."""

    stage: str
    done: int
    total: int
    detail: str = ""


ProgressFn = Callable[[ProgressEvent], None]
