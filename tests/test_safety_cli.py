"""The causes of exit 70 ("internal error") in issue 16, each now one line and exit 2, through the
real command line in a subprocess: a read-only output folder, a full disk (the store, ``instance``
never leaving a 0-byte file, ``nodes > /dev/full``), the schema's largest resolution, a lone
surrogate in a session, periods beyond 2^20, ``--budget inf``, ``--timing-periods 0``, a camera
at 1e308, a corrupt PNG (no libpng line before ours), a garbage binary STL.

Full and read-only file systems are real: small tmpfs mounts where the machine allows them (root
in a container), else a file-size limit (``RLIMIT_FSIZE``, the kernel refusing writes) or a
folder without write permission.
"""
from __future__ import annotations

import json
import os
import stat
import struct
import subprocess
import zlib

import numpy as np
import pytest

from safety_cli import QUICK_PROFILE, SESSION, one_error_line, rrcache, session, tree, write_case

AREA = "safety: exit 70 causes, now exit 2 (subprocess)"


def _mount(target, options: str) -> bool:
    target.mkdir(parents=True, exist_ok=True)
    proc = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(target)],
                          capture_output=True, text=True)
    return proc.returncode == 0


@pytest.fixture
def mounts():
    made = []

    def mount(target, options):
        if _mount(target, options):
            made.append(target)
            return True
        return False

    yield mount
    for target in reversed(made):
        subprocess.run(["umount", "-l", str(target)], capture_output=True)


@pytest.fixture
def case_dir(tmp_path):
    write_case(tmp_path)
    return tmp_path


def _node(folder) -> str:
    code, out, lines = rrcache(folder, "nodes", "scene.frag", "--json")
    assert code == 0, lines
    return json.loads(out)["nodes"][0]["id"]


def test_read_only_output_folder(case_dir, mounts, stability_case):
    ro = case_dir / "ro"
    if mounts(ro, "ro,size=64k"):
        how = "a read-only tmpfs"
    elif os.geteuid() != 0:
        ro.mkdir()
        ro.chmod(0o555)
        how = "a folder without write permission"
    else:
        pytest.skip("cannot mount a read-only file system here, and root ignores permissions")
    node = _node(case_dir)
    case = stability_case("read-only output folder", AREA, f"render/profile/instance --out into {how}")
    seen = {}
    for name, args in {
        "render": ["render", "scene.frag", "scene.json", "--frames", "1", "--out", "ro/frames"],
        "profile": ["profile", "scene.frag", "scene.json", "--out", "ro/p", *QUICK_PROFILE],
        "instance": ["instance", "scene.frag", "--node", node, "--out", "ro/i"],
    }.items():
        code, _, lines = rrcache(case_dir, *args)
        seen[name] = one_error_line(code, lines).replace(str(case_dir), "TMP")
        assert "ro" in seen[name]
    case.observe(**seen)


def test_full_disk_instance_leaves_no_empty_file(case_dir, mounts, stability_case):
    node = _node(case_dir)
    full = case_dir / "full"
    popen = {}
    if mounts(full, "size=16k"):
        (full / "pad").write_bytes(b"\0" * 12 * 1024)  # leaves room for a few shader files, not all
        how = "a 16 KiB tmpfs, 12 KiB already used"
    else:
        full.mkdir()
        popen = {"file_size": 600}
        how = "RLIMIT_FSIZE = 600 bytes"
    case = stability_case("disk full: rrcache instance", AREA, f"rrcache instance --out on {how}")
    code, _, lines = rrcache(case_dir, "instance", "scene.frag", "--node", node, "--out", "full/i", **popen)
    line = one_error_line(code, lines)
    files = {p.name: p.stat().st_size for p in (full / "i").iterdir()} if (full / "i").exists() else {}
    case.observe(exit=code, stderr=line.replace(str(case_dir), "TMP"), files_left=files)
    assert all(size > 0 for size in files.values()), files
    assert "manifest.json" not in files
    assert not any(name.startswith(".") for name in files)  # no temporary file left


def test_full_disk_profile_store(case_dir, mounts, stability_case):
    full = case_dir / "full"
    popen = {}
    if mounts(full, "size=96k"):
        how = "a 96 KiB tmpfs"
    else:
        full.mkdir()
        popen = {"file_size": 40 * 1024}
        how = "RLIMIT_FSIZE = 40 KiB"
    case = stability_case("disk full: rrcache profile's store", AREA, f"rrcache profile --out on {how}, then again")
    code, _, lines = rrcache(case_dir, "profile", "scene.frag", "scene.json", "--out", "full/p", *QUICK_PROFILE, **popen)
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line.replace(str(case_dir), "TMP"))
    assert "full/p" in line


def test_nodes_to_dev_full(case_dir, stability_case):
    """stdout on a private node with /dev/full's numbers (1, 7), made here: never the system's."""
    full = case_dir / "full"
    try:
        os.mknod(full, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
    except (PermissionError, OSError):
        pytest.skip("mknod needs root")
    case = stability_case("disk full: rrcache nodes > /dev/full", AREA,
                          "rrcache nodes scene.frag > a private (1,7) node")
    with open(full, "w") as sink:
        code, _, lines = rrcache(case_dir, "nodes", "scene.frag", stdout=sink)
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line)
    assert "No space left on device" in line


def test_schema_largest_resolution(case_dir, stability_case):
    write_case(case_dir, session(resolution=[16384, 16384], frames=1), name="big")
    case = stability_case("the schema's largest resolution", AREA, "resolution [16384, 16384], rrcache render")
    code, _, lines = rrcache(case_dir, "render", "big.frag", "big.json")
    # a driver that can make the targets renders it; llvmpipe cannot make a 4 GiB float target
    if code == 0:
        case.observe(exit=0)
        return
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line)
    assert "16384x16384" in line and "big.json: resolution" in line


BAD_VALUES = {
    "lone surrogate in a session string": (
        ["render", "sur.frag", "sur.json", "--frames", "1"], "sur.json: name",
        lambda d: (d / "sur.json").write_text(json.dumps(SESSION).replace('"fps": 30', '"fps": 30, "name": "a\\ud800"'))),
    "--period 3000000000": (["render", "scene.frag", "scene.json", "--node", "NODE", "--period", "3000000000"],
                            "--period", None),
    "instance --period 99999999999999999999": (
        ["instance", "scene.frag", "--node", "NODE", "--period", "99999999999999999999", "--out", "inst"], "--period",
        None),
    "--budget inf": (["profile", "scene.frag", "scene.json", "--budget", "inf", "--out", "p"], "--budget", None),
    "--timing-periods 0": (["profile", "scene.frag", "scene.json", "--timing-periods", "0", "--out", "p"],
                           "--timing-periods", None),
    "camera radius 1e308": (
        ["render", "far.frag", "far.json", "--frames", "1"], "far.json: camera.orbit",
        lambda d: write_case(d, session(camera={"fov": 45, "orbit": {"center": [0, 0, 0], "radius": 1e308}}), name="far")),
}


@pytest.mark.parametrize("name", list(BAD_VALUES), ids=lambda n: n.replace(" ", "-"))
def test_bad_values(case_dir, stability_case, name):
    args, place, prepare = BAD_VALUES[name]
    if prepare is not None:
        if "sur" in args[1]:
            (case_dir / "sur.frag").write_text((case_dir / "scene.frag").read_text())
        prepare(case_dir)
    if "NODE" in args:
        args = [_node(case_dir) if a == "NODE" else a for a in args]
    case = stability_case(name, AREA, "rrcache " + " ".join(args))
    code, _, lines = rrcache(case_dir, *args)
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line)
    assert place in line
    if name == "camera radius 1e308":
        assert "up vector" not in line and "1e+308" in line
    if name.startswith("instance"):
        assert not (case_dir / "inst").exists()
    if name == "--budget inf":
        assert not (case_dir / "p").exists()  # refused before any store is made


def _corrupt_png(path):
    import OpenImageIO as oiio
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(16, 16, 3, oiio.UINT8))
    out.write_image(np.random.default_rng(1).random((16, 16, 3)).astype(np.float32))
    out.close()
    data = bytearray(path.read_bytes())
    for i in range(60, len(data) - 12):
        data[i] ^= 0x5A
    path.write_bytes(bytes(data))


def test_corrupt_png_one_line(case_dir, stability_case):
    _corrupt_png(case_dir / "bad.png")
    shader = ("#version 330\nuniform sampler2D u_tex;\nout vec4 c;\n"
              "void main() { c = texture(u_tex, vec2(0.5)); }\n")
    write_case(case_dir, session(textures={"u_tex": "bad.png"}), shader=shader, name="png")
    case = stability_case("corrupt PNG", AREA, "a PNG with its data scrambled, sampled by the shader")
    code, _, lines = rrcache(case_dir, "render", "png.frag", "png.json", "--frames", "1")
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line.replace(str(case_dir), "TMP"), stderr_lines=len(lines))
    assert len(lines) == 1 and "libpng" not in lines[0].split("rrcache: error:")[0]
    assert "textures.u_tex" in line


def test_garbage_binary_stl(case_dir, stability_case):
    rng = np.random.default_rng(5)
    (case_dir / "junk.stl").write_bytes(b"\0" * 80 + struct.pack("<I", 1000) + rng.bytes(50 * 30))
    write_case(case_dir, session(objects=[{"mesh": "junk.stl"}]), name="stl")
    case = stability_case("garbage binary STL", AREA, "80-byte header, 1000 triangles declared, 1500 random bytes")
    code, _, lines = rrcache(case_dir, "render", "stl.frag", "stl.json", "--frames", "1")
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line.replace(str(case_dir), "TMP"))
    assert "objects[0].mesh" in line


def test_huge_png_never_decoded(case_dir, stability_case):
    """A 20000×20000 black PNG of about a megabyte, listed as a texture the shader never
    samples: refused from its header, nothing decoded. (Its deflate stream repeats one
    full-flushed block of a MiB of zeros: made in milliseconds, not the seconds of compressing
    1.2 GB.)"""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    ihdr = struct.pack(">IIBBBBB", 20000, 20000, 8, 2, 0, 0, 0)
    z = zlib.compressobj(9)
    first = z.compress(b"\0" * (1 << 20)) + z.flush(zlib.Z_FULL_FLUSH)
    block = z.compress(b"\0" * (1 << 20)) + z.flush(zlib.Z_FULL_FLUSH)
    idat = first + block * 1144 + z.flush()
    (case_dir / "huge.png").write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat)
                                        + chunk(b"IEND", b""))
    write_case(case_dir, session(textures={"u_unused": "huge.png"}), name="huge")
    case = stability_case("20000×20000 PNG listed, never sampled", AREA,
                          f"a {(case_dir / 'huge.png').stat().st_size}-byte PNG declaring 20000×20000")
    before = tree(case_dir)
    code, _, lines = rrcache(case_dir, "render", "huge.frag", "huge.json", "--frames", "1")
    line = one_error_line(code, lines)
    raised, _, raised_lines = rrcache(case_dir, "--max-texture-pixels", str(20000 * 20000), "render",
                                      "huge.frag", "huge.json", "--frames", "1")
    case.observe(exit=code, stderr=line.replace(str(case_dir), "TMP"), with_budget_raised=raised)
    assert "400,000,000" in line and "--max-texture-pixels" in line and "nothing was decoded" in line
    # raised, the texture is still never decoded: the shader does not sample it
    assert raised == 0, raised_lines
    assert tree(case_dir) == before
