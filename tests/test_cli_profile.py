"""``rrcache profile`` and ``rrcache select`` through the command line, in real subprocesses:

- the profile end to end: the folder's files, profile.json, the summary; ``select --json`` and
  ``select --out``; located errors with exit code 2 for bad options and files;
- resume: a profile killed with SIGKILL part-way is rerun and finishes with the same fitted α, λ
  as an uninterrupted run, computing exactly the runs that were not stored (the store's run log
  counts them; the summary says how many were skipped);
- SIGINT: exit code 130, the stored runs are listed, the store is intact and resumable.
"""
from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time

import pytest

from child import python_argv
from safety_cli import stored_error_runs
from scene_files import CLI_SETTINGS, write_scene

from rrcache.profiles import read_store

# the same entry point as `python -m rrcache`, with the two commands registered if the package
# does not list them yet
ENTRY = ["-m", "rrcache"]  # the installed entry point's module, in a real subprocess


def _env():
    env = dict(os.environ, LP_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    return env


def rrcache(*args, check=True, **kw):
    proc = subprocess.run([sys.executable, *ENTRY, *map(str, args)], capture_output=True, text=True,
                          env=_env(), timeout=120, **kw)
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def _spawn(*args):
    # SIGINT at its default in the child: the test sends it (tests/child.py)
    return subprocess.Popen(python_argv([*ENTRY, *args], sigint_default=True), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=_env())


def _wait_for_runs(proc, path, at_least: int) -> int:
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            pytest.fail(f"the profile finished before it could be interrupted: {proc.stderr.read()}")
        n = stored_error_runs(path)
        if n >= at_least:
            return n
        time.sleep(0.01)
    proc.kill()
    pytest.fail("no run was stored in time")


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    """An uninterrupted profile, through the CLI."""
    folder = tmp_path_factory.mktemp("cli")
    shader, session = write_scene(folder)
    proc = rrcache("profile", shader, session, "--out", folder / "out", *CLI_SETTINGS)
    return folder, proc


def _fits(folder):
    data = json.loads((folder / "profile.json").read_text())
    return {n["id"]: (n["alpha"], n["lam"]) for n in data["nodes"]}


def test_profile_end_to_end(full):
    folder, proc = full
    out = folder / "out"
    for name in ("profile.json", "profile.sqlite", "tradeoff.png", "tradeoff.svg", "hitrate.png"):
        assert (out / name).exists(), name
    data = json.loads((out / "profile.json").read_text())
    assert data["rrcache_profile"] == 2 and all(n["trained"] for n in data["nodes"])
    assert [s["label"] for s in data["selections"]] == ["e1", "e2", "e3", "e4"]
    for sel in data["selections"]:
        assert (out / "optimized" / sel["label"] / "manifest.json").exists()
        if sel["parts"]:  # a cached selection was rendered beside the original
            assert sel["frames"] == 12 and sel["measured_error"] is not None
            assert list((out / "optimized" / sel["label"]).glob("*.frag"))
    assert f"nodes trained: {len(data['nodes'])} of {len(data['nodes'])}" in proc.stdout
    assert "selections" in proc.stdout and "μ =" in proc.stdout
    # every selection is stored as validated (the original ones too), and counted after validation
    assert data["counts"]["validations"] >= 4
    # default levels: predicted PSNR >= 45, 40, 35, 30 dB; the original's image is exact, never "100.0"
    assert [s["min_psnr"] for s in data["selections"]] == [45.0, 40.0, 35.0, 30.0]
    for sel in data["selections"]:
        if not sel["parts"]:
            assert sel["exact"] and sel["measured_psnr"] is None and sel["measured_speedup"] == 1.0
    if any(not s["parts"] for s in data["selections"]):
        assert "∞ (exact)" in proc.stdout
    assert data["ceiling"] is not None and data["verdict"] is None  # --min-gain 0: measured, never stops


def test_select_json_and_out(full, tmp_path):
    folder, _ = full
    out = folder / "out"
    proc = rrcache("select", out, "--max-error", "1e9", "--json")
    choice = json.loads(proc.stdout)
    assert set(choice) == {"node", "period", "predicted_error", "predicted_ms", "predicted_speedup",
                           "predicted_speedup_range", "predicted_psnr", "predicted_psnr_uncertainty", "exact",
                           "visible_artifacts", "source", "note", "warnings", "measured_error", "measured_psnr",
                           "measured_psnr_uncertainty", "measured_speedup", "speedups", "measured_flip",
                           "measured_temporal_psnr"}
    assert choice["source"] in ("measured", "predicted")  # docs/levels.md: each figure says which
    data = json.loads((out / "profile.json").read_text())
    if choice["node"] is not None:
        assert choice["node"] in {n["id"] for n in data["nodes"]} and 1 <= choice["period"] <= 50
    by_psnr = json.loads(rrcache("select", out, "--min-psnr", "40", "--json").stdout)
    assert by_psnr["node"] is None or by_psnr["predicted_psnr"] >= 40 - 1e-9
    assert by_psnr["exact"] == (by_psnr["node"] is None or by_psnr["predicted_error"] == 0)
    both = rrcache("select", out, "--min-psnr", "40", "--max-error", "0.1", check=False)
    assert both.returncode == 2 and "one of --max-error, --min-psnr and --max-flip" in both.stderr
    strict = json.loads(rrcache("select", out / "profile.json", "--max-error", "0", "--json").stdout)
    assert strict["predicted_error"] <= 1e-12 and strict["predicted_ms"] >= choice["predicted_ms"]
    written = rrcache("select", out, "--max-error", "1e9", "--out", tmp_path / "opt")
    manifest = json.loads((tmp_path / "opt" / "manifest.json").read_text())
    if choice["node"] is not None:
        assert manifest["node"]["id"] == choice["node"] and manifest["period"] == choice["period"]
        assert list((tmp_path / "opt").glob("*.frag"))
    else:
        assert manifest["node"] is None
    assert "wrote" in written.stdout


@pytest.mark.parametrize("args,message", [
    (["select", "{tmp}", "--max-error", "0.1"], "no profile here"),
    (["select", "{out}", "--max-error", "-1"], "--max-error"),
    (["profile", "{shader}", "{session}", "--out", "{out}", "--periods", "2,4,9"], "--fresh"),
    (["profile", "{shader}", "{session}", "--out", "{tmp}/x", "--periods", "2,0"], "--periods"),
    (["profile", "{shader}", "{session}", "--out", "{tmp}/y", "--frames", "40"], "the session has 12"),
])
def test_errors_are_one_located_line(full, tmp_path, args, message):
    folder, _ = full
    names = dict(tmp=tmp_path, out=folder / "out", shader=folder / "noise.frag", session=folder / "orbit.json")
    proc = rrcache(*[a.format(**names) for a in args], check=False)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rrcache: error:") and message in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("command", [["select", "--max-error", "0.1"], ["report"], ["accuracy"]])
def test_a_bad_profile_document_exits_2_naming_the_key(full, tmp_path, command):
    """Every command that reads profile.json refuses a document outside its declared shape with
    one line naming the file and the key path, exit code 2."""
    folder, _ = full
    data = json.loads((folder / "out" / "profile.json").read_text())
    data["nodes"][1]["alpha"] = -1
    (tmp_path / "profile.json").write_text(json.dumps(data))
    proc = rrcache(command[0], tmp_path, *command[1:], check=False)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "profile.json: nodes[1].alpha: must be a finite number >= 0" in lines[0], proc.stderr


def test_resume_after_sigkill(full, tmp_path, stability_case):
    case = stability_case("profile killed (SIGKILL) and resumed", "profile store: interruption and damage",
                          "rrcache profile, SIGKILL after 3 stored error runs, then the same command again")
    folder, _ = full
    shader, session = write_scene(tmp_path)
    out = tmp_path / "out"
    store_path = out / "profile.sqlite"
    # the same algorithm as the uninterrupted run: 'auto' chooses by timing, and on a loaded
    # machine the two runs could choose differently (three-pass and two-pass images differ in
    # the last bits, and so would the fitted α, λ)
    algorithm = json.loads((folder / "out" / "profile.json").read_text())["algorithm"]
    # and the same cache filter ('auto' chooses it by timing too)
    filter_ = json.loads((folder / "out" / "profile.json").read_text())["filter"]
    proc = _spawn("profile", shader, session, "--out", out, *CLI_SETTINGS, "--algorithm", algorithm, "--filter", filter_)
    _wait_for_runs(proc, store_path, 3)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    killed_at = stored_error_runs(store_path)
    total = 3 * len(_fits(folder / "out"))
    assert 3 <= killed_at < total
    assert not (out / "profile.json").exists()  # nothing is written before training finishes

    again = rrcache("profile", shader, session, "--out", out, *CLI_SETTINGS, "--algorithm", algorithm, "--filter", filter_)
    assert f"computed; {killed_at} error and" in again.stdout  # the summary: stored runs skipped
    with read_store(store_path) as store:
        log = store.run_log()
        assert [r["status"] for r in log] == ["running", "done"]  # the killed run never finished
        assert log[0]["error_runs_computed"] == killed_at
        assert log[1]["error_runs_computed"] == total - killed_at
        assert log[1]["error_runs_skipped"] == killed_at
        assert store.counts()["error_runs"] == total
    reference, resumed = _fits(folder / "out"), _fits(out)
    case.observe(runs_at_kill=killed_at, runs_in_all=total, skipped_on_resume=log[1]["error_runs_skipped"],
                 computed_on_resume=log[1]["error_runs_computed"], run_log=[r["status"] for r in log],
                 fits_as_uninterrupted=reference.keys() == resumed.keys() and all(
                     math.isclose(resumed[n][i], reference[n][i], rel_tol=1e-6, abs_tol=1e-12)
                     for n in reference for i in (0, 1)))
    assert reference.keys() == resumed.keys()
    for node, (alpha, lam) in reference.items():
        assert resumed[node][0] == pytest.approx(alpha, rel=1e-6, abs=1e-12), node
        assert resumed[node][1] == pytest.approx(lam, rel=1e-6, abs=1e-12), node


def test_sigint_exits_130_and_keeps_the_store(tmp_path, stability_case):
    case = stability_case("profile interrupted (SIGINT)", "profile store: interruption and damage",
                          "rrcache profile, SIGINT after 2 stored error runs, then resumed")
    shader, session = write_scene(tmp_path)
    out = tmp_path / "out"
    # every node trained (--min-saving 0) at 16 periods: enough work that the signal lands before
    # the end (with the three periods of CLI_SETTINGS the whole profile took 2.7 s on a quiet
    # machine and the signal once arrived after it had finished)
    settings = [*CLI_SETTINGS, "--min-saving", "0", "--periods", "2,3,4,5,6,7,8,10,12,14,16,20,24,28,32,40"]
    proc = _spawn("profile", shader, session, "--out", out, *settings)
    _wait_for_runs(proc, out / "profile.sqlite", 2)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=60)
    case.observe(exit=proc.returncode, stderr=" ".join(stderr.split()).replace(str(tmp_path), "TMP"))
    assert proc.returncode == 130, stderr
    assert "interrupted" in stderr and "error runs over" in stderr and "resume" in stderr
    assert "Traceback" not in stderr
    with read_store(out / "profile.sqlite") as store:  # read_store runs the integrity check
        assert store.run_log()[-1]["status"] == "interrupted"
        stored = store.counts()["error_runs"]
        assert stored >= 2
        for run in store.error_runs():  # every stored run is complete
            assert len(store.error_frames(run.node, run.period)) == run.frames == 12
    assert not (out / "profile.json").exists()
    resumed = rrcache("profile", shader, session, "--out", out, *settings, "--no-validate")
    case.observe(stored_at_interrupt=stored, resumed_skipping=f"computed; {stored} error and" in resumed.stdout)
    assert f"computed; {stored} error and" in resumed.stdout
