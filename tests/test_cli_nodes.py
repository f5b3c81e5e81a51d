"""``rrcache nodes``: table, --json schema, --all, -D, errors."""
from __future__ import annotations

import json

import jsonschema
import pytest

from rrcache.cli import main

SHADER = """#version 330
in vec3 v_n;
out vec4 fragColor;
uniform float u_k;
void main() {
#ifdef BRIGHT
    vec3 c = exp(v_n) * sin(v_n) + 1.0;
#else
    vec3 c = exp(v_n) * sin(v_n);
#endif
    float s = 0.0;
    for (int i = 0; i < int(u_k); i++) s += exp(v_n.x * float(i));
    fragColor = vec4(c * s, 1.0);
}
"""

NODE = {"type": "object", "required": ["id", "type", "line", "column", "text", "cost",
                                       "call_chain"],
        "properties": {"id": {"type": "string", "pattern": "^n[0-9]+$"},
                       "type": {"enum": ["float", "vec2", "vec3", "vec4"]},
                       "line": {"type": "integer", "minimum": 1},
                       "column": {"type": "integer", "minimum": 1},
                       "text": {"type": "string"}, "cost": {"type": "integer", "minimum": 0},
                       "call_chain": {"type": "array", "items": {"type": "string"}}}}
EXCLUDED = {"type": "object", "required": ["id", "reason", "line", "column", "text"],
            "properties": {"reason": {"enum": ["type", "dynamic", "uniform", "derivative",
                                               "duplicate", "cheap"]}}}
SCHEMA = {"type": "object", "required": ["shader", "nodes", "excluded"],
          "properties": {"shader": {"type": "string"},
                         "nodes": {"type": "array", "items": NODE},
                         "excluded": {"type": "array", "items": EXCLUDED}}}


@pytest.fixture
def shader_file(tmp_path):
    path = tmp_path / "s.frag"
    path.write_text(SHADER)
    return str(path)


def run(capsys, *args):
    try:
        main(list(args))
        code = 0
    except SystemExit as e:
        code = e.code
    out, err = capsys.readouterr()
    return code, out, err


def test_json_output_follows_the_schema(capsys, shader_file):
    code, out, _ = run(capsys, "nodes", shader_file, "--json", "--all")
    assert code == 0
    doc = json.loads(out)
    jsonschema.validate(doc, SCHEMA)
    assert doc["shader"] == shader_file
    texts = {n["text"] for n in doc["nodes"]}
    assert "exp(v_n) * sin(v_n)" in texts and "vec4(c * s, 1.0)" in texts
    dynamic = {x["text"] for x in doc["excluded"] if x["reason"] == "dynamic"}
    assert "exp(v_n.x * float(i))" in dynamic


def test_json_without_all_has_no_excluded(capsys, shader_file):
    code, out, _ = run(capsys, "nodes", shader_file, "--json")
    assert code == 0 and json.loads(out)["excluded"] == []


def test_defines_change_the_nodes(capsys, shader_file):
    _, out, _ = run(capsys, "nodes", shader_file, "--json", "-D", "BRIGHT")
    texts = {n["text"] for n in json.loads(out)["nodes"]}
    assert "exp(v_n) * sin(v_n) + 1.0" in texts


def test_text_table(capsys, shader_file):
    code, out, _ = run(capsys, "nodes", shader_file)
    assert code == 0
    assert out.splitlines()[0].split()[:4] == ["id", "type", "line:col", "cost"]
    assert "exp(v_n) * sin(v_n)" in out and "cacheable nodes" in out
    code, out_all, _ = run(capsys, "nodes", shader_file, "--all")
    assert "reason" in out_all.splitlines()[0] and " dynamic " in out_all
    assert len(out_all.splitlines()) > len(out.splitlines())


@pytest.mark.parametrize("content, message", [
    (None, "cannot read shader file"),
    ("#version 330\nout vec4 c;\nvoid main() { c = vec4(x); }\n", "s.frag:3:"),
])
def test_errors_exit_nonzero_without_traceback(capsys, tmp_path, content, message):
    path = tmp_path / "s.frag"
    if content is not None:
        path.write_text(content)
    code, out, err = run(capsys, "nodes", str(path))
    assert code == 2
    assert message in err and "Traceback" not in err and out == ""


def test_bad_define_is_a_usage_error(capsys, shader_file):
    code, _, err = run(capsys, "nodes", shader_file, "-D", "1BAD")
    assert code == 2 and "NAME or NAME=VALUE" in err and "Traceback" not in err


# --- which GLSL a shader without #version was read as (issue 14, item 7) -------------------------

SKETCH = """// a Book of Shaders sketch: no #version
#ifdef GL_ES
precision mediump float;
#endif
uniform vec2 u_resolution;
uniform float u_time;
varying vec2 v_texcoord;

void main() {
    vec2 st = v_texcoord * 4.0;
#ifdef GL_ES
    float w = sin(st.x * 3.0 + u_time) * cos(st.y * 5.0 - u_time);
#else
    float w = 0.0; // the desktop branch: never what the sketch tools run
#endif
    gl_FragColor = vec4(vec3(0.5 + 0.5 * w), 1.0);
}
"""


@pytest.mark.parametrize("source,es,says", [
    (SKETCH, True, "GLSL ES 1.00 (no #version;"),
    ("varying vec2 v_texcoord;\nvoid main() { gl_FragColor = vec4(sin(v_texcoord * 9.0), 0.0, 1.0); }\n",
     False, "desktop GLSL 1.10 (no #version"),
    ("#version 330\nin vec2 v_texcoord; out vec4 c;\nvoid main() { c = vec4(sin(v_texcoord * 9.0), 0.0, 1.0); }\n",
     False, "GLSL 330 core"),
])
def test_nodes_says_which_glsl(capsys, tmp_path, source, es, says):
    path = tmp_path / "sketch.frag"
    path.write_text(source)
    code, out, _ = run(capsys, "nodes", str(path))
    assert code == 0 and out.splitlines()[-1].startswith("read as " + says)
    code, out, _ = run(capsys, "nodes", str(path), "--json")
    lang = json.loads(out)["language"]
    assert lang["es"] is es and lang["text"].startswith(says)
    assert lang["assumed"] is ("no #version" in says)


def test_es_sketch_takes_its_gl_es_branch(capsys, tmp_path):
    path = tmp_path / "sketch.frag"
    path.write_text(SKETCH)
    code, out, _ = run(capsys, "nodes", str(path), "--json", "--all")
    doc = json.loads(out)
    texts = [n["text"] for n in doc["nodes"] + doc["excluded"]]
    assert any("cos(st.y * 5.0 - u_time)" in t for t in texts), texts


# --- included files, source text as written, MODEL_VERTEX_* hints (issue 14) ---------------------

SNOISE = """#ifndef FNC_SNOISE
#define FNC_SNOISE
float snoise(vec3 p) {
    vec3 i = floor(p);
    vec3 f = fract(p);
    f = f * f * (3.0 - 2.0 * f);
    float n = dot(i, vec3(1.0, 57.0, 113.0));
    return mix(fract(sin(n) * 43758.5453), fract(sin(n + 1.0) * 43758.5453), f.x) * 2.0 - 1.0;
}
#endif
"""

FBM = """#include "snoise.glsl"

#ifndef FBM_OCTAVES
#define FBM_OCTAVES 4
#endif

#ifndef FNC_FBM
#define FNC_FBM
float fbm(vec3 p) {
    float sum = 0.0;
    float amp = 0.5;
    for (int i = 0; i < FBM_OCTAVES; i++) {
        sum = sum + amp * snoise(p);
        p *= 2.0;
        amp *= 0.5;
    }
    return sum;
}
#endif
"""

LYGIA_MAIN = """#ifdef GL_ES
precision mediump float;
#endif

#include "lygia/generative/fbm.glsl"

uniform float u_time;
varying vec4 v_position;
#ifdef MODEL_VERTEX_NORMAL
varying vec3 v_normal;
#endif

void main() {
    vec3 color = vec3(0.5);
#ifdef MODEL_VERTEX_NORMAL
    float f = fbm(v_position.xyz * 3.0 + u_time);
    color = mix(vec3(0.1, 0.2, 0.5), vec3(0.9, 0.8, 0.6), f) * max(dot(normalize(v_normal), vec3(0.0, 0.0, 1.0)), 0.0);
#endif
    gl_FragColor = vec4(color, 1.0);
}
"""


@pytest.fixture
def lygia_sketch(tmp_path):
    lib = tmp_path / "lygia" / "generative"
    lib.mkdir(parents=True)
    (lib / "snoise.glsl").write_text(SNOISE)
    (lib / "fbm.glsl").write_text(FBM)
    main_file = tmp_path / "main.frag"
    main_file.write_text(LYGIA_MAIN)
    return main_file


def test_included_lines_name_their_file_and_read_as_written(capsys, lygia_sketch):
    code, out, _ = run(capsys, "nodes", str(lygia_sketch), "-D", "MODEL_VERTEX_NORMAL")
    assert code == 0
    rows = [line for line in out.splitlines() if "lygia/generative/fbm.glsl:13:15" in line]
    assert len(rows) == 4  # one per unrolled octave
    assert all(r.rstrip().endswith("sum + amp * snoise(p)") and "fbm>for i=" in r for r in rows)
    assert "_rr_" not in out
    assert any("lygia/generative/snoise.glsl:8:12" in line for line in out.splitlines())
    code, out, _ = run(capsys, "nodes", str(lygia_sketch), "-D", "MODEL_VERTEX_NORMAL", "--json", "--all")
    doc = json.loads(out)
    entries = doc["nodes"] + doc["excluded"]
    assert not any("_rr_" in n["text"] for n in entries)
    fbm_sum = [n for n in doc["nodes"] if n["line"] == 13 and n["column"] == 15]
    assert fbm_sum and all(n["file"].endswith("fbm.glsl") and n["text"] == "sum + amp * snoise(p)"
                           and n["call_chain"] for n in fbm_sum)
    assert all(n["file"] is None for n in entries if n["line"] == 19)  # the main file's lines


def test_without_session_the_mesh_defines_are_hinted(capsys, lygia_sketch):
    code, out, _ = run(capsys, "nodes", str(lygia_sketch))
    assert code == 0 and "0 cacheable nodes" in out
    assert out.splitlines()[-1].startswith("hint: the shader tests MODEL_VERTEX_NORMAL") and "--session" in out
    code, out, _ = run(capsys, "nodes", str(lygia_sketch), "--json")
    assert "MODEL_VERTEX_NORMAL" in json.loads(out)["hint"]
    # defined by hand: no hint
    code, out, _ = run(capsys, "nodes", str(lygia_sketch), "-D", "MODEL_VERTEX_NORMAL")
    assert "hint:" not in out


def test_an_error_from_an_off_branch_carries_the_hint(capsys, tmp_path):
    path = tmp_path / "n.frag"
    path.write_text("#ifdef MODEL_VERTEX_NORMAL\nvarying vec3 v_normal;\n#endif\n"
                    "void main() { gl_FragColor = vec4(normalize(v_normal), 1.0); }\n")
    code, _, err = run(capsys, "nodes", str(path))
    assert code == 2 and "n.frag:4:" in err and "MODEL_VERTEX_NORMAL" in err and "--session" in err
    assert len(err.strip().splitlines()) == 1


def test_sort_by_cost_orders_rows_costliest_first_and_names_the_unit(capsys, shader_file):
    code, out, _ = run(capsys, "nodes", shader_file, "--sort", "cost")
    assert code == 0
    rows = [line.split() for line in out.splitlines()[1:] if line[:1] == "n"]
    costs = [int(r[3]) for r in rows]
    assert len(costs) > 2 and costs == sorted(costs, reverse=True)
    assert "cost: the static estimate" in out and "rrcache/analysis/cost.py" in out
    _, by_id, _ = run(capsys, "nodes", shader_file)
    assert sorted(out.splitlines()) == sorted(by_id.splitlines())  # the same rows, reordered
    _, js, _ = run(capsys, "nodes", shader_file, "--json", "--all", "--sort", "cost")
    doc = json.loads(js)
    assert [n["cost"] for n in doc["nodes"]] == sorted((n["cost"] for n in doc["nodes"]), reverse=True)
    assert [x["cost"] for x in doc["excluded"]] == sorted((x["cost"] for x in doc["excluded"]), reverse=True)
