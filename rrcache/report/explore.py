"""The notebooks' figures and HTML pieces, from a profile and its folder only (the interactive
widget, which renders and measures new choices, is :mod:`rrcache.explorer`).

Figures (matplotlib): :func:`tradeoff_figure` (every node path, the amortized estimators'
options, the original's time, the Pareto front, the selections), :func:`node_figure` (a node's
measured errors with the fitted error model, and its predicted frame time over Δn),
:func:`images_figure` (a choice's original, cached frame, error map, payload and hit/miss map;
a cached node's or an amortized estimator's). HTML: :func:`source_html` (the shader with a node
highlighted), :func:`selections_html` (the four selections, predicted against measured).

>>> prof = demo_profile("demo.rrprofile")          # doctest: +SKIP
>>> tradeoff_figure(prof)                          # doctest: +SKIP
"""
from __future__ import annotations

import html
import math
import time
from pathlib import Path
from typing import Optional

import numpy as np

from rrcache.report.data import read_source, selection_timing  # noqa: F401 (selection_timing re-exported)
from rrcache.report.images import CAPTIONS, read_frames


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


def selections_figure(prof, frames: Optional[dict] = None):
    """One row of images per selection (e1..e4; see :func:`images_figure`): the original, a cached
    node or an amortized estimator (several nodes at once: their description only), as the
    profiler rendered them into the profile folder (``frames``: label → images given instead)."""
    frames = read_frames(prof.path) if frames is None else frames
    plt = _pyplot()
    names = list(CAPTIONS)
    fig, axes = plt.subplots(len(prof.selections), len(names), figsize=(2.4 * len(names), 2.2 * len(prof.selections)),
                             dpi=100, squeeze=False)
    for row, sel in zip(axes, prof.selections):
        if sel.parts and not sel.choice.has_frames:  # no frames (several nodes at once)
            for ax in row:
                ax.axis("off")
            row[0].text(-0.08, 0.5, f"{sel.label}: {sel.describe()}", transform=row[0].transAxes, rotation=90,
                        ha="right", va="center", fontsize=8)
            continue
        images = frames.get(sel.label)
        if images is None:
            for ax in row:
                ax.axis("off")
            row[0].text(-0.08, 0.5, f"{sel.label}: {sel.describe()} (no frames in the folder)",
                        transform=row[0].transAxes, rotation=90, ha="right", va="center", fontsize=8)
            continue
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
        if sel.parts and sel.choice.one_node:
            return sel.node, int(sel.period)
    node = prof.trained_nodes[0]
    return node.id, int(max(node.periods))


def default_selection(prof):
    """The last selection that changes the shader (a cached node or an amortized estimator; not
    several nodes at once, which have no frames), else the original's selection: what
    :func:`describe_choice` and :meth:`FrameShots.selection_images` show first."""
    for sel in reversed(prof.selections):
        if sel.parts and sel.choice.has_frames:
            return sel
    return prof.selections[0] if prof.selections else None


def describe_choice(prof, choice) -> str:
    """One line of HTML saying what a selection does: the original, a node cached every Δn
    frames, or an estimator amortized (m of N terms per frame, blend λ, its history)."""
    if not choice.parts:
        return "<b>the original shader</b>: no variant is predicted faster within this error"
    return choice.choice.sentence_html(choice, prof)


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
        node_cell, period_cell = s.choice.cells(s) if s.parts else ("original", "–")
        cells = [s.label, _f(s.max_error), node_cell, period_cell, _f(s.predicted_error),
                 _f(s.measured_error), _f(s.predicted_ms), _f(s.measured_ms), _f(s.predicted_speedup, 3),
                 _f(s.measured_speedup, 3), _f(s.measured_psnr, 3), _f(s.hit_rate, 3)]
        rows.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells) + "</tr>")
    return ("<table><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr>" + "".join(rows) + "</table>")
