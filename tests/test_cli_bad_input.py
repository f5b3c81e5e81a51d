"""Bad input through ``rrcache render``, end to end: each case gives one error line that names the
file and the place, exit code 2, and no Python traceback."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from rrcache.cli import main

DATA = Path(__file__).parent / "data" / "sessions"

SHADER = """#version 330
in vec3 v_normal;
uniform float u_gain;
out vec4 fragColor;
void main() { fragColor = vec4(normalize(v_normal) * u_gain, 1.0); }
"""

SESSION = {
    "rrcache_session": 1, "resolution": [32, 24], "frames": 2, "fps": 30,
    "camera": {"fov": 45, "near": 0.1, "far": 100,
               "keyframes": [{"frame": 0, "eye": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0]}]},
    "objects": [{"procedural": {"type": "icosphere", "subdivisions": 1}}],
    "uniforms": {"u_gain": 1.0},
}


def _write(tmp_path, session=None, shader=SHADER, raw=None):
    shader_path = tmp_path / "lit.frag"
    shader_path.write_text(shader)
    session_path = tmp_path / "scene.json"
    session_path.write_text(raw if raw is not None else json.dumps(session or SESSION))
    return shader_path, session_path


def _run(capsys, *args):
    with pytest.raises(SystemExit) as info:
        main(["render", *map(str, args), "--frames", "1"])
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert info.value.code == 2, err
    assert "Traceback" not in err
    return " ".join(lines)


def _with(**changes):
    doc = json.loads(json.dumps(SESSION))
    for path, value in changes.items():
        target = doc
        keys = path.split(".")
        for key in keys[:-1]:
            target = target[int(key)] if key.isdigit() else target[key]
        last = keys[-1]
        if value is _DELETE:
            del target[last]
        else:
            target[int(last) if last.isdigit() else last] = value
    return doc


_DELETE = object()


def test_invalid_json(tmp_path, capsys):
    shader, session = _write(tmp_path, raw='{"rrcache_session": 1,\n  "frames": 3,,\n}')
    msg = _run(capsys, shader, session)
    assert "scene.json" in msg and "line 2" in msg  # the line of the stray comma


def test_schema_violation_names_the_json_path(tmp_path, capsys):
    shader, session = _write(tmp_path, _with(**{"camera.fov": "wide"}))
    msg = _run(capsys, shader, session)
    assert "scene.json" in msg and "camera.fov" in msg


def test_unknown_key_suggests_the_right_one(tmp_path, capsys):
    doc = _with()
    doc["camera"]["keyframe"] = doc["camera"].pop("keyframes")
    shader, session = _write(tmp_path, doc)
    msg = _run(capsys, shader, session)
    assert "keyframe" in msg and "keyframes" in msg


def test_missing_mesh_file(tmp_path, capsys):
    shader, session = _write(tmp_path, _with(**{"objects": [{"mesh": "meshes/nowhere.obj"}]}))
    msg = _run(capsys, shader, session)
    assert "objects[0].mesh" in msg and "nowhere.obj" in msg


def test_missing_texture_file(tmp_path, capsys):
    shader, session = _write(tmp_path, _with(textures={"u_tex": "textures/none.png"}))
    msg = _run(capsys, shader, session)
    assert "textures.u_tex" in msg and "none.png" in msg


def test_unreadable_image(tmp_path, capsys):
    (tmp_path / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\nthis is not a png at all")
    shader, session = _write(tmp_path, _with(textures={"u_tex": "broken.png"}))
    msg = _run(capsys, shader, session)
    assert "broken.png" in msg and "u_tex" in msg


def test_uniform_the_session_does_not_supply(tmp_path, capsys):
    shader, session = _write(tmp_path, _with(uniforms={}))
    msg = _run(capsys, shader, session)
    assert "u_gain" in msg and "lit.frag:3:" in msg and "scene.json" in msg


def test_sampler_the_session_does_not_supply(tmp_path, capsys):
    sampled = SHADER.replace("uniform float u_gain;", "uniform float u_gain;\nuniform sampler2D u_albedo;").replace(
        "* u_gain", "* u_gain * texture(u_albedo, vec2(0.5)).rgb")
    shader, session = _write(tmp_path, shader=sampled)
    msg = _run(capsys, shader, session)
    assert "u_albedo" in msg and "lit.frag:4:" in msg and "textures" in msg


def test_shader_the_driver_refuses_is_mapped_to_the_original_line(tmp_path, capsys):
    refused = "#version 330\n// a comment line\n#extension GL_NV_made_up_extension : require\n" + SHADER.split("\n", 1)[1]
    shader, session = _write(tmp_path, shader=refused)
    msg = _run(capsys, shader, session)
    assert "lit.frag:3:" in msg and "GL_NV_made_up_extension" in msg


def test_malformed_glsl(tmp_path, capsys):
    shader, session = _write(tmp_path, shader=SHADER.replace("uniform float u_gain;", "uniform float u_gain"))
    msg = _run(capsys, shader, session)
    assert "lit.frag:4:" in msg


def test_missing_shader_file(tmp_path, capsys):
    _, session = _write(tmp_path)
    msg = _run(capsys, tmp_path / "absent.frag", session)
    assert "absent.frag" in msg


def test_vertex_shader_is_refused(tmp_path, capsys):
    vertex = "#version 330\nin vec3 a_position;\nvoid main() { gl_Position = vec4(a_position, 1.0); }\n"
    shader, session = _write(tmp_path, shader=vertex)
    msg = _run(capsys, shader, session)
    assert "lit.frag:3:" in msg and "gl_Position" in msg


def test_obj_mesh_that_is_garbage(tmp_path, capsys):
    (tmp_path / "junk.obj").write_text("this is not\nan obj file at all\n")
    shader, session = _write(tmp_path, _with(**{"objects": [{"mesh": "junk.obj"}]}))
    msg = _run(capsys, shader, session)
    assert "junk.obj" in msg and "objects[0].mesh" in msg
