"""The one rule for reading (issue 30, :mod:`rrcache.files`): every file a user names is opened
once, checked on its descriptor (kind, folder, size) before a byte is read, read from that
descriptor and hashed as read.

Each hostile case runs the real command line in a subprocess, traced (:func:`rrcache_traced`):
exit 0 or 2 with one line, the child's peak memory measured (its own ``wait4`` rusage; the bound
asserted is far above what a refusal takes and far below what reading the input would), and the
paths it opened. FIFOs and device nodes are the test's own, made in its temporary folder
(``mknod`` needs root: without it the device cases skip); ``/proc/self/fd/0`` is the child's own
stdin, a pipe this test holds open.
"""
from __future__ import annotations

import json
import os
import stat
import subprocess

import numpy as np
import pytest

from safety_cli import (REFUSAL_PEAK_MIB, RUN_PEAK_MIB, made_profile, one_error_line, rrcache_traced,  # noqa: F401
                        session, write_case)

AREA = "safety: the one rule for reading"

TEX_SHADER = ("#version 330\nuniform sampler2D u_t;\nin vec3 v_normal;\nout vec4 c;\n"
              "void main() { c = texture(u_t, v_normal.xy * 0.5 + 0.5); }\n")


def _png(path, value=0.5, size=4):
    import OpenImageIO as oiio
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(size, size, 3, oiio.UINT8))
    out.write_image(np.full((size, size, 3), value, np.float32))
    out.close()


def _special(path, kind: str) -> bool:
    """Make ``path`` a FIFO or a private character device with /dev/zero's numbers (1, 5)."""
    if kind == "fifo":
        os.mkfifo(path)
        return True
    try:
        os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, 5))
        return True
    except (PermissionError, OSError):
        return False


#: role -> (the name the special file takes, the command, what the error names)
ROLES = {
    "shader": ("x.frag", ["nodes", "x.frag"], "x.frag"),
    "include": ("lib.glsl", ["nodes", "inc.frag"], "lib.glsl"),
    "session": ("s.json", ["render", "scene.frag", "s.json", "--frames", "1"], "s.json"),
    "mesh": ("m.obj", ["render", "scene.frag", "mesh.json", "--frames", "1"], "objects[0].mesh"),
    "texture": ("t.png", ["render", "tex.frag", "tex.json", "--frames", "1"], "textures.u_t"),
    "vertex": ("v.vert", ["render", "scene.frag", "vert.json", "--frames", "1"], "vertex"),
    "profile.json": ("p/profile.json", ["report", "p"], "profile.json"),
    "profile.json (select)": ("p/profile.json", ["select", "p", "--max-error", "0.1"], "profile.json"),
}


def _case(folder):
    write_case(folder)
    (folder / "inc.frag").write_text("#version 330\n#include \"lib.glsl\"\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n")
    write_case(folder, session(objects=[{"mesh": "m.obj"}]), name="mesh")
    write_case(folder, session(textures={"u_t": "t.png"}), shader=TEX_SHADER, name="tex")
    write_case(folder, session(vertex="v.vert"), name="vert")
    (folder / "p").mkdir()


@pytest.mark.parametrize("kind", ["fifo", "device"])
@pytest.mark.parametrize("role", list(ROLES))
def test_not_a_regular_file_is_refused_as_what_it_is(tmp_path, stability_case, role, kind):
    _case(tmp_path)
    name, args, place = ROLES[role]
    if not _special(tmp_path / name, kind):
        pytest.skip("mknod needs root")
    words = "FIFO" if kind == "fifo" else "character device"
    case = stability_case(f"{role} is a {words}", AREA, f"rrcache {' '.join(args)}, {name} a private {words}")
    code, _, lines, peak, opened = rrcache_traced(tmp_path, *args, timeout=120)
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line.replace(str(tmp_path), "TMP"), peak_mib=round(peak))
    assert words in line and place in line, line
    assert "not found" not in line
    assert peak < REFUSAL_PEAK_MIB


def test_own_stdin_as_a_session(tmp_path, stability_case):
    """``/proc/self/fd/0`` (what ``/dev/stdin`` links to) is the child's stdin: a pipe this test
    keeps open and never writes, so a reader would wait for ever."""
    write_case(tmp_path)
    read_end, write_end = os.pipe()
    try:
        code, _, lines, peak, _ = rrcache_traced(tmp_path, "render", "scene.frag", "/proc/self/fd/0", timeout=120,
                                                 stdin=read_end)
    finally:
        os.close(read_end)
        os.close(write_end)
    line = one_error_line(code, lines)
    stability_case("session from the process's own stdin", AREA, "rrcache render scene.frag /proc/self/fd/0, "
                   "stdin a pipe held open").observe(exit=code, stderr=line, peak_mib=round(peak))
    assert "FIFO" in line and peak < REFUSAL_PEAK_MIB


def _sparse(path, size=100 * 1024 ** 3, head=b""):
    with open(path, "wb") as f:
        f.write(head)
        try:
            f.truncate(size)
        except OSError:
            return False
    return os.stat(path).st_size == size


SPARSE = {
    "texture": ("t.png", ["render", "tex.frag", "tex.json", "--frames", "1"], "--max-asset-bytes", b"\x89PNG\r\n\x1a\n"),
    "mesh": ("m.ply", ["render", "scene.frag", "ply.json", "--frames", "1"], "--max-asset-bytes",
             b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"),
    "shader": ("x.frag", ["nodes", "x.frag"], "--max-source-bytes", b"#version 330\n"),
    "include": ("lib.glsl", ["nodes", "inc.frag"], "--max-source-bytes", b"float f() { return 1.0; }\n"),
    "session": ("s.json", ["render", "scene.frag", "s.json"], "--max-document-bytes", b'{"rrcache_session": 1, '),
    "profile.json": ("p/profile.json", ["report", "p"], "--max-document-bytes", b'{"shader": "scene.frag", '),
}


@pytest.mark.parametrize("role", list(SPARSE))
def test_sparse_100_gb_file_is_refused_before_reading(tmp_path, stability_case, role):
    _case(tmp_path)
    write_case(tmp_path, session(objects=[{"mesh": "m.ply"}]), name="ply")
    name, args, option, head = SPARSE[role]
    if not _sparse(tmp_path / name, head=head):
        pytest.skip("this file system cannot hold a sparse 100 GB file")
    case = stability_case(f"sparse 100 GB {role}", AREA, f"rrcache {' '.join(args)}, {name} truncated to 100 GiB")
    code, _, lines, peak, _ = rrcache_traced(tmp_path, *args, timeout=120)
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line.replace(str(tmp_path), "TMP"), peak_mib=round(peak))
    assert option in line and "107,374,182,400" in line and peak < REFUSAL_PEAK_MIB, (line, peak)


MESHES = {
    "PLY claiming 10⁹ vertices (binary)": (
        "big.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\n"
        b"property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        + bytes(100), "1,000,000,000 vertices"),
    "PLY claiming 10⁹ vertices (ASCII)": (
        "biga.ply", b"ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\n"
        b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n"
        b"0 1 0\n3 0 1 2\n", "1,000,000,000 vertices"),
    "OFF claiming 10⁹ vertices": ("big.off", b"OFF\n1000000000 1 0\n0 0 0\n", "1,000,000,000 vertices"),
    "OFF claiming 10⁹ faces": ("bigf.off", b"OFF\n3 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                               "1,000,000,000 faces"),
    "OBJ vertex with two coordinates": ("two.obj", b"v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "line 1"),
}


@pytest.mark.parametrize("name", list(MESHES))
def test_mesh_headers_and_vertices(tmp_path, stability_case, name):
    file, data, expected = MESHES[name]
    (tmp_path / file).write_bytes(data)
    write_case(tmp_path, session(objects=[{"mesh": file}]))
    case = stability_case(name, AREA, f"rrcache render with {file} as the mesh")
    code, _, lines, peak, _ = rrcache_traced(tmp_path, "render", "scene.frag", "scene.json", "--frames", "1")
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line.replace(str(tmp_path), "TMP"), peak_mib=round(peak))
    assert expected in line and "objects[0].mesh" in line and peak < REFUSAL_PEAK_MIB


def test_nul_in_a_texture_path(tmp_path, stability_case):
    write_case(tmp_path, session(textures={"u_t": "a\u0000b.png"}), shader=TEX_SHADER)
    code, _, lines, peak, _ = rrcache_traced(tmp_path, "render", "scene.frag", "scene.json", "--frames", "1")
    line = one_error_line(code, lines)
    stability_case("NUL in a texture path", AREA, '"textures": {"u_t": "a\\u0000b.png"}').observe(
        exit=code, stderr=line.replace(str(tmp_path), "TMP"), peak_mib=round(peak))
    assert "NUL" in line and "textures.u_t" in line and "\x00" not in line and peak < REFUSAL_PEAK_MIB


#: writes a huge session in a process of its own (this test process stays small: a child's peak
#: memory as the kernel counts it starts from its parent's at the fork)
_HUGE = """
import json, sys
sys.path.insert(0, sys.argv[3])
from safety_cli import session
n = int(sys.argv[2])
if sys.argv[1] == "keyframes":
    doc = session(camera={"fov": 45, "keyframes": [{"frame": i, "eye": [0, 0, 4 + i * 1e-6]} for i in range(n)]})
else:
    doc = session(objects=[{"procedural": {"type": "box", "size": 1}}] * n)
json.dump(doc, open("scene.json", "w"))
"""

SESSIONS = {
    "10⁶ camera keyframes": (("keyframes", 1_000_000), "--max-document-bytes"),
    "10⁵ camera keyframes": (("keyframes", 100_000), "--max-session-values"),
    "10⁵ objects": (("objects", 100_000), "--max-session-objects"),
}


@pytest.mark.parametrize("name", list(SESSIONS))
def test_huge_schema_valid_sessions_are_refused_by_a_budget(tmp_path, stability_case, name):
    import sys

    (kind, n), option = SESSIONS[name]
    write_case(tmp_path)
    subprocess.run([sys.executable, "-c", _HUGE, kind, str(n), os.path.dirname(__file__)], cwd=tmp_path, check=True)
    size = (tmp_path / "scene.json").stat().st_size
    case = stability_case(f"schema-valid session with {name}", AREA, f"rrcache render ({size:,} bytes of JSON)")
    code, _, lines, peak, _ = rrcache_traced(tmp_path, "render", "scene.frag", "scene.json", "--frames", "1",
                                             timeout=120)
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line.replace(str(tmp_path), "TMP"), peak_mib=round(peak), json_bytes=size)
    assert option in line and peak < REFUSAL_PEAK_MIB, (line, peak)


def test_a_session_just_inside_the_budgets_loads(tmp_path):
    from rrcache.budgets import budget
    from rrcache.session import load_session

    n = budget.session_objects
    write_case(tmp_path, session(objects=[{"procedural": {"type": "box", "size": 1}}] * n))
    loaded = load_session(tmp_path / "scene.json")
    assert len(loaded.objects) == n and loaded.objects[-1].name == f"box_{n}"
    assert len({id(o.mesh) for o in loaded.objects}) == 1  # one shape, built once


# ----------------------------------------------------------------------------- symlink races

#: a process that points a link at each target in turn (atomically: a new link renamed over it)
#: until it is told to stop, then prints how often it flipped (a process, not a thread: the
#: reader's Python would otherwise hold the interpreter between flips)
_FLIPPER = """
import os, random, signal, sys
link, targets = sys.argv[1], sys.argv[2:]
k = 0
def stop(*_):
    print(k, flush=True)
    os._exit(0)
signal.signal(signal.SIGTERM, stop)
print("ready", flush=True)
while True:
    tmp = f"{link}.{k % 2}.tmp"
    try:
        if os.path.lexists(tmp):
            os.unlink(tmp)
        os.symlink(targets[k % len(targets)], tmp)
        os.replace(tmp, link)
    except OSError:
        pass
    k += 1
    for _ in range(random.randrange(2000)):  # a random phase: a reader scheduled at the same
        pass                                   # point of every loop would see one target only
"""


def _race(link, targets, attempt, runs=200, until=("refused", "read"), most=2000):
    """Run ``attempt()`` ``runs`` times while another process flips ``link`` between
    ``targets``, and on (up to ``most`` times) until the outcomes include each kind in ``until``
    (``refused``: an error; ``read``: a value; on a busy machine the flipper may start late);
    the outcomes (what attempt returned, or the error type's name) counted."""
    import signal
    import sys

    flipper = subprocess.Popen([sys.executable, "-c", _FLIPPER, str(link), *map(str, targets)],
                               stdout=subprocess.PIPE, text=True)
    assert flipper.stdout.readline().strip() == "ready"
    outcomes: dict = {}
    seen = set()
    try:
        for k in range(most):
            if k >= runs and seen >= set(until):
                break
            try:
                got = attempt()
                seen.add("read")
            except Exception as err:  # noqa: BLE001 - a refusal is one of the outcomes counted
                got = type(err).__name__
                seen.add("refused")
            seen.add(got)
            outcomes[got] = outcomes.get(got, 0) + 1
    finally:
        flipper.send_signal(signal.SIGTERM)
        flips = int(flipper.communicate(timeout=30)[0].split()[-1])
    assert flips > 10, f"the link flipped only {flips} times"
    return outcomes


def test_the_race_catches_a_check_then_open(tmp_path):
    """The harness itself: the pattern the loader had (check the resolved path, then open the
    path by name again) does read the outside file under the same flipping."""
    import time

    (tmp_path / "inside.txt").write_text("inside")
    (tmp_path / "outside.txt").write_text("outside")
    os.symlink("inside.txt", tmp_path / "link")

    def check_then_open():
        real = os.path.realpath(tmp_path / "link")
        if real.endswith("outside.txt"):
            return "refused"
        time.sleep(0.001)  # the loader did other work between its check and its second open
        return open(tmp_path / "link").read()

    outcomes = _race(tmp_path / "link", ["inside.txt", str(tmp_path / "outside.txt")], check_then_open,
                     until=("outside",))
    assert outcomes.get("outside", 0) > 0, outcomes


def _texture_case(proj, outside):
    from rrcache.session import load_session

    _png(proj / "inside.png", 0.25)
    _png(outside / "secret.png", 1.0)
    (proj / "s.json").write_text(json.dumps(session(textures={"u_t": "t.png"})))
    return ("t.png", "inside.png", outside / "secret.png",
            lambda: f"{float(load_session(proj / 's.json').textures['u_t'].data.max()):.2f}", "0.25", "1.00")


def _mesh_case(proj, outside):
    from rrcache.session import load_session

    (proj / "inside.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (outside / "secret.obj").write_text("v 0 0 0\nv 7 0 0\nv 0 7 0\nf 1 2 3\n")
    (proj / "s.json").write_text(json.dumps(session(objects=[{"mesh": "m.obj"}])))
    return ("m.obj", "inside.obj", outside / "secret.obj",
            lambda: f"{float(load_session(proj / 's.json').objects[0].mesh.positions.max()):.0f}", "1", "7")


def _include_case(proj, outside):
    from rrcache.glsl.preprocessor import preprocess_file

    (proj / "inside.glsl").write_text("float inside_value() { return 1.0; }\n")
    (outside / "secret.glsl").write_text("float TOP_SECRET() { return 1.0; }\n")
    (proj / "main.frag").write_text("#version 330\n#include \"lib.glsl\"\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n")

    def attempt():
        names = [t.text for t in preprocess_file(proj / "main.frag").tokens]
        return "secret" if "TOP_SECRET" in names else "inside" if "inside_value" in names else "neither"

    return "lib.glsl", "inside.glsl", outside / "secret.glsl", attempt, "inside", "secret"


RACES = {"texture (session)": _texture_case, "mesh (session)": _mesh_case, "#include (shader)": _include_case}


@pytest.mark.parametrize("name", list(RACES))
def test_a_link_flipped_during_loading_never_reads_outside(tmp_path, stability_case, name):
    """A process flips a link in the folder between a file inside and one outside while the
    loader runs at least 200 times: every load reads the inside file or refuses; none reads the
    outside one."""
    from rrcache.budgets import reset_budget

    reset_budget()
    proj, outside = tmp_path / "proj", tmp_path / "outside"
    proj.mkdir()
    outside.mkdir()
    link, inside_name, secret, attempt, inside_value, secret_value = RACES[name](proj, outside)
    os.symlink(inside_name, proj / link)
    outcomes = _race(proj / link, [inside_name, str(secret)], attempt)
    stability_case(f"{name} link flipped in and out of its folder", AREA,
                   f"{sum(outcomes.values())} loads while a process flips {link} -> {inside_name} / "
                   f"../outside/{secret.name}").observe(**outcomes)
    assert secret_value not in outcomes, outcomes
    refused = sum(v for k, v in outcomes.items() if k.endswith("Error"))
    assert outcomes.get(inside_value, 0) > 0 and refused > 0, outcomes


# ----------------------------------------------------------------------------- a tampered profile

SECRET = "TOP_SECRET_4711"

TAMPER = {
    "shader: a file outside, no shader name": ("shader", "outside/shadow", "not a shader file"),
    "shader: a shader file outside, other content": ("shader", "outside/evil.glsl", "changed since it was profiled"),
    "session: a JSON file outside": ("session", "outside/secret.json", None),
    "session: a file outside, no JSON name": ("session", "outside/shadow", "not a session file"),
}


@pytest.mark.parametrize("command", ["report", "accuracy"])
@pytest.mark.parametrize("name", list(TAMPER))
def test_a_tampered_profile_reads_nothing_it_names(made_profile, tmp_path, stability_case, name, command):
    import shutil
    key, target, expected = TAMPER[name]
    shutil.copytree(made_profile, tmp_path / "case")
    case_dir = tmp_path / "case"
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "shadow").write_text(f"root:{SECRET}:19000:0:99999:7:::\n")
    (outside / "evil.glsl").write_text(f"{SECRET} is not GLSL\n")
    (outside / "secret.json").write_text(json.dumps({"rrcache_session": 1, "resolution": SECRET}))
    doc = json.loads((case_dir / "p" / "profile.json").read_text())
    doc[key] = str(tmp_path / target)
    (case_dir / "p" / "profile.json").write_text(json.dumps(doc))
    args = [command, "p"] + (["--nodes", "n1"] if command == "accuracy" else [])
    code, out, lines, peak, opened = rrcache_traced(case_dir, *args, timeout=300)
    text = out + "\n".join(lines) + "".join(p.read_text(errors="replace") for p in case_dir.rglob("*.html"))
    stability_case(f"tampered profile.json: {name} ({command})", AREA,
                   f"profile.json's {key!r} -> {target}; rrcache {' '.join(args)}").observe(
        exit=code, stderr=" | ".join(lines).replace(str(tmp_path), "TMP"), peak_mib=round(peak))
    assert SECRET not in text and peak < RUN_PEAK_MIB
    assert code in (0, 2)
    if code == 2:
        one_error_line(code, lines)
    if expected is not None and (code == 2 or command == "accuracy"):  # the report may not need the file
        assert code == 2 and expected in lines[-1], lines
    if "no shader name" in name or "no JSON name" in name:
        assert not any(os.path.realpath(path) == str(outside / "shadow") for path in opened if os.path.isabs(path)), \
            [p for p in opened if "outside" in p]
        assert str(outside / "shadow") not in opened


def _copy_and_a_secret_image(made_profile, tmp_path):
    """(the copied profile folder, an outside folder with ``secret.png``, that image's base64 as
    a report would embed it)."""
    import base64
    import shutil
    shutil.copytree(made_profile, tmp_path / "case")
    outside = tmp_path / "outside"
    outside.mkdir()
    _png(outside / "secret.png", 1.0, size=9)
    return tmp_path / "case" / "p", outside, base64.b64encode((outside / "secret.png").read_bytes()).decode()


def test_a_plot_linked_outside_is_not_embedded(made_profile, tmp_path, stability_case):
    folder, outside, secret = _copy_and_a_secret_image(made_profile, tmp_path)
    (folder / "tradeoff.png").unlink()
    os.symlink(outside / "secret.png", folder / "tradeoff.png")
    code, _, lines, _, _ = rrcache_traced(tmp_path / "case", "report", "p", "--out", "r.html", timeout=300)
    assert code == 0, lines
    assert secret not in (tmp_path / "case" / "r.html").read_text()
    assert os.path.islink(folder / "tradeoff.png")


@pytest.mark.parametrize("how", ["a path out of the folder", "a link out of the folder"])
def test_frames_json_cannot_name_a_file_outside(made_profile, tmp_path, stability_case, how):
    """``frames/frames.json`` names the report's images: edited to name a file outside the profile
    (by its path, or through a link placed in the folder), the report refuses it and embeds
    nothing of it."""
    folder, outside, secret = _copy_and_a_secret_image(made_profile, tmp_path)
    path = folder / "frames" / "frames.json"
    doc = json.loads(path.read_text())
    label = sorted(doc["selections"])[0]
    if how.startswith("a path"):
        doc["selections"][label]["images"]["original"] = os.path.relpath(outside / "secret.png", folder)
    else:
        os.symlink(outside / "secret.png", folder / "frames" / "link.png")
        doc["selections"][label]["images"]["original"] = "frames/link.png"
    path.write_text(json.dumps(doc))
    code, _, lines, _, opened = rrcache_traced(tmp_path / "case", "report", "p", "--out", "r.html", timeout=300)
    line = one_error_line(code, lines)
    stability_case(f"frames.json naming {how}", AREA, "rrcache report p").observe(
        exit=code, stderr=line.replace(str(tmp_path), "TMP"))
    assert "outside the profile's folder" in line and "nothing of it was read" in line
    assert not (tmp_path / "case" / "r.html").exists() or secret not in (tmp_path / "case" / "r.html").read_text()
