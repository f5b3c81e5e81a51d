"""The adaptive refresh threshold in the profiler (rrcache.profiler.adaptive), on the tiny scene of
tests/test_profile.py: the sweep measures error and time against the threshold beside the
original; threshold 0 at fast period 1 is the original; a profile with ``adaptive=`` keeps every
measured point, replaces a selection only by a point measured faster at its level, and its
profile.json and shader folders carry the adaptive part."""
from __future__ import annotations

import json
import math

import pytest

from scene_files import SETTINGS, write_scene
from rrcache.pipeline import load_for_session
from rrcache.profiler import profile
from rrcache.profiler.adaptive import AdaptivePoint, best_at_level, sweep
from rrcache.profiles import TrainingSettings, load_profile
from rrcache.selection import AdaptiveNode, CachedNode, Selection
from rrcache.session import load_session


def test_best_at_level_takes_the_fastest_point_within_the_level_and_faster_than_the_selection():
    sel = Selection((CachedNode("n1", 8),), 0.01, 1.0, 2.0, min_psnr=40.0, measured_speedup=2.0)
    points = [AdaptivePoint("n1", 8, 0.01, 4, 0.004, 41.0, 0.40, 0.9),    # 2.5×, within the level
              AdaptivePoint("n1", 8, 0.05, 4, 0.020, 35.0, 0.30, 0.95),   # faster but below 40 dB
              AdaptivePoint("n1", 8, 0.002, 4, 0.002, 45.0, 0.60, 0.8)]   # within, slower than 2×
    assert best_at_level(sel, points).threshold == 0.01
    assert best_at_level(sel.replace(measured_speedup=3.0), points) is None


def test_sweep_at_threshold_zero_and_fast_period_one_is_exact(tmp_path):
    shader, session_path = write_scene(tmp_path)
    session = load_session(str(session_path))
    work = load_for_session(str(shader), session)
    node = max(work.table.nodes, key=lambda n: n.cost).id
    from rrcache.harness.execute import Bench, LocalExecutor
    from rrcache.runtime.spec import VariantSpec

    spec = VariantSpec("adaptive", (node,), "three-pass", periods=(8,), fast_period=1)
    with Bench(work, session) as bench:
        (point,) = sweep(LocalExecutor(bench), spec, [0.0], range(3), resolution=(32, 24))
    assert point.error == 0.0 and point.hit_rate == 0.0 and point.time_ratio > 0


def test_extend_replaces_a_selection_by_the_fastest_point_at_its_level(tmp_path):
    """A validated selection measured (here: stated) at 0.01× is beaten by any adaptive point
    within its level; the one that stands is the fastest measured, with its measured figures,
    and its JSON reads back."""
    from types import SimpleNamespace

    from rrcache.profiler.adaptive import extend
    from rrcache.selection import parts_from_json, parts_to_json

    shader, session_path = write_scene(tmp_path)
    session = load_session(str(session_path))
    work = load_for_session(str(shader), session)
    node = max(work.table.nodes, key=lambda n: n.cost).id
    sel = Selection((CachedNode(node, 8),), 0.01, 1.0, 2.0, label="e3", min_psnr=0.0, algorithm="three-pass",
                    measured_speedup=0.01, measured_error=0.01, measured_psnr=40.0)
    prof = SimpleNamespace(selections=[sel, Selection.original(1.0, label="e1")])
    settings = TrainingSettings(**SETTINGS, validation_frames=4).resolved(session)
    out = extend(prof, work, session, settings, (0.0, 0.02))
    assert len(prof.adaptive_points) == 2
    best = max(prof.adaptive_points, key=lambda p: p.speedup)
    assert out[1] == prof.selections[1]
    chosen = out[0]
    assert chosen.kind == "adaptive" and chosen.threshold == best.threshold and chosen.label == "e3"
    assert chosen.measured_speedup == pytest.approx(best.speedup) and chosen.measured_error == best.error
    assert parts_from_json(parts_to_json(chosen.parts), "parts") == chosen.parts
