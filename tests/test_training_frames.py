"""Training where the session goes (issue 29 item 2; rrcache/profiler/plan.py):

- a segment of the error frames that starts after Δn warm-up frames holds what a run from frame 0
  holds there (but for values resampled across a block edge) (real renders of the tiny scene): the claim that lets a long session be
  covered in segments;
- the error runs of a profile cover every frame of a session as long as the default, their plan
  is kept in profile.json and the summary says which frames and window;
- the error window's share comes from CPU time, which load moves little, and never drops below a
  sixteenth without the settings asking;
- the frames a budget leaves out widen the predicted PSNR's ± by their share.
"""
from __future__ import annotations

import numpy as np

from rrcache.harness.segments import restart, run_order, warmup_frames
from rrcache.profiler.plan import MIN_ERROR_FRACTION, Plan, error_fraction, error_segments
from test_profile import write_scene


def test_a_warmed_up_segment_holds_what_a_run_from_frame_0_holds(tmp_path, gl_ctx):
    from rrcache.harness.cached import CachedRenderer
    from rrcache.pipeline import load_for_session, variant_for
    from rrcache.session import load_session

    shader, session_path = write_scene(tmp_path)
    session = load_session(session_path)
    work = load_for_session(shader, session)
    node = max(work.table.nodes, key=lambda n: n.cost)
    variant = variant_for(work, node.id, "two-pass")
    from rrcache.harness.metrics import mean_l2
    from rrcache.harness.renderer import Renderer

    period, start = 4, 9
    with CachedRenderer(variant, session, work.prepared, (64, 48), period=period) as cached, \
            Renderer(work.prepared, session, (64, 48)) as original:
        cached.reset()
        whole = {i: cached.render_frame(i).image.copy() for i in range(12)}
        [segment] = run_order([start, start + 1, start + 2], period)
        assert [i for i, compared in segment if not compared] == warmup_frames(start, period) == list(range(1, 9))
        restart(cached, segment[0][0])
        warmed = {i: cached.render_frame(i).image.copy() for i, _ in segment}
        cached.reset()  # no warm-up, the clock at 0: what the segments would be without the plan
        cold = cached.render_frame(start).image.copy()
        refs = {i: original.render_frame(i) for i in range(start, start + 3)}
    for i in range(start, start + 3):
        error = mean_l2(whole[i], refs[i].image, refs[i].mask)[0]
        # only values resampled across a block edge from before the warm-up may differ
        assert mean_l2(warmed[i], whole[i], refs[i].mask)[0] <= 0.01 * error, i
    assert mean_l2(cold, whole[start], refs[start].mask)[0] > 0.1 * mean_l2(whole[start], refs[start].image,
                                                                         refs[start].mask)[0]


def test_the_error_runs_cover_the_session(tmp_path, gl_ctx):
    from rich.console import Console

    from rrcache.cli.profile import _summary
    from rrcache.profiler import profile
    from rrcache.profiles import TrainingSettings

    shader, session_path = write_scene(tmp_path)
    prof = profile(shader, session_path, tmp_path / "out",
                   TrainingSettings(periods=(2, 4), timing_frames=4, timing_periods=(2, 4), min_gain=0.0,
                                    validate=False, max_sets=0), plots=False)
    plan = Plan.from_json(prof.plan)
    assert plan.error_segments == [(0, 12)] and plan.error_frames(prof.settings.frames) == list(range(12))
    assert plan.original_cpu_ms > 0 and prof.uncovered_share() == 0.0
    # every frame of the session is in every error run (frame 0 stored, left out of the mean)
    from rrcache.profiles.store import read_store

    with read_store(tmp_path / "out" / "profile.sqlite") as store:
        node = prof.trained_nodes[0].id
        assert [f.frame for f in store.error_frames(node, 4)] == list(range(12))
    console = Console(record=True, width=200)
    _summary(prof, console)
    assert "error runs: frames 0–11 (all 12 of the session) in a" in console.export_text()


def test_the_error_window_comes_from_cpu_time():
    # Marble's full frame: ~100 ms of CPU time quiet, ~140 ms at load 12: a quarter either way
    assert error_fraction(100.0) == error_fraction(140.0) == 0.25
    assert error_fraction(2800.0) == MIN_ERROR_FRACTION and error_fraction(float("nan")) == 0.25
    # a long session is covered in segments from frame 0 to its end, each as long as the largest period
    segments = error_segments(900, 150, 50)
    assert segments[0][0] == 0 and segments[-1][0] + segments[-1][1] == 900
    assert all(n >= 50 for _, n in segments) and sum(n for _, n in segments) <= 150


def test_uncovered_frames_widen_the_uncertainty():
    from rrcache.profiles.document import Profile
    from rrcache.profiles import TrainingSettings

    def share(plan, frames):
        return Profile("s", "t", "", "", TrainingSettings(frames=frames, validation_frames=150), "two-pass", [],
                       plan=plan).uncovered_share()

    assert share({"error_segments": [[0, 150]]}, 150) == 0.0
    assert abs(share({"error_segments": [[0, 50], [100, 50]]}, 100) - 1 / 3) < 1e-9
    assert abs(share(None, 64) - 86 / 150) < 1e-9  # a profile planned before: its first 64 frames


def test_the_window_regions_tool_prints_each_region(tmp_path):
    """tools/window_regions.py (docs/levels.md, "The window check"): one row per window and one for
    the whole frame, whose two columns are the same run."""
    import subprocess
    import sys
    from pathlib import Path

    from scene_files import write_scene

    shader, session = write_scene(tmp_path)
    tool = Path(__file__).resolve().parents[1] / "tools" / "window_regions.py"
    p = subprocess.run([sys.executable, str(tool), str(shader), str(session), "n12", "4", "--frames", "6",
                        "--window", "0,0,32,24"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    rows = [line for line in p.stdout.splitlines() if line.startswith("| (")]
    assert len(rows) == 2 and rows[0].startswith("| (0, 0, 32, 24) |"), p.stdout
    whole = rows[1].split("|")
    assert float(whole[2]) == float(whole[3]) and float(whole[2]) >= 0.0


def test_a_later_segment_renders_the_same_on_a_new_renderer_and_a_used_one(tmp_path):
    """An error run over frames 21..30 (warm-up from frame 13, the clock set there) measures the
    same on a bench whose renderer is new (its first frame warms the driver up untimed) as on one
    that served another run of the variant first: the warm-up leaves the clock where the run set
    it (it once reset it to 0, which shifted the refresh schedule of a new renderer's run)."""
    from rrcache.gl.formats import ERROR_FORMAT
    from rrcache.harness.execute import execute
    from rrcache.pipeline import WorkSource, load_bench
    from rrcache.runs import RunSpec
    from rrcache.runtime.spec import VariantSpec
    from scene_files import session_doc

    shader, session = write_scene(tmp_path, None, session_doc(frames=40))
    spec = VariantSpec("cache", ("n12",), "three-pass", "bilinear", periods=(4,))
    run = RunSpec("error", spec, tuple(range(21, 31)), (32, 24), None, ERROR_FORMAT)
    with load_bench(WorkSource(str(shader), str(session))) as bench:
        new = [f.error for f in execute(run, bench).frames]
    with load_bench(WorkSource(str(shader), str(session))) as bench:
        execute(RunSpec("error", spec.with_runtime(periods=(8,)), (0, 1, 2, 3, 4), (32, 24), None, ERROR_FORMAT), bench)
        used = [f.error for f in execute(run, bench).frames]
    assert len(new) == 10 and max(new) > 0 and new == used
