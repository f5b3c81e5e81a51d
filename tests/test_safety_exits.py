"""The remaining hostile cases of issue 30 that exited 70 or hung, each now exit 0 or 2 with one
line (the real command line in a subprocess unless said otherwise):

- SIGTERM is handled like SIGINT: one line, exit 143, the store consistent, its run log
  ``interrupted`` (never left ``running``), and the next run resumes; through the frame
  watchdog's supervisor too;
- ``--debug`` shows the traceback and keeps exit 2; a closed stdout is one line, exit 2, after the
  work is saved; ``--max-source-bytes 1e11`` and ``bench-cache``'s ``--periods``,
  ``--compare-period`` and ``--frames`` are checked;
- a damaged store is refused on resume with its table, row and column; a ``profile.json`` whose
  per-node lists differ in length with the key path;
- macro bombs are refused in well under a second of expansion and a small amount of memory (the
  peak measured);
- a variant the driver refuses: ``instance`` writes nothing and says so; ``profile`` drops the node
  with the reason and trains the others. The refusal is the one place a real driver cannot be made
  to refuse on demand: the driver's compile is replaced, in process, by one that refuses one node.
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import time

import pytest

from child import python_argv
from safety_cli import (QUICK_PROFILE, REFUSAL_PEAK_MIB, RUN_PEAK_MIB, env, launched, made_profile,  # noqa: F401
                        one_error_line, peak_mib, rrcache, rrcache_traced, stored_error_runs, write_case)
from scene_files import CLI_SETTINGS, write_scene

AREA = "safety: exits, signals and damaged documents"


# ----------------------------------------------------------------------------- SIGTERM

@pytest.mark.parametrize("watchdog", [False, True], ids=["direct", "under-the-frame-watchdog"])
def test_sigterm_is_handled_like_sigint(tmp_path, stability_case, watchdog):
    from rrcache.profiles.store import read_store

    shader, session = write_scene(tmp_path)
    out = tmp_path / "out"
    settings = [*CLI_SETTINGS, "--min-saving", "0", "--periods", "2,3,4,5,6,7,8,10,12,14,16,20,24,28,32,40"]
    head = ["--frame-timeout", "60"] if watchdog else []
    usage = tmp_path / "usage"
    proc = subprocess.Popen(launched(usage, *head, "profile", shader, session, "--out", out, *settings),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env())
    deadline = time.monotonic() + 120
    while stored_error_runs(out / "profile.sqlite") < 2:
        if proc.poll() is not None:
            pytest.fail(f"the profile ended before the signal: {proc.stderr.read()}")
        if time.monotonic() > deadline:
            proc.kill()
            pytest.fail("no run was stored in time")
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=120)
    lines = [line for line in stderr.splitlines() if line.strip()]
    case = stability_case(f"SIGTERM during a profile{' (frame watchdog)' if watchdog else ''}", AREA,
                          "rrcache profile, SIGTERM after 2 stored error runs, then the same command again")
    case.observe(exit=proc.returncode, stderr=" | ".join(lines).replace(str(tmp_path), "TMP"),
                 peak_mib=round(peak_mib(usage)))
    assert proc.returncode == 143, stderr
    assert peak_mib(usage) < RUN_PEAK_MIB
    assert "Traceback" not in stderr
    said = [line for line in lines if line.startswith("rrcache:")]
    assert len(said) == 1 and said[0].startswith("rrcache: terminated (SIGTERM); the run in flight was dropped"), lines
    with read_store(out / "profile.sqlite") as store:  # read_store runs SQLite's integrity check
        assert store.run_log()[-1]["status"] == "interrupted"
        stored = store.counts()["error_runs"]
    resumed = subprocess.run([sys.executable, "-m", "rrcache", "profile", str(shader), str(session), "--out",
                              str(out), *settings, "--no-validate", "--budget", "1"], capture_output=True, text=True,
                             env=env())
    assert resumed.returncode == 0, resumed.stderr
    with read_store(out / "profile.sqlite") as store:
        assert store.run_log()[-1]["error_runs_skipped"] >= stored >= 2


# ----------------------------------------------------------------------------- exits

def test_debug_keeps_exit_2(tmp_path, stability_case):
    write_case(tmp_path)
    code, _, lines, peak, _ = rrcache_traced(tmp_path, "--debug", "nodes", "missing.frag")
    assert code == 2 and "Traceback" in "\n".join(lines) and peak < REFUSAL_PEAK_MIB
    assert lines[-1].startswith("rrcache: error: cannot read shader file 'missing.frag': not found")
    with open(os.devnull, "w") as null:  # an OSError (the output folder is a file) is exit 2 as well
        (tmp_path / "afile").write_text("x")
        code2, _, lines2 = rrcache(tmp_path, "--debug", "instance", "scene.frag", "--node", "n1", "--out",
                                   "afile/x", stdout=null)
    stability_case("--debug on a bad input", AREA, "rrcache --debug nodes missing.frag; instance --out afile/x").observe(
        exit=code, last_line=lines[-1], instance_exit=code2, peak_mib=round(peak))
    assert code2 == 2 and lines2[-1].startswith("rrcache: error:"), lines2


def test_closed_stdout(tmp_path, stability_case):
    write_case(tmp_path)
    # launched(...)[1:]: the launcher's arguments to python, which python_argv starts with stdout closed
    proc = subprocess.run(python_argv(launched(tmp_path / "usage", "nodes", "scene.frag")[1:], close_stdout=True),
                          cwd=tmp_path, env=env(), stderr=subprocess.PIPE, text=True)
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    line = one_error_line(proc.returncode, lines)
    peak = peak_mib(tmp_path / "usage")
    # a profile run with no stdout keeps what it computed: the folder is written, then the table fails
    prof = subprocess.run(python_argv(launched(tmp_path / "usage", "profile", "scene.frag", "scene.json", "--out", "p",
                                               *QUICK_PROFILE)[1:], close_stdout=True),
                          cwd=tmp_path, env=env(), stderr=subprocess.PIPE, text=True)
    prof_lines = [x for x in prof.stderr.splitlines() if x.strip() and x.startswith("rrcache:")]
    stability_case("stdout closed", AREA, "rrcache nodes >&-; rrcache profile >&-").observe(
        exit=proc.returncode, stderr=line, profile_exit=prof.returncode, profile_stderr=prof_lines[-1:],
        peak_mib=round(peak), profile_peak_mib=round(peak_mib(tmp_path / "usage")))
    assert "standard output is closed" in line
    assert peak < REFUSAL_PEAK_MIB and peak_mib(tmp_path / "usage") < RUN_PEAK_MIB
    assert prof.returncode == 2 and (tmp_path / "p" / "profile.json").exists(), prof.stderr
    assert prof_lines and "standard output is closed" in prof_lines[-1]


BAD_OPTIONS = {
    "--max-source-bytes 1e11": (["--max-source-bytes", "1e11", "nodes", "scene.frag"], "--max-source-bytes"),
    "--max-source-bytes 10^11": (["--max-source-bytes", str(10 ** 11), "nodes", "scene.frag"], "--max-source-bytes"),
    "bench-cache --periods 0,8": (["bench-cache", "scene.frag", "scene.json", "--node", "n1", "--periods", "0,8"],
                                  "--periods"),
    "bench-cache --periods 3e9 as an integer": (["bench-cache", "scene.frag", "scene.json", "--node", "n1", "--periods",
                                                 "3000000000"], "--periods"),
    "bench-cache --compare-period 0": (["bench-cache", "scene.frag", "scene.json", "--node", "n1", "--compare-period",
                                        "0"], "--compare-period"),
    "bench-cache --frames -5": (["bench-cache", "scene.frag", "scene.json", "--node", "n1", "--frames", "-5"],
                                "--frames"),
    "bench-cache --frames 0": (["bench-cache", "scene.frag", "scene.json", "--node", "n1", "--frames", "0"], "--frames"),
}


@pytest.mark.parametrize("name", list(BAD_OPTIONS))
def test_unchecked_options_are_checked(tmp_path, stability_case, name):
    write_case(tmp_path)
    args, option = BAD_OPTIONS[name]
    code, _, lines, peak, _ = rrcache_traced(tmp_path, *args)
    line = one_error_line(code, lines)
    stability_case(name, AREA, "rrcache " + " ".join(args)).observe(exit=code, stderr=line, peak_mib=round(peak))
    assert option in line and peak < REFUSAL_PEAK_MIB


# ----------------------------------------------------------------------------- damaged documents

DAMAGE = {
    "a wall time that is text": ("UPDATE error_run SET wall_s = 'x'", "error_run", "wall_s"),
    "a frame count of 1e300": ("UPDATE error_run SET frames = 1e300", "error_run", "frames"),
    "a timing run's period that is text": ("UPDATE timing_run SET period = 'zz'", "timing_run", "period"),
    "a timed frame's ms below 0": ("UPDATE timing_frame SET ms = -1", "timing_frame", "ms"),
    "a reference frame's coverage that is text": ("UPDATE reference_frame SET covered = 'q'", "reference_frame",
                                                  "covered"),
    "the plan that is not JSON": ("UPDATE meta SET value = '{not json' WHERE key = 'plan'", "meta('plan')", "JSON"),
    "an error run's frames deleted": ("DELETE FROM error_frame", "error_run", "frames"),
    "an overhead that is text": ("UPDATE overhead SET ms = 'x'", "overhead", "ms"),
}


@pytest.mark.parametrize("name", list(DAMAGE))
def test_damaged_store_rows_are_refused_on_resume(made_profile, tmp_path, stability_case, name):
    sql, table, column = DAMAGE[name]
    shutil.copytree(made_profile, tmp_path / "case")
    conn = sqlite3.connect(tmp_path / "case" / "p" / "profile.sqlite")
    changed = conn.execute(sql).rowcount
    conn.commit()
    conn.close()
    assert changed > 0
    code, _, lines, peak, _ = rrcache_traced(tmp_path / "case", "profile", "scene.frag", "scene.json", "--out", "p",
                                             *QUICK_PROFILE)
    line = one_error_line(code, lines)
    stability_case(f"damaged store on resume: {name}", AREA, sql).observe(exit=code, stderr=line, peak_mib=round(peak))
    assert table in line and column in line and "--fresh" in line, line
    assert peak < RUN_PEAK_MIB


def test_profile_json_lists_of_different_lengths(made_profile, tmp_path, stability_case):
    shutil.copytree(made_profile, tmp_path / "case")
    path = tmp_path / "case" / "p" / "profile.json"
    doc = json.loads(path.read_text())
    i = next(k for k, n in enumerate(doc["nodes"]) if n["trained"])
    doc["nodes"][i]["periods"], doc["nodes"][i]["errors"] = [2, 6, 10], [0.1]
    path.write_text(json.dumps(doc))
    seen, peaks = {}, []
    for command in (["select", "p", "--max-error", "0.1"], ["report", "p"], ["accuracy", "p"]):
        code, _, lines, peak, _ = rrcache_traced(tmp_path / "case", *command)
        seen[command[0]] = one_error_line(code, lines)
        peaks.append(round(peak))
        assert f"profile.json: nodes[{i}].errors: has 1 value, but nodes[{i}].periods has 3" in seen[command[0]]
    stability_case("profile.json: periods [2,6,10], errors [0.1]", AREA, "select, report, accuracy").observe(
        **seen, peak_mib=max(peaks))
    assert max(peaks) < REFUSAL_PEAK_MIB, peaks


# ----------------------------------------------------------------------------- macro bombs

BOMBS = {
    "D(x) x x nested 24 deep": "#define D(x) x x\n" + "D(" * 24 + "a" + ")" * 24,
    "thirty macros, each twice the last": "#define A0 x\n" + "".join(f"#define A{i} A{i - 1} A{i - 1}\n"
                                                                      for i in range(1, 31)) + "A30\n",
    "F(a) a a a nested 16 deep": "#define F(a) a a a\n" + "F(" * 16 + "z" + ")" * 16,
    "ten copies, eight deep": "#define A0 x\n" + "".join(f"#define A{i} " + " ".join([f"A{i - 1}"] * 10) + "\n"
                                                         for i in range(1, 9)) + "A8\n",
}


@pytest.mark.parametrize("name", list(BOMBS))
def test_macro_bombs_are_refused_small(tmp_path, stability_case, name):
    (tmp_path / "bomb.frag").write_text("#version 330\nout vec4 c;\n" + BOMBS[name] + "\nvoid main() { c = vec4(1.0); }\n")
    code, _, lines, peak, _ = rrcache_traced(tmp_path, "nodes", "bomb.frag", timeout=120)
    line = one_error_line(code, lines)
    stability_case(f"macro bomb: {name}", AREA, "rrcache nodes bomb.frag").observe(
        exit=code, stderr=line.replace(str(tmp_path), "TMP"), peak_mib=round(peak))
    assert "macro expansion too large" in line and "200,000 tokens" in line
    assert peak < REFUSAL_PEAK_MIB, peak


# ----------------------------------------------------------------------------- a refused variant

@pytest.fixture
def refusing_driver(monkeypatch):
    """The driver refuses every pass of the variants caching ``refused["node"]`` (``"*"``: every
    variant), set by the test: the driver's compile, as :class:`rrcache.compiler.Variant` calls it,
    raises the GLError a driver's log becomes; the variant's own handling of it is the real one."""
    from rrcache.compiler import variant as variant_module
    from rrcache.errors import GLError

    real = variant_module.build_program
    refused = {"node": None, "calls": 0}

    def build_program(ctx, vertex, fragment, line_map, **names):
        caller = sys._getframe(1).f_locals.get("self")  # the Variant whose pass this is
        node = getattr(caller, "node_id", None)
        if refused["node"] is not None and refused["node"] in ("*", node):
            refused["calls"] += 1
            raise GLError("0:12(3): error: the driver refuses this pass (a test's stand-in for a driver bug)",
                          names.get("fragment_name"))
        return real(ctx, vertex, fragment, line_map, **names)

    monkeypatch.setattr(variant_module, "build_program", build_program)
    return refused


def _main(*args) -> int:
    from rrcache.cli import main

    try:
        main(list(args))
    except SystemExit as done:
        return done.code or 0
    return 0


def test_instance_writes_nothing_the_driver_refuses(tmp_path, refusing_driver, gl_ctx, capsys, monkeypatch):
    write_case(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert _main("nodes", "scene.frag", "--json") == 0
    node = json.loads(capsys.readouterr().out)["nodes"][0]["id"]
    refusing_driver["node"] = "*"
    code = _main("instance", "scene.frag", "--node", node, "--out", "v")
    err = [x for x in capsys.readouterr().err.splitlines() if x.strip()]
    assert code == 2 and len(err) == 1 and "was refused" in err[0] and node in err[0], err
    assert not (tmp_path / "v").exists() or not os.listdir(tmp_path / "v")
    refusing_driver["node"] = None
    assert _main("instance", "scene.frag", "--node", node, "--out", "v") == 0
    assert (tmp_path / "v" / "manifest.json").exists()


@pytest.mark.parametrize("which", [0, 1], ids=["the costliest (the ceiling's node)", "the second (in training)"])
def test_profile_drops_a_node_the_driver_refuses(tmp_path, refusing_driver, gl_ctx, which):
    from rrcache.profiler.run import profile
    from rrcache.profiles import TrainingSettings

    shader, session = write_scene(tmp_path)
    settings = TrainingSettings(periods=(2, 4), resolution=(32, 24), timing_frames=2, timing_periods=(2,),
                                min_gain=0.0, min_saving=0.0, validate=False, algorithm="three-pass", budget_s=60.0)
    first = profile(shader, session, tmp_path / "a", settings)
    order = [n.id for n in first.nodes if n.trained]
    assert len(order) >= 2
    refusing_driver["node"] = order[which]
    prof = profile(shader, session, tmp_path / "b", settings)
    dropped = prof.node(order[which])
    assert refusing_driver["calls"] >= 1
    assert not dropped.trained and dropped.note.startswith("dropped: the driver refused its variant")
    assert "the driver refuses this pass" in dropped.note
    assert [n.id for n in prof.nodes if n.trained] == [n for n in order if n != order[which]]
