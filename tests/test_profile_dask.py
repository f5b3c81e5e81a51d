"""A profile through Dask (a real LocalCluster: two worker processes, tiny renders) against the
same profile in this process:

- the same nodes trained, every error run equal within 1e-6 (frame by frame), the same
  selections (a seeded scene whose costliest node dominates, so the choice rests on the error
  models, which are deterministic);
- a worker killed (SIGKILL) mid-profile: the profile completes with the same result;
- no timing run beside another run on one host, from the recorded start and end times, and the
  store records the host of every timing run;
- a scheduler and two workers started as separate processes profile the bundled demo scene end
  to end through ``rrcache profile --scheduler``.
"""
from __future__ import annotations

import json
import os
import sqlite3
import subprocess
import sys

import pytest

from rrcache.profiler import profile
from rrcache.profiles import TrainingSettings, read_store
from farm import killing_a_busy_worker, local_farm
from scene_files import WAVE, fragment, session_doc, write_scene

#: eight octaves of wave noise: the whole noise costs far more than any other node
SHADER = fragment("""void main() {
    vec3 p = v_objectPosition * u_scale;
    float n = 0.0;
    float a = 0.5;
    float f = 1.0;
    n += a * wave(p, f); a *= 0.5; f *= 2.03;
    n += a * wave(p, f); a *= 0.5; f *= 2.03;
    n += a * wave(p, f); a *= 0.5; f *= 2.03;
    n += a * wave(p, f); a *= 0.5; f *= 2.03;
    n += a * wave(p, f); a *= 0.5; f *= 2.03;
    n += a * wave(p, f); a *= 0.5; f *= 2.03;
    vec3 albedo = mix(vec3(0.9, 0.8, 0.6), vec3(0.3, 0.2, 0.1), 0.5 + 0.5 * n);
    float diffuse = max(dot(normalize(v_normal), normalize(u_light - v_position.xyz)), 0.0);
    fragColor = vec4(albedo * (0.2 + 0.8 * diffuse), 1.0);
}""", helpers=WAVE)
#: the algorithm and the filter given, not "auto": "auto" chooses them by timing (the filter by
#: timing runs of the first node, rrcache.profiler.filters), and on a loaded machine two profiles
#: may then choose differently and cache with another filter: every error run of them would differ
SETTINGS = TrainingSettings(periods=(2, 4, 8), resolution=(32, 24), frames=12, timing_frames=4,
                            timing_periods=(2, 8), min_gain=0.0, algorithm="three-pass", filter="bilinear",
                            budget_s=600.0, max_sets=0, validate=False)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scene")
    return write_scene(folder, SHADER, session_doc(frames=12))


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    from rrcache.cluster.client import connect

    lock = tmp_path_factory.mktemp("hostlock") / "host.lock"
    with connect(workers=2, lock_path=str(lock), dashboard_address=":0") as c:
        yield c


@pytest.fixture(scope="module")
def in_process(scene, tmp_path_factory):
    shader, session = scene
    return profile(shader, session, tmp_path_factory.mktemp("local") / "p", SETTINGS, plots=False)


def _error_frames(folder) -> dict:
    with read_store(folder / "profile.sqlite") as store:
        return {(r.node, r.period): [f.mean_error for f in store.error_frames(r.node, r.period)]
                for r in store.error_runs()}


def _same(local, remote) -> None:
    assert [n.id for n in remote.trained_nodes] == [n.id for n in local.trained_nodes]
    assert len(local.trained_nodes) >= 3
    ours, theirs = _error_frames(local.path), _error_frames(remote.path)
    assert set(ours) == set(theirs)
    for key, frames in ours.items():
        assert len(theirs[key]) == len(frames)
        assert max(abs(a - b) for a, b in zip(frames, theirs[key])) <= 1e-6, key
    for a, b in zip(local.trained_nodes, remote.trained_nodes):
        assert a.errors == pytest.approx(b.errors, abs=1e-6) and a.hit_rates == pytest.approx(b.hit_rates, abs=1e-9)
    assert [s.describe() for s in remote.selections] == [s.describe() for s in local.selections]


def _overlap(a, b) -> bool:
    return a.started < b.finished and b.started < a.finished


def test_a_profile_through_dask_equals_the_one_in_process(scene, cluster, in_process, tmp_path):
    shader, session = scene
    before = len(cluster.placements)
    remote = profile(shader, session, tmp_path / "p", SETTINGS, plots=False, executor=cluster)
    _same(in_process, remote)
    placed = cluster.placements[before:]
    assert {p.kind for p in placed} == {"error", "timing"} and len({p.pid for p in placed}) == 2
    for a in placed:  # a timing run had its host to itself
        if a.kind == "timing":
            assert not [b for b in placed if b is not a and b.host == a.host and _overlap(a, b)], a
    # profile.json records the cluster, what its capacity bought and where each timed run ran
    record = json.loads((tmp_path / "p" / "profile.json").read_text())["cluster"]
    assert record["workers"] == 2 and record["hosts"] == [placed[0].host]
    assert record["capacity"]["frames"] == SETTINGS.frames and record["capacity"]["budget_factor"] == 2.0
    timed = [p.label for p in placed if p.kind == "timing"]
    assert sorted(record["timing_hosts"][placed[0].host]) == sorted(timed)
    with sqlite3.connect(tmp_path / "p" / "profile.sqlite") as db:  # and the store, per timing run
        hosts = [h for (h,) in db.execute("SELECT host FROM timing_run")]
    assert hosts and all(h == placed[0].host for h in hosts)


def test_a_worker_killed_mid_profile(scene, cluster, in_process, tmp_path):
    shader, session = scene
    cluster.client.wait_for_workers(2, timeout=60)
    with killing_a_busy_worker(cluster.client, matching="error") as victims:
        remote = profile(shader, session, tmp_path / "p", SETTINGS, plots=False, executor=cluster)
    assert victims, "no worker was seen busy with an error run"
    _same(in_process, remote)
    cluster.client.wait_for_workers(2, timeout=60)


def test_a_farm_profiles_the_demo_scene_end_to_end(tmp_path):
    from rrcache.profiler.demo import DEMO_SESSION, DEMO_SHADER

    env = {"RRCACHE_HOST_LOCK": str(tmp_path / "host.lock"), "LP_NUM_THREADS": "1"}
    with local_farm(tmp_path / "farm", env=env) as address:
        proc = subprocess.run(
            [sys.executable, "-m", "rrcache", "profile", str(DEMO_SHADER), str(DEMO_SESSION), "--out",
             str(tmp_path / "demo"), "--scheduler", address, "--periods", "2,4,8", "--frames", "12",
             "--timing-frames", "3", "--timing-periods", "2,8", "--budget", "20", "--sets", "0",
             "--min-gain", "0", "--validation-frames", "6"],
            capture_output=True, text=True, timeout=600, env=dict(os.environ, **env))
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert f"scheduler {address}" in proc.stderr
    doc = json.loads((tmp_path / "demo" / "profile.json").read_text())
    assert [s["label"] for s in doc["selections"]] == ["e1", "e2", "e3", "e4"]
    assert any(n["trained"] for n in doc["nodes"])
    assert (tmp_path / "demo" / "report.html").exists()


def test_profile_library_with_workers_prints_the_dashboard(scene, tmp_path):
    shader, session = scene
    proc = subprocess.run(
        [sys.executable, "-m", "rrcache", "profile-library", "--shaders", str(shader), "--sessions", str(session),
         "--out", str(tmp_path / "lib"), "--workers", "2", "--periods", "2,4,8", "--frames", "8",
         "--timing-frames", "3", "--timing-periods", "2,8", "--budget", "5", "--min-gain", "0", "--no-validate",
         "--no-plots"],
        capture_output=True, text=True, timeout=600, env=dict(os.environ, LP_NUM_THREADS="1"))
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Dask cluster (started here): 2 workers on 1 host" in proc.stderr and "/status" in proc.stderr
    assert "[1/1] noise-orbit" in proc.stderr and "noise-orbit" in proc.stdout
    doc = json.loads((tmp_path / "lib" / "noise-orbit" / "profile.json").read_text())
    assert doc["cluster"]["workers"] == 2 and doc["settings"]["frames"] == 8


def test_the_farm_waits_for_a_whole_scheduler_file(tmp_path):
    """The scheduler creates its file before writing it: an empty file is read again until the
    address is there (a fresh-clone CI run read it empty once)."""
    import threading

    from farm import _scheduler_address

    class Running:
        def poll(self):
            return None

    file = tmp_path / "scheduler.json"
    file.write_text("")
    writer = threading.Timer(0.3, lambda: file.write_text(json.dumps({"address": "tcp://127.0.0.1:1"})))
    writer.start()
    try:
        assert _scheduler_address(file, Running(), tmp_path / "scheduler.log") == "tcp://127.0.0.1:1"
    finally:
        writer.join()
    with pytest.raises(AssertionError, match="no scheduler address"):
        _scheduler_address(tmp_path / "never.json", Running(), tmp_path / "scheduler.log", within_s=0.3)
