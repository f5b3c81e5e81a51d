"""Held-out accuracy of a profile's models (rrcache.profiler.accuracy, ``rrcache accuracy``) and
the training order (rrcache.profiler.order), on the tiny scene of test_profile:

- the nodes that matter are the predicted Pareto front's (plus the selections'); each is measured
  at periods training did not use, as training measures; predictions come from the profile's
  grids; the summary figures are finite and computed from the points;
- ``rrcache accuracy --json`` prints the report; a period beyond the models is a located error;
- the order skips nodes too cheap to win and groups the rest by what they depend on.
"""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from scene_files import SETTINGS, write_scene

from rrcache.errors import RRCacheError
from rrcache.pipeline import load_for_session
from rrcache.profiler import profile
from rrcache.profiles import TrainingSettings
from rrcache.profiler.accuracy import held_out, nodes_that_matter
from rrcache.profiler.train import training_order
from rrcache.session import load_session


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    folder = tmp_path_factory.mktemp("accuracy")
    shader, session = write_scene(folder)
    prof = profile(shader, session, folder / "out", TrainingSettings(**SETTINGS, validate=False))
    return prof, folder


def test_held_out_points_compare_prediction_and_measurement(trained):
    prof, _ = trained
    nodes, how = nodes_that_matter(prof)
    assert nodes and all(prof.node(n).trained for n in nodes)
    assert len(nodes) <= 8 and how  # at 64×48 nothing may beat the original: then spread by cost
    report = held_out(prof, periods=(3, 6))
    assert report.nodes == nodes and len(report.points) == 2 * len(nodes)
    index = {nid: i for i, nid in enumerate(prof.table.node_ids)}
    for p in report.points:
        i = index[p.node]
        assert p.predicted_error == pytest.approx(prof.table.E[i, p.period - 1])
        assert p.predicted_ms == pytest.approx(prof.table.T[i, p.period - 1])
        assert p.measured_error > 0 and p.measured_ms > 0 and 0 < p.hit_rate < 1
    rel = [abs(p.predicted_ms - p.measured_ms) / p.measured_ms for p in report.points]
    assert report.time_mean_relative_error == pytest.approx(float(np.mean(rel)))
    assert np.isfinite(report.error_r2) or len({p.measured_error for p in report.points}) < 2
    data = report.to_json()
    assert {"time_mean_relative_error", "error_r2_held_out", "error_r2_training", "points"} <= set(data)


def test_accuracy_cli_json_and_bad_period(trained):
    prof, _ = trained
    node = prof.trained_nodes[0].id
    proc = subprocess.run([sys.executable, "-m", "rrcache", "accuracy", str(prof.path), "--periods", "5",
                           "--nodes", node, "--json"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert data["nodes"] == [node] and [p["period"] for p in data["points"]] == [5]
    with pytest.raises(RRCacheError, match="outside 1..50"):
        held_out(prof, periods=(80,))
    bad = subprocess.run([sys.executable, "-m", "rrcache", "accuracy", str(prof.path), "--periods", "80"],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr and "--periods" in bad.stderr


def test_order_skips_cheap_nodes_and_groups_by_inputs(tmp_path):
    shader, session_path = write_scene(tmp_path)
    session = load_session(session_path)
    work = load_for_session(shader, session)
    order = training_order(work, session, TrainingSettings(**SETTINGS).resolved(session))
    top = max(n.cost for n in work.table.nodes)
    assert {n.id for n in order.nodes} == {n.id for n in work.table.nodes if n.cost >= 0.1 * top}
    assert set(order.skipped) == {n.id for n in work.table.nodes if n.cost < 0.1 * top}
    assert order.nodes[0].cost == top
    # the lit colour depends on the light and the normal; the pattern only on the object position
    sigs = set(order.signatures.values())
    assert any("u_light" in s and "v_normal" in s for s in sigs)
    assert any(s == "v_objectPosition" for s in sigs)
    # the first node of each group comes before the second node of any group
    firsts = {}
    for pos, n in enumerate(order.nodes):
        firsts.setdefault(order.signatures[n.id], pos)
    assert max(firsts.values()) < len(firsts) + 1
