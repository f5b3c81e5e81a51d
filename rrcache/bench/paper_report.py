"""``bench.md``: the tables of :mod:`rrcache.bench.paper` as Markdown.

One overview table (the paper's Table 1 and the selected results), then per scene the four
selections (Figs. 7–9), the cache algorithms on the medium selection's node, and the
equal-time comparison (§5.4, Fig. 10).
"""
from __future__ import annotations

from typing import Optional


def _f(value, spec: str = ".3g", none: str = "–") -> str:
    if value is None:
        return none
    try:
        if value != value:  # NaN
            return none
        return format(value, spec)
    except (TypeError, ValueError):
        return str(value)


def _code(text: Optional[str], limit: int = 70) -> str:
    if text is None:
        return "(original)"
    text = " ".join(str(text).split())
    if len(text) > limit:
        text = text[: limit - 1] + "…"
    return "`" + text.replace("|", "\\|").replace("`", "'") + "`"


def _methods(rows, title: str) -> list[str]:
    lines = [f"**{title}**", "", "| method | setting | speed-up | mean error | PSNR dB | ms | original ms |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        flag = "" if r.matched in (None, True) else " (not within the tolerance of the target)"
        lines.append(f"| {r.method}{flag} | {r.setting} | {_f(r.speedup, '.2f')}× | {_f(r.mean_error, '.4f')} | "
                     f"{_f(r.psnr, '.1f')} | {_f(r.ms, '.2f')} | {_f(r.original_ms, '.2f')} |")
    return lines + [""]


def _what(r) -> tuple[str, str]:
    """The node and Δn cells of a selection: an estimator at m samples and λ has no Δn; several
    nodes show each expression and period, in part order."""
    if not r.parts:
        return _code(None), _f(None, "d")
    what, period = r.choice.cells(r, texts=True)  # the kind of choice says what its cells show
    return _code(what, limit=110), period


def _filter_text(s) -> str:
    """``. Cache filter: plane (auto: ...)`` from what the profile measured, or nothing."""
    from rrcache.profiles.document import filter_text

    chosen = getattr(s, "filter", None)
    return f". Cache filter: {filter_text(chosen, getattr(s, 'filter_times', None))}" if chosen else ""


def scene_markdown(s) -> str:
    w, h = s.resolution
    lines = [f"### {s.name}", "",
             f"`{s.shader}` over `{s.session}`, {w}×{h}, {s.frames} frames. Profile: `{s.profile}` "
             f"({s.trained_nodes} of {s.cacheable_nodes} nodes trained; precomputation "
             f"{_f(s.precompute_s, '.1f')} s{', resumed from its store' if s.precompute_resumed else ''})"
             f"{_filter_text(s)}.", ""]
    if s.selections:
        lines += ["| level | max error | node | Δn | speed-up | mean error | PSNR dB | hit rate | predicted speed-up |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for r in s.selections:
            what, period = _what(r)
            lines.append(f"| {r.label} | {_f(r.max_error, '.4f')} | {what} | "
                         f"{period} | {_f(r.measured_speedup, '.2f')}× | {_f(r.measured_error, '.4f')} | "
                         f"{_f(r.measured_psnr, '.1f')} | "
                         f"{_f(r.hit_rate, '.3f')} | {_f(r.predicted_speedup, '.2f')}× |")
        lines.append("")
    if getattr(s, "amortized", None):
        lines += _methods(s.amortized, "amortized sampling at the paper's setting (N/4 per frame, λ = 3/5; error "
                                       "against the original; the profile's own amortized options compete in e1..e4)")
    if s.algorithms:
        lines += _methods(s.algorithms, f"cache algorithms on the {s.medium} node")
    if s.limit_speedup is not None:
        which = f", {s.limit_algorithm}" if s.limit_algorithm else ""
        lines += [f"Limit (every pixel hits{which}): {_f(s.limit_ms, '.2f')} ms against {_f(s.limit_original_ms, '.2f')} ms: "
                  f"at most {_f(s.limit_speedup, '.2f')}×.", ""]
    if getattr(s, "misses", None):
        from rrcache.bench.cache import MissRow, miss_table

        lines += [f"**Why the {s.medium} node misses** (an untimed run reading the hit maps; a 4×4 block is counted "
                  "under the cause of most of its missing pixels)", ""]
        lines += miss_table([MissRow(**m) for m in s.misses]) + [""]
    if s.equal_time:
        lines += _methods(s.equal_time, f"equal time: tuned to the {s.medium} speed-up {_f(s.target_speedup, '.2f')}×")
    if getattr(s, "figure", None):
        lines += [f"![{s.name}: error against frame time]({s.figure})", ""]
    for note in s.notes:
        lines.append(f"- note: {note}")
    if s.notes:
        lines.append("")
    return "\n".join(lines)


def markdown(result) -> str:
    """The whole ``bench.md``."""
    kind = ("**quick run** (reduced resolution, frames and training budget; not the full run)"
            if result.settings.quick else "full run")
    lines = ["# rrcache bench", "",
             f"{kind}, started {result.started}, {_f(result.wall_s, '.0f')} s wall, "
             f"LP_NUM_THREADS={result.to_json()['threads'] or 'unset'}. Speed-ups are ratios of median frame times "
             "measured side by side with the original in this run; error is the mean RGB L2 distance over covered "
             "pixels; static cost is our cost model's total for the output colour (rrcache.analysis.cost).", "",
             "| scene | static cost | cacheable nodes | precomputation s | original ms | medium selection | "
             "speed-up | PSNR dB | limit |",
             "|---|---|---|---|---|---|---|---|---|"]
    for s in result.scenes:
        med = next((r for r in s.selections if r.label == s.medium), None)
        lines.append(f"| {s.name} | {s.static_cost} | {s.cacheable_nodes} | {_f(s.precompute_s, '.1f')}"
                     f"{' (resumed)' if s.precompute_resumed else ''} | {_f(s.original_ms, '.2f')} | "
                     f"{s.medium or '–'} | {_f(med.measured_speedup if med else None, '.2f')}× | "
                     f"{_f(med.measured_psnr if med else None, '.1f')} | {_f(s.limit_speedup, '.2f')}× |")
    lines.append("")
    for s in result.scenes:
        lines.append(scene_markdown(s))
    return "\n".join(lines).rstrip() + "\n"
