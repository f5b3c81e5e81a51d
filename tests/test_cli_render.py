"""``rrcache render`` end to end: real front-end, real session loader, tiny renders."""
from __future__ import annotations

import json

import numpy as np
import pytest

from rrcache.cli import main
from rrcache.cli.options import parse_defines
from rrcache.compiler.prepared import prepare_file
from rrcache.harness.renderer import render
from rrcache.session import load_session

SESSION = {
    "rrcache_session": 1, "resolution": [64, 48], "frames": 3, "fps": 30,
    "camera": {"fov": 45, "near": 0.1, "far": 100,
               "keyframes": [{"frame": 0, "eye": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0]},
                             {"frame": 2, "eye": [1, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0]}]},
    "light": {"color": [1, 1, 1], "keyframes": [{"frame": 0, "position": [2, 2, 2]}]},
    "objects": [{"procedural": {"type": "icosphere", "subdivisions": 2},
                 "keyframes": [{"frame": 0, "translate": [0, 0, 0]}]}],
    "uniforms": {"u_gain": 0.5, "u_unused": 3},
}

SHADER = """#ifdef GL_ES
precision mediump float;
#endif
uniform vec3 u_light;
uniform float u_gain;
varying vec4 v_position;
varying vec3 v_normal;
void main() {
    vec3 l = normalize(u_light - v_position.xyz);
    float d = max(dot(normalize(v_normal), l), 0.0) * u_gain;
#ifdef RED
    gl_FragColor = vec4(d, 0.0, 0.0, 1.0);
#else
    gl_FragColor = vec4(vec3(d), 1.0);
#endif
}
"""


@pytest.fixture
def files(tmp_path):
    session = tmp_path / "session.json"
    session.write_text(json.dumps(SESSION))
    shader = tmp_path / "lit.frag"
    shader.write_text(SHADER)
    return shader, session


def test_parse_defines():
    assert parse_defines(["A=1", "B", "C="]) == {"A": "1", "B": "1", "C": ""}
    import click
    with pytest.raises(click.BadParameter):
        parse_defines(["1X=2"])


def test_json_summary(gl_ctx, files, capsys):
    shader, session = files
    main([ "render", str(shader), str(session), "--json", "--frames", "2"])
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    assert set(summary) == {"frames", "resolution", "ms_per_frame", "covered_pixels", "nonfinite_pixels", "frame_ms",
                            "color_format", "noise", "reliable"}
    # a replay draws exactly (NaN/Inf can only be counted in a float target)
    assert summary["color_format"] == "rgba32f" and len(summary["frame_ms"]) == 2 and summary["noise"] >= 0
    assert summary["nonfinite_pixels"] == [0, 0]
    assert summary["frames"] == 2 and summary["resolution"] == [64, 48]
    assert summary["ms_per_frame"] > 0
    loaded = load_session(session)
    direct = render(prepare_file(shader, loaded), loaded, frames=2)
    assert summary["covered_pixels"] == [f.covered_pixels for f in direct.frames]
    assert all(0 < c < 64 * 48 for c in summary["covered_pixels"])
    assert "u_unused" in captured.err   # the note goes to stderr


def test_out_writes_exr_and_png(gl_ctx, files, tmp_path, capsys):
    import OpenImageIO as oiio

    shader, session = files
    out = tmp_path / "frames"
    main(["render", str(shader), str(session), "--out", str(out), "--resolution", "32x24", "-D", "RED"])
    assert "median" in capsys.readouterr().out
    names = sorted(p.name for p in out.iterdir())
    assert names == [f"frame_{i:04d}.{ext}" for i in range(3) for ext in ("exr", "png")]
    inp = oiio.ImageInput.open(str(out / "frame_0001.exr"))
    exr = inp.read_image(oiio.FLOAT)
    inp.close()
    loaded = load_session(session)
    expected = render(prepare_file(shader, loaded, {"RED": "1"}), loaded, frames=[1], resolution=(32, 24)).frames[0]
    np.testing.assert_array_equal(exr, expected.image)
    assert exr[..., 1].max() == 0.0 and exr[..., 0].max() > 0.1   # -D RED took effect
    png = oiio.ImageInput.open(str(out / "frame_0001.png"))
    assert (png.spec().width, png.spec().height, png.spec().format) == (32, 24, oiio.TypeDesc("uint8"))
    png.close()


def test_missing_uniform_is_a_one_line_error(gl_ctx, files, capsys):
    shader, session = files
    doc = dict(SESSION)
    doc["uniforms"] = {}
    session.write_text(json.dumps(doc))
    with pytest.raises(SystemExit) as info:
        main(["render", str(shader), str(session)])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rrcache: error: ") and len(err.splitlines()) == 1
    assert f"{shader}:5:" in err and str(session) in err and '"u_gain"' in err


def test_bad_resolution_is_a_usage_error(files, capsys):
    shader, session = files
    with pytest.raises(SystemExit) as info:
        main(["render", str(shader), str(session), "--resolution", "big"])
    assert info.value.code == 2
    assert "WIDTHxHEIGHT" in capsys.readouterr().err


@pytest.mark.parametrize("double_sided", [False, True])
def test_back_faces_are_culled_unless_the_object_is_double_sided(tmp_path, double_sided):
    """A plane seen from behind: culled (nothing covered) unless the session says double_sided."""
    session = dict(SESSION, frames=1, uniforms={"u_gain": 0.5})
    session["objects"] = [{"procedural": {"type": "plane", "size": [2, 2]}, "double_sided": double_sided,
                           # the plane faces +Y; rotate it to face away from the camera at +Z
                           "keyframes": [{"frame": 0, "rotate": [-90, 1, 0, 0]}]}]
    path = tmp_path / "plane.json"
    path.write_text(json.dumps(session))
    shader = tmp_path / "lit.frag"
    shader.write_text(SHADER)
    result = render(str(shader), load_session(path), frames=1)
    covered = result.frames[0].covered_pixels
    assert (covered > 100) if double_sided else (covered == 0)


def _final_node(shader, session, capsys):
    main(["nodes", str(shader), "--session", str(session), "--json"])
    doc = json.loads(capsys.readouterr().out)
    return doc["nodes"][-1]["id"]


def test_render_node_compares_with_the_original(files, capsys):
    shader, session = files
    node = _final_node(shader, session, capsys)
    main(["render", str(shader), str(session), "--node", node, "--period", "1", "--json"])
    doc = json.loads(capsys.readouterr().out)
    keys = {"mean_error", "psnr", "hit_rate", "hits", "misses", "ms_per_frame", "original_ms_per_frame", "speedup"}
    assert keys <= set(doc)
    assert doc["mean_error"] <= 1e-6 and doc["hit_rate"] == 0.0 and doc["hits"] == 0
    main(["render", str(shader), str(session), "--node", node, "--period", "2", "--json", "--algorithm", "two-pass"])
    doc = json.loads(capsys.readouterr().out)
    assert doc["hits"] > 0 and doc["speedup"] > 0


def test_render_node_speedup_has_a_spread(files, capsys):
    """``--repeats``: the speed-up is the median of whole side-by-side comparisons, with their
    range and a bootstrap interval over frame pairs; the noise of the original's times is there,
    and a run noisier than 10% says so on stderr and in ``reliable``."""
    shader, session = files
    node = _final_node(shader, session, capsys)
    main(["render", str(shader), str(session), "--node", node, "--period", "4", "--frames", "8", "--repeats", "3",
          "--json"])
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert doc["repeats"] == 3 and len(doc["speedup_repeats"]) == 3
    lo, hi = doc["speedup_range"]
    assert lo <= doc["speedup"] <= hi and sorted(doc["speedup_repeats"])[1] == doc["speedup"]
    ci_lo, ci_hi = doc["speedup_ci95"]
    assert 0 < ci_lo <= ci_hi and doc["noise"] >= 0 and doc["color_format"] == "rgba8"
    assert doc["reliable"] == (doc["noise"] <= 0.1 and "unreliable" not in captured.err)


def test_render_unknown_node_is_a_clear_error(files, capsys):
    shader, session = files
    with pytest.raises(SystemExit) as info:
        main(["render", str(shader), str(session), "--node", "n999999"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "n999999" in err and "rrcache nodes" in err and "Traceback" not in err


def test_instance_writes_every_pass_and_a_manifest(files, tmp_path, capsys):
    shader, session = files
    node = _final_node(shader, session, capsys)
    out = tmp_path / "variant"
    main(["instance", str(shader), "--node", node, "--period", "12", "--session", str(session), "--out", str(out)])
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["period"] == 12 and manifest["node"]["id"] == node
    for name in ("reproject", "payload", "shade"):
        assert (out / f"{name}.frag").read_text().startswith("#version 330")
        assert (out / f"{name}.vert").exists()
    assert "u_gain" in manifest["uniforms"]


def test_bench_cache_measures_every_configuration(files, capsys):
    """``rrcache bench-cache`` on a tiny scene: every configuration measured ``--repeats``
    times (the row is the median repeat, its range around it), the no-refresh row hits at
    least as often as the refreshed one, and the all-hit limit is there."""
    shader, session = files
    node = _final_node(shader, session, capsys)
    main(["bench-cache", str(shader), str(session), "--node", node, "--frames", "3", "--periods", "2",
          "--compare-period", "2", "--repeats", "2", "--resolution", "32x24", "--json"])
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert [r["label"] for r in doc["periods"]] == ["Δn=2"]
    assert [r["algorithm"] for r in doc["algorithms"]] == ["three-pass", "two-pass", "one-pass"]
    assert [r["block"] for r in doc["blocks"]] == [1, 2, 4]
    for row in doc["periods"] + doc["algorithms"] + doc["blocks"] + [doc["no_refresh"]]:
        lo, hi = row["speedup_range"]
        assert 0 < lo <= row["speedup"] <= hi
        assert row["ms_per_frame"] > 0 and row["original_ms_per_frame"] > 0
    assert doc["no_refresh"]["hit_rate"] >= doc["periods"][0]["hit_rate"]
    assert doc["limit_speedup"] > 0 and doc["limit_ms"] > 0
    assert [r["filter"] for r in doc["filters"]] == ["bilinear", "edge", "plane"]
    assert captured.err.count("[2/2]") == 1 + 3 + 3 + 1 + 3 and "limit: every pixel hits" in captured.err
    assert doc["color_format"] == "rgba8"
    # each filter's misses sorted by cause: they add up to the missing pixels of its run
    assert [m["filter"] for m in doc["misses"]] == ["bilinear", "edge", "plane"]
    for m in doc["misses"]:
        missing = sum(m["pixels"].values())
        assert m["covered"] > 0 and abs(missing / m["covered"] - (1 - m["hit_rate"])) < 1e-9
        assert 0 < sum(m["blocks"].values()) <= m["covered_blocks"]
        assert m["pixels"]["refresh"] > 0   # Δn = 2 refreshes half the blocks


def test_bench_cache_breakdown(files, capsys):
    """``--breakdown``: the all-hit frame stage by stage, per algorithm and colour format, with
    each stage's fixed cost at 8×8 and its cost per covered pixel, beside the original's."""
    shader, session = files
    node = _final_node(shader, session, capsys)
    main(["bench-cache", str(shader), str(session), "--node", node, "--frames", "3", "--breakdown", "--repeats", "1",
          "--json"])
    doc = json.loads(capsys.readouterr().out)
    configs = [(r["algorithm"], r["color_format"]) for r in doc["rows"]]
    assert configs == [("three-pass", "rgba32f"), ("three-pass", "rgba8"), ("two-pass", "rgba32f"),
                       ("two-pass", "rgba8")]
    for row in doc["rows"]:
        passes = ("reproject", "payload", "shade") if row["algorithm"] == "three-pass" else ("hit", "miss")
        assert set(row["cached"]["full_ms"]) == {"clear", *passes, "queries", "read-back"}
        assert set(row["original"]["full_ms"]) == {"clear", "draw", "queries", "read-back"}
        assert all(v >= 0 for v in row["cached"]["per_pixel_ns"].values())
        assert row["cached"]["pixels"] > 0 and row["cached"]["plain_ms"] > 0 and row["original"]["plain_ms"] > 0


def test_bench_cache_leaves_out_the_groups_given_empty_but_not_all(files, capsys):
    """``--periods ''`` (and the other lists) leaves that group of rows out; with every group out
    there is nothing to compare: one line, exit 2."""
    shader, session = files
    node = _final_node(shader, session, capsys)
    base = ["bench-cache", str(shader), str(session), "--node", node, "--frames", "3", "--repeats", "1",
            "--resolution", "32x24", "--compare-period", "2", "--periods", "", "--algorithms", "", "--blocks", ""]
    main(base + ["--filters", "plane", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert doc["periods"] == doc["algorithms"] == doc["blocks"] == [] and doc["no_refresh"] is None
    assert [r["filter"] for r in doc["filters"]] == ["plane"] and [m["filter"] for m in doc["misses"]] == ["plane"]
    with pytest.raises(SystemExit) as info:
        main(base + ["--filters", ""])
    assert info.value.code == 2 and "nothing to compare" in capsys.readouterr().err
