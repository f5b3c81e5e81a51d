"""Write tests/data/marble_validations.json from real profile folders: what the tests of the
predictions' uncertainty need (tests/test_prediction_uncertainty.py).

For each profile folder: the timing noise, the stored original time, the timing runs' typical
original per frame with the covered pixels inside the timing window and in the whole frame, the
ceiling's fixed cost of the original, and per validated selection its node's training runs
(periods, errors, PSNRs, per-frame errors), the prediction and what validation measured, and
the covered fractions of the error window and of the validated region.

    python tools/validation_fixture.py /tmp/fresh1/marble-marble.rrprofile /tmp/trust/marble/marble.rrprofile \
        /tmp/trust2/sdf.rrprofile
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from rrcache.profiler.train import _typical_originals, _window_pixels
from rrcache.profiles.document import load_profile
from rrcache.profiles.store import read_store

OUT = Path(__file__).resolve().parent.parent / "tests" / "data" / "marble_validations.json"


def extract(folder: str) -> dict:
    prof = load_profile(folder)
    store = read_store(Path(folder) / "profile.sqlite")
    trained = [n.id for n in prof.trained_nodes]
    nodes, selections = {}, []
    for s in prof.selections:
        if not s.parts or s.measured_psnr is None:
            continue
        node = prof.node(s.node)
        nodes[s.node] = {
            "periods": node.periods, "errors": node.errors, "psnrs": node.psnrs,
            "perf_residual_ms": node.perf_fit.get("residual_rms"),
            "frame_errors": {str(p): [f.mean_error for f in store.error_frames(s.node, p) if not f.left_out]
                             for p in node.periods}}
        selections.append({"label": s.label, "node": s.node, "period": s.period,
                           "predicted_error": s.predicted_error, "predicted_ms": s.predicted_ms,
                           "predicted_speedup": s.predicted_speedup, "predicted_psnr": s.predicted_psnr,
                           "measured_error": s.measured_error, "measured_psnr": s.measured_psnr,
                           "measured_speedup": s.measured_speedup, "speedups": list(s.speedups)})
    width, height = prof.settings.resolution
    error_window, timing_window = (prof.plan or {}).get("error_window"), (prof.plan or {}).get("timing_window")
    runs = [r for n in trained for r in store.error_runs(n) if r.frames > 0]
    window_pixels = _window_pixels(store, trained, prof.settings)
    coverage = {"train_covered": sum(r.covered / r.frames for r in runs) / len(runs),
                "train_area": error_window[2] * error_window[3] if error_window else width * height,
                "check_covered": (sum(window_pixels.values()) / len(window_pixels) if timing_window
                                  else prof.pixels),
                "check_area": timing_window[2] * timing_window[3] if timing_window else width * height}
    return {"folder": Path(folder).name, "timing_noise": prof.timing_noise, "original_ms": prof.original_ms,
            "coverage": coverage,
            "timing_window": (prof.plan or {}).get("timing_window"),
            "original_fixed_ms": ((prof.plan or {}).get("ceiling") or {}).get("original_fixed_ms", 0.0),
            "typical_original_ms": {str(k): v for k, v in _typical_originals(store, trained, prof.settings).items()},
            "window_pixels": {str(k): v for k, v in _window_pixels(store, trained, prof.settings).items()},
            "frame_pixels": {str(f): c for f, _, c in store.reference_timing()},
            "nodes": nodes, "selections": selections}


if __name__ == "__main__":
    OUT.write_text(json.dumps({"profiles": [extract(f) for f in sys.argv[1:]]}, indent=1) + "\n")
    print(OUT)
