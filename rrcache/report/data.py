"""What the report and the notebooks show, as plain data taken from a :class:`~rrcache.profiles.Profile`
(its nodes, selections and the model table; nothing is rendered here).

- :func:`chart_data`: every trained node's predicted (ms per frame, error) over Δn = 1..50, the
  Pareto front, the original's time and the four selections, for the error-against-run-time chart;
- :func:`node_details`: one node's place, call chain, models and measured error runs;
- :func:`node_benefits`: each node's best predicted speed-up (what the source view marks);
- :func:`source_lines`: the shader source, line by line, with the nodes on each line.

>>> data = chart_data(load_profile("demo.rrprofile"))      # doctest: +SKIP
>>> sorted(data)                                           # doctest: +SKIP
['front', 'nodes', 'original_ms', 'selections']
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np


def _plot_label(sel) -> dict:
    """The chart's ``node`` and ``period`` of a selection (its kind's; the original: none)."""
    node, period = sel.choice.plot_label(sel) if sel.parts else (None, None)
    return {"node": node, "period": period}


def _num(value) -> Optional[float]:
    """A finite float, or None (JSON has no NaN or infinity)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def chart_data(prof) -> dict:
    """The error-against-run-time chart: ``nodes`` (id, text, ``points`` [[Δn, ms, error], ...]
    for the finite predictions), ``front`` ([[ms, error, node, Δn], ...]), ``original_ms`` and
    ``selections`` (label, node, Δn, predicted ms and error)."""
    from rrcache.model import pareto_front

    table = prof.table
    nodes = []
    for i, node_id in enumerate(table.node_ids):
        node = prof.node(node_id)
        points = [[int(p), float(t), float(e)] for p, t, e in zip(table.periods, table.T[i], table.E[i])
                  if math.isfinite(t) and math.isfinite(e)]
        if points:
            nodes.append({"id": node_id, "text": node.text, "line": node.line, "points": points})
    front = [[float(p.predicted_ms), float(p.predicted_error), p.node, p.period] for p in pareto_front(table)]
    options = prof.amortized_options()
    if options:  # one front over the cached nodes and the amortized estimators
        merged = sorted(front + [[float(o.predicted_ms), float(o.predicted_error), o.describe(), None]
                                 for o in options], key=lambda p: (p[0], p[1]))
        front, best = [], math.inf
        for point in merged:
            if point[1] < best:
                front.append(point)
                best = point[1]
    selections = [{"label": s.label, **_plot_label(s), "what": s.describe(),
                   "ms": _num(s.predicted_ms), "error": _num(s.predicted_error)} for s in prof.selections]
    # the amortized estimators' options (estimator, m, λ) on the same axes
    amortized = [[float(o.predicted_ms), float(o.predicted_error), o.describe()] for o in options]
    return {"nodes": nodes, "front": front, "original_ms": float(prof.original_ms), "selections": selections,
            "amortized": amortized}


def node_benefits(prof) -> dict:
    """Node id → its best predicted speed-up over Δn = 1..50 (trained nodes; the original's time
    over the node's fastest predicted time)."""
    table = prof.table
    out = {}
    for i, node_id in enumerate(table.node_ids):
        best = float(np.min(table.T[i])) if table.T.shape[1] else math.inf
        out[node_id] = prof.original_ms / best if math.isfinite(best) and best > 0 else None
    return out


def node_details(prof, node_id: str) -> dict:
    """One node as JSON-able data: id, type, line, column, text, call chain, static cost, whether
    trained (and the profiler's ``note`` on why not, when it gives one), α, λ (with fit quality and
    R²), t_hit and t_miss (ms per pixel), the measured error runs (Δn, error, hit rate, PSNR), its best predicted speed-up, and the predicted error and ms at
    each trained Δn."""
    node = prof.node(node_id)
    out = {
        "id": node.id, "type": node.type, "line": node.line, "column": node.column, "text": node.text,
        "call_chain": [str(c) for c in node.call_chain], "cost": node.cost, "trained": node.trained,
        "alpha": _num(node.alpha), "lam": _num(node.lam), "error_quality": node.error_quality,
        "error_r2": _num(node.error_r2), "t_hit": _num(node.t_hit), "t_miss": _num(node.t_miss),
        "perf_quality": node.perf_quality, "note": getattr(node, "note", None),
        "runs": [{"period": int(p), "error": _num(e), "hit_rate": _num(h), "psnr": _num(s)}
                 for p, e, h, s in zip(node.periods, node.errors, node.hit_rates,
                                       node.psnrs or [None] * len(node.periods))],
        "benefit": None,
    }
    if node.trained:
        out["benefit"] = node_benefits(prof).get(node.id)
        table = prof.table
        i = table.node_ids.index(node.id)
        for run in out["runs"]:
            j = run["period"] - 1
            if 0 <= j < table.max_period:
                run["predicted_error"] = _num(table.E[i, j])
                run["predicted_ms"] = _num(table.T[i, j])
    return out


def read_source(prof) -> list[str]:
    """The profiled shader's lines (RRCacheError naming the file when it cannot be read)."""
    from rrcache.profiles.inputs import shader_source

    return shader_source(prof).splitlines()


def source_lines(prof) -> list[dict]:
    """Per source line: ``number``, ``text`` and ``nodes`` (id, column, text, trained, benefit)
    of the cacheable nodes that start on it."""
    benefits = node_benefits(prof) if prof.trained_nodes else {}
    by_line: dict = {}
    for node in prof.nodes:
        by_line.setdefault(int(node.line), []).append(
            {"id": node.id, "column": int(node.column), "text": node.text, "trained": node.trained,
             "benefit": _num(benefits.get(node.id))})
    return [{"number": i, "text": text, "nodes": by_line.get(i, [])}
            for i, text in enumerate(read_source(prof), start=1)]


def selection_timing(prof, repeats: int = 200) -> dict:
    """How long :meth:`Profile.select` takes: ``median_ms`` and ``max_ms`` over ``repeats``
    thresholds spread log-evenly across the four selections' levels (the model table is built
    first, once, as a slider's first move does)."""
    import statistics
    import time

    levels = [s.max_error for s in prof.selections if s.max_error and s.max_error > 0] or [1e-3]
    lo, hi = min(levels) / 10.0, max(levels) * 10.0
    _ = prof.table  # built once, like the first move of a slider
    times = []
    for level in np.geomspace(lo, hi, max(1, int(repeats))):
        start = time.perf_counter()
        prof.select(float(level))
        times.append((time.perf_counter() - start) * 1000.0)
    return {"median_ms": statistics.median(times), "max_ms": max(times), "repeats": len(times),
            "nodes": len(prof.table.node_ids), "periods": int(prof.table.max_period)}
