"""A profile of a shader with ``#include`` is re-selected from anywhere (issue 14, item 6).

The shader hash covers file *content*, never path strings: a profile made from a relative path
(``rrcache profile shaders/main.frag ...`` in the project folder) is re-selected with ``rrcache
select --out`` and checked with ``rrcache accuracy`` from another working directory. When the hash
does differ, the error names the file that changed, and says so when none did.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from rrcache.selection import CachedNode, Selection

import pytest

from scene_files import SESSION

from rrcache.glsl.frontend import describe_change, file_records, load_shader
from rrcache.profiles import load_profile
from rrcache.choice import write as choice_write

MAIN = """// glslViewer-style sketch: the noise lives in a library file
#ifdef GL_ES
precision mediump float;
#endif

#include "lib/wave.glsl"

uniform vec3 u_light;
uniform float u_scale;
varying vec4 v_position;
varying vec3 v_normal;
varying vec3 v_objectPosition;

void main() {
    vec3 p = v_objectPosition * u_scale;
    float n = 0.5 + 0.25 * wave(p, 1.0) + 0.125 * wave(p, 2.1);
    vec3 albedo = mix(vec3(0.9, 0.8, 0.6), vec3(0.3, 0.2, 0.1), n);
    float diffuse = max(dot(normalize(v_normal), normalize(u_light - v_position.xyz)), 0.0);
    gl_FragColor = vec4(albedo * (0.2 + 0.8 * diffuse), 1.0);
}
"""

WAVE = """#ifndef FNC_WAVE
#define FNC_WAVE
float wave(vec3 p, float f) {
    return sin(p.x * f + 1.3 * cos(p.y * f)) * cos(p.z * f * 0.7 + sin(p.x * f * 1.9));
}
#endif
"""

SETTINGS = ["--periods", "2,4,8", "--resolution", "32x24", "--timing-frames", "4",
            "--timing-periods", "2,8", "--no-validate", "--min-gain", "0"]


def _run(*args, cwd, check=True):
    env = dict(os.environ, LP_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [os.path.dirname(os.path.dirname(
        os.path.abspath(__file__))), env.get("PYTHONPATH")]))
    proc = subprocess.run([sys.executable, "-m", "rrcache", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, env=env, timeout=300)
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def _project(root):
    (root / "proj" / "shaders").mkdir(parents=True)
    (root / "proj" / "shaders" / "lib").mkdir()
    (root / "proj" / "shaders" / "main.frag").write_text(MAIN)
    (root / "proj" / "shaders" / "lib" / "wave.glsl").write_text(WAVE)
    (root / "proj" / "orbit.json").write_text(json.dumps(SESSION))
    return root / "proj"


def test_hash_is_content_not_path(tmp_path, monkeypatch):
    proj = _project(tmp_path)
    monkeypatch.chdir(proj)
    relative = load_shader("shaders/main.frag")
    recorded = file_records(relative)  # absolute paths, as a profile records them
    monkeypatch.chdir(tmp_path)
    absolute = load_shader(str(proj / "shaders" / "main.frag"))
    spelled = load_shader("proj/shaders/lib/../main.frag")
    assert relative.hash == absolute.hash == spelled.hash
    assert len(relative.files) == 2 and relative.files != absolute.files
    # a different content of the included file is a different hash, and is named
    (proj / "shaders" / "lib" / "wave.glsl").write_text(WAVE.replace("1.3", "1.4"))
    edited = load_shader(str(proj / "shaders" / "main.frag"))
    assert edited.hash != absolute.hash
    assert describe_change(recorded, edited) == f"'{edited.files[1]}' changed"
    assert describe_change(file_records(absolute), absolute) == "no shader file changed"


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    root = tmp_path_factory.mktemp("hash")
    proj = _project(root)
    _run("profile", "shaders/main.frag", "orbit.json", "--out", "out", *SETTINGS, cwd=proj)
    return root, proj


def test_select_and_accuracy_from_another_directory(made, tmp_path, monkeypatch):
    root, proj = made
    data = json.loads((proj / "out" / "profile.json").read_text())
    assert [os.path.basename(f["path"]) for f in data["shader_files"]] == ["main.frag", "wave.glsl"]
    # nodes written in the library file say so, and read as written there
    from_lib = [n for n in data["nodes"] if n["file"] and n["file"].endswith("wave.glsl")]
    assert from_lib and not any("_rr_" in n["text"] for n in data["nodes"])
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    profile = os.path.relpath(proj / "out", elsewhere)
    written = _run("select", profile, "--max-error", "1e9", "--out", "opt", cwd=elsewhere)
    assert "wrote" in written.stdout
    manifest = json.loads((elsewhere / "opt" / "manifest.json").read_text())
    assert "node" in manifest
    node = next(n["id"] for n in data["nodes"] if n["trained"])
    # the selection above may be the original (nothing to load at this tiny size): write a
    # cached node's variant too, which loads the shader again and checks its hash
    monkeypatch.chdir(elsewhere)
    prof = load_profile(profile)
    choice = Selection(parts=(CachedNode(node, 4),))
    written = choice_write(prof, choice, "opt2")
    assert any(p.endswith(".frag") for p in written)
    assert json.loads((elsewhere / "opt2" / "manifest.json").read_text())["node"]["id"] == node
    acc = _run("accuracy", profile, "--periods", "3", "--nodes", node, "--json", cwd=elsewhere)
    report = json.loads(acc.stdout)
    assert report["points"] and report["points"][0]["node"] == node


def test_errors_name_the_changed_file_or_none(made, tmp_path):
    root, proj = made
    # the profile's hash was made some other way (an older rrcache): no file is blamed
    out = tmp_path / "copy"
    out.mkdir()
    data = json.loads((proj / "out" / "profile.json").read_text())
    data["shader_hash"] = "0" * 64
    (out / "profile.json").write_text(json.dumps(data))
    node = next(n["id"] for n in data["nodes"] if n["trained"])
    proc = _run("accuracy", out, "--periods", "3", "--nodes", node, cwd=tmp_path, check=False)
    assert proc.returncode == 2
    assert "no shader file changed" in proc.stderr and "changed since" not in proc.stderr
    # the included file really changed: it is named
    lib = proj / "shaders" / "lib" / "wave.glsl"
    lib.write_text(WAVE.replace("0.7", "0.75"))
    try:
        proc = _run("accuracy", proj / "out", "--periods", "3", "--nodes", node, cwd=tmp_path, check=False)
    finally:
        lib.write_text(WAVE)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "changed since it was profiled" in lines[0] and "wave.glsl' changed" in lines[0]
    assert "main.frag' changed" not in lines[0]
