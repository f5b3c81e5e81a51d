"""Measure chosen amortized options of a trained profile beside the original, as the profile's
validation measures its selections (three repeats, error and PSNR against the original), and
print predicted against measured. Usage:

    python tools/validate_amortized.py PROFILE ESTIMATOR:M:LAMBDA:HISTORY [...] [--frames N] [--json]

e.g. ``python tools/validate_amortized.py /tmp/slotsprof/temple e1:4:0:slots e1:4:0.6:blend
--frames 60``. An option must be one the profile offers (``Profile.amortized_options``).
"""
import argparse
import dataclasses
import json
import sys
import tempfile
from pathlib import Path

from rrcache.pipeline import load_for_session
from rrcache.profiler.validate import validate
from rrcache.profiles import load_profile
from rrcache.profiles.store import ProfileStore, StoreKey
from rrcache.session import load_session

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("profile")
parser.add_argument("options", nargs="+", metavar="ESTIMATOR:M:LAMBDA:HISTORY")
parser.add_argument("--frames", type=int, default=None, help="validation frames (default: the profile's)")
parser.add_argument("--json", action="store_true")
args = parser.parse_args()

prof = load_profile(args.profile)
offered = {(o.parts[0].estimator, o.parts[0].samples, round(o.parts[0].blend, 6), o.parts[0].history): o
           for o in prof.amortized_options()}
choices = []
for k, text in enumerate(args.options):
    try:
        est, m, lam, history = text.split(":")
        option = offered[(est, int(m), round(float(lam), 6), history)]
    except (ValueError, KeyError):
        sys.exit(f"{text}: not an option of {args.profile} (give estimator:m:lambda:history, e.g. e1:4:0.6:slots)")
    choices.append(prof.adopt(option, label=f"a{k + 1}", max_error=option.predicted_error))
session = load_session(prof.session)
work = load_for_session(prof.shader, session, prof.defines, prof.include_dirs, vertex=prof.vertex)
settings = prof.settings
if args.frames is not None:
    settings = dataclasses.replace(settings, validation_frames=args.frames)
settings = settings.resolved(session)
with tempfile.TemporaryDirectory() as tmp:
    key = StoreKey(work.hash, session.hash, settings.key_hash(), "validate_amortized", settings.key_json())
    with ProfileStore.open(Path(tmp) / "v.sqlite", key) as store:
        rows = validate(work, session, settings, store, choices, fallback=False)
out = [{"option": c.describe(), "history": c.parts[0].history, "predicted_speedup": c.predicted_speedup,
        "measured_speedup": r.measured_speedup, "speedups": list(r.speedups or ()),
        "predicted_psnr": c.predicted_psnr, "measured_psnr": r.measured_psnr,
        "predicted_error": c.predicted_error, "measured_error": r.measured_error, "hit_rate": r.hit_rate,
        "frames": r.frames, "measured_noise": r.measured_noise} for c, r in zip(choices, rows)]
if args.json:
    print(json.dumps(out, indent=1))
else:
    for o in out:
        print(f"{o['option']}: speed-up predicted {o['predicted_speedup']:.2f}x, measured {o['measured_speedup']:.2f}x "
              f"(repeats {', '.join(f'{s:.2f}' for s in o['speedups'])}); PSNR predicted {o['predicted_psnr']:.1f} dB, "
              f"measured {o['measured_psnr']:.1f} dB; error {o['predicted_error']:.4f} / {o['measured_error']:.4f}")
