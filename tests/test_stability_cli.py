"""Bad input through the command line, end to end in a subprocess (issue 7, part 3), one row of
docs/stability.md each: exit code 2, exactly one line on stderr naming the file and the place,
no Python traceback; ``--debug`` shows the traceback (checked on one shader, one session and the
EGL case). Also through ``rrcache render``: a resolution too large, NaN/Inf pixels counted in
``--json``, a one-frame session refused by ``rrcache profile``. The in-process versions of many
of these (and all 81 malformed corpus shaders) are in test_cli_bad_input.py and
test_cli_malformed.py; these run the installed entry point as a user would.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

AREA = "bad input through the CLI (subprocess)"

GOOD = "#version 330\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"
SHADERS = {
    "malformed GLSL": ("bad.frag", "#version 330\nout vec4 c;\nvoid main() { c = vec4(1.0) }\n", "bad.frag:3:29:"),
    "vertex shader": ("vert.frag", "#version 330\nin vec3 a_position;\nvoid main() { gl_Position = vec4(a_position, 1.0); }\n",
                      "vert.frag:3:"),
    "geometry shader": ("geom.frag", "#version 330\nlayout(triangles) in;\nlayout(triangle_strip, max_vertices = 3) out;\n"
                        "void main() { gl_Position = gl_in[0].gl_Position; EmitVertex(); EndPrimitive(); }\n", "geom.frag:3:"),
    "compute shader": ("comp.frag", "#version 430\nlayout(local_size_x = 8, local_size_y = 8) in;\n"
                       "layout(rgba32f, binding = 0) uniform image2D img;\n"
                       "void main() { imageStore(img, ivec2(gl_GlobalInvocationID.xy), vec4(1.0)); }\n", "comp.frag:2:"),
    "several colour outputs": ("two.frag", "#version 330\nlayout(location = 0) out vec4 a;\nlayout(location = 1) out vec4 b;\n"
                               "void main() { a = vec4(1.0); b = vec4(0.5); }\n", "two.frag:3:"),
}
SESSION = {
    "rrcache_session": 1, "resolution": [32, 24], "frames": 2, "fps": 30,
    "camera": {"fov": 45, "near": 0.1, "far": 100,
               "keyframes": [{"frame": 0, "eye": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0]}]},
    "objects": [{"procedural": {"type": "icosphere", "subdivisions": 1}}],
}


def _session(**changes):
    doc = json.loads(json.dumps(SESSION))
    for key, value in changes.items():
        if value is None:
            doc.pop(key)
        else:
            doc[key] = value
    return doc


# name: (session document or None for no file, what is wrong with it, the place the message names)
SESSIONS = {
    "session: invalid field": (_session(camera={**SESSION["camera"], "fov": "wide"}), 'camera.fov = "wide"',
                               "scene.json: camera.fov:"),
    "session: missing required field": (_session(camera=None), "no camera",
                                        "scene.json: missing required key 'camera'"),
    "session: missing mesh file": (_session(objects=[{"mesh": "meshes/none.obj"}]), "mesh meshes/none.obj absent",
                                   "scene.json: objects[0].mesh:"),
    "session: missing session file": (None, "no such file", "absent.json:"),
}


def rrcache(cwd, *args, env=None):
    """Run ``python -m rrcache ARGS`` in ``cwd``: (exit code, stdout, the non-empty stderr lines)."""
    full_env = {**os.environ, "LP_NUM_THREADS": "1", **(env or {})}
    proc = subprocess.run([sys.executable, "-m", "rrcache", *map(str, args)], cwd=cwd, env=full_env,
                          capture_output=True, text=True, timeout=300)
    return proc.returncode, proc.stdout, [line for line in proc.stderr.splitlines() if line.strip()]


def _one_line(code, lines) -> str:
    assert code == 2, lines
    assert len(lines) == 1, lines
    assert "Traceback" not in lines[0]
    return lines[0]


def _debug_shows_traceback(cwd, args, env=None) -> bool:
    code, _, lines = rrcache(cwd, "--debug", *args, env=env)
    return code != 0 and any(line.startswith("Traceback") for line in lines)


def _write_session(tmp_path, doc=SESSION):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize("name", list(SHADERS), ids=lambda n: n.replace(" ", "-"))
def test_shader_we_do_not_handle(tmp_path, stability_case, name):
    file, source, place = SHADERS[name]
    (tmp_path / file).write_text(source)
    session = _write_session(tmp_path)
    case = stability_case(name, AREA, f"rrcache render {file} scene.json")
    code, _, lines = rrcache(tmp_path, "render", file, session.name)
    case.observe(exit=code, stderr=" / ".join(lines))
    line = _one_line(code, lines)
    assert place in line and "hint:" in line
    if name == "malformed GLSL":
        debug = _debug_shows_traceback(tmp_path, ["render", file, session.name])
        case.observe(debug_traceback=debug)
        assert debug


@pytest.mark.parametrize("name", list(SESSIONS), ids=lambda n: n.split(": ")[1].replace(" ", "-"))
def test_bad_session(tmp_path, stability_case, name):
    doc, wrong, place = SESSIONS[name]
    (tmp_path / "ok.frag").write_text(GOOD)
    session = _write_session(tmp_path, doc).name if doc is not None else "absent.json"
    case = stability_case(name, AREA, f"rrcache render ok.frag {session} ({wrong})")
    code, _, lines = rrcache(tmp_path, "render", "ok.frag", session, "--frames", "1")
    case.observe(exit=code, stderr=" / ".join(lines).replace(str(tmp_path), "TMP"))
    line = _one_line(code, lines)
    assert place in line
    assert "hint:" in line
    if name == "session: invalid field":
        debug = _debug_shows_traceback(tmp_path, ["render", "ok.frag", session, "--frames", "1"])
        case.observe(debug_traceback=debug)
        assert debug


def test_no_egl(tmp_path, stability_case):
    """libglvnd finds no EGL vendor: moderngl's EGL context creation itself fails."""
    (tmp_path / "ok.frag").write_text(GOOD)
    session = _write_session(tmp_path)
    env = {"__EGL_VENDOR_LIBRARY_FILENAMES": str(tmp_path / "no-such-vendor.json")}
    case = stability_case("no EGL available", AREA,
                          "__EGL_VENDOR_LIBRARY_FILENAMES pointing at no file; rrcache render ok.frag scene.json")
    code, _, lines = rrcache(tmp_path, "render", "ok.frag", session.name, "--frames", "1", env=env)
    debug = _debug_shows_traceback(tmp_path, ["render", "ok.frag", session.name, "--frames", "1"], env=env)
    case.observe(exit=code, stderr=" / ".join(lines), debug_traceback=debug)
    line = _one_line(code, lines)
    assert "EGL" in line and "apt-get install" in line and "libegl" in line
    assert debug


def test_resolution_too_large(tmp_path, stability_case):
    (tmp_path / "ok.frag").write_text(GOOD)
    session = _write_session(tmp_path)
    case = stability_case("resolution too large (CLI)", AREA, "rrcache render ok.frag scene.json --resolution 100000x100000")
    code, _, lines = rrcache(tmp_path, "render", "ok.frag", session.name, "--resolution", "100000x100000")
    case.observe(exit=code, stderr=" / ".join(lines))
    line = _one_line(code, lines)
    assert f"{100000 * 100000 * 57:,} bytes" in line and "GL_MAX_TEXTURE_SIZE" in line and "hint:" in line


def test_nan_pixels_in_render_json(tmp_path, stability_case):
    poisoned = ("#version 330\nout vec4 c;\nuniform float u_zero;\n"
                "void main() { c = gl_FragCoord.x < 16.0 ? vec4(u_zero / u_zero) : vec4(1.0); }\n")
    (tmp_path / "nan.frag").write_text(poisoned)
    session = _write_session(tmp_path, {**SESSION, "uniforms": {"u_zero": 0.0}})
    case = stability_case("NaN pixels in rrcache render --json", AREA,
                          "left half of the covered pixels 0/0; rrcache render nan.frag scene.json --json")
    code, out, lines = rrcache(tmp_path, "render", "nan.frag", session.name, "--json", "--frames", "2")
    summary = json.loads(out)
    case.observe(exit=code, nonfinite_pixels=summary["nonfinite_pixels"], covered_pixels=summary["covered_pixels"])
    assert code == 0
    assert all(0 < n < c for n, c in zip(summary["nonfinite_pixels"], summary["covered_pixels"]))


def test_profile_refuses_one_frame(tmp_path, stability_case):
    (tmp_path / "ok.frag").write_text(GOOD)
    session = _write_session(tmp_path, {**SESSION, "frames": 1})
    case = stability_case("one-frame session through rrcache profile", AREA,
                          "rrcache profile ok.frag scene.json (frames = 1)")
    code, _, lines = rrcache(tmp_path, "profile", "ok.frag", session.name, "--out", "p.rrprofile")
    case.observe(exit=code, stderr=" / ".join(lines))
    line = _one_line(code, lines)
    assert "scene.json" in line and "one frame" in line and "hint:" in line
