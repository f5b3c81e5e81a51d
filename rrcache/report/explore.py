"""The notebooks' figures and the interactive profiler widget (``notebooks/explore.ipynb`` and
``notebooks/interactive.ipynb`` call only this module and :func:`rrcache.profiler.demo_profile`).

Figures (matplotlib): :func:`tradeoff_figure` (every node path, the amortized estimators'
options, the original's time, the Pareto front, the selections), :func:`node_figure` (a node's
measured errors with the fitted error model, and its predicted frame time over Δn),
:func:`images_figure` (a choice's original, cached frame, error map, payload and hit/miss map;
a cached node's or an amortized estimator's). HTML: :func:`source_html` (the shader with a node
highlighted), :func:`selections_html` (the four selections, predicted against measured).

:class:`Explorer` is the paper's interactive profiler (§4.5): a log-scale slider for the error
threshold re-selects from the models as it moves (:meth:`Profile.select`, microseconds; the time
of each re-selection is shown), then shows the chosen node highlighted in the source, its Δn, the
predicted and measured speed-up and error, a frame with and without the cache side by side, the
payload and the hit/miss map; a button writes the chosen shader files. A choice that amortizes an
estimator (m of its N terms per frame, blend λ, history ``blend`` or ``slots``) is shown,
rendered and measured the same way, its loop highlighted in the source.

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

import numpy as np

from rrcache.errors import RRCacheError
from rrcache.report.data import read_source, selection_timing  # noqa: F401 (selection_timing re-exported)
from rrcache.report.images import CAPTIONS, FrameShots  # noqa: F401 (FrameShots re-exported)


def _pyplot():
    """pyplot, with figures shown as PNG in IPython whatever the backend (the profiler switches
    matplotlib to Agg, which leaves a notebook without its inline figure display)."""
    import matplotlib.pyplot as plt

    try:
        from IPython import get_ipython
    except ImportError:
        return plt
    shell = get_ipython()
    if shell is not None:
        from IPython.core.pylabtools import print_figure
        from matplotlib.figure import Figure

        formatter = shell.display_formatter.formatters["image/png"]
        formatter.for_type(Figure, lambda fig: print_figure(fig, "png", bbox_inches="tight"))
    return plt


def _f(value, digits: int = 4) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return f"{float(value):.{digits}g}"


# ---------------------------------------------------------------------- figures
def tradeoff_figure(prof, log_error: bool = True, highlight: Optional[str] = None):
    """Error against ms per frame: every trained node over Δn = 1..50 (from the model table), the
    amortized estimators' options (m, λ; :func:`rrcache.report.plots.draw_amortized`), the
    original's time (dashed), the Pareto front over both (black) and the four selections
    (squares); ``highlight`` draws one node's path thicker. Returns the matplotlib figure."""
    from rrcache.report.plots import draw_amortized, front_points

    plt = _pyplot()
    table = prof.table
    fig, ax = plt.subplots(figsize=(8, 5), dpi=100)
    cmap = plt.get_cmap("viridis")
    first = 1 if log_error else 0  # Δn = 1 has error 0: left out of a log axis
    for i, node_id in enumerate(table.node_ids):
        wide = node_id == highlight
        ax.plot(table.T[i, first:], table.E[i, first:], "-", lw=2.5 if wide else 0.9,
                color="crimson" if wide else cmap(i / max(1, len(table.node_ids) - 1)), alpha=1 if wide else 0.7)
    amortized = draw_amortized(ax, prof, positive_only=log_error)
    front = [(err, ms) for err, ms in front_points(prof) if not log_error or err > 0]
    ax.plot([ms for _, ms in front], [err for err, _ in front], "-", color="black", lw=2,
            alpha=0.5, label="Pareto front")
    ax.axvline(prof.original_ms, ls="--", color="gray", label=f"original ({prof.original_ms:.3g} ms)")
    for sel in prof.selections:
        if sel.parts:
            ax.plot(sel.predicted_ms, sel.predicted_error, "s", mfc="none", mec="crimson", ms=8, mew=1.8)
            ax.annotate(f"{sel.label}: {sel.describe()}", (sel.predicted_ms, sel.predicted_error),
                        textcoords="offset points", xytext=(7, 4), fontsize=8, color="crimson")
    if log_error:
        ax.set_yscale("log")
    ax.set_xlabel("ms per frame (predicted)")
    ax.set_ylabel("mean RGB L2 error (predicted)")
    title = f"{Path(prof.shader).name}: {len(table.node_ids)} trained nodes over Δn = 1..{table.max_period}"
    ax.set_title(title + (f", {amortized} amortized options" if amortized else ""))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    plt.close(fig)
    return fig


def node_figure(prof, node_id: str):
    """Two panels for one trained node: its measured error runs with the fitted
    α(1 − e^(−λ(Δn−1))) and the predicted ms per frame over Δn (the original's time dashed)."""
    plt = _pyplot()
    node = prof.node(node_id)
    table = prof.table
    i = table.node_ids.index(node.id)
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.4), dpi=100)
    a.plot(table.periods, table.E[i], "-", color="tab:blue",
           label=f"model α = {_f(node.alpha, 3)}, λ = {_f(node.lam, 3)}")
    a.plot(node.periods, node.errors, "o", color="black", label="measured")
    a.set_xlabel("refresh period Δn")
    a.set_ylabel("mean RGB L2 error")
    a.set_title(f"{node.id}: error")
    a.legend(fontsize=8)
    b.plot(table.periods, table.T[i], "-", color="tab:green",
           label=f"t_hit = {_f(node.t_hit, 3)}, t_miss = {_f(node.t_miss, 3)} ms/px")
    b.axhline(prof.original_ms, ls="--", color="gray", label="original")
    b.set_xlabel("refresh period Δn")
    b.set_ylabel("ms per frame (predicted)")
    b.set_title(f"{node.id}: time")
    b.legend(fontsize=8)
    for ax in (a, b):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    plt.close(fig)
    return fig


def images_figure(images):
    """A row of a choice's images (:class:`~rrcache.report.images.ChoiceImages`)."""
    plt = _pyplot()
    names = [n for n in CAPTIONS if n in images.arrays]
    fig, axes = plt.subplots(1, len(names), figsize=(2.6 * len(names), 2.4), dpi=100, squeeze=False)
    for ax, name in zip(axes[0], names):
        ax.imshow(np.clip(images.arrays[name], 0, 1), interpolation="nearest")
        ax.set_title(images.caption(name), fontsize=7)
        ax.axis("off")
    fig.suptitle(f"{images.what}, frame {images.frame}", fontsize=9)
    fig.tight_layout()
    plt.close(fig)
    return fig


def selections_figure(prof, shots: FrameShots):
    """One row of images per selection (e1..e4; see :func:`images_figure`): the original, a cached
    node or an amortized estimator (several nodes at once: their description only)."""
    plt = _pyplot()
    names = list(CAPTIONS)
    fig, axes = plt.subplots(len(prof.selections), len(names), figsize=(2.4 * len(names), 2.2 * len(prof.selections)),
                             dpi=100, squeeze=False)
    for row, sel in zip(axes, prof.selections):
        if sel.multi:  # no frames (the shots render one cached node or one amortized estimator)
            for ax in row:
                ax.axis("off")
            row[0].text(-0.08, 0.5, f"{sel.label}: {sel.describe()}", transform=row[0].transAxes, rotation=90,
                        ha="right", va="center", fontsize=8)
            continue
        images = shots.selection_images(sel)
        for ax, name in zip(row, names):
            ax.axis("off")
            if name in images.arrays:
                ax.imshow(np.clip(images.arrays[name], 0, 1), interpolation="nearest")
                ax.set_title(images.caption(name), fontsize=7)
        what = images.what if images.cached else "original"
        row[0].text(-0.08, 0.5, f"{sel.label}: {what}", transform=row[0].transAxes, rotation=90,
                    ha="right", va="center", fontsize=8)
    fig.tight_layout()
    plt.close(fig)
    return fig


def default_choice(prof) -> tuple:
    """``(node, Δn)`` worth a first look at one *node* (the notebook's node section): the last
    selection that caches a node, else the costliest trained node at the largest trained period.
    Amortized selections are not nodes: :func:`selections_figure` and the :class:`Explorer` show
    them; :func:`default_selection` returns the last selection of any kind."""
    for sel in reversed(prof.selections):
        if sel.parts and sel.kind == "cache":
            return sel.node, int(sel.period)
    node = prof.trained_nodes[0]
    return node.id, int(max(node.periods))


def default_selection(prof):
    """The last selection that changes the shader (a cached node or an amortized estimator; not
    several nodes at once, which have no frames), else the original's selection: what
    :func:`describe_choice` and :meth:`FrameShots.selection_images` show first."""
    for sel in reversed(prof.selections):
        if sel.parts and not sel.multi:
            return sel
    return prof.selections[0] if prof.selections else None


def describe_choice(prof, choice) -> str:
    """One line of HTML saying what a selection does: the original, a node cached every Δn
    frames, or an estimator amortized (m of N terms per frame, blend λ, its history)."""
    if not choice.parts:
        return "<b>the original shader</b>: no variant is predicted faster within this error"
    if choice.kind == "amortize":
        part = choice.parts[0]
        est = next((e for e in prof.estimators if e.id == part.estimator), None)
        of = f" of {est.samples}" if est is not None else ""
        loop = f" <code>{html.escape(est.text)}</code>" if est is not None and est.text else ""
        how = ("its N/m subset sums kept apart (slots history)" if part.history == "slots"
               else "blended with the reprojected estimate (blend history)")
        return (f"amortize estimator <b>{html.escape(part.estimator)}</b>{loop}: <b>{part.samples}{of}</b> terms "
                f"per frame, {how}, <b>λ = {part.blend:g}</b>")
    if choice.multi:
        return "cache " + " + ".join(f"<b>{html.escape(n)}</b> every Δn = {p}"
                                     for n, p in zip(choice.nodes, choice.periods))
    return (f"cache <b>{html.escape(choice.node)}</b> <code>{html.escape(prof.node(choice.node).text)}</code> "
            f"every <b>Δn = {choice.period}</b> frames")


# ---------------------------------------------------------------------- HTML pieces
def source_html(prof, node_id: Optional[str] = None, context: Optional[int] = None) -> str:
    """The shader source as HTML, the line of ``node_id`` highlighted from its column on (lines
    where other trained nodes start get a faint mark). ``node_id`` may also name an estimator
    (``e1``: its loop). ``context``: only that many lines around the node."""
    lines = read_source(prof)
    estimator = next((e for e in prof.estimators if e.id == node_id), None) if node_id else None
    if estimator is not None:  # an estimator's loop (no mark where its line is not known)
        node = estimator if estimator.line else None
    else:
        node = prof.node(node_id) if node_id else None
    starts = {int(n.line) for n in prof.trained_nodes}
    lo, hi = 1, len(lines)
    if node is not None and context is not None:
        lo, hi = max(1, node.line - context), min(len(lines), node.line + context)
    rows = []
    for number in range(lo, hi + 1):
        text = lines[number - 1]
        if node is not None and number == node.line:
            col = max(0, node.column - 1)
            body = (html.escape(text[:col]) + '<mark style="background:#ffe066">' + html.escape(text[col:])
                    + "</mark>")
            style = "background:#fff6cc"
        else:
            body, style = html.escape(text), ("background:#eef6ee" if number in starts else "")
        rows.append(f'<div style="{style}"><span style="color:#999;display:inline-block;width:3em">{number}</span>'
                    f"{body}</div>")
    return ('<div style="font:12px/1.35 monospace;white-space:pre;max-height:360px;overflow:auto;'
            'border:1px solid #ddd;padding:4px">' + "".join(rows) + "</div>")


def selections_html(prof) -> str:
    """The four selections as an HTML table: threshold, node, Δn, predicted and measured error,
    ms per frame and speed-up, PSNR and hit rate."""
    head = ["", "max error", "node", "Δn", "pred. error", "meas. error", "pred. ms", "meas. ms",
            "pred. speed-up", "meas. speed-up", "PSNR", "hit rate"]
    rows = []
    for s in prof.selections:
        if s.kind == "amortize":  # an amortized estimator: m of N terms per frame, blend λ
            node_cell, period_cell = s.describe(), "–"
        else:
            node_cell = " + ".join(s.nodes) if s.multi else (s.node or "original")
            period_cell = " + ".join(str(p) for p in s.periods) if s.multi else (s.period or "–")
        cells = [s.label, _f(s.max_error), node_cell, period_cell, _f(s.predicted_error),
                 _f(s.measured_error), _f(s.predicted_ms), _f(s.measured_ms), _f(s.predicted_speedup, 3),
                 _f(s.measured_speedup, 3), _f(s.measured_psnr, 3), _f(s.hit_rate, 3)]
        rows.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells) + "</tr>")
    return ("<table><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr>" + "".join(rows) + "</table>")


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
        # adaptive refresh is measured as its node at its max age, as before (no adaptive runtime here)
        node, period = ((choice.node, choice.period) if choice.kind in ("cache", "adaptive", "original")
                        else (None, None))
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
    if choice.kind in ("cache", "adaptive"):
        variant, period = shots.variant(node), int(period)
    else:  # an amortized estimator (its variant does not use the refresh rule), several nodes
        variant, period = shots.selection_variant(choice)
    result = compare(variant, shots.session, shots.work.prepared, range(count), period=period,
                     **settings.cache_options())
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
        shown = choice.parts[0].estimator if choice.kind == "amortize" else (choice.node if choice.parts else None)
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
        answer = getattr(self, "answer", None)
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
        self.written = self.prof.write_variant(self.choice, self.out_dir)
        self.status.value = (f"wrote {len(self.written)} files to <code>{html.escape(str(self.out_dir))}</code>: "
                             + ", ".join(html.escape(Path(p).name) for p in self.written))
        return self.written

    def _repr_mimebundle_(self, **kwargs):
        return self.widget._repr_mimebundle_(**kwargs)
