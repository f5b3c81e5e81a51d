"""The Dask cluster under rrcache, for real: a LocalCluster of two worker processes.

- each worker opened its own EGL context once (its own process, llvmpipe, ``LP_NUM_THREADS=1``)
  on the plugin's GL thread, and the cluster's dashboard link is announced;
- the host lock: runs of kind ``error`` overlap each other on the two workers, and no run of kind
  ``timing`` overlaps any other run on the host (from the recorded start and end times);
- a run whose worker is killed (SIGKILL) mid-run is started again on a worker and completes; a
  run that kills every worker it lands on is reported after the allowed retries, and the
  cluster's other runs complete;
- the default path imports no Dask.
"""
from __future__ import annotations

import os
import subprocess
import sys

import cloudpickle
import pytest

import cluster_runs
from farm import killing_a_busy_worker

cloudpickle.register_pickle_by_value(cluster_runs)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    from rrcache.cluster.client import connect

    said = []
    lock = tmp_path_factory.mktemp("hostlock") / "host.lock"
    with connect(workers=2, lock_path=str(lock), dashboard_address=":0", announce=said.append) as c:
        yield c, said


def _overlap(a, b) -> bool:
    return a.started < b.finished and b.started < a.finished


def test_each_worker_opened_its_own_gl_context(cluster):
    c, said = cluster
    assert len(c.workers) == 2
    pids = {info["pid"] for info in c.workers.values()}
    assert len(pids) == 2 and os.getpid() not in pids
    for info in c.workers.values():
        assert "llvmpipe" in info["renderer"] and info["lp_num_threads"] == "1"
        assert info["thread"].startswith("rrcache-gl")
    assert len(said) == 1 and "2 workers on 1 host" in said[0] and "/status" in said[0]


def test_timing_runs_never_share_the_host(cluster):
    from rrcache.cluster.executor import DaskRuns

    c, _ = cluster
    runs = DaskRuns(c)
    name = runs.open("sleepy", cluster_runs.Sleepy())
    kinds = ["error", "error", "timing", "error", "error", "timing", "timing", "error", "error", "error"]
    try:
        done = list(runs.map(name, [(0.4, kind) for kind in kinds]))
    finally:
        runs.close(name)
    assert len(done) == len(kinds)
    placed = [p for _, p in done]
    assert all(p.result["pixel"] == [64, 128, 191, 255] for p in placed)
    assert {p.kind for p in placed} == {"error", "timing"} and len({p.pid for p in placed}) == 2
    for a in placed:
        if a.kind == "timing":
            beside = [b for b in placed if b is not a and b.host == a.host and _overlap(a, b)]
            assert not beside, (a, beside)
    # the error runs did run side by side (else the lock would be a global one)
    errors = [p for p in placed if p.kind == "error"]
    assert any(_overlap(a, b) for i, a in enumerate(errors) for b in errors[i + 1:])
    assert runs.placements and all(p.result is None for p in runs.placements)


def test_a_killed_worker_loses_only_its_run(cluster):
    from rrcache.cluster.executor import DaskRuns, RunFailure

    c, _ = cluster
    runs = DaskRuns(c)
    name = runs.open("sleepy", cluster_runs.Sleepy())
    with killing_a_busy_worker(c.client) as victims:
        try:
            done = list(runs.map(name, [(1.0, "error") for _ in range(4)]))
        finally:
            runs.close(name)
    assert victims, "no worker was busy to be killed"
    assert len(done) == 4 and not any(isinstance(p, RunFailure) for _, p in done)
    assert victims[0] not in {p.pid for _, p in done}
    c.client.wait_for_workers(2, timeout=60)  # the nanny restarted it, with its plugin


def test_a_run_that_always_kills_its_worker_is_reported(cluster):
    from distributed import KilledWorker

    from rrcache.cluster.executor import DaskRuns, RunFailure

    c, _ = cluster
    c.client.wait_for_workers(2, timeout=60)
    runs = DaskRuns(c)
    dies, sleepy = runs.open("dies", cluster_runs.Dies()), runs.open("fine", cluster_runs.Sleepy())
    try:
        failed = list(runs.map(dies, [(None, "error")]))
        fine = list(runs.map(sleepy, [(0.0, "error"), (0.0, "timing")]))
    finally:
        runs.close()
    assert len(failed) == 1 and isinstance(failed[0][1], RunFailure)
    assert isinstance(failed[0][1].error, KilledWorker)
    assert len(fine) == 2 and not any(isinstance(p, RunFailure) for _, p in fine)


def test_the_default_path_imports_no_dask(tmp_path):
    """A whole in-process profile (and the commands' modules) without a Dask module loaded."""
    from scene_files import write_scene

    shader, session = write_scene(tmp_path / "scene")
    code = ("import sys, rrcache\n"
            "import rrcache.cli, rrcache.cli.profile, rrcache.cli.profile_library, rrcache.profiler.library\n"
            "from rrcache.profiles import TrainingSettings\n"
            f"p = rrcache.profile({str(shader)!r}, {str(session)!r}, {str(tmp_path / 'out')!r}, "
            "TrainingSettings(periods=(2, 4), resolution=(32, 24), timing_frames=2, timing_periods=(2,), "
            "min_gain=0.0, budget_s=1.0, max_sets=0, validate=False), plots=False)\n"
            "assert p.trained_nodes\n"
            "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed'))\n"
            "assert not bad, bad\n")
    env = dict(os.environ, LP_NUM_THREADS="1")
    env.pop("RRCACHE_SCHEDULER", None)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr


def test_a_scheduler_and_workers_started_apart(tmp_path, monkeypatch):
    from farm import local_farm

    from rrcache.cluster.client import SCHEDULER_ENV, connect
    from rrcache.cluster.executor import DaskRuns

    with local_farm(tmp_path / "farm", env={"RRCACHE_HOST_LOCK": str(tmp_path / "host.lock")}) as address:
        monkeypatch.setenv(SCHEDULER_ENV, address)
        said = []
        with connect(announce=said.append) as c:
            c.client.wait_for_workers(2, timeout=60)
            runs = DaskRuns(c)
            name = runs.open("sleepy", cluster_runs.Sleepy())
            done = list(runs.map(name, [(0.2, "error"), (0.2, "timing"), (0.2, "error")]))
            runs.close()
        assert f"scheduler {address}" in said[0]
    assert len(done) == 3 and all(p.result["pixel"] == [64, 128, 191, 255] for _, p in done)
