"""``rrcache profile-library``: a library of (shader, session) pairs, one profile folder each, with
a summary (library.json, library.csv, index.html linking each report.html).

- manifests (TOML, JSON, a bare JSON list) with globs expand to the pairs; every mistake names the
  manifest and the key;
- a library with a shader that does not compile: its row says why, the other pair is profiled;
- run again, a current profile is kept as it is; a changed shader file starts its profile over;
- the command line prints the table and exits 1 when a pair failed.
"""
from __future__ import annotations

import csv
import json
import os
import subprocess
import sys

import pytest

from rrcache.errors import RRCacheError
from rrcache.profiler.library import profile_library
from rrcache.profiler.manifest import entries_from_globs, read_manifest
from rrcache.profiles import TrainingSettings, load_profile
from scene_files import write_scene

#: tiny profiles: four timing frames, no sets, no validation (the summary reads the predictions)
FAST = dict(periods=[2, 4, 8], resolution=[32, 24], timing_frames=4, timing_periods=[2, 8], min_gain=0.0,
            budget_s=4.0, max_sets=0, validate=False)
BROKEN = "void main() { gl_FragColor = vec4(1.0) }\n"


def _scene(folder):
    shader, session = write_scene(folder)
    (folder / "broken.frag").write_text(BROKEN)
    return shader, session


def test_toml_manifest_globs_and_settings(tmp_path):
    _scene(tmp_path / "scene")
    (tmp_path / "lib.toml").write_text(
        '[settings]\nbudget_s = 30\n\n[[profile]]\nshader = "scene/*.frag"\nsession = "scene/orbit.json"\n'
        'defines = { Q = 2 }\nsettings = { frames = 6 }\n')
    entries, settings = read_manifest(tmp_path / "lib.toml")
    assert settings == {"budget_s": 30}
    assert [e.name for e in entries] == ["broken-orbit", "noise-orbit"]
    assert all(e.defines == {"Q": "2"} and e.settings == {"frames": 6} for e in entries)
    assert all(os.path.isabs(e.shader) and os.path.isabs(e.session) for e in entries)


def test_json_manifest_and_globs(tmp_path, monkeypatch):
    _scene(tmp_path / "scene")
    (tmp_path / "lib.json").write_text(json.dumps([{"shader": "scene/noise.frag", "session": "scene/orbit.json",
                                                    "name": "mine"}]))
    entries, settings = read_manifest(tmp_path / "lib.json")
    assert [e.name for e in entries] == ["mine"] and settings == {}
    monkeypatch.chdir(tmp_path)
    assert [e.name for e in entries_from_globs(["scene/*.frag"], ["scene/orbit.json"])] == ["broken-orbit",
                                                                                          "noise-orbit"]


@pytest.mark.parametrize("text, message", [
    ('[[profile]]\nshader = "scene/none*.frag"\nsession = "scene/orbit.json"\n', "profile[0].shader: 'scene/none*.frag' matches no file"),
    ('[[profile]]\nshader = "scene/noise.frag"\n', "profile[0]: no 'session'"),
    ('[[profile]]\nshader = "scene/noise.frag"\nsession = "scene/orbit.json"\nshaders = 1\n', "unknown key(s) ['shaders']"),
    ('[[profile]]\nshader = "scene/noise.frag"\nsession = "scene/orbit.json"\n'
     '[[profile]]\nshader = "scene/noise.frag"\nsession = "scene/orbit.json"\n', "two entries would both be profiled into 'noise-orbit'"),
    ('[[profile]]\nshader = "scene/*.frag"\nsession = "scene/orbit.json"\nname = "x"\n', "profile[0].name: 'name' given"),
    ('[[profile]\n', "not valid TOML"),
])
def test_manifest_errors_name_the_file_and_key(tmp_path, text, message):
    _scene(tmp_path / "scene")
    (tmp_path / "lib.toml").write_text(text)
    with pytest.raises(RRCacheError) as err:
        read_manifest(tmp_path / "lib.toml")
    assert str(err.value).startswith(str(tmp_path / "lib.toml")) and message in str(err.value), str(err.value)


def test_a_failure_is_reported_and_the_rest_profiled_then_resumed(tmp_path):
    shader, _ = _scene(tmp_path / "scene")
    (tmp_path / "lib.json").write_text(json.dumps({"settings": FAST, "profile": [
        {"shader": "scene/*.frag", "session": "scene/orbit.json"}]}))
    entries, settings = read_manifest(tmp_path / "lib.json")
    said = []
    rows = profile_library(entries, tmp_path / "lib", manifest_settings=settings, announce=said.append)
    bad, good = rows
    assert bad["status"] == "failed" and "broken.frag:1:" in bad["error"] and bad["folder"] is None
    assert good["status"] == "done" and good["nodes_trained"] >= 1 and good["wall_s"] > 0
    assert good["verdict"].startswith("predicted only") or good["verdict"].startswith("original")
    prof = load_profile(tmp_path / "lib" / "noise-orbit")
    assert good["nodes_trained"] == len(prof.trained_nodes) and prof.settings.budget_s == FAST["budget_s"]
    # the summary: CSV rows, an index linking the report, library.json
    with open(tmp_path / "lib" / "library.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert [r["name"] for r in table] == ["broken-orbit", "noise-orbit"] and table[0]["status"] == "failed"
    assert (tmp_path / "lib" / good["report"]).exists()
    index = (tmp_path / "lib" / "index.html").read_text()
    assert 'href="noise-orbit/report.html"' in index and "broken-orbit" in index
    assert json.loads((tmp_path / "lib" / "library.json").read_text())["rows"][1]["name"] == "noise-orbit"

    # again: the finished profile is kept as it is (profile.json untouched)
    stamp = (tmp_path / "lib" / "noise-orbit" / "profile.json").stat().st_mtime_ns
    said.clear()
    again = profile_library(entries, tmp_path / "lib", manifest_settings=settings, announce=said.append)
    assert any("noise-orbit: current, kept" in line for line in said), said
    assert (tmp_path / "lib" / "noise-orbit" / "profile.json").stat().st_mtime_ns == stamp
    assert again[1]["verdict"] == good["verdict"] and again[0]["status"] == "failed"

    # a changed shader file: that profile starts over (its old store moved aside)
    shader.write_text(shader.read_text() + "\n// edited\n")
    said.clear()
    third = profile_library(entries, tmp_path / "lib", manifest_settings=settings, announce=said.append)
    assert any("noise.frag changed; starting over" in line for line in said), said
    assert third[1]["status"] == "done"
    assert (tmp_path / "lib" / "noise-orbit" / "profile.sqlite.bak").exists()
    assert load_profile(tmp_path / "lib" / "noise-orbit").shader_hash != prof.shader_hash


def test_cli_prints_the_table_and_exits_1_on_a_failure(tmp_path):
    _scene(tmp_path / "scene")
    (tmp_path / "lib.toml").write_text(
        '[[profile]]\nshader = "scene/*.frag"\nsession = "scene/orbit.json"\n')
    args = ["--periods", "2,4,8", "--timing-frames", "4", "--timing-periods", "2,8", "--min-gain", "0",
            "--budget", "3", "--no-validate", "--no-plots"]
    env = dict(os.environ, LP_NUM_THREADS="1")
    proc = subprocess.run([sys.executable, "-m", "rrcache", "profile-library", str(tmp_path / "lib.toml"),
                           "--out", str(tmp_path / "lib"), *args, "--frames", "8"],
                          capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 1, proc.stderr
    assert "broken-orbit" in proc.stdout and "noise-orbit" in proc.stdout and "summary:" in proc.stdout
    assert "[2/2] noise-orbit" in proc.stderr
    assert TrainingSettings.from_json(json.loads(
        (tmp_path / "lib" / "noise-orbit" / "profile.json").read_text())["settings"]).frames == 8
    usage = subprocess.run([sys.executable, "-m", "rrcache", "profile-library", "--shaders", "x.glsl"],
                           capture_output=True, text=True, env=env, timeout=60)
    assert usage.returncode == 2 and "give a manifest, or both --shaders and --sessions" in usage.stderr
