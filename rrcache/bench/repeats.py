"""Repeated profiles of one shader side by side: did any of them ship a measured slowdown?

Issue 15's check that the profiler can be trusted: profile the same shader over the same session
several times (each a whole ``rrcache profile`` run into its own folder) and read what each one
shipped at each level. Every shipped selection was measured by validation beside the original,
several times (:mod:`rrcache.profiler.validate`); here each is classed by those repeats:

- ``faster``: every repeat at or above 1.0× (or the original itself, 1.0× by definition);
- ``within noise``: the median below 1.0× but some repeat at or above it (validation lets it
  stand and shows the range);
- ``slowdown``: every repeat below 1.0×: validation should have fallen back, so this is a
  defect of the profiler, and :func:`slowdowns` lists it.

:func:`rows` reads the folders; :func:`markdown` writes one line per shipped selection and
:func:`summary_markdown` one line per scene and level over all the runs (the README's table).
Issue 29's checks are here too (docs/levels.md): each row says whether the shipped selection met
its level as measured (``met``: its measured PSNR at least the level minus its uncertainty, or
the original), how many candidates its level measured (``tries``), its mean FLIP; and
:func:`predictions` gives the PSNR predictions' error over every choice each profile validated,
from the models alone and as calibrated when each was measured (``--predictions``).

>>> classify(())
'original'
>>> classify((0.97, 1.02, 0.99))
'within noise'
>>> classify((0.91, 0.95, 0.97))
'slowdown'
"""
from __future__ import annotations

import statistics
from pathlib import Path
from typing import Iterable, Optional

from rrcache.profiles.document import load_profile


def classify(speedups, exact_original: bool = True) -> str:
    """``original`` (nothing cached), ``faster``, ``within noise`` or ``slowdown`` (see the
    module docstring) from a selection's measured speed-up repeats."""
    if not speedups:
        return "original" if exact_original else "not measured"
    if min(speedups) >= 1.0:
        return "faster"
    if max(speedups) >= 1.0:
        return "within noise"
    return "slowdown"


def rows(folders: Iterable) -> list[dict]:
    """One row per shipped selection of each profile folder: the scene (shader and session
    names), the run (the folder's name), the level, what it caches, the predicted and measured
    speed-ups (median and range of the repeats), the predicted and measured PSNR, the fallback,
    and the class (:func:`classify`)."""
    out = []
    for folder in folders:
        profile = load_profile(folder)
        scene = f"{Path(profile.shader).stem} / {Path(profile.session).stem}"
        verdict = profile.verdict["answer"] if profile.verdict else None
        if not profile.selections:
            out.append(dict(scene=scene, run=Path(folder).name, level="all", cached="the original shader",
                            kind="original", predicted_speedup=1.0, speedup=None, speedup_range=None,
                            psnr=None, predicted_psnr=None, fallback=verdict, cls="original",
                            ceiling=(profile.ceiling or {}).get("speedup")))
            continue
        for sel in profile.selections:
            speedups = tuple(sel.speedups) or ((sel.measured_speedup,) if sel.measured_speedup else ())
            met = _met(sel)
            out.append(dict(
                scene=scene, run=Path(folder).name, level=sel.label, min_psnr=sel.min_psnr,
                cached=sel.describe(), kind=sel.kind, predicted_speedup=sel.predicted_speedup,
                speedup=statistics.median(speedups) if speedups else None,
                speedup_range=(min(speedups), max(speedups)) if speedups else None,
                psnr=None if sel.exact else sel.measured_psnr, exact=sel.exact,
                predicted_psnr=sel.predicted_psnr, fallback=sel.fallback,
                cls="original" if not sel.parts else classify(speedups, exact_original=False),
                ceiling=(profile.ceiling or {}).get("speedup"), tries=int(sel.tries or (1 if sel.parts else 0)),
                met=met, status=_status(sel, met), psnr_uncertainty=sel.measured_psnr_uncertainty, flip=sel.measured_flip,
                visible=bool(sel.visible_artifacts), temporal_psnr=sel.measured_temporal_psnr))
    return out


def _met(sel) -> str:
    """``met`` (measured within its level's uncertainty, or exact), ``below`` (measured below it:
    a miss shipped, with the reason in the fallback), or ``–`` (not measured)."""
    if not sel.parts:
        return "met"
    if sel.measured_error is None:
        return "–"
    if sel.level_met is not None:
        return "met" if sel.level_met else "below"
    if sel.min_psnr is None or sel.exact:
        return "met"
    psnr = sel.measured_psnr if sel.measured_psnr is not None else float("inf")
    return "met" if psnr + float(sel.measured_psnr_uncertainty or 0.0) >= sel.min_psnr else "below"


def _status(sel, met: str) -> str:
    """The row's word on its level, as the profile table says it (``met``, ``met, try 2``,
    ``original (2 tried)``), or ``below: <why>`` for a selection shipped below its level (a
    profile whose validation did not enforce the level: its note, else the measured PSNR)."""
    if met == "below":
        why = sel.level_note or (f"measured {sel.measured_psnr:.1f}"
                                 + (f" ± {sel.measured_psnr_uncertainty:.1f}" if sel.measured_psnr_uncertainty else "")
                                 + f" dB, below the level {sel.min_psnr:g} dB" if sel.min_psnr is not None
                                 and sel.measured_psnr is not None else "measured above its error level")
        return f"below: {why}"
    if met != "met":
        return met
    tries = int(sel.tries or 0)
    if not sel.parts:
        return f"original ({tries} tried)" if tries else ("original" if sel.fallback else "met")
    return f"met, try {tries}" if tries > 1 else "met"


def predictions(folders: Iterable) -> list[dict]:
    """Per profile folder, |predicted − measured| PSNR (dB) over the distinct choices its
    validation measured (``Profile.measured``; a profile from before it: its shipped selections):
    ``raw`` from the models alone, ``calibrated`` as predicted when each was measured
    (:mod:`rrcache.model.calibration`), ``replayed`` the profile's calibration points as today's
    rule predicts each from those before it (:func:`rrcache.model.calibration.replay`; the window
    check's point calibrates the later ones and is left out of the figures), each
    ``{"n", "mean", "worst"}``, and the pairs (and ``replayed_pairs``)."""
    from rrcache.model.calibration import Calibration, prediction_errors, replay
    from rrcache.profiler.window_check import CHECK_PREFIX

    out = []
    for folder in folders:
        profile = load_profile(folder)
        seen, pairs = set(), []
        for sel in list(getattr(profile, "measured", None) or []) + list(profile.selections):
            if not sel.parts or sel.exact or sel.key in seen or sel.predicted_psnr is None or sel.measured_psnr is None:
                continue
            seen.add(sel.key)
            raw = sel.predicted_psnr - float(sel.calibration_db or 0.0)
            pairs.append((sel.describe(), raw, sel.predicted_psnr, sel.measured_psnr))
        # every point calibrates the later ones; the window check's is not a validated choice
        again = [(c, m) for key, c, m in replay(Calibration.from_json(getattr(profile, "calibration", None)))
                 if not key.startswith(CHECK_PREFIX)]
        out.append(dict(scene=f"{Path(profile.shader).stem} / {Path(profile.session).stem}", run=Path(folder).name,
                        raw=prediction_errors([(r, m) for _, r, _, m in pairs]),
                        calibrated=prediction_errors([(c, m) for _, _, c, m in pairs]), pairs=pairs,
                        replayed=prediction_errors(again), replayed_pairs=again))
    return out


def predictions_markdown(table: list[dict]) -> str:
    """:func:`predictions` as a Markdown table, with every profile's choices pooled last."""
    from rrcache.model.calibration import prediction_errors

    def cell(e):
        return "–" if not e["n"] else f"{e['mean']:.2f} / {e['worst']:.2f}"

    lines = ["| scene | run | validated choices | |pred − meas| dB, models alone (mean / worst) | "
             "calibrated when measured (mean / worst) | today's calibration rule, replayed (mean / worst) |",
             "|---|---|---|---|---|---|"]
    for r in table:
        lines.append(f"| {r['scene']} | {r['run']} | {r['raw']['n']} | {cell(r['raw'])} | {cell(r['calibrated'])} | "
                     f"{cell(r['replayed'])} |")
    raw = prediction_errors([(p[1], p[3]) for r in table for p in r["pairs"]])
    cal = prediction_errors([(p[2], p[3]) for r in table for p in r["pairs"]])
    again = prediction_errors([p for r in table for p in r["replayed_pairs"]])
    lines.append(f"| all | {len(table)} profiles | {raw['n']} | {cell(raw)} | {cell(cal)} | {cell(again)} |")
    return "\n".join(lines)


def slowdowns(table: list[dict]) -> list[dict]:
    """The rows that shipped a selection slower than the original in every repeat."""
    return [r for r in table if r["cls"] == "slowdown"]


def _x(value: Optional[float]) -> str:
    return "–" if value is None else f"{value:.2f}×"


def markdown(table: list[dict]) -> str:
    """The rows as a Markdown table (one line per shipped selection) and a closing count."""
    lines = ["| scene | run | level | cached | predicted | measured (range of repeats) | PSNR dB "
             "(predicted) | mean FLIP | level met | tries | class |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in table:
        rng = r["speedup_range"]
        measured = _x(r["speedup"]) + (f" ({rng[0]:.2f}–{rng[1]:.2f})" if rng and rng[0] != rng[1] else "")
        psnr = "∞ (exact)" if r.get("exact") or r["kind"] == "original" else (
            "–" if r["psnr"] is None else f"{r['psnr']:.1f}" + (
                f" ± {r['psnr_uncertainty']:.1f}" if r.get("psnr_uncertainty") else ""))
        if r.get("predicted_psnr") is not None:
            psnr += f" ({r['predicted_psnr']:.1f})"
        cached = r["cached"] + (f" ↩ {r['fallback']}" if r.get("fallback") else "")
        level = r["level"] + (f" ≥{r['min_psnr']:.0f} dB" if r.get("min_psnr") else "")
        flip = "0" if r["kind"] == "original" or r.get("exact") else (
            "–" if r.get("flip") is None else f"{r['flip']:.3f}" + (" (visible)" if r.get("visible") else ""))
        lines.append(f"| {r['scene']} | {r['run']} | {level} | {cached} | {_x(r['predicted_speedup'])} | "
                     f"{measured} | {psnr} | {flip} | {r.get('status', r.get('met', '–'))} | {r.get('tries', '–')} | {r['cls']} |")
    bad = slowdowns(table)
    later = sum(1 for r in table if _needed_second(r) and r["kind"] != "original")
    kept = sum(1 for r in table if _needed_second(r) and r["kind"] == "original")
    unmeasured = sum(1 for r in table if r["kind"] == "original" and not r.get("tries") and r.get("fallback"))
    lines.append("")
    lines.append(f"{len(table)} shipped selections in {len({(r['scene'], r['run']) for r in table})} profiles; "
                 f"{len(bad)} measured slower than the original in every repeat; "
                 f"{sum(1 for r in table if r.get('met') == 'below')} shipped below their level; "
                 f"{later + kept} levels needed a second candidate ({later} stood with a later candidate, "
                 f"{kept} kept the original after its candidates were refused); {unmeasured} kept the original "
                 "with no candidate measured for it (its fallback says why).")
    return "\n".join(lines)


def _needed_second(row: dict) -> bool:
    """Whether the row's level measured its first candidate and refused it: a later candidate
    stood (tries > 1), or the original stands after a candidate was tried."""
    tries = row.get("tries") or 0
    return tries > 1 or (row["kind"] == "original" and tries > 0)


def summary_markdown(table: list[dict]) -> str:
    """One line per scene and level over every run: how many runs shipped what, the measured
    speed-ups (lowest to highest run median, and the lowest single repeat) and the measured PSNR
    range; the originals and fallbacks counted."""
    groups: dict = {}
    for r in table:
        groups.setdefault((r["scene"], r["level"], r.get("min_psnr")), []).append(r)
    lines = ["| scene | level | runs | shipped | measured speed-up (run medians) | lowest repeat | "
             "PSNR dB (range) | met | fell back | second candidate |", "|---|---|---|---|---|---|---|---|---|---|"]
    for (scene, level, min_psnr), rs in groups.items():
        cached = [r for r in rs if r["kind"] != "original"]
        shipped = ", ".join(f"{k}× {n}" for n, k in _counts(r["cached"] if r["kind"] != "original"
                                                            else "original" for r in rs))
        medians = [r["speedup"] for r in cached if r["speedup"] is not None]
        lows = [r["speedup_range"][0] for r in cached if r["speedup_range"]]
        psnrs = [r["psnr"] for r in cached if r["psnr"] is not None]
        span = lambda v, f: "–" if not v else (f(min(v)) if min(v) == max(v) else f"{f(min(v))}–{f(max(v))}")
        speed = span(medians, lambda x: f"{x:.2f}×") if medians else "1.00× (original)"
        psnr = span(psnrs, lambda x: f"{x:.1f}") if psnrs else "∞ (exact)"
        label = level + (f" ≥{min_psnr:.0f} dB" if min_psnr else "")
        lines.append(f"| {scene} | {label} | {len(rs)} | {shipped} | {speed} | "
                     f"{'–' if not lows else f'{min(lows):.2f}×'} | {psnr} | "
                     f"{sum(1 for r in rs if r.get('met') == 'met')}/{len(rs)} | "
                     f"{sum(1 for r in rs if r.get('fallback'))} | {sum(1 for r in rs if _needed_second(r))} |")
    return "\n".join(lines)


def scenes_markdown(table: list[dict]) -> str:
    """One line per scene, one column per level (the README's table): each run's shipped
    selection as measured (PSNR ± its uncertainty, speed-up, mean FLIP) and how its level stood
    (``met``, ``met, try 2``, ``original (N tried)``, ``below: …``); runs of a scene separated by
    ``;``."""
    levels: dict = {}
    scenes: dict = {}
    for r in table:
        levels.setdefault(r["level"], r.get("min_psnr"))
        scenes.setdefault(r["scene"], {}).setdefault(r["level"], []).append(r)

    def cell(r) -> str:
        status = r.get("status") or r.get("met", "–")
        if r["kind"] == "original" or r.get("exact"):
            return status if status.startswith("original") else "original"
        psnr = "–" if r["psnr"] is None else f"{r['psnr']:.1f}" + (
            f" ± {r['psnr_uncertainty']:.1f}" if r.get("psnr_uncertainty") else "")
        flip = "" if r.get("flip") is None else f", FLIP {r['flip']:.3f}" + (" (visible)" if r.get("visible") else "")
        return f"{psnr} dB, {_x(r['speedup'])}{flip}: " + ("BELOW the level" if status.startswith("below") else status)

    names = list(levels)
    lines = ["| scene | " + " | ".join(n + (f" ≥ {levels[n]:g} dB" if levels[n] else "") for n in names) + " |",
             "|---|" + "---|" * len(names)]
    for scene, by_level in scenes.items():
        lines.append(f"| {scene} | " + " | ".join("; ".join(cell(r) for r in by_level.get(n, [])) or "–"
                                               for n in names) + " |")
    return "\n".join(lines)


def _counts(items) -> list[tuple[str, int]]:
    out: dict = {}
    for item in items:
        out[item] = out.get(item, 0) + 1
    return list(out.items())
