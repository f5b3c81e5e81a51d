"""Confinement (issue 16, security): ``#include`` reads only shader files inside the shader's own
folder tree and the include directories the user names (``-I DIR``, the session's
``"include_dirs"``); session meshes, textures and include folders stay inside the session's
folder tree unless the session or the command line opts out. A refusal never quotes the content
of the file it refused, nor echoes raw control bytes. Real files, real processes."""
from __future__ import annotations

import json
import os

import pytest

from rrcache.errors import AssetError, PreprocessorError
from rrcache.glsl.preprocessor import preprocess_file
from rrcache.session import load_session
from safety_cli import SESSION, rrcache, one_error_line, session, write_case

AREA = "safety: confined includes and asset paths"
SECRET = "TOP_SECRET_4711"


def _main(folder, include_line, name="main.frag"):
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(f"#version 330\n{include_line}\nout vec4 c;\nvoid main() {{ c = vec4(helper()); }}\n")
    return path


@pytest.fixture
def layout(tmp_path):
    """proj/ (the shader's tree, with lib/), outside/ (a sibling folder with a secret shader)."""
    proj, outside = tmp_path / "proj", tmp_path / "outside"
    (proj / "lib").mkdir(parents=True)
    outside.mkdir()
    (proj / "lib" / "ok.glsl").write_text("float helper() { return 0.5; }\n")
    (outside / "secret.glsl").write_text(f"{SECRET} helper() {{ return 1.0; }}\n")
    (proj / "lib" / "notes.txt").write_text(f"root:x:0:0:{SECRET}\n")
    return proj, outside


CASES = {
    "absolute path (/etc/passwd)": ('#include "/etc/passwd"', "outside the folders includes are read from"),
    "../ out of the tree": ('#include "../outside/secret.glsl"', "outside the folders includes are read from"),
    "/proc/self/environ via ../": ('#include "' + "../" * 12 + 'proc/self/environ"',
                                   "outside the folders includes are read from"),
    "<...> to an absolute path": ("#include </etc/hostname>", "outside the folders includes are read from"),
    "a text file inside the tree": ('#include "lib/notes.txt"', "is not a shader file"),
}


@pytest.mark.parametrize("name", list(CASES), ids=lambda n: n.split(" (")[0].replace(" ", "-"))
def test_include_outside_is_refused_without_reading(layout, stability_case, name):
    proj, _ = layout
    line, expected = CASES[name]
    path = _main(proj, line)
    case = stability_case(f"#include: {name}", AREA, f"{line} in proj/main.frag")
    with pytest.raises(PreprocessorError) as info:
        preprocess_file(path)
    msg = str(info.value)
    case.observe(error=msg.replace(str(proj.parent), "TMP"))
    assert expected in msg and f"{path}:2:" in msg
    assert SECRET not in msg and "root:" not in msg


def test_symlink_out_of_the_tree_is_refused(layout, stability_case):
    proj, outside = layout
    os.symlink(outside / "secret.glsl", proj / "lib" / "link.glsl")
    path = _main(proj, '#include "lib/link.glsl"')
    case = stability_case("#include: a symbolic link out of the tree", AREA,
                          "proj/lib/link.glsl -> ../outside/secret.glsl")
    with pytest.raises(PreprocessorError) as info:
        preprocess_file(path)
    case.observe(error=str(info.value).replace(str(proj.parent), "TMP"))
    assert "outside the folders" in str(info.value) and SECRET not in str(info.value)


def test_inside_the_tree_and_named_include_dirs_are_read(layout):
    proj, outside = layout
    assert "helper" in [t.text for t in preprocess_file(_main(proj, '#include "lib/ok.glsl"')).tokens]
    # a ../ that stays inside the tree is fine (a library's files including each other)
    (proj / "lib" / "gen").mkdir()
    (proj / "lib" / "gen" / "fbm.glsl").write_text('#include "../ok.glsl"\n')
    nested = _main(proj, '#include "lib/gen/fbm.glsl"', "nested.frag")
    assert "helper" in [t.text for t in preprocess_file(nested).tokens]
    # but the tree is the main shader's folder: a shader in sub/ cannot reach ../lib
    with pytest.raises(PreprocessorError):
        preprocess_file(_main(proj / "sub", '#include "../lib/ok.glsl"'))
    # the secret folder, once named as an include directory, is the user's choice
    named = _main(proj, '#include <secret.glsl>', "named.frag")
    assert SECRET in [t.text for t in preprocess_file(named, include_dirs=[outside]).tokens]


def test_cli_refusal_is_one_line_without_content_or_control_bytes(layout, stability_case):
    proj, _ = layout
    _main(proj, '#include "' + "../" * 12 + 'proc/self/environ"')
    # a shader inside the tree holding a NUL byte: the error names the place, never the byte
    (proj / "lib" / "nul.glsl").write_bytes(b"float helper() { return 0.5; }\n\x00\x1b[31mred\n")
    _main(proj, '#include "lib/nul.glsl"', "nul.frag")
    case = stability_case("#include /proc/self/environ and a NUL byte through rrcache nodes", AREA,
                          "rrcache nodes main.frag; rrcache nodes nul.frag (an include with a NUL byte)")
    code, _, lines = rrcache(proj, "nodes", "main.frag")
    line = one_error_line(code, lines)
    code2, _, lines2 = rrcache(proj, "nodes", "nul.frag")
    line2 = one_error_line(code2, lines2)
    case.observe(exit=code, stderr=line.replace(str(proj), "PROJ"), nul_exit=code2,
                 nul_stderr=line2.replace(str(proj), "PROJ"))
    assert "environ" in line and "=" not in line.split("hint:")[0].split("environ")[-1]
    assert "NUL byte" in line2 and "nul.glsl:2:" in line2
    for text in (line, line2):
        assert not any(ord(ch) < 32 for ch in text)


def test_dash_I_on_the_commands(layout, stability_case):
    proj, outside = layout
    lib = outside / "lib"
    lib.mkdir()
    (lib / "noise.glsl").write_text("float helper() { return 0.25; }\n")
    frag, sess = write_case(proj, SESSION, shader=(
        "#version 330\n#include <noise.glsl>\nin vec3 v_normal;\nout vec4 c;\n"
        "void main() { c = vec4(normalize(v_normal) * helper() * sin(v_normal.x), 1.0); }\n"))
    case = stability_case("-I DIR on nodes, render and instance", AREA, "#include <noise.glsl> from ../outside/lib")
    code, _, lines = rrcache(proj, "nodes", frag.name)
    refused = one_error_line(code, lines)
    code, out, lines = rrcache(proj, "nodes", "-I", str(lib), frag.name, "--json")
    assert code == 0, lines
    node = json.loads(out)["nodes"][0]["id"]
    results = {}
    for args in (["nodes", frag.name], ["render", frag.name, sess.name, "--frames", "1"],
                 ["instance", frag.name, "--node", node, "--out", "inst"]):
        code, out, lines = rrcache(proj, *args[:1], "-I", str(lib), *args[1:])
        results[args[0]] = code
        assert code == 0, lines
    case.observe(without=refused.split(": ", 2)[-1][:60], **results)
    assert "cannot find include file 'noise.glsl'" in refused
    assert (proj / "inst" / "manifest.json").exists()


def test_session_include_dirs(layout, stability_case):
    proj, outside = layout
    (proj / "shaders").mkdir()
    (proj / "glsl").mkdir()
    (proj / "glsl" / "h.glsl").write_text("float helper() { return 0.5; }\n")
    shader = "#version 330\n#include \"h.glsl\"\nout vec4 c;\nvoid main() { c = vec4(helper()); }\n"
    (proj / "shaders" / "a.frag").write_text(shader)
    (proj / "s.json").write_text(json.dumps(session(include_dirs=["glsl"])))
    (proj / "bad.json").write_text(json.dumps(session(include_dirs=["../outside"])))
    (proj / "trusted.json").write_text(json.dumps(session(include_dirs=["../outside"], allow_outside_paths=True)))
    case = stability_case('session "include_dirs"', AREA,
                          '"include_dirs": ["glsl"]; ["../outside"]; ["../outside"] with "allow_outside_paths"')
    ok, _, ok_lines = rrcache(proj, "render", "shaders/a.frag", "s.json", "--frames", "1")
    bad, _, bad_lines = rrcache(proj, "render", "shaders/a.frag", "bad.json", "--frames", "1")
    line = one_error_line(bad, bad_lines)
    with pytest.raises(AssetError):
        load_session(proj / "bad.json")
    assert load_session(proj / "trusted.json").include_dirs == (str(outside),)
    case.observe(inside=ok, outside=line.replace(str(proj.parent), "TMP"))
    assert ok == 0, ok_lines
    assert "bad.json: include_dirs[0]" in line and "outside the session's folder" in line


def test_session_assets_are_confined_unless_allowed(tmp_path, stability_case):
    proj, outside = tmp_path / "proj", tmp_path / "outside"
    proj.mkdir()
    outside.mkdir()
    (outside / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    import numpy as np
    import OpenImageIO as oiio
    out = oiio.ImageOutput.create(str(outside / "t.png"))
    out.open(str(outside / "t.png"), oiio.ImageSpec(4, 4, 3, oiio.UINT8))
    out.write_image(np.zeros((4, 4, 3), np.float32))
    out.close()
    mesh_doc = session(objects=[{"mesh": "../outside/tri.obj"}])
    tex_doc = session(textures={"u_t": str(outside / "t.png")})
    frag, _ = write_case(proj, mesh_doc, name="mesh")
    write_case(proj, tex_doc, name="tex")
    write_case(proj, {**mesh_doc, "allow_outside_paths": True}, name="trusted")
    case = stability_case("session paths outside the session's folder", AREA,
                          "a mesh ../outside/tri.obj, a texture at an absolute path; then the opt-outs")
    code, _, lines = rrcache(proj, "render", "mesh.frag", "mesh.json", "--frames", "1")
    mesh_line = one_error_line(code, lines)
    code, _, lines = rrcache(proj, "render", "tex.frag", "tex.json", "--frames", "1")
    tex_line = one_error_line(code, lines)
    allowed_key, _, l1 = rrcache(proj, "render", "trusted.frag", "trusted.json", "--frames", "1")
    allowed_flag, _, l2 = rrcache(proj, "--allow-outside-paths", "render", "mesh.frag", "mesh.json", "--frames", "1")
    case.observe(mesh=mesh_line.replace(str(tmp_path), "TMP"), texture=tex_line.replace(str(tmp_path), "TMP"),
                 session_opt_out=allowed_key, flag_opt_out=allowed_flag)
    assert "objects[0].mesh" in mesh_line and "outside the session's folder" in mesh_line
    assert "textures.u_t" in tex_line and "allow_outside_paths" in tex_line
    assert allowed_key == 0 and allowed_flag == 0, (l1, l2)
