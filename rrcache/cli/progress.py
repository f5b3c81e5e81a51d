"""Progress on stderr for the long commands (profile, bench, bench-cache, render).

On a terminal: rich's progress bar (description, bar, done/total, elapsed, ETA), cleared at the
end. Elsewhere (CI, a log file, a notebook): one plain line per finished step, with the elapsed
time and, when the total is known, the ETA::

    [     12.4 s] error n2392 Δn=10: done (412/1630, ETA 48 s)

A step is what the library reports under one label (frame numbers at the end of a label are
left out, so a reference run of 64 frames is one step). ``quiet`` shows nothing.

>>> import io
>>> from rich.console import Console
>>> out = io.StringIO()
>>> with Reporter(Console(file=out, force_terminal=False), clock=iter(range(0, 100, 5)).__next__) as rep:
...     rep.update("reference frame 0", 1, 4); rep.update("reference frame 1", 2, 4)
...     rep.update("error n1 Δn=2", 3, 4); rep.update("error n1 Δn=2", 4, 4)
>>> print(out.getvalue().strip())
[     10.0 s] reference: done (2/4, ETA 10 s)
[     20.0 s] error n1 Δn=2: done (4/4)
"""
from __future__ import annotations

import re
import time
from typing import Callable, Optional

from rich.console import Console
from rich.progress import (BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn,
                           TimeRemainingColumn)

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


class Reporter:
    """Progress for one command (see the module docstring): ``update(label, done, total)`` as
    work proceeds (``done``/``total`` may be None), ``line(text)`` for a message of its own."""

    def __init__(self, console: Optional[Console] = None, quiet: bool = False, width: int = 40,
                 clock: Callable[[], float] = time.perf_counter):
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

    def __enter__(self) -> "Reporter":
        self._start = self._clock()
        if self.terminal:
            self._bar = Progress(TextColumn(f"{{task.description:<{self._width}}}"), BarColumn(),
                                 MofNCompleteColumn(), TimeElapsedColumn(), TextColumn("ETA"),
                                 TimeRemainingColumn(), console=self.console, transient=True)
            self._bar.__enter__()
            self._task = self._bar.add_task("starting", total=None)
        return self

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.__exit__(*exc)
            self._bar = None
        elif exc[0] is None:
            self._finish_step()

    def _elapsed(self) -> float:
        return self._clock() - self._start if self._start is not None else 0.0

    def _finish_step(self) -> None:
        if self._key is None or self.quiet:
            return
        done, total, elapsed = self._last
        where = ""
        if done is not None and total:
            where = f" ({done}/{total}"
            if 0 < done < total:
                where += f", ETA {_duration(elapsed / done * (total - done))}"
            where += ")"
        self.console.print(f"[{elapsed:9.1f} s] {self._key}: done{where}", highlight=False, markup=False,
                           soft_wrap=True)
        self._key = None

    def update(self, label: str, done: Optional[int] = None, total: Optional[int] = None) -> None:
        """The work under ``label`` has reached ``done`` of ``total``."""
        if self.quiet:
            return
        if self._bar is not None:
            kwargs = {"description": label[:self._width]}
            if done is not None:
                kwargs["completed"] = done
            if total is not None:
                kwargs["total"] = total
            self._bar.update(self._task, **kwargs)
            return
        key = _FRAME.sub("", label).strip() or label
        now = self._elapsed()
        if key != self._key:
            self._finish_step()
            self._key = key
        # the library reports a unit of work when it is done: the step ends at its last report
        self._last = (done, total, now)

    def line(self, text: str) -> None:
        """A message of its own (above the bar on a terminal; with the elapsed time elsewhere)."""
        if self.quiet:
            return
        if self._bar is not None:
            self._bar.console.print(text, highlight=False, markup=False)
        else:
            self._finish_step()
            self.console.print(f"[{self._elapsed():9.1f} s] {text}", highlight=False, markup=False, soft_wrap=True)

    def event(self, event) -> None:
        """A :class:`~rrcache.profiler.train.ProgressEvent` (stage, done, total, detail)."""
        self.update(f"{event.stage} {event.detail}".strip(), event.done, event.total)


def quiet_option(func):
    """The ``--quiet`` option of every command with progress."""
    import click

    return click.option("--quiet", "-q", is_flag=True, help="No progress on stderr.")(func)
