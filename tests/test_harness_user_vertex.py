"""A user's own vertex shader (glslViewer's ``.vert`` beside the ``.frag``; ``--vert FILE`` or
``"vertex"`` in a session), issue 14:

- the text: legacy ``attribute``/``varying`` become core ``in``/``out``, the outputs (the
  varyings) are found, ``MODEL_VERTEX_*`` and the ES rule apply, names reserved for rrcache and
  fragment inputs the vertex shader does not write are errors at their place;
- rendered: a glslViewer-style pair with a custom varying (``v_ratio``) renders; a user vertex
  shader computing what the generated one does gives the same image; every algorithm's variants
  reproduce the original at Δn = 1, and at Δn = 4 reproject as well as with the generated
  vertex shader (the previous clip position is right);
- sessions: ``"vertex"`` is relative to the session file; ``--vert`` on the CLI.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from scene_files import SESSION

from rrcache.errors import RRCacheError, SessionError, UnsupportedShaderError
from rrcache.harness.cached import compare
from rrcache.harness.renderer import render
from rrcache.compiler.user_vertex import user_vertex_from_text
from rrcache.pipeline import load_for_session, variant_for
from rrcache.session import load_session
from rrcache.choice import write as choice_write

# glslViewer's conventions: attribute vec4 a_position, MODEL_VERTEX_* guards, a custom varying
VERT = """#ifdef GL_ES
precision mediump float;
#endif

uniform mat4 u_modelViewProjectionMatrix;
uniform mat4 u_modelMatrix;
uniform mat3 u_normalMatrix;

attribute vec4 a_position;
varying vec4 v_position;

#ifdef MODEL_VERTEX_NORMAL
attribute vec3 a_normal;
varying vec3 v_normal;
#endif

varying float v_ratio;
varying vec3 v_objectPos;

void main(void) {
    v_position = u_modelMatrix * a_position;
#ifdef MODEL_VERTEX_NORMAL
    v_normal = normalize(u_normalMatrix * a_normal);
#endif
    v_objectPos = a_position.xyz;
    v_ratio = 0.5 + 0.5 * a_position.y;
    gl_Position = u_modelViewProjectionMatrix * a_position;
}
"""

FRAG = """#ifdef GL_ES
precision mediump float;
#endif

uniform vec3 u_light;

varying vec4 v_position;
varying vec3 v_normal;
varying float v_ratio;
varying vec3 v_objectPos;

float stripes(vec3 p) {
    return 0.5 + 0.5 * sin(p.x * 9.0 + 2.0 * sin(p.y * 7.0) + cos(p.z * 5.0));
}

void main() {
    vec3 base = mix(vec3(0.9, 0.3, 0.2), vec3(0.2, 0.4, 0.9), v_ratio);
    vec3 albedo = base * (0.4 + 0.6 * stripes(v_objectPos * 2.0));
    float diffuse = max(dot(normalize(v_normal), normalize(u_light - v_position.xyz)), 0.0);
    gl_FragColor = vec4(albedo * (0.2 + 0.8 * diffuse), 1.0);
}
"""

# the same picture with the generated vertex shader: v_ratio from the object position
FRAG_GENERATED = FRAG.replace("varying float v_ratio;\nvarying vec3 v_objectPos;",
                              "varying vec3 v_objectPosition;").replace(
    "v_ratio)", "0.5 + 0.5 * v_objectPosition.y)").replace("v_objectPos * 2.0", "v_objectPosition * 2.0")

ALGORITHMS = ("three-pass", "two-pass", "one-pass")


def test_legacy_text_becomes_core():
    v = user_vertex_from_text(VERT, "gv.vert", {"MODEL_VERTEX_NORMAL": "1"})
    assert v.outputs == {"v_position": "vec4", "v_normal": "vec3", "v_ratio": "float", "v_objectPos": "vec3"}
    src = v.source(prev_clip=True)
    assert src.startswith("#version 330 core\ninvariant gl_Position;\n")
    assert "attribute" not in src and "varying" not in src and "in vec4 a_position ;" in src
    assert "void rr_userMain ( void )" in src and "rr_prevClip = u_reprojectionMatrix * gl_Position;" in src
    assert "u_reprojectionMatrix" not in v.source(prev_clip=False)
    # without the mesh define the normal branch is off, as glslViewer compiles it
    assert "v_normal" not in user_vertex_from_text(VERT, "gv.vert").outputs
    assert set(v.uniform_names(True)) == {"u_modelViewProjectionMatrix", "u_modelMatrix", "u_normalMatrix",
                                          "u_reprojectionMatrix"}


def test_core_vertex_shader_keeps_its_version():
    v = user_vertex_from_text("#version 410 core\nlayout(location = 0) in vec3 a_position;\n"
                              "layout(location = 1) out vec2 v_uv;\nuniform mat4 u_modelViewProjectionMatrix;\n"
                              "void main() { v_uv = a_position.xy; gl_Position = u_modelViewProjectionMatrix"
                              " * vec4(a_position, 1.0); }\n", "core.vert")
    assert v.version_line == "#version 410 core" and v.outputs == {"v_uv": "vec2"}


@pytest.mark.parametrize("text,message", [
    ("void main() { }", "never writes gl_Position"),
    ("out vec2 rr_x; void main() { gl_Position = vec4(0.0); }", "reserved for rrcache"),
    ("void main() { gl_FragColor = vec4(1.0); gl_Position = vec4(0.0); }", "fragment shader"),
])
def test_bad_vertex_shaders(text, message):
    with pytest.raises(RRCacheError, match=message):
        user_vertex_from_text(text, "bad.vert")


def test_fragment_inputs_must_be_written(tmp_path):
    v = user_vertex_from_text(VERT, "gv.vert", {"MODEL_VERTEX_NORMAL": "1"})
    from rrcache.errors import SourceLoc

    with pytest.raises(UnsupportedShaderError, match=r"f\.frag:4:9: fragment input `v_missing` is not an output"):
        v.check_inputs({"v_missing": "vec2"}, {"v_missing": SourceLoc("f.frag", 4, 9)})
    with pytest.raises(UnsupportedShaderError, match="`vec2` but the vertex shader .* writes a `float`"):
        v.check_inputs({"v_ratio": "vec2"})


def _scene(folder, vertex=True, frag=FRAG):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "shaders").mkdir(exist_ok=True)
    (folder / "shaders" / "gv.vert").write_text(VERT)
    (folder / "shaders" / "gv.frag").write_text(frag)
    doc = {k: v for k, v in SESSION.items() if k != "uniforms"}
    if vertex:
        doc["vertex"] = "shaders/gv.vert"
    (folder / "s.json").write_text(json.dumps(doc))
    return folder / "shaders" / "gv.frag", folder / "s.json"


def test_session_vertex_is_relative_to_the_session(tmp_path):
    frag, session = _scene(tmp_path / "a")
    loaded = load_session(session)
    assert loaded.vertex == str(tmp_path / "a" / "shaders" / "gv.vert")
    doc = json.loads(session.read_text())
    doc["vertex"] = "nope.vert"
    session.write_text(json.dumps(doc))
    with pytest.raises(RRCacheError, match=r"s\.json: vertex: cannot find the vertex shader"):
        load_session(session)
    doc["vertex"] = 3
    session.write_text(json.dumps(doc))
    with pytest.raises(SessionError, match="vertex"):
        load_session(session)


def test_pair_renders_like_the_generated_vertex_shader(gl_ctx, tmp_path):
    frag, session = _scene(tmp_path / "user")
    gen_frag, gen_session = _scene(tmp_path / "gen", vertex=False, frag=FRAG_GENERATED)
    user = render(load_for_session(frag, load_session(session)).prepared, load_session(session), range(3))
    gen = render(load_for_session(gen_frag, load_session(gen_session)).prepared, load_session(gen_session), range(3))
    for a, b in zip(user.frames, gen.frames):
        assert a.covered_pixels == b.covered_pixels > 500
        assert np.abs(a.image - b.image).max() < 2e-3


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_variants_reproduce_the_original(gl_ctx, tmp_path, algorithm):
    frag, session_path = _scene(tmp_path)
    session = load_session(session_path)
    work = load_for_session(frag, session)
    assert work.vertex is not None and "v_ratio" in work.prepared.inputs
    # the nodes that read the custom varyings: the mixed base colour, and the final colour
    chosen = [n for n in work.table.nodes if "v_ratio" in n.text or n.final][:2]
    assert chosen
    for node in chosen:
        variant = variant_for(work, node.id, algorithm)
        assert all("rr_userMain" in p.vertex for p in variant.passes.values())
        result = compare(variant, session, work.prepared, range(4), period=1)
        s = result.summary()
        assert s["mean_error"] < 1e-6, (node.id, node.text, s)


def test_reprojection_matches_the_generated_vertex_shader(gl_ctx, tmp_path):
    """At Δn = 4 the cache hits where it hits with the generated vertex shader: rr_prevClip from
    u_reprojectionMatrix * gl_Position is the previous frame's clip position."""
    frag, session_path = _scene(tmp_path / "user")
    gen_frag, gen_session_path = _scene(tmp_path / "gen", vertex=False, frag=FRAG_GENERATED)
    rates = []
    for f, sp in ((frag, session_path), (gen_frag, gen_session_path)):
        session = load_session(sp)
        work = load_for_session(f, session)
        node = next(n for n in work.table.nodes if n.final)
        result = compare(variant_for(work, node.id, "three-pass"), session, work.prepared, range(8), period=4)
        rates.append(result.summary()["hit_rate"])
    assert rates[0] > 0.5 and math.isclose(rates[0], rates[1], abs_tol=0.01), rates


def test_cli_vert_option(tmp_path, capsys):
    from rrcache.cli import main

    frag, session = _scene(tmp_path, vertex=False)
    vert = frag.with_suffix(".vert")

    def run(*args):
        try:
            main([str(a) for a in args])
            code = 0
        except SystemExit as e:
            code = e.code
        return code, *capsys.readouterr()

    code, out, err = run("render", frag, session, "--frames", "2", "--json", "--vert", vert)
    assert code == 0, err
    assert json.loads(out)["covered_pixels"][0] > 500
    # without it the generated vertex shader cannot supply v_ratio: one located line
    code, out, err = run("render", frag, session, "--frames", "1", "--json")
    assert code == 2 and "gv.frag:10:" in err and "v_objectPos`" in err and "--vert FILE" in err
    assert len(err.strip().splitlines()) == 1
    code, out, err = run("nodes", frag, "--session", session, "--vert", vert)
    assert code == 0, err
    code, out, err = run("instance", frag, "--node", "n57", "--session", session, "--vert", vert,
                         "--out", tmp_path / "inst")
    assert code == 0, err
    assert "rr_userMain" in (tmp_path / "inst" / "reproject.vert").read_text()
    manifest = json.loads((tmp_path / "inst" / "manifest.json").read_text())
    assert manifest["vertex"] == str(vert) and "u_reprojectionMatrix" in manifest["passes"]["reproject"]["uniforms"]


def test_profile_remembers_the_vertex_shader(gl_ctx, tmp_path):
    """A profile made with --vert re-selects with it, and a changed vertex shader is named."""
    from rrcache.selection import CachedNode, Selection

    from rrcache.profiler import profile
    from rrcache.profiles import TrainingSettings, load_profile

    frag, session = _scene(tmp_path, vertex=False)
    vert = frag.with_suffix(".vert")
    settings = TrainingSettings(periods=(2, 4, 8), resolution=(32, 24), timing_frames=4, timing_periods=(2, 8),
                                validate=False, min_gain=0)
    prof = profile(frag, session, tmp_path / "out", settings, vertex=vert, plots=False)
    assert prof.vertex == str(vert) and prof.vertex_hash
    node = next(n.id for n in prof.nodes if n.trained)
    again = load_profile(tmp_path / "out")
    written = choice_write(again, Selection(parts=(CachedNode(node, 4),)), tmp_path / "sel")
    assert "rr_userMain" in next(open(p).read() for p in written if p.endswith("reproject.vert") or
                                 p.endswith("hit.vert") or p.endswith("single.vert"))
    vert.write_text(VERT.replace("0.5 + 0.5 * a_position.y", "0.5 + 0.4 * a_position.y"))
    with pytest.raises(RRCacheError, match="the vertex shader .*gv.vert' changed") as info:
        choice_write(again, Selection(parts=(CachedNode(node, 4),)), tmp_path / "sel2")
    assert "gv.frag' changed" not in str(info.value)


def test_an_error_in_the_users_vertex_shader_names_its_line(tmp_path, capsys):
    from rrcache.cli import main

    frag, session = _scene(tmp_path, vertex=False)
    bad = tmp_path / "bad.vert"
    bad.write_text(VERT.replace("v_ratio = 0.5 + 0.5 * a_position.y;", "v_ratio = 0.5 + 0.5 * a_positon.y;"))
    with pytest.raises(SystemExit) as info:
        main(["render", str(frag), str(session), "--vert", str(bad), "--frames", "1"])
    err = capsys.readouterr().err
    assert info.value.code == 2 and f"{bad}:26:" in err and "a_positon" in err
    assert "bug in rrcache" not in err and len(err.strip().splitlines()) == 1
