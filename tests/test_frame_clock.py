"""The frame clock (rrcache.harness.timing): one interface behind every timed site, the wall clock
by default, GL timer queries by option, recorded in a profile's settings."""
from __future__ import annotations

import ast
import math
from pathlib import Path

import pytest

import rrcache
from rrcache.harness.timing import CLOCKS, DEFAULT_CLOCK, GLTimerClock, WallClock, make_clock
from rrcache.profiles.settings import TrainingSettings

ROOT = Path(rrcache.__file__).resolve().parent
SHADER = "shaders/glslviewer_basic.glsl"
SESSION = "sessions/marble.json"


def test_clocks_by_name(gl_ctx):
    assert DEFAULT_CLOCK == "wall" and set(CLOCKS) == {"wall", "gl-timer"}
    assert isinstance(make_clock("wall", gl_ctx), WallClock)
    assert isinstance(make_clock("gl-timer", gl_ctx), GLTimerClock)
    with pytest.raises(ValueError, match="gl-timer, wall"):
        make_clock("sundial", gl_ctx)


@pytest.mark.parametrize("clock", sorted(CLOCKS))
def test_every_renderer_times_with_the_chosen_clock(gl_ctx, clock):
    """The original, the cached variant and the side-by-side comparison each time their frames
    with the clock asked for, and get a finite, non-negative time from it."""
    from rrcache.harness.cached import compare
    from rrcache.harness.renderer import Renderer
    from rrcache.pipeline import load_for_session, variant_for
    from rrcache.session import load_session

    session = load_session(SESSION)
    work = load_for_session(SHADER, session)
    with Renderer(work.prepared, session, (32, 24), clock=clock) as r:
        assert r.clock.name == clock
        frame = r.render_frame(1)
    assert math.isfinite(frame.ms) and frame.ms >= 0.0 and math.isfinite(frame.cpu_ms)
    variant = variant_for(work, max(work.table.nodes, key=lambda n: n.cost).id, "two-pass")
    run = compare(variant, session, work.prepared, [0, 1, 2], period=2, resolution=(32, 24), clock=clock)
    assert all(math.isfinite(f.ms) and f.ms >= 0.0 and math.isfinite(f.original_ms) for f in run.frames)


def test_the_clock_is_a_setting_recorded_and_keyed():
    """``--clock`` is recorded in the profile's settings; the default leaves the store key as it
    was before the clock was a setting (stores trained then resume), another clock changes it."""
    wall, gpu = TrainingSettings(), TrainingSettings(clock="gl-timer")
    assert wall.to_json()["clock"] == "wall" and gpu.to_json()["clock"] == "gl-timer"
    assert "clock" not in wall.key_json() and '"clock":"gl-timer"' in gpu.key_json()
    assert wall.key_hash() != gpu.key_hash()
    assert TrainingSettings.from_json({k: v for k, v in wall.to_json().items() if k != "clock"}) == wall
    with pytest.raises(rrcache.RRCacheError, match="clock: unknown frame clock 'sundial'"):
        TrainingSettings(clock="sundial")


def test_no_timed_site_keeps_its_own_stopwatch():
    """Only rrcache/harness/timing.py waits for the GPU (``ctx.finish()``) to time: every timed
    frame of the harness, the alternatives, the runtime, the profiler and the report goes through
    a FrameClock (the bench's own micro-benchmarks of GPU stages are left to it)."""
    offenders = []
    for path in sorted(ROOT.rglob("*.py")):
        if path.name == "timing.py" and path.parent.name == "harness":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "finish" \
                    and not node.args and path.relative_to(ROOT).parts[0] in ("harness", "alternatives", "runtime",
                                                                              "profiler", "report"):
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not offenders, offenders
