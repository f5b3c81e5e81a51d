"""The summary of a profiled shader library: one row per (shader, session), as CSV and as an HTML
index linking each profile's ``report.html``.

A row is a plain dict (:func:`profile_row` from a finished profile, :func:`failed_row` for one that
stopped on an error) with the keys of :data:`COLUMNS`; the speed-ups are the measured ones of the
selections e1..e4 (None where a level was not measured). The verdict is one line: ``cache: 2.31×
at e3 (n12 Δn=34)`` where a selection measured at least the profile's ``min_gain``; ``original:
...`` with the reason otherwise.

>>> row = failed_row("bad-orbit", "bad.glsl", "orbit.json", "bad.glsl:3:1: syntax error", 0.4)
>>> row["status"], row["verdict"]
('failed', 'failed: bad.glsl:3:1: syntax error')
"""
from __future__ import annotations

import csv
import html
import io
import math
from typing import Optional

from rrcache.atomic import write_text

LEVELS = ("e1", "e2", "e3", "e4")
#: the row keys, in the CSV's column order
COLUMNS = ("name", "status", "verdict", "best_speedup") + tuple(f"{lv}_speedup" for lv in LEVELS) + (
    "nodes_trained", "nodes", "wall_s", "shader", "session", "folder", "report", "error")


def _finite(value) -> Optional[float]:
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) else None


def verdict(prof) -> str:
    """The profile's answer in one line (see the module docstring)."""
    if prof.verdict is not None:
        ceiling, gain = _finite(prof.verdict.get("ceiling")), _finite(prof.verdict.get("min_gain"))
        if ceiling is not None and gain is not None:
            return f"original: the ceiling {ceiling:.2f}× is below {gain:.2f}×"
        return "original: the ceiling is below --min-gain"
    measured = [s for s in prof.selections if s.parts and _finite(s.measured_speedup) is not None]
    if not prof.selections:
        return "original: no node could be trained"
    if not measured:
        if any(s.parts for s in prof.selections) and not prof.settings.validate:
            best = max((s for s in prof.selections if s.parts), key=lambda s: s.predicted_speedup)
            return f"predicted only: {best.predicted_speedup:.2f}× ({best.label}, {best.describe()}; not validated)"
        return "original: no cached selection stood validation"
    best = max(measured, key=lambda s: s.measured_speedup)
    if best.measured_speedup < prof.settings.min_gain:
        return f"original: the best measured was {best.measured_speedup:.2f}× (below {prof.settings.min_gain:.2f}×)"
    return f"cache: {best.measured_speedup:.2f}× at {best.label} ({best.describe()})"


def profile_row(prof, name: str, folder: str, report: Optional[str], wall_s: Optional[float]) -> dict:
    """The row of a finished profile (``folder`` and ``report`` relative to the library folder)."""
    by_label = {s.label: s for s in prof.selections}
    speedups = {}
    for level in LEVELS:
        sel = by_label.get(level)
        speedups[f"{level}_speedup"] = (None if sel is None else
                                        1.0 if not sel.parts and sel.measured_speedup is None and prof.settings.validate
                                        else _finite(sel.measured_speedup))
    cached = [v for v in speedups.values() if v is not None]
    return dict(name=name, status="done", verdict=verdict(prof), best_speedup=max(cached) if cached else None,
                **speedups, nodes_trained=len(prof.trained_nodes), nodes=len(prof.nodes),
                wall_s=_finite(wall_s), shader=prof.shader, session=prof.session, folder=folder, report=report,
                error=None)


def failed_row(name: str, shader: str, session: str, error: str, wall_s: Optional[float],
               status: str = "failed", folder: Optional[str] = None) -> dict:
    """The row of a profile that stopped on ``error`` (one line)."""
    row = {key: None for key in COLUMNS}
    row.update(name=name, status=status, verdict=f"{status}: {error}", shader=shader, session=session,
               wall_s=_finite(wall_s), folder=folder, error=error)
    return row


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def csv_text(rows: list[dict]) -> str:
    """The rows as CSV (columns :data:`COLUMNS`; empty cells for None)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(COLUMNS)
    for row in rows:
        writer.writerow([_cell(row.get(key)) for key in COLUMNS])
    return out.getvalue()


def _x(value) -> str:
    return "–" if value is None else f"{value:.2f}×"


def _duration(seconds) -> str:
    if seconds is None:
        return "–"
    seconds = float(seconds)
    if seconds < 90:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.1f} min"


def index_html(rows: list[dict], title: str = "rrcache: shader library") -> str:
    """A self-contained page: the table of the rows, each name linking its ``report.html``."""
    e = lambda v: html.escape(str(v), quote=True)  # noqa: E731
    done = sum(1 for r in rows if r["status"] == "done")
    wins = sum(1 for r in rows if str(r.get("verdict", "")).startswith("cache"))
    total = sum(r["wall_s"] or 0.0 for r in rows)
    head = "".join(f"<th>{e(h)}</th>" for h in ("profile", "verdict", *LEVELS, "nodes trained", "wall time"))
    body = []
    for r in rows:
        name = e(r["name"])
        link = f'<a href="{e(r["report"])}">{name}</a>' if r.get("report") else name
        cls = "failed" if r["status"] != "done" else "win" if str(r["verdict"]).startswith("cache") else ""
        cells = [link, e(r["verdict"])] + [e(_x(r.get(f"{lv}_speedup"))) for lv in LEVELS]
        nodes = f"{r['nodes_trained']} of {r['nodes']}" if r.get("nodes") is not None else "–"
        cells += [e(nodes), e(_duration(r.get("wall_s")))]
        tip = e(f"{r['shader']} × {r['session']}")
        body.append(f'<tr class="{cls}" title="{tip}">' + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{e(title)}</title>
<style>
body {{ font: 14px system-ui, sans-serif; margin: 2em; color: #222; }}
table {{ border-collapse: collapse; }}
th, td {{ padding: 4px 10px; border-bottom: 1px solid #ddd; text-align: left; }}
td:nth-child(n+3):nth-child(-n+6) {{ text-align: right; font-variant-numeric: tabular-nums; }}
tr.win td:nth-child(2) {{ color: #0a6b2d; }}
tr.failed td {{ color: #a11; }}
</style></head><body>
<h1>{e(title)}</h1>
<p>{len(rows)} profiles: {done} finished, {wins} with a measured speed-up worth caching,
{len(rows) - done} failed or not finished; {e(_duration(total))} of profiling in all.
The speed-ups are measured beside the original at each selection level (e1: the highest quality).
CSV: <a href="library.csv">library.csv</a>.</p>
<table><thead><tr>{head}</tr></thead><tbody>
{chr(10).join(body)}
</tbody></table></body></html>
"""


def write_summary(rows: list[dict], folder) -> None:
    """``library.csv`` and ``index.html`` in ``folder`` (each written whole or not at all)."""
    from pathlib import Path

    folder = Path(folder)
    write_text(folder / "library.csv", csv_text(rows))
    write_text(folder / "index.html", index_html(rows))
