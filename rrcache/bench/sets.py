"""The set rule of :mod:`rrcache.model.sets` against measured sets, and the fronts' figure.

``python -m rrcache.bench.sets PROFILE SHADER SESSION --pairs 4 --out result.json`` loads a
trained profile, predicts every pair of its trained nodes at the period pair the rule finds best
against the single-node front (improving or not) and measures the ``--pairs`` best of them, plus any ``--set
n1:4,n2:50``, exactly as the profiler's set stage trains a set (:func:`rrcache.profiler.sets.train_set`:
the error over the training frames in the error window, the time on the timing frames each
beside the original). It prints and writes predicted against measured error and time, and with
``--plot`` draws the single-node front, the front with the measured sets and the profile's
validated selections (:func:`rrcache.report.sets_plot.plot_fronts`).

The measured pairs are not a profile's choices (the profiler trains only those predicted to
improve the front); they test the rule where it says "no".
"""
from __future__ import annotations

import argparse
import itertools
import json
import time
from typing import Optional

import numpy as np

from rrcache import atomic


def _json(path) -> dict:
    """A JSON file this tool was given, read by rrcache.files' rule."""
    from rrcache.budgets import budget
    from rrcache.files import read_bytes

    return json.loads(read_bytes(path, budget.document_bytes))


def _parse_set(text: str) -> tuple[list[str], list[int]]:
    nodes, periods = [], []
    for item in text.split(","):
        node, _, period = item.partition(":")
        nodes.append(node.strip())
        periods.append(int(period))
    return nodes, periods


def measure(profile_dir, shader, session_path, pairs: int = 4, extra=(), clock=time.perf_counter) -> dict:
    """Predict and measure (see the module docstring); returns the JSON-able result."""
    from rrcache.model.sets import SetOption, _pair_grids, _SingleFront, set_prediction
    from rrcache.pipeline import load_for_session
    from rrcache.harness.execute import Bench, LocalExecutor
    from rrcache.profiler.jobs import Meter
    from rrcache.profiler.sets import feeds, layout_for, train_set
    from rrcache.profiles import load_profile
    from rrcache.session import load_session

    prof = load_profile(profile_dir)
    session = load_session(session_path)
    work = load_for_session(shader, session, prof.defines, prof.include_dirs)
    table = prof.table
    relation = feeds(work.table, table.node_ids)
    layout = layout_for(work, prof.algorithm, table.node_ids)
    # each pair of trained nodes at the period pair the rule predicts best against the singles
    single = _SingleFront(table)
    candidates = []
    for a, b in itertools.combinations(range(len(table.node_ids)), 2):
        err, ms = _pair_grids(table, a, b, relation, layout)
        gain = np.where(np.isfinite(err) & np.isfinite(ms) & (ms > 0), single.best(err) / np.where(ms > 0, ms, 1), 0)
        i, j = np.unravel_index(int(np.argmax(gain)), gain.shape)
        candidates.append(SetOption([table.node_ids[a], table.node_ids[b]], [int(i) + 2, int(j) + 2], layout,
                                    float(err[i, j]), float(ms[i, j]), None, float(gain[i, j])))
    chosen = sorted(candidates, key=lambda o: -o.gain)[:pairs]
    for nodes, periods in extra:
        rows = [table.node_ids.index(n) for n in nodes]
        err, ms = set_prediction(table, rows, periods, relation, layout)
        chosen.append(SetOption(nodes, periods, layout, err, ms, None, 0.0))
    executor = LocalExecutor(Bench(work, session))
    rows_out = []
    try:
        for o in chosen:
            start = clock()
            train_set(prof, prof.settings, session, o, executor, Meter(None))
            idx = [table.node_ids.index(n) for n in o.nodes]
            nested = [(o.nodes[a], o.nodes[b]) for a in range(len(idx)) for b in range(len(idx))
                      if (idx[a], idx[b]) in relation]
            singles = [(float(table.E[i, p - 1]), float(table.T[i, p - 1])) for i, p in zip(idx, o.periods)]
            rows_out.append({**o.to_json(), "feeds": nested, "singles_predicted": singles,
                             "predicted_speedup": prof.original_ms / o.predicted_ms,
                             "measured_speedup": prof.original_ms / o.trained_ms,
                             "error_ratio": o.trained_error / o.predicted_error if o.predicted_error else None,
                             "time_ratio": o.trained_ms / o.predicted_ms, "seconds": clock() - start})
            print(f"{o.describe():32s} predicted {o.predicted_error:.4f} {prof.original_ms / o.predicted_ms:.2f}×  "
                  f"measured {o.trained_error:.4f} {prof.original_ms / o.trained_ms:.2f}×  (gain {o.gain:.2f}, "
                  f"feeds {nested})", flush=True)
    finally:
        executor.close()
    return {"profile": str(profile_dir), "original_ms": prof.original_ms, "layout": layout,
            "algorithm": prof.algorithm, "sets": rows_out,
            "selections": [s.to_json() for s in prof.selections]}


def levels(profile_dir, shader, session_path, validation_frames: int = 8, extra_sets=()) -> dict:
    """Per level of the profile: the single-node choice and the choice with the profile's trained
    sets (and ``extra_sets``, trained :class:`SetOption` JSON, e.g. :func:`measure`'s), each
    validated as the profiler validates (:func:`rrcache.profiler.validate.validate`: beside the
    original, three timing repeats, the fallback of today) over ``validation_frames`` frames.
    A choice both sides share is measured once."""
    import dataclasses

    import rrcache
    from rrcache.model.sets import SetOption
    from rrcache.pipeline import load_for_session
    from rrcache.profiler.sets import keep_faster
    from rrcache.profiler.validate import validate
    from rrcache.profiles import load_profile
    from rrcache.profiles.store import STORE_NAME, ProfileStore, StoreKey
    from rrcache.session import load_session

    prof = load_profile(profile_dir)
    session = load_session(session_path)
    work = load_for_session(shader, session, prof.defines, prof.include_dirs)
    sets = list(prof.sets) + [SetOption.from_json(d) for d in extra_sets]
    prof.sets = []
    single = prof.threshold_selections()
    prof.sets = sets
    with_sets = prof.threshold_selections()
    settings = prof.settings
    key = StoreKey(prof.shader_hash, prof.session_hash, settings.key_hash(), rrcache.__version__, settings.key_json())
    from rrcache.profiler.plan import Plan

    window = Plan.from_json(prof.plan).timing_window if prof.plan else None
    quick = dataclasses.replace(settings, validation_frames=validation_frames)
    with ProfileStore.open(prof.path / STORE_NAME, key) as store:
        measured_single = validate(work, session, quick, store, single, window=window,
                                   candidates=prof.front_candidates)
        measured_sets = validate(work, session, quick, store, with_sets, window=window,
                                 candidates=prof.front_candidates)
        # as the profiler: a set stands only where it beats the single choice it displaced
        measured_sets = keep_faster(prof, work, session, quick, store, measured_sets, window=window)
    rows = []
    for a, b in zip(measured_single, measured_sets):
        rows.append({"label": a.label, "min_psnr": a.min_psnr, "single": a.to_json(), "with_sets": b.to_json(),
                     "changed": a.key != b.key})
    prof.selections = measured_sets
    return {"profile": str(profile_dir), "validation_frames": validation_frames, "levels": rows,
            "sets": [o.to_json() for o in sets], "original_ms": prof.original_ms}


def plot(profile_dirs: list, measured: list, levels_json: list, path, titles=None) -> list[str]:
    """The fronts' figure (:func:`rrcache.report.sets_plot.plot_fronts`): per profile its trained
    sets, the sets :func:`measure` measured (``measured``: its JSON files) and the selections that
    stood in :func:`levels` (``levels_json``: its JSON files; the single-node ones and those with
    the sets)."""
    from rrcache.model.sets import SetOption
    from rrcache.profiles import load_profile
    from rrcache.profiles.document import _read_dataclass
    from rrcache.report.sets_plot import plot_fronts
    from rrcache.selection import Selection

    profiles = []
    for folder, bench, lev in zip(profile_dirs, measured, levels_json):
        prof = load_profile(folder)
        known = {o.key for o in prof.sets if o.trained}
        extra = [SetOption.from_json(r) for r in _json(bench)["sets"]] if bench else []
        extra = [o for o in extra if o.key not in known]
        taken = {o.key for o in extra}  # a measured set replaces its untrained prediction
        prof.sets = [o for o in prof.sets if o.key not in taken] + extra
        rows = _json(lev)["levels"] if lev else []
        prof.selections = [_read_dataclass(Selection, r[side], "", lev) for r in rows for side in ("single", "with_sets")
                           if side == "single" or r["changed"]]
        profiles.append(prof)
    return plot_fronts(profiles, path, titles)


def main(argv: Optional[list] = None) -> None:  # pragma: no cover - a measurement, run by hand
    ap = argparse.ArgumentParser(description="the set rule against measured sets")
    ap.add_argument("profile")
    ap.add_argument("shader")
    ap.add_argument("session")
    ap.add_argument("--pairs", type=int, default=4)
    ap.add_argument("--set", dest="sets", action="append", default=[], help="n1:4,n2:50")
    ap.add_argument("--out", default=None)
    ap.add_argument("--levels", action="store_true",
                    help="validate each level's single-node choice and its choice with the trained sets instead")
    ap.add_argument("--validation-frames", type=int, default=8)
    ap.add_argument("--extra", default=None, help="a --out JSON of this command: its measured sets join the levels")
    ap.add_argument("--plot", default=None, help="draw the fronts' figure here from --figure-inputs")
    ap.add_argument("--figure-inputs", nargs="*", default=[],
                    help="PROFILE:MEASURED_JSON:LEVELS_JSON per panel (the positional arguments are ignored)")
    a = ap.parse_args(argv)
    if a.plot:
        triples = [item.split(":") for item in a.figure_inputs]
        print(plot([t[0] for t in triples], [t[1] or None for t in triples], [t[2] or None for t in triples],
                   a.plot))
        return
    if a.levels:
        extra = _json(a.extra)["sets"] if a.extra else []
        result = levels(a.profile, a.shader, a.session, a.validation_frames, extra)
        for row in result["levels"]:
            for side in ("single", "with_sets"):
                s = row[side]
                what = " + ".join(f"{p['node']} Δn={p['period']}" for p in s["parts"]) or "original"
                print(f"{row['label']} {side:9s} {what:34s} error {s['measured_error'] or 0:.4f} "
                      f"PSNR {s['measured_psnr'] or float('inf'):.1f} speed-up {s['measured_speedup'] or 1:.2f}× "
                      f"{s['speedups']}", flush=True)
        if a.out:
            atomic.write_text(a.out, json.dumps(result, indent=1))
        return
    result = measure(a.profile, a.shader, a.session, a.pairs, [_parse_set(s) for s in a.sets])
    if a.out:
        atomic.write_text(a.out, json.dumps(result, indent=1))


if __name__ == "__main__":  # pragma: no cover
    main()
