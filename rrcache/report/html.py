"""``report.html``: one self-contained page about a profile, that works offline.

Everything is inside the file: the style sheet and the script (:mod:`rrcache.report.assets`), the
data (JSON in a ``<script type="application/json">``), and every image as a ``data:`` URI. The page
has a summary; the interactive error-against-run-time chart (hover: node, Δn, predicted error and
time; click: the node's source, call chain, α, λ, t_hit, t_miss and measured error runs); the
shader source with each cacheable node's line marked by its best predicted speed-up; the four
selections with real renders (original, cached, error map, payload, hit/miss map, from
:mod:`rrcache.report.images`) and their measured against predicted figures; the model
validation plots; the settings and how long training took.

>>> write_report(load_profile("demo.rrprofile"), "demo.rrprofile")     # doctest: +SKIP
PosixPath('demo.rrprofile/report.html')
"""
from __future__ import annotations

import html
import json
import math
import os
import tempfile
import time
from pathlib import Path
from typing import Optional

from rrcache.atomic import OutputFolder
from rrcache.budgets import budget
from rrcache.errors import RRCacheError
from rrcache.files import Refused, read_file
from rrcache.jsonable import script_json  # noqa: F401  (the data block; tests import it from here too)
from rrcache.profiles.document import algorithm_line
from rrcache.profiles.notices import run_warnings
from rrcache.report import assets
from rrcache.report.data import chart_data, node_benefits, node_details, read_source, selection_timing
from rrcache.report.images import CAPTIONS, data_uri, read_frames
from rrcache.report.next_steps import next_steps_html

REPORT_NAME = "report.html"
#: the figures of :mod:`rrcache.report.plots` the report shows, with their captions
PLOTS = (("tradeoff.png", "error against run time (static, every node over Δn = 1..50)"),
         ("hitrate.png", "hit rate: measured per node and the fitted γ(Δn) = μ(1 − 1/Δn)"),
         ("validation.png", "validation: predicted against measured error and frame time"))


def _e(value) -> str:
    return html.escape(str(value), quote=True)


def _f(value, digits: int = 4, suffix: str = "") -> str:
    """A number in plain units: ``digits`` significant digits, large ones whole with thousands
    separators (139,730 covered pixels, not 1.39730e+05), only tiny ones in exponent form."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    value = float(value)
    if value != 0 and abs(value) < 1e-4:
        return f"{value:.{max(1, digits - 1)}e}{suffix}"
    if abs(value) >= 10 ** digits:
        return f"{value:,.0f}{suffix}"
    return f"{value:.{digits}g}{suffix}"


def _x(value) -> str:
    """A speed-up with two decimals (1.995 is 2.00×, not 2×)."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return f"{float(value):.2f}×"


def benefit_color(speedup: Optional[float], best: float) -> str:
    """The source view's mark: grey for no predicted gain (or untrained), then pale yellow to
    green as the node's best predicted speed-up approaches the profile's best.

    >>> benefit_color(None, 2.0), benefit_color(2.0, 2.0)
    ('#e4e6eb', 'hsl(130,60%,62%)')
    """
    if speedup is None or speedup <= 1.0 or best <= 1.0:
        return "#e4e6eb"
    share = min(1.0, math.log(speedup) / math.log(best))
    return f"hsl({round(55 + 75 * share)},{round(85 - 25 * share)}%,{round(82 - 20 * share)}%)"


def _summary(prof, timing: dict) -> str:
    best = max((s for s in prof.selections if s.measured_speedup is not None),
               key=lambda s: s.measured_speedup, default=None)
    counts = prof.counts or {}
    cells = [
        (f"{len(prof.trained_nodes)} / {len(prof.nodes)}", "nodes trained / cacheable"),
        (_f(prof.original_ms, 4, " ms"), "original frame time"),
        (_f(prof.mu, 3), "μ (hit rate limit)"),
        (_f(prof.overhead_ms, 3, " ms"), "cache overhead per frame"),
        (f"{round(prof.pixels):,}" if prof.pixels else "–", "covered pixels per frame"),
        ((_x(best.measured_speedup) + f" ({best.label})") if best else "–", "best measured speed-up"),
        (_f(prof.training_wall_s, 3, " s"), "training time"),
        (_f(timing["median_ms"], 2, " ms"), f"re-selection (median of {timing['repeats']})"),
    ]
    if counts:
        cells.append((f"{counts.get('error_runs_computed', 0)} + {counts.get('timing_runs_computed', 0)}",
                      "error + timing runs computed"))
    ceiling = prof.measured_ceiling
    if ceiling is not None:
        cells.insert(6, (_x(ceiling.speedup), f"ceiling: every pixel hitting ({ceiling.algorithm})"))
    return ('<div class="summary">' + "".join(f"<div><b>{_e(v)}</b><span>{_e(k)}</span></div>" for v, k in cells)
            + "</div>" + _warnings(prof))


def _warnings(prof) -> str:
    """The ceiling in words and every warning of the run (rrcache.profiles.notices), under the tiles."""
    ceiling = prof.measured_ceiling
    items = [f"<li>ceiling: {_e(ceiling.summary())}</li>"] if ceiling is not None else []
    warnings = run_warnings(prof)
    items += [f'<li class="warn">warning: {_e(w)}</li>' for w in warnings]
    if not warnings:
        items.append("<li>no warnings: the timings were steady and every level was met as chosen</li>")
    return f'<ul class="notices">{"".join(items)}</ul>'


def _source(prof, lines: list[str]) -> str:
    benefits = node_benefits(prof) if prof.trained_nodes else {}
    best = max([b for b in benefits.values() if b] + [1.0])
    by_line: dict = {}
    for node in prof.nodes:
        by_line.setdefault(int(node.line), []).append(node)
    rows = []
    for number, text in enumerate(lines, start=1):
        nodes = by_line.get(number, [])
        if not nodes:
            rows.append(f'<div id="L{number}"><span class="ln">{number}</span><span class="mk"></span>'
                        f"<code>{_e(text)}</code></div>")
            continue
        scored = [(benefits.get(n.id) or 0.0, n) for n in nodes]
        top, lead = max(scored, key=lambda s: s[0])
        title = "; ".join(f"{n.id}: " + (f"best {b:.2f}×" if b else "not trained") for b, n in scored)
        mark = f"{top:.2f}×" if top else "·"
        rows.append(f'<div id="L{number}" class="has" data-node="{_e(lead.id)}" title="{_e(title)}" '
                    f'style="background:{benefit_color(top or None, best)}"><span class="ln">{number}</span>'
                    f'<span class="mk">{_e(mark)} ({len(nodes)})</span><code>{_e(text)}</code></div>')
    legend = ('<p class="legend">Lines where cacheable nodes start, by their best predicted speed-up '
              "(over Δn = 1..50; the count of nodes in brackets; click a line for its best node): "
              f'<span style="background:{benefit_color(None, best)}">no gain or not trained</span>'
              f'<span style="background:{benefit_color(best ** 0.25, best)}">{best ** 0.25:.2f}×</span>'
              f'<span style="background:{benefit_color(best ** 0.5, best)}">{best ** 0.5:.2f}×</span>'
              f'<span style="background:{benefit_color(best, best)}">{best:.2f}×</span></p>')
    return legend + '<div class="src">' + "".join(rows) + "</div>"


def _multi_selection(prof, sel, note: str = "several nodes: no frames are shown for this choice") -> str:
    """A selection shown without frames (a kind without them, several nodes; or a folder without
    them): what it caches and its figures."""
    what = (sel.choice.report_html(sel, prof) if sel.parts
            else "keep the original shader (nothing is predicted faster at this level)")
    rows = [("error (mean RGB L2)", _f(sel.predicted_error), _f(sel.measured_error)),
            ("ms per frame", _f(sel.predicted_ms), _f(sel.measured_ms)),
            ("speed-up", _x(sel.predicted_speedup), _x(sel.measured_speedup)),
            ("PSNR", "", _f(sel.measured_psnr, 3, " dB")),
            ("hit rate", "", _f(sel.hit_rate, 3))]
    table = ("<table><tr><th></th><th class=num>predicted</th><th class=num>measured</th></tr>"
             + "".join(f"<tr><th>{a}</th><td class=num>{b}</td><td class=num>{c}</td></tr>" for a, b, c in rows)
             + "</table>")
    files = f" · shader files: <code>{_e(sel.files)}</code>" if sel.files else ""
    return (f'<div class="sel" id="sel-{_e(sel.label)}" data-node="{_e("+".join(sel.nodes))}">'
            f"<h3>{_e(sel.label)}: {_e(_level(sel))}</h3><p>{what}{files}</p>{table}"
            f'<p class="muted">{_e(note)}</p>'
            f"{next_steps_html(prof, sel, _session_size(prof))}</div>")


def _session_size(prof) -> tuple:
    """The session's resolution, read from its file (the training's when it cannot be read)."""
    from rrcache.profiles.inputs import session_document

    try:
        return tuple(int(v) for v in session_document(prof)["resolution"])
    except (RRCacheError, ValueError, KeyError, TypeError):
        return tuple(prof.settings.resolution or (0, 0))


def _level(sel) -> str:
    if sel.min_psnr is not None:
        return f"PSNR ≥ {sel.min_psnr:g} dB (predicted)"
    return f"error ≤ {_f(sel.max_error)}"


def _selection(prof, sel, frames: dict) -> str:
    kind = sel.choice  # None: the original shader
    if kind is not None and not kind.has_frames:
        return _multi_selection(prof, sel)
    images = frames.get(sel.label)  # rendered by the profiler into the folder (rrcache.profiler.frames)
    if images is None:
        return _multi_selection(prof, sel, "no frames in the profile folder: 'rrcache report' renders them")
    what = (kind.report_html(sel, prof) if kind is not None
            else "keep the original shader (nothing is predicted faster at this level)")
    what += _level_marks(sel)
    exact = sel.exact or not sel.parts
    predicted_psnr = ("∞ (exact)" if exact else
                      "–" if sel.predicted_psnr is None else
                      f"{sel.predicted_psnr:.1f} ± {sel.predicted_psnr_uncertainty or 0:.1f} dB")
    measured_psnr = ("–" if sel.measured_error is None else "∞ (exact)" if exact else
                     _f(sel.measured_psnr, 3, " dB") + (f" ± {sel.measured_psnr_uncertainty:.1f}"
                                                       if sel.measured_psnr_uncertainty else ""))
    speedup = _x(sel.measured_speedup)
    if len(sel.speedups) > 1:
        lo, hi = sel.speedup_range
        speedup += f" ({lo:.2f}–{hi:.2f}, {len(sel.speedups)} repeats)"
    predicted_speedup = _x(sel.predicted_speedup)
    if sel.parts and len(sel.predicted_speedup_range) == 2:
        predicted_speedup += f" ({sel.predicted_speedup_range[0]:.2f}–{sel.predicted_speedup_range[1]:.2f})"
    rows = [("error (mean RGB L2)", _f(sel.predicted_error), _f(sel.measured_error)),
            ("ms per frame", _f(sel.predicted_ms), _f(sel.measured_ms)),
            ("speed-up", predicted_speedup, speedup),
            ("PSNR", predicted_psnr, measured_psnr),
            ("hit rate", "", _f(sel.hit_rate, 3))] + _measured_rows(sel)
    table = ("<table><tr><th></th><th class=num>predicted</th><th class=num>measured</th></tr>"
             + "".join(f"<tr><th>{a}</th><td class=num>{b}</td><td class=num>{c}</td></tr>" for a, b, c in rows)
             + "</table>")
    figures = []
    for name in CAPTIONS:
        if name in images.arrays:
            # small frames are shown enlarged, up to five of them across a 1280-pixel-wide window
            w0, h0 = images.size
            w = max(w0, min(2 * w0, 228))
            h = round(h0 * w / w0)
            figures.append(f'<figure><img alt="{_e(name)}" data-image="{_e(name)}" width="{w}" height="{h}" '
                           f'src="{images.uri(name)}"><figcaption>{_e(images.caption(name))}</figcaption></figure>')
    settled = kind.settled_note if kind is not None else ""
    frame_note = (f"frame {images.frame} at {images.size[0]}×{images.size[1]}"
                  + (f", after {images.frame + 1} frames with the cache{settled}: this frame's error "
                     f"{_f(images.error)}, hit rate {_f(images.hit_rate, 3)}; the table's measurements are over "
                     f"{sel.frames} frames of the session" if images.cached else ""))
    files = f" · shader files: <code>{_e(sel.files)}</code>" if sel.files else ""
    node_attr = sel.single_node or ""
    return (f'<div class="sel" id="sel-{_e(sel.label)}" data-node="{_e(node_attr)}" data-kind="{_e(sel.kind)}">'
            f"<h3>{_e(sel.label)}: {_e(_level(sel))}</h3><p>{what}{files}</p>{table}"
            f'<p class="muted">{_e(frame_note)}</p>'
            f'<div class="shots">{"".join(figures)}</div>{next_steps_html(prof, sel, _session_size(prof))}</div>')


def _answer(prof) -> str:
    """The profile's answer when it stopped before training (``Profile.verdict``: the ceiling
    below the gain worth having, or no value a cache can hold): the answer, why, and what would
    change it."""
    v = prof.verdict
    ceiling = prof.measured_ceiling
    measured = f"<p>ceiling: {_e(ceiling.summary())}</p>" if ceiling is not None else ""
    changes = "".join(f"<li>{_e(c)}</li>" for c in v.get("changes") or [])
    return (f'<div class="sel" id="answer"><h3>{_e(v["answer"])}</h3>{measured}<p>why: {_e(v["reason"])}</p>'
            f"<p>what would change it:</p><ul>{changes}</ul>"
            "<p class=\"muted\">the original shader's manifest is in <code>optimized/original</code></p></div>")


def _level_marks(sel) -> str:
    """What became of the selection's level (docs/levels.md): the choices refused and why, a
    miss shipped as measured, visible artifacts."""
    from rrcache.model.levels import VISIBLE_FLIP

    out = ""
    if sel.fallback:
        out += f'<br><span class="warn">fell back: {_e(sel.fallback)}</span>'
    if sel.level_met is False:
        out += f'<br><span class="warn miss">MISSED its level as measured: {_e(sel.level_note or "")}</span>'
    if sel.visible_artifacts:
        why = (f"mean FLIP {sel.measured_flip:.3f} ≥ {VISIBLE_FLIP:g}" if sel.measured_flip is not None
               else "below 30 dB PSNR (predicted)")
        out += f'<br><span class="warn">{_e(why)}: visible artifacts (a choice, not a default)</span>'
    return out


def _measured_rows(sel) -> list:
    """The measured-only rows of a selection's table: FLIP, the temporal error, the level."""
    exact = sel.exact or not sel.parts
    flip = "0" if exact and sel.measured_error is not None else (
        "–" if sel.measured_flip is None else
        f"{sel.measured_flip:.4f}" + (f" ± {sel.measured_flip_uncertainty:.4f}" if sel.measured_flip_uncertainty else ""))
    temporal = "∞ (exact)" if exact and sel.measured_error is not None else _f(sel.measured_temporal_psnr, 3, " dB")
    if sel.level_met is None:
        level = "–"
    elif not sel.level_met:
        level = "missed"
    elif sel.parts:
        level = "met" + (f" (candidate {sel.tries})" if sel.tries > 1 else "")
    else:
        level = "original" + (f" ({sel.tries} measured, none met it)" if sel.tries else "")
    return [("mean FLIP", "", flip), ("PSNR of the frame-to-frame changes", "", temporal), ("level", "", level)]


def _prediction_errors(prof) -> str:
    """How far the PSNR predictions were from validation's measurements (``Profile.calibration``)."""
    cal = getattr(prof, "calibration", None) or {}
    raw, calibrated = cal.get("raw") or {}, cal.get("calibrated") or {}
    if not raw.get("n"):
        return ""
    return (f'<p class="muted">PSNR predicted against measured on the {raw["n"]} choices validation measured: '
            f"|predicted − measured| mean {raw['mean']:.1f} dB, worst {raw['worst']:.1f} dB from the models alone; "
            f"mean {calibrated['mean']:.1f} dB, worst {calibrated['worst']:.1f} dB as predicted with the calibration "
            f"of the choices measured before each. The profile now predicts a node measured by validation with "
            f"its own shift, and a cached node without points of its own with a "
            f"{float(cal.get('shift') or 0.0):+.1f} dB calibration (± {float(cal.get('spread') or 0.0):.1f} dB; "
            "docs/levels.md).</p>")


def _plots(prof) -> str:
    folder = Path(prof.path) if prof.path is not None else None
    have = {}
    for name, _ in PLOTS:  # the folder's plots, read by rrcache.files' rule inside it (a link out is redrawn)
        if folder is not None:
            try:
                have[name] = read_file(folder / name, budget.asset_bytes, [os.path.realpath(folder)]).data
            except Refused:
                pass
    with tempfile.TemporaryDirectory() as tmp:
        if len(have) < len(PLOTS) and prof.trained_nodes:
            from rrcache.report.plots import write_plots

            for path in write_plots(prof, tmp):
                have.setdefault(Path(path).name, read_file(path, None).data)
        parts = [f'<figure><img alt="{_e(name)}" src="{data_uri(have[name])}">'
                 f"<figcaption>{_e(caption)}</figcaption></figure>" for name, caption in PLOTS if name in have]
    return '<div class="plots">' + "".join(parts) + "</div>" if parts else "<p>No plots (no trained node).</p>"


def _settings(prof) -> str:
    rows = [(k, json.dumps(v)) for k, v in prof.settings.to_json().items()]
    rows += [("algorithm used", algorithm_line(prof)), ("shader", prof.shader), ("session", prof.session),
             ("defines", json.dumps(prof.defines) if prof.defines else "–"),
             ("training time", _f(prof.training_wall_s, 4, " s")),
             ("budget stopped training", str(bool(prof.budget_stopped))),
             ("untrained nodes", str(len(prof.untrained)))]
    counts = prof.counts or {}
    rows += [(k.replace("_", " "), str(v)) for k, v in counts.items()]
    return "<table>" + "".join(f"<tr><th>{_e(k)}</th><td><code>{_e(v)}</code></td></tr>" for k, v in rows) + "</table>"


def _estimators(prof) -> str:
    """The shader's estimators (amortized sampling): N, the error and time fits, and the best
    option at each trained m (the options are on the tradeoff plot with the nodes)."""
    if not prof.estimators:
        return ""
    rows = []
    for est in prof.estimators:
        for history in ("blend", "slots"):
            runs = est.runs(history)
            if runs is None:
                continue
            ef, tf = runs.error_fit or {}, runs.time_fit or {}
            if not runs.trained:
                fit = _e(runs.note or "not trained")
            elif history == "slots":
                floors = ", ".join(f"c<sub>{m}</sub> = {_f(c)}" for m, c in zip(ef.get("samples", []), ef.get("base", [])))
                fit = f"{floors}, b = {_f(ef.get('b'))}, R² = {_f(ef.get('r2'), 3)}"
            else:
                fit = f"a = {_f(ef.get('a'))}, b = {_f(ef.get('b'))}, R² = {_f(ef.get('r2'), 3)}"
            per = _f(float(tf.get("t_sample") or 0.0) * 1e6, 3) if runs.trained else "–"
            rows.append(f"<tr><td>{_e(est.id)}</td><td>{history}</td><td class=num>{est.line}</td>"
                        f"<td class=num>{est.samples}</td><td><code>{_e(est.text)}</code></td><td>{fit}</td>"
                        f"<td class=num>{per}</td></tr>")
    return ("<h2>Amortized sampling</h2><p class=\"muted\">Loops that sum independent terms, evaluated at m of "
            "their N terms per frame. The blend history blends them with the reprojected estimate by λ; error "
            "against the original ε = a·sqrt(s(m)(1−λ)/(1+λ)) + b·sqrt(λ/(1−λ)), s(m) = (N−m)/(m(N−1)). The "
            "slots history keeps the N/m subset sums apart, each blended with its own reprojected value by λ "
            "(where they fit the payload); ε = sqrt(c<sub>m</sub>² + b²·λ/(1−λ)), a floor c<sub>m</sub> per "
            "trained m. Predictions are held to the error runs: each run's measured/predicted ratio, "
            "interpolated between runs, scales the fit. Time per evaluated term (per frame, over every evaluated term) from timed frames, per "
            "history. Their options compete with the cached nodes at every level.</p><table><tr>"
            "<th>estimator</th><th>history</th><th class=num>line</th><th class=num>N</th><th>loop</th>"
            "<th>error model</th><th class=num>ms per 1e6 terms</th></tr>" + "".join(rows) + "</table>")


def report_html(prof, frames: Optional[dict] = None) -> str:
    """The report page of ``prof`` as a string, from its folder's files: the selections' frames
    are those the profiler rendered there (:func:`rrcache.report.images.read_frames`; ``frames``:
    label → images given instead)."""
    if frames is None:
        frames = read_frames(prof.path) if prof.path is not None else {}
    lines = read_source(prof)
    timing = selection_timing(prof) if prof.trained_nodes else {"median_ms": None, "repeats": 0}
    data = {"source": lines, "details": {n.id: node_details(prof, n.id) for n in prof.nodes}}
    if prof.trained_nodes:
        data.update(chart_data(prof))
    else:
        data.update({"nodes": [], "front": [], "original_ms": float(prof.original_ms), "selections": []})
    payload = script_json(data)
    name = Path(prof.shader).name
    sections = [
        "<h2>Summary</h2>", _answer(prof) if prof.verdict is not None else "",
        _summary(prof, timing) if prof.trained_nodes else "<p>No node was trained.</p>",
        "<h2>Error against run time</h2>",
        '<p class="muted">Each path is one node over Δn = 1..50 as the fitted models predict it (larger '
        "dots: the trained periods); the black line is the Pareto front, the dashed line the original's "
        "frame time, the squares the four selections. Hover a point; click it for "
        "the node. On the log scale Δn = 1 (error 0, refreshed every frame) is left out.</p>",
        '<p id="yscale">error axis: <button data-scale="log">log</button> <button data-scale="linear">linear</button></p>'
        '<div class="chartrow"><svg id="chart" viewBox="0 0 720 440" width="720" height="440" '
        'role="img" aria-label="error against run time"></svg>'
        '<div id="details"><h3>Node details</h3><p class="muted">Click a point of the chart or a marked '
        "source line.</p></div></div>",
        f"<h2>Shader source: {_e(name)}</h2>", _source(prof, lines),
        "<h2>Selections</h2>",
        '<p class="muted">The four levels e1..e4; predicted by the models, measured by rendering '
        "the session with the chosen variant beside the original. A level ships only what was measured to "
        "meet it (docs/levels.md).</p>",
        "".join(_selection(prof, s, frames) for s in prof.selections) or "<p>No selection.</p>",
        _prediction_errors(prof),
        _estimators(prof),
        "<h2>Model validation</h2>", _plots(prof),
        "<h2>Settings and training</h2>", _settings(prof),
    ]
    generated = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>rrcache profile: {_e(name)}</title><style>{assets.CSS}</style></head><body>"
            f"<header><h1>rrcache profile: {_e(name)}</h1><p>session {_e(Path(prof.session).name)} · "
            f"written {generated}</p></header><main>{''.join(sections)}</main>"
            '<div id="tooltip"></div>'
            f'<script id="rr-data" type="application/json">{payload}</script>'
            f"<script>{assets.JS}</script></body></html>\n")


def write_report(profile, out_dir, filename: str = REPORT_NAME, frames: Optional[dict] = None) -> Path:
    """Write the report of ``profile`` into ``out_dir`` (as ``filename``, default ``report.html``)
    and return its path: it reads the profile folder's files only (its frames rendered there by
    the profiler, :mod:`rrcache.profiler.frames`; ``frames`` given instead)."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise RRCacheError("the report's folder is a file", str(out), hint="give a folder, or --out FILE.html")
    with OutputFolder(out) as folder:
        folder.regular_or_missing(filename)  # a device or a link as --out: refused before rendering
        folder.write_text(filename, report_html(profile, frames))
    return out / filename
