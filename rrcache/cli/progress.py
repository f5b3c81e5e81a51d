"""Progress on stderr for the long commands (profile, bench, bench-cache, render, accuracy).

On a terminal: rich's progress bar (description, bar, done/total, elapsed, ETA), cleared at the
end. Elsewhere (CI, a log file, a pipe, a notebook): one plain line per finished step, with the
elapsed time and, when the total is known, the ETA, and a line every ``interval`` seconds (10 by
default) while a long step runs, so a command on a pipe never goes quiet for minutes::

    [     12.4 s] error n2392 Δn=10: done (412/1630, ETA 48 s)
    [     22.4 s] rendering: 40/150 (ETA estimating)

The ETA says "estimating" until it is stable (:class:`Eta`): the first minutes of a profile
render references and measure the ceiling at other rates than the training that follows, and an
ETA taken from them would swing from hours to minutes.

A step is what the library reports under one label (frame numbers at the end of a label are
left out, so a reference run of 64 frames is one step). ``quiet`` shows nothing.

>>> import io
>>> from rich.console import Console
>>> out = io.StringIO()
>>> with Reporter(Console(file=out, force_terminal=False), clock=iter(range(0, 100, 5)).__next__) as rep:
...     rep.update("reference frame 0", 1, 4); rep.update("reference frame 1", 2, 4)
...     rep.update("error n1 Δn=2", 3, 4); rep.update("error n1 Δn=2", 4, 4)
>>> print(out.getvalue().strip())
[     10.0 s] reference: done (2/4, ETA estimating)
[     20.0 s] error n1 Δn=2: done (4/4)
"""
from __future__ import annotations

import re
import time
from typing import Callable, Optional

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

_FRAME = re.compile(r"\s*(?:timing\s+)?frames?\s+\d+\s*$")


def _duration(seconds: float) -> str:
    seconds = max(0.0, float(seconds))
    if seconds < 90:
        return f"{seconds:.0f} s"
    minutes, sec = divmod(int(round(seconds)), 60)
    if minutes < 90:
        return f"{minutes} min {sec:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


class Eta:
    """The time left, or None ("estimating") until the estimate is stable.

    Each update projects when the work will be done from the average rate since its counter
    started (a new counter, one that goes back to fewer done, starts where the last update of
    the old one was). The estimate is shown once at least ``min_share`` of the work is done, at
    least ``min_seconds`` have passed on this counter, and the last ``samples`` projections
    (taken at least ``spacing`` seconds apart) agree within ``agree`` (25%) of the counter's
    projected duration; it goes back to "estimating" whenever they stop agreeing (the rate changed, or the
    plan grew or shrank).

    >>> eta = Eta(min_seconds=10, spacing=2)
    >>> [eta.update(t, t, 100) for t in (1, 3, 5)]      # too early: estimating
    [None, None, None]
    >>> eta.update(12, 12, 100), eta.text()             # a steady rate: 88 s left
    (88.0, '88 s')
    >>> eta.update(14, 20, 100) is None                 # the rate changed: estimating again
    True
    >>> eta.update(20, 2, 50) is None                   # a new counter: a new estimate
    True
    """

    def __init__(self, min_share: float = 0.05, min_seconds: float = 20.0, agree: float = 0.25,
                 samples: int = 3, spacing: float = 5.0):
        self.min_share, self.min_seconds, self.agree = min_share, min_seconds, agree
        self.samples, self.spacing = samples, spacing
        self._projections: list[tuple[float, float]] = []  # (elapsed, projected time left)
        self._origin = 0.0  # when the current counter started
        self._last = (0.0, 0)  # the last update's (elapsed, done)
        self._left: Optional[float] = None

    def update(self, elapsed: float, done: Optional[int], total: Optional[int]) -> Optional[float]:
        """Record progress; return the seconds left, or None while estimating."""
        self._left = None
        if done is None or not total:
            return None
        elapsed = float(elapsed)
        if done < self._last[1]:  # a new counter: a new estimate, from the old one's last update
            self._projections = []
            self._origin = self._last[0]
        self._last = (elapsed, done)
        spent = elapsed - self._origin
        if done <= 0 or done >= total or spent <= 0:
            return None
        left = spent / done * (total - done)
        if self._projections and elapsed - self._projections[-1][0] < self.spacing:
            self._projections[-1] = (self._projections[-1][0], elapsed + left)
        else:
            self._projections.append((elapsed, elapsed + left))
        self._projections = self._projections[-self.samples:]
        ends = [end for _, end in self._projections]
        span = max(ends) - min(ends)
        if (done / total < self.min_share or spent < self.min_seconds or len(ends) < self.samples
                or span > self.agree * (spent + left)):
            return None
        self._left = left
        return left

    def text(self) -> str:
        """The last update's estimate in words, or "estimating"."""
        return "estimating" if self._left is None else _duration(self._left)


class Reporter:
    """Progress for one command (see the module docstring): ``update(label, done, total)`` as
    work proceeds (``done``/``total`` may be None), ``line(text)`` for a message of its own.
    ``interval``: off a terminal, the seconds between the lines of a step still running."""

    def __init__(self, console: Optional[Console] = None, quiet: bool = False, width: int = 40,
                 clock: Callable[[], float] = time.perf_counter, interval: float = 10.0):
        self.console = console or Console(stderr=True)
        self.quiet = quiet
        self.terminal = self.console.is_terminal and not quiet
        self._clock = clock
        self._start = None
        self._key: Optional[str] = None
        self._last = (None, None, 0.0)
        self._bar = None
        self._task = None
        self._width = width
        self._interval = float(interval)
        self._printed = 0.0
        self.eta = Eta()

    def __enter__(self) -> "Reporter":
        self._start = self._clock()
        if self.terminal:
            self._bar = Progress(TextColumn(f"{{task.description:<{self._width}}}"), BarColumn(),
                                 MofNCompleteColumn(), TimeElapsedColumn(), TextColumn("ETA {task.fields[eta]}"),
                                 console=self.console, transient=True)
            self._bar.__enter__()
            self._task = self._bar.add_task("starting", total=None, eta="estimating")
        return self

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.__exit__(*exc)
            self._bar = None
        elif exc[0] is None:
            self._finish_step()

    def _elapsed(self) -> float:
        return self._clock() - self._start if self._start is not None else 0.0

    def _where(self, done, total, finished: bool) -> str:
        """' (2/4, ETA 10 s)' after a finished step's 'done'; ': 40/150 (ETA estimating)' for a
        step still running."""
        if done is None or not total:
            return ""
        eta = f"ETA {self.eta.text()}" if 0 < done < total else ""
        if finished:
            return f" ({done}/{total}" + (f", {eta}" if eta else "") + ")"
        return f": {done}/{total}" + (f" ({eta})" if eta else "")

    def _print(self, text: str, at: float) -> None:
        self.console.print(text, highlight=False, markup=False, emoji=False, soft_wrap=True)
        self._printed = at

    def _finish_step(self) -> None:
        if self._key is None or self.quiet:
            return
        done, total, elapsed = self._last
        self._print(f"[{elapsed:9.1f} s] {self._key}: done{self._where(done, total, True)}", elapsed)
        self._key = None

    def update(self, label: str, done: Optional[int] = None, total: Optional[int] = None) -> None:
        """The work under ``label`` has reached ``done`` of ``total``."""
        if self.quiet:
            return
        now = self._elapsed()
        self.eta.update(now, done, total)
        if self._bar is not None:
            kwargs = {"description": label[:self._width], "eta": self.eta.text()}
            if done is not None:
                kwargs["completed"] = done
            if total is not None:
                kwargs["total"] = total
            self._bar.update(self._task, **kwargs)
            return
        key = _FRAME.sub("", label).strip() or label
        if key != self._key:
            self._finish_step()
            self._key = key
            self._printed = now  # a step's first progress line comes an interval after it starts
        # the library reports a unit of work when it is done: the step ends at its last report
        self._last = (done, total, now)
        if now - self._printed >= self._interval and not (done is not None and total and done >= total):
            self._print(f"[{now:9.1f} s] {key}{self._where(done, total, False)}", now)

    def line(self, text: str) -> None:
        """A message of its own (above the bar on a terminal; with the elapsed time elsewhere)."""
        if self.quiet:
            return
        if self._bar is not None:
            self._bar.console.print(text, highlight=False, markup=False)
        else:
            self._finish_step()
            now = self._elapsed()
            self._print(f"[{now:9.1f} s] {text}", now)

    def event(self, event) -> None:
        """A :class:`~rrcache.profiler.train.ProgressEvent` (stage, done, total, detail)."""
        self.update(f"{event.stage} {event.detail}".strip(), event.done, event.total)


def quiet_option(func):
    """The ``--quiet`` option of every command with progress."""
    import click

    return click.option("--quiet", "-q", is_flag=True, help="No progress on stderr.")(func)
