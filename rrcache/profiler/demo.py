"""The demo profile of the notebooks: a small scene shipped with rrcache (a marbled sphere whose
eight-octave trigonometric noise is worth caching, 160×120, 24 frames), profiled with settings
that take seconds, so a new user can run the notebooks top to bottom.

>>> prof = demo_profile("demo.rrprofile")     # doctest: +SKIP
>>> [s.label for s in prof.selections]         # doctest: +SKIP
['e1', 'e2', 'e3', 'e4']
"""
from __future__ import annotations

from pathlib import Path

from rrcache.errors import RRCacheError

DEMO_DIR = Path(__file__).parent / "demo"
DEMO_SHADER = DEMO_DIR / "marbled_sphere.glsl"
DEMO_SESSION = DEMO_DIR / "marbled_sphere.json"

#: training settings that profile the demo scene in seconds (the budget trains the costliest nodes)
DEMO_SETTINGS = dict(periods=(2, 4, 8, 16), timing_frames=6, timing_periods=(2, 16), budget_s=8.0)


def demo_profile(out_dir="demo.rrprofile", progress=None):
    """The demo scene's profile in ``out_dir``: loaded when a profile is there, made otherwise
    (seconds; the report is written with it)."""
    from rrcache.profiler.run import profile
    from rrcache.profiles import TrainingSettings, load_profile

    out = Path(out_dir)
    if (out / "profile.json").exists():
        try:
            return load_profile(out)
        except RRCacheError:
            pass  # another version's profile: make it again
    return profile(DEMO_SHADER, DEMO_SESSION, out, TrainingSettings(**DEMO_SETTINGS), progress=progress)
