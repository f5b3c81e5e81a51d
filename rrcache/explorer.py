"""The interactive profiler of the notebooks (``notebooks/interactive.ipynb``; the paper's §4.5):
:class:`Explorer`, and :func:`measure_choice`, which renders a choice beside the original.

A log-scale slider for the error threshold re-selects from the models as it moves
(:meth:`Profile.select`, microseconds; the time of each re-selection is shown), then shows the
chosen node highlighted in the source, its Δn, the predicted and measured speed-up and error, a
frame with and without the cache side by side, the payload and the hit/miss map; a button writes
the chosen shader files. A choice that amortizes an estimator (m of its N terms per frame, blend
λ, history ``blend`` or ``slots``) is shown, rendered and measured the same way, its loop
highlighted in the source. The figures and HTML pieces are :mod:`rrcache.report.explore`'s; the
frames of new choices are rendered here (:class:`rrcache.profiler.frames.FrameShots`).

>>> prof = demo_profile("demo.rrprofile")          # doctest: +SKIP
>>> Explorer(prof)                                 # doctest: +SKIP
"""
from __future__ import annotations

import asyncio
import html
import math
import threading
import time
from pathlib import Path
from typing import Optional

from rrcache.choice import write as choice_write
from rrcache.errors import RRCacheError
from rrcache.profiler.frames import FrameShots  # noqa: F401 (the notebooks' shots)
from rrcache.report.data import selection_timing  # noqa: F401 (re-exported for the notebooks)
from rrcache.report.explore import CAPTIONS, _f, describe_choice, source_html


# ---------------------------------------------------------------------- measuring a choice
def measure_choice(prof, node, period: Optional[int], shots: FrameShots,
                   frames: Optional[int] = None) -> dict:
    """Render the session with the choice beside the original (:func:`rrcache.harness.cached.compare`,
    at the session's resolution, the first ``frames`` frames, default the profile's validation
    frames) and return ``{"error", "psnr", "speedup", "ms", "original_ms", "hit_rate", "frames"}``.
    The choice is ``node`` cached every ``period`` frames (``node`` None: the original), or
    ``node`` a :class:`~rrcache.selection.Selection` of any kind with a variant (an amortized
    estimator included; ``period`` is then not read). A choice the profile validated is not
    rendered again: its stored figures are returned."""
    from rrcache.selection import CachedNode, Selection

    if isinstance(node, Selection):
        choice = node
    else:
        choice = (Selection((CachedNode(node, int(period)),)) if node is not None
                  else Selection.original(prof.original_ms))
    for sel in list(prof.selections) + list(getattr(prof, "measured", None) or []):
        if sel.key == choice.key and sel.measured_error is not None and (sel.parts or sel.frames):
            return {"error": sel.measured_error, "psnr": sel.measured_psnr, "speedup": sel.measured_speedup,
                    "ms": sel.measured_ms, "original_ms": sel.measured_original_ms, "hit_rate": sel.hit_rate,
                    "frames": sel.frames, "stored": True}
    if not choice.parts:
        return {"error": 0.0, "psnr": None, "speedup": 1.0, "ms": prof.original_ms, "original_ms": prof.original_ms,
                "hit_rate": None, "frames": 0, "stored": True}
    from rrcache.harness.cached import compare

    settings = prof.settings
    count = min(int(frames or settings.validation_frames or shots.session.frames), int(shots.session.frames))
    variant, _ = shots.selection_variant(choice)  # its spec is the choice's, whole
    result = compare(variant, shots.session, shots.work.prepared, range(count), variant.spec)
    return {"error": result.mean_error, "psnr": result.psnr, "speedup": result.speedup, "ms": result.ms_per_frame,
            "original_ms": result.original_ms_per_frame, "hit_rate": result.hit_rate, "frames": count,
            "stored": False}


# ---------------------------------------------------------------------- the widget
class Explorer:
    """The interactive profiler (see the module docstring). ``value`` is the starting threshold
    (default: the profile's e2 level). Attributes: ``slider``, ``button``, ``choice`` (the last
    :class:`rrcache.selection.Selection`), ``select_ms`` (the last re-selection's time), ``render_ms``
    (the last new choice's frames and measurement),
    ``measured`` (the last choice's measurement), ``written`` (files the button wrote into
    ``out_dir``, default ``chosen/`` in the profile folder).
    ``measure=False`` skips rendering the session for choices the profile did not validate."""

    def __init__(self, prof, value: Optional[float] = None, out_dir=None, measure: bool = True,
                 shots: Optional[FrameShots] = None):
        import ipywidgets as w

        self.prof = prof
        self.out_dir = Path(out_dir) if out_dir is not None else Path(prof.path or ".") / "chosen"
        self.measure = measure
        self.shots = shots or FrameShots(prof)
        levels = [s.max_error for s in prof.selections if s.max_error and s.max_error > 0] or [1e-3]
        lo, hi = math.log10(min(levels) / 10.0), math.log10(max(levels) * 10.0)
        start = value if value is not None else levels[min(1, len(levels) - 1)]
        self.slider = w.FloatLogSlider(value=start, base=10, min=lo, max=hi, step=(hi - lo) / 200,
                                       description="max error", readout_format=".2e", continuous_update=True,
                                       layout=w.Layout(width="640px"))
        self.button = w.Button(description="Write shader files", icon="save", button_style="primary",
                               tooltip=f"write the chosen variant's passes and manifest into {self.out_dir}/",
                               layout=w.Layout(width="190px"))
        self.summary = w.HTML()
        self.source = w.HTML()
        self.status = w.HTML()
        self.frames = w.HBox()
        self.widget = w.VBox([w.HBox([self.slider, self.button]), self.summary, self.frames, self.source,
                              self.status])
        self.choice = None
        self.error: Optional[BaseException] = None
        self.images = None
        self.render_ms: Optional[float] = None
        self.select_ms: Optional[float] = None
        self.measured: Optional[dict] = None
        self.answer = None  # the last rrcache.profiles.measured.Choice: measured or predicted, warnings
        self.written: list = []
        # GL work must run on the thread that holds the GL context (the one building the widget);
        # a frontend may deliver widget events on another thread (JupyterLab's kernel subshells)
        self._thread = threading.current_thread()
        try:
            self._loop = asyncio.get_running_loop()  # the kernel's loop, when built in a notebook cell
        except RuntimeError:
            self._loop = None
        self.slider.observe(lambda change: self._on_gl_thread(self.update, change["new"]), names="value")
        self.button.on_click(lambda _: self._on_gl_thread(self.write_files))
        self.update(self.slider.value)

    def _on_gl_thread(self, action, *args) -> None:
        """Run a widget callback on the widget's own thread (handed to its event loop when the event
        arrives on another thread)."""
        if threading.current_thread() is self._thread or self._loop is None:
            self._guarded(action, *args)
        else:
            self._loop.call_soon_threadsafe(self._guarded, action, *args)

    def _guarded(self, action, *args):
        """Run a widget callback; an error shows in the widget (a callback's traceback would
        otherwise go only to the kernel's log) and the widget keeps working."""
        try:
            return action(*args)
        except Exception as err:  # shown to the user in the widget, not lost in the log
            import traceback

            self.error = err
            detail = "" if isinstance(err, RRCacheError) else f"<pre>{html.escape(traceback.format_exc())}</pre>"
            self.status.value = (f'<span style="color:#b00020">[{html.escape(threading.current_thread().name)}] '
                                 f'{html.escape(type(err).__name__)}: '
                                 f"{html.escape(str(err))}</span>{detail}")
            return None

    def update(self, max_error: float):
        """Re-select for ``max_error`` and refresh the view (renders only when the choice changes).
        Where the profile's validation measured a choice, its measurement answers
        (:func:`rrcache.profiles.measured.choose`); :attr:`answer` says which figures were measured."""
        from rrcache.profiles.measured import choose

        start = time.perf_counter()
        self.prof.select(max_error)  # the threshold's own checks
        self.answer = choose(self.prof, max_error=max_error)  # a cached node, an amortized estimator or the original
        choice = self.answer.selection
        self.select_ms = (time.perf_counter() - start) * 1000.0
        changed = self.choice is None or choice.key != self.choice.key
        self.choice = choice
        if changed:  # the predictions show at once; the frames and the measurement follow
            self.measured = None
            self._show_summary(max_error, pending=True)
            start = time.perf_counter()
            self._show_choice(choice)
            self.render_ms = (time.perf_counter() - start) * 1000.0
        self._show_summary(max_error)
        return choice

    def _show_choice(self, choice) -> None:
        import ipywidgets as w

        kind = choice.choice if choice.parts else None
        if kind is not None and not kind.has_frames:  # several nodes at once: measured, not shown
            images = None
            boxes = [w.HTML(f"<small>{html.escape(choice.describe())}: a choice of {html.escape(kind.title)} has no "
                            "frames here (as in the report); each node's are shown by "
                            "<code>FrameShots.images(node, period)</code></small>")]
        else:
            images = self.shots.selection_images(choice)
            boxes = []
            for name in CAPTIONS:
                if name in images.arrays:
                    boxes.append(w.VBox([w.Image(value=images.png(name), format="png",
                                                 width=2 * images.size[0] if images.size[0] <= 200 else images.size[0]),
                                         w.HTML(f"<small>{html.escape(images.caption(name))}</small>")]))
        self.frames.children = boxes
        self.images = images
        if self.measure or not choice.parts:
            self.measured = measure_choice(self.prof, choice, None, self.shots)
        else:
            self.measured = None
        shown = choice.choice.anchor(choice.parts) if choice.parts else None
        self.source.value = source_html(self.prof, shown, context=8) if shown else source_html(self.prof)

    def _show_summary(self, max_error: float, pending: bool = False) -> None:
        c, m = self.choice, self.measured or {}
        what = describe_choice(self.prof, c)
        measured = (f"measured over {m.get('frames')} frames{' (stored by the profile)' if m.get('stored') else ''}: "
                    f"speed-up <b>{_f(m.get('speedup'), 3)}×</b>, error <b>{_f(m.get('error'))}</b>, "
                    f"PSNR {_f(m.get('psnr'), 3)} dB, hit rate {_f(m.get('hit_rate'), 3)}"
                    if m else ("rendering and measuring…" if pending else "not measured (measure=False)"))
        shown = (f"this frame rendered at {self.images.size[0]}×{self.images.size[1]}, frame {self.images.frame}, "
                 f"with the measurement in {self.render_ms:.0f} ms" if self.images is not None and not pending else "")
        answer = self.answer
        source = (f"<b>{answer.source}</b>" + (f": {html.escape(answer.note)}" if answer.note else "")
                  if answer is not None else "")
        warnings = "".join(f'<br><span style="color:#b00020">warning: {html.escape(w)}</span>'
                           for w in (answer.warnings if answer is not None else []))
        self.summary.value = (
            f"<div>max error {max_error:.3g} → {what} ({source}){warnings}<br>"
            f"predicted: speed-up <b>{_f(c.predicted_speedup, 3)}×</b>, error <b>{_f(c.predicted_error)}</b>, "
            f"{_f(c.predicted_ms)} ms per frame (original {_f(self.prof.original_ms)} ms)<br>{measured}<br>"
            f"<small>re-selected in {self.select_ms:.3f} ms from the models and the profile's measurements; "
            f"{shown}</small></div>")

    def write_files(self) -> list:
        """Write the chosen shader files into ``out_dir`` (the button does this)."""
        self.written = choice_write(self.prof, self.choice, self.out_dir)
        self.status.value = (f"wrote {len(self.written)} files to <code>{html.escape(str(self.out_dir))}</code>: "
                             + ", ".join(html.escape(Path(p).name) for p in self.written))
        return self.written

    def _repr_mimebundle_(self, **kwargs):
        return self.widget._repr_mimebundle_(**kwargs)
