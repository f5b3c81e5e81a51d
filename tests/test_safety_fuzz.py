"""The command line under random damaged inputs (issue 16): hypothesis mutates a session, a shader
and a profile document (hostile values at random places, include lines reaching out of the tree,
truncated and corrupted text, control bytes, deep nesting, paths to the machine's files) and runs
``rrcache render``, ``rrcache nodes`` and ``rrcache select`` on them. Every run must end with exit
0 or 2, at most one line on stderr (exactly one, ``rrcache: error: ...``, for exit 2), no
traceback, no raw control byte, and no file outside the output folder touched.

The runs are in-process (``rrcache.cli.main`` with file descriptors 1 and 2 captured, so C
libraries' own output would be seen too) for speed, and a few through a real subprocess.
"""
from __future__ import annotations

import contextlib
import json
import os
import string
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings, strategies as st

from safety_cli import SESSION, SHADER, rrcache, tree

HOSTILE_VALUES = [None, -1, 0, 1e308, -1e308, 2 ** 63, 3.5, "x", "a\ud800b", "\x00\x1b[31m", [], {}, True,
                  16385, [0, 0, 0], [[[[[[[[[[1]]]]]]]]]], "../outside/secret.png", "/etc/passwd",
                  "/proc/self/environ", "../outside/tri.obj", "junk.stl", "~/.ssh/id_rsa", "é" * 50]
SESSION_PATHS = [["resolution"], ["resolution", 0], ["frames"], ["fps"], ["name"], ["background"],
                 ["camera", "fov"], ["camera", "near"], ["camera", "keyframes", 0, "eye"],
                 ["camera", "keyframes", 0, "up"], ["camera", "keyframes"], ["objects"], ["objects", 0],
                 ["objects", 0, "mesh"], ["objects", 0, "procedural", "type"], ["uniforms"],
                 ["uniforms", "u_gain"], ["textures"], ["textures", "u_tex"], ["include_dirs"],
                 ["include_dirs", 0], ["rrcache_session"], ["allow_outside_paths"]]
INCLUDES = ['#include "/etc/passwd"', '#include "../outside/secret.glsl"', "#include <secret.glsl>",
            '#include "' + "../" * 10 + 'proc/self/environ"', '#include "lib.glsl"', '#include "missing.glsl"',
            '#include "lib.glsl"\n#include "lib.glsl"', "#include", '#include "\x00"']
PROFILE_PATHS = [["mu"], ["nodes"], ["nodes", 0], ["nodes", 0, "alpha"], ["nodes", 0, "lam"],
                 ["nodes", 0, "t_hit"], ["nodes", 0, "t_miss"], ["nodes", 0, "trained"],
                 ["nodes", 0, "error_fit", "alpha"], ["nodes", 0, "perf_fit", "t_miss"], ["hit_fit", "mu"],
                 ["settings"], ["settings", "periods"], ["pixels"], ["original_ms"], ["overhead_ms"],
                 ["rrcache_profile"], ["selections"], ["shader"], ["algorithm"]]


def _profile_doc() -> dict:
    """A small valid profile document (one trained node, real fits) for ``rrcache select``."""
    from rrcache.model import fit_error, fit_hit_rate, fit_performance
    from rrcache.profiles.document import NodeProfile, Profile, _fit_json
    from rrcache.profiles.settings import TrainingSettings

    periods = [2, 4, 8, 16]
    ef = fit_error(periods, [0.01 * (1 - np.exp(-0.2 * (p - 1))) for p in periods])
    hits = np.array([1000, 2000, 3000, 4000, 5000.0])
    pf = fit_performance(hits, 10000 - hits, hits * 1e-5 + (10000 - hits) * 1e-4 + 0.2)
    hf = fit_hit_rate(periods, [0.8 * (1 - 1 / p) for p in periods])
    node = NodeProfile(id="n3", type="vec3", line=7, column=3, text="sin(x)", cost=100, trained=True,
                       alpha=float(ef.alpha), lam=float(ef.lam), t_hit=float(pf.t_hit), t_miss=float(pf.t_miss),
                       periods=periods, errors=[0.001] * 4, hit_rates=[0.5] * 4, psnrs=[40.0] * 4,
                       error_fit=_fit_json(ef), perf_fit=_fit_json(pf), error_quality="ok", perf_quality="ok")
    return Profile(shader="scene.frag", session="scene.json", shader_hash="a" * 64, session_hash="b" * 64,
                   settings=TrainingSettings(), algorithm="three-pass", nodes=[node], mu=float(hf.mu),
                   hit_fit=_fit_json(hf), overhead_ms=0.2, original_ms=1.2, pixels=10000.0).to_json()


PROFILE = _profile_doc()
FUZZ_SHADER = SHADER.replace("uniform float u_time;", "uniform float u_time;\nuniform float u_gain;\n"
                             "uniform sampler2D u_tex;").replace(
    "c = vec4(vec3(s * 0.1 + 0.5), 1.0);", "c = vec4(vec3(s * 0.1 + 0.5) * u_gain, 1.0) + texture(u_tex, n.xy) * 0.1;")
FUZZ_SESSION = {**json.loads(json.dumps(SESSION)), "resolution": [16, 12], "uniforms": {"u_gain": 1.0},
                "textures": {"u_tex": "tex.png"}}


def _set(doc, path, value):
    """``doc`` with ``value`` at ``path`` (as far as the path exists; else at its deepest part)."""
    target = doc
    for key in path[:-1]:
        try:
            target = target[key]
        except (KeyError, IndexError, TypeError):
            return
    try:
        target[path[-1]] = value
    except (IndexError, TypeError):
        pass


@st.composite
def damaged_json(draw, base, paths):
    doc = json.loads(json.dumps(base))
    for _ in range(draw(st.sampled_from([0, 0, 1, 1, 2, 3]))):
        _set(doc, draw(st.sampled_from(paths)), draw(st.sampled_from(HOSTILE_VALUES)))
    text = json.dumps(doc, ensure_ascii=draw(st.booleans()))
    how = draw(st.sampled_from(["as is", "as is", "as is", "as is", "truncated", "byte noise", "deep"]))
    if how == "truncated":
        text = text[:draw(st.integers(0, len(text)))]
    elif how == "byte noise":
        at = draw(st.integers(0, len(text)))
        text = text[:at] + draw(st.text(alphabet=string.printable + "\x00\x7f\ud7ff", max_size=8)) + text[at:]
    elif how == "deep":
        text = text[:-1] + ', "zz": ' + "[" * 50_000 + "]" * 50_000 + "}"
    return text


@st.composite
def damaged_shader(draw):
    lines = FUZZ_SHADER.split("\n")
    for _ in range(draw(st.integers(0, 3))):
        kind = draw(st.sampled_from(["include", "delete", "duplicate", "noise", "chain"]))
        at = draw(st.integers(1, len(lines) - 1))
        if kind == "include":
            lines.insert(at, draw(st.sampled_from(INCLUDES)))
        elif kind == "delete" and len(lines) > 2:
            del lines[at]
        elif kind == "duplicate":
            lines.insert(at, lines[at - 1])
        elif kind == "noise":
            lines[at] += draw(st.text(alphabet=string.printable + "\x00\x01\x1b", max_size=6))
        else:
            lines.insert(at, "float zz = 1.0" + " + 1.0" * draw(st.integers(100, 3000)) + ";")
    return "\n".join(lines)


def _write_png(path):
    import OpenImageIO as oiio
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(4, 4, 3, oiio.UINT8))
    out.write_image(np.full((4, 4, 3), 0.5, np.float32))
    out.close()


def _workspace(base: Path, shader: str, session_text: str, profile_text: str) -> Path:
    work = base / "work"
    outside = base / "outside"
    work.mkdir()
    outside.mkdir()
    (outside / "secret.glsl").write_text("SECRET_9173 helper;\n")
    (outside / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    _write_png(outside / "secret.png")
    _write_png(work / "tex.png")
    (work / "lib.glsl").write_text("float helper() { return 0.5; }\n")
    (work / "junk.stl").write_bytes(b"\0" * 80 + (500).to_bytes(4, "little") + bytes(range(256)) * 3)
    (work / "scene.frag").write_text(shader, errors="surrogatepass")
    (work / "scene.json").write_bytes(session_text.encode("utf-8", "surrogatepass"))
    (work / "p").mkdir()
    (work / "p" / "profile.json").write_bytes(profile_text.encode("utf-8", "surrogatepass"))
    return work


@contextlib.contextmanager
def _captured(folder: Path):
    """File descriptors 1 and 2 (and Python's streams) into files, the current folder ``folder``."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    out_path, err_path = folder / ".stdout", folder / ".stderr"
    cwd = os.getcwd()
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        streams = sys.stdout, sys.stderr  # (pytest's capture replaces them: point them at 1 and 2)
        sys.stdout = open(1, "w", encoding="utf-8", errors="backslashreplace", closefd=False)
        sys.stderr = open(2, "w", encoding="utf-8", errors="backslashreplace", closefd=False)
        os.chdir(folder)
        box = {}
        try:
            yield box
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            sys.stdout, sys.stderr = streams
            os.chdir(cwd)
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
    box["stderr"] = err_path.read_bytes().decode("utf-8", "replace")
    out_path.unlink()
    err_path.unlink()


def _main(folder: Path, args: list[str]) -> tuple[int, list[str]]:
    from rrcache.cli import main

    with _captured(folder.parent) as box:
        os.chdir(folder)
        try:
            main(args)
            code = 0
        except SystemExit as stop:
            code = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
    return code, [line for line in box["stderr"].splitlines() if line.strip()]


COMMANDS = {
    "render": ["render", "scene.frag", "scene.json", "--frames", "1", "--out", "out"],
    "nodes": ["nodes", "scene.frag"],
    "nodes --session": ["nodes", "scene.frag", "--session", "scene.json"],
    "select": ["select", "p", "--max-error", "0.005", "--json"],
    "select --out": ["select", "p", "--max-error", "0.005", "--out", "out"],
}


def _check(code, lines, before_outside, before_inputs, base: Path, work: Path, label):
    assert code in (0, 2), (label, code, lines)
    text = "\n".join(lines)
    assert "Traceback" not in text, (label, text)
    assert not any(ord(ch) < 32 and ch != "\t" for ch in text), (label, text)
    if code == 2:
        assert len(lines) == 1 and lines[0].startswith("rrcache: error: "), (label, lines)
    else:
        assert not any("error" in line for line in lines), (label, lines)
    assert "SECRET_9173" not in text
    assert tree(base / "outside") == before_outside, label
    after = {k: v for k, v in tree(work).items() if "/out/" not in k and not k.endswith("/out")}
    assert after == before_inputs, (label, set(after) ^ set(before_inputs))


def _fuzz(command, shader, session_text, profile_text, run) -> None:
    """One fuzz case: the workspace made, ``run(work, args)`` → (exit code, stderr lines), checked."""
    with tempfile.TemporaryDirectory(prefix="rrfuzz-") as tmp:
        base = Path(tmp)
        work = _workspace(base, shader, session_text, profile_text)
        before_outside, before_inputs = tree(base / "outside"), tree(work)
        code, lines = run(work, COMMANDS[command])
        event(f"{command}: exit {code}")
        _check(code, lines, before_outside, before_inputs, base, work, command)


def _subprocess(work, args):
    code, _, lines = rrcache(work, *args)
    return code, lines


@settings(max_examples=80, deadline=None, suppress_health_check=list(HealthCheck))
@given(command=st.sampled_from(list(COMMANDS)), shader=damaged_shader(),
       session_text=damaged_json(FUZZ_SESSION, SESSION_PATHS), profile_text=damaged_json(PROFILE, PROFILE_PATHS))
def test_cli_survives_damaged_inputs(command, shader, session_text, profile_text):
    _fuzz(command, shader, session_text, profile_text, _main)


@settings(max_examples=3, deadline=None, suppress_health_check=list(HealthCheck))
@given(command=st.sampled_from(list(COMMANDS)), shader=damaged_shader(),
       session_text=damaged_json(FUZZ_SESSION, SESSION_PATHS), profile_text=damaged_json(PROFILE, PROFILE_PATHS))
def test_cli_survives_damaged_inputs_in_a_subprocess(command, shader, session_text, profile_text):
    _fuzz(command, shader, session_text, profile_text, _subprocess)
