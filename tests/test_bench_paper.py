"""``rrcache bench`` on a tiny scene: an icosphere at 64×48, 16 frames, a noise shader whose
octave loop runs a uniform number of times (so a pixel is costly but the program has only a
few cacheable nodes: the loop is not unrolled and its inside is dynamic).

- scene lists: the paper's names, SHADER:SESSION pairs, and their errors;
- scaled sessions: absolute asset paths, the requested size and frames, not rewritten when equal;
- the whole bench through the CLI (``--quick --json``) for the shape only (timings are never
  asserted), bench.json and bench.md written; a second run resumes the profile;
- an interrupted two-scene run keeps the finished scene in bench.json and exits 130;
- the medium-selection rule.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from child import python_argv

from rrcache.bench import paper
from rrcache.bench.scenes import PAPER_SCENES, Scene, default_root, resolve_scenes, scaled_session
from rrcache.errors import RRCacheError
from rrcache.selection import CachedNode, Selection
from rrcache.session import load_session

from scene_files import WAVE, fragment, moving_camera, session_doc
from scene_files import write_scene as write_files

SHADER = fragment("""void main() {
    vec3 p = v_objectPosition * u_scale;
    float n = 0.5;
    float amp = 0.25;
    float f = 1.0;
    for (int i = 0; i < u_octaves; i++) { n += amp * wave(p, f); f *= 1.13; amp *= 0.97; }
    vec3 albedo = mix(vec3(0.9, 0.8, 0.6), vec3(0.3, 0.2, 0.1), n);
    vec3 nrm = normalize(v_normal);
    vec3 l = normalize(u_light - v_position.xyz);
    float diffuse = max(dot(nrm, l), 0.0);
    fragColor = vec4(albedo * (0.2 + 0.8 * diffuse), 1.0);
}
""", WAVE, uniforms=("int u_octaves",))

SESSION = session_doc(frames=16, camera=moving_camera(16, (0, 0.4, 2.4), (0.8, 0.5, 2.2)),
                      uniforms={"u_scale": 3.0, "u_octaves": 100})

SCENE_KEYS = {"name", "cacheable_nodes", "precompute_s", "original_ms", "limit_speedup", "selections"}
#: a bench selection is the profile's Selection record (rrcache.selection), measured again
SELECTION_KEYS = {"label", "max_error", "parts", "algorithm", "predicted_speedup", "measured_speedup",
                  "measured_error", "measured_psnr", "speedups"}


def write_scene(folder, name="noise"):
    return write_files(folder, SHADER, SESSION, f"{name}.frag", f"{name}.json")


def rrcache(*args, timeout=240):
    env = dict(os.environ, LP_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    return subprocess.run([sys.executable, "-m", "rrcache", *map(str, args)], capture_output=True, text=True,
                          env=env, timeout=timeout)


# ---------------------------------------------------------------- scenes
def test_resolve_scenes(tmp_path):
    names = [s.name for s in resolve_scenes("marble,trashcan,chess,temple")]
    assert names == list(PAPER_SCENES)
    shader, session = write_scene(tmp_path)
    (scene,) = resolve_scenes(f"{shader}:{session}")
    assert scene == Scene("noise", str(shader), str(session))
    with pytest.raises(RRCacheError, match="unknown scene 'marbel'"):
        resolve_scenes("marbel")
    with pytest.raises(RRCacheError, match="no such file"):
        resolve_scenes(f"{tmp_path / 'none.frag'}:{session}")
    with pytest.raises(RRCacheError, match="twice"):
        resolve_scenes("chess,chess")
    with pytest.raises(RRCacheError, match="no scene"):
        resolve_scenes(" , ")


def test_scaled_session_loads_from_elsewhere(tmp_path):
    source = default_root() / PAPER_SCENES["trashcan"][1]
    out = scaled_session(source, tmp_path / "deep" / "trashcan.json", (40, 30), 12)
    doc = json.loads(out.read_text())
    assert all(os.path.isabs(t["path"]) for t in doc["textures"].values())
    session = load_session(out)
    assert tuple(session.resolution) == (40, 30) and session.frames == 12
    assert set(session.textures) == set(load_session(source).textures)
    stamp = out.stat().st_mtime_ns
    time.sleep(0.01)
    scaled_session(source, out, (40, 30), 12)
    assert out.stat().st_mtime_ns == stamp  # unchanged content is not rewritten: profiles keyed on it resume


# ---------------------------------------------------------------- end to end
@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bench")
    shader, session = write_scene(folder)
    proc = rrcache("bench", "--quick", "--scenes", f"{shader}:{session}", "--out", folder / "out", "--json")
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout), folder, shader, session


def test_json_shape(quick_run):
    doc, _, _, _ = quick_run
    assert doc["quick"] is True and doc["rrcache_bench"] == 1
    (scene,) = doc["scenes"]
    assert SCENE_KEYS <= set(scene), SCENE_KEYS - set(scene)
    assert scene["name"] == "noise" and scene["cacheable_nodes"] >= 2
    assert scene["static_cost"] > 0 and scene["precompute_s"] > 0 and scene["original_ms"] > 0
    assert scene["precompute_resumed"] is False
    assert [s["label"] for s in scene["selections"]] == ["e1", "e2", "e3", "e4"]
    for sel in scene["selections"]:
        assert SELECTION_KEYS <= set(sel)
        assert sel["measured_speedup"] > 0 and sel["measured_error"] >= 0 and 0 < sel["measured_psnr"] <= 100
        assert all(part["kind"] == "cache" and part["period"] >= 1 for part in sel["parts"])
        assert len(sel["speedups"]) == (1 if sel["parts"] else 0)  # QUICK: one side-by-side run
    if scene["medium"] is not None:  # something is cached at some level
        assert scene["limit_speedup"] > 0
        assert [a["method"] for a in scene["algorithms"]] == ["three-pass", "two-pass", "one-pass"]
        if scene["equal_time"]:
            methods = [r["method"] for r in scene["equal_time"]]
            assert methods[0] == "reprojection cache (ours)" and "dynamic resolution" in methods
            assert paper.RENDER_CACHE in methods or any("render cache" in n for n in scene["notes"])
            for row in scene["equal_time"]:
                assert row["speedup"] > 0 and row["mean_error"] >= 0 and 0 < row["psnr"] <= 100
        else:
            assert any("no equal-time" in n for n in scene["notes"])


def test_files_written(quick_run):
    doc, folder, _, _ = quick_run
    out = folder / "out"
    stored = json.loads((out / "bench.json").read_text())
    assert stored["scenes"][0]["name"] == doc["scenes"][0]["name"]
    md = (out / "bench.md").read_text()
    assert "quick run" in md and "| scene | static cost | cacheable nodes |" in md
    assert "| e3 |" in md
    assert (out / "noise.rrprofile" / "profile.json").exists()
    figure = out / doc["scenes"][0]["figure"]
    assert figure.name == "noise-error-time.png" and figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"]({figure.name})" in md


def test_second_run_resumes_the_profile(quick_run):
    doc, folder, shader, session = quick_run
    again = paper.run([Scene("noise", str(shader), str(session))], paper.QUICK, folder / "out")
    (scene,) = again.scenes
    assert scene.precompute_resumed
    first = doc["scenes"][0]
    assert scene.training_s == pytest.approx(first["training_s"], rel=1e-6)  # nothing new was trained
    assert scene.precompute_s >= first["precompute_s"]  # the resumed invocation adds its own time
    assert [s.key for s in scene.selections] == [
        tuple((p["kind"], p["node"], p["period"]) for p in s["parts"]) for s in doc["scenes"][0]["selections"]]


def test_interrupted_run_keeps_finished_scenes(tmp_path):
    first = write_scene(tmp_path, "first")
    second = write_scene(tmp_path, "second")
    out = tmp_path / "out"
    env = dict(os.environ, LP_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(python_argv(["-m", "rrcache", "bench", "--quick", "--out", out, "--scenes",
                                         f"{first[0]}:{first[1]},{second[0]}:{second[1]}"], sigint_default=True),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.time() + 180
    while not (out / "bench.json").exists() and proc.poll() is None and time.time() < deadline:
        time.sleep(0.05)
    assert proc.poll() is None, proc.communicate()[1]
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    if proc.returncode == 0:
        pytest.skip("the second scene finished before the interrupt arrived")
    assert proc.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    doc = json.loads((out / "bench.json").read_text())
    assert [s["name"] for s in doc["scenes"]] == ["first"]


def test_bad_scene_is_one_line_exit_2(tmp_path):
    proc = rrcache("bench", "--quick", "--scenes", "nosuchscene", "--out", tmp_path / "out", timeout=60)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "unknown scene 'nosuchscene'" in lines[0] and "Traceback" not in proc.stderr


# ---------------------------------------------------------------- the medium selection
def _row(label, node):
    parts = (CachedNode(node, 8, f"text of {node}"),) if node else ()
    return Selection(parts, 0.01, 1.0, 1.5, label=label, max_error=0.01).with_measurement(0.01, 40.0, 1.0, 1.5, 1.5,
                                                                                           0.9, 10)


def test_medium_is_e3_or_the_nearest_cached():
    rows = [_row("e1", "n1"), _row("e2", "n2"), _row("e3", "n3"), _row("e4", "n4")]
    assert paper._choose_medium(rows).label == "e3"
    rows[2] = _row("e3", None)
    assert paper._choose_medium(rows).label == "e4"
    rows[3] = _row("e4", None)
    assert paper._choose_medium(rows).label == "e2"
    assert paper._choose_medium([_row(label, None) for label in ("e1", "e2", "e3", "e4")]) is None


def test_quick_settings_shrink_chess_further():
    chess = paper.QUICK.for_scene("chess")
    marble = paper.QUICK.for_scene("marble")
    assert chess.resolution[0] * chess.resolution[1] < marble.resolution[0] * marble.resolution[1]
    assert chess.quick and chess.scene_overrides == {}


def test_effective_session_fits_the_size_and_keeps_the_aspect(tmp_path):
    shader, session = write_scene(tmp_path)
    scene = Scene("noise", str(shader), str(session))
    path = paper._effective_session(scene, paper.BenchSettings(resolution=(40, 40), frames=10), tmp_path / "out")
    scaled = load_session(path)
    assert tuple(scaled.resolution) == (40, 30) and scaled.frames == 10
    assert paper._effective_session(scene, paper.BenchSettings(), tmp_path / "out") == str(session)
    assert paper._effective_session(scene, paper.BenchSettings(resolution=(640, 480), frames=99),
                                    tmp_path / "out") == str(session)


def test_the_scene_table_shows_several_nodes_and_an_estimator():
    """A selection of several nodes (each at its own Δn) and an amortized one both get their row
    (the bench stopped at writing bench.md when Marble's e2 cached two nodes)."""
    from rrcache.bench.paper_report import scene_markdown
    from rrcache.selection import AmortizedLoop

    pair = Selection((CachedNode("n1", 50, text="noise(p)"), CachedNode("n2", 4, text="albedo * light")),
                     0.01, 2.0, 3.0).replace(label="e2", max_error=0.0036, measured_speedup=3.1, measured_error=0.003,
                                             measured_psnr=44.0)
    amort = Selection((AmortizedLoop("e1", 4, 0.6, "slots", text="for (int i = 0; i < 16; i++)", payload="u8"),),
                      0.001, 2.0, 2.0).replace(label="e1", max_error=0.0005, measured_speedup=2.2)
    scene = paper.SceneResult("temple", "s.glsl", "s.json", (64, 48), 10, 100, 5, selections=[amort, pair])
    text = scene_markdown(scene)
    assert "| e2 | 0.0036 | `noise(p) + albedo * light` | 50 + 4 | 3.10× |" in text
    assert "| e1 | 0.0005 | `e1 m=4 λ=0.6 slots/frame u8: for (int i = 0; i < 16; i++)` | – | 2.20× |" in text


def test_paper_size_measures_the_shipped_selections_again(quick_run):
    """python -m rrcache.bench.paper_size: the bench's cached selections measured again over the
    scene's session beside the original, each row beside the bench's figures."""
    from rrcache.bench import paper_size

    doc, folder, _, _ = quick_run
    scene = doc["scenes"][0]
    cached = [s for s in scene["selections"] if s["parts"]]
    result = paper_size.run(folder / "out", scenes=("noise",), labels=("e1", "e2", "e3", "e4"), frames=4,
                            progress=lambda *_: None)
    assert [r.label for r in result.rows] == [s["label"] for s in cached]
    for row, sel in zip(result.rows, cached):
        assert row.frames == 4 and row.speedup > 0 and 0 <= row.hit_rate <= 1 and 0 < row.psnr <= 100
        assert row.bench_speedup == pytest.approx(sel["measured_speedup"])
        assert (row.limit_speedup is not None) == (row.label == scene["medium"])
    assert result.markdown().count("| noise |") == 2 * len(cached)
    assert paper_size.main([str(folder / "nowhere")]) == 2


def test_render_cache_equal_time_measures_the_bench_medium_selection(quick_run, tmp_path):
    """python -m rrcache.bench.render_cache equal-time --bench OUT --scene S: the reprojection
    cache row is the bench's medium selection (compiled with its profile's filter) measured again,
    beside dynamic resolution and the render cache tuned to it; a scene the bench has not measured,
    or whose medium selection caches nothing, is a clear error."""
    import shutil

    from rrcache.bench import render_cache as bench
    from rrcache.pipeline import load_for_session

    doc, folder, shader, session = quick_run
    bench_out = tmp_path / "out"
    shutil.copytree(folder / "out", bench_out)
    scene = doc["scenes"][0]
    scene["profile"] = str(bench_out / "noise.rrprofile")
    work = load_for_session(shader, load_session(session))
    node = max((n for n in work.table.nodes if not n.final), key=lambda n: n.cost)
    # the quick bench's own medium selection depends on its timings (it may cache nothing): set one
    scene["medium"] = "e3"
    e3 = next(s for s in scene["selections"] if s["label"] == "e3")
    e3.update(parts=[{"kind": "cache", "node": node.id, "period": 4}], algorithm="two-pass")
    (bench_out / "bench.json").write_text(json.dumps(doc))
    out = tmp_path / "rc"
    assert bench.main(["equal-time", "--bench", str(bench_out), "--scene", f"{shader}:{session}",
                       "--search-frames", "3", "--out", str(out)]) == 0
    (row,) = json.loads((out / "equal_time.json").read_text())["scenes"]
    assert row["name"] == "noise" and row["frames"] == scene["frames"]
    assert row["choice"].startswith(f"e3: {node.id} Δn=4, two-pass, {scene['filter']} filter")
    assert row["texts"] == [node.text]
    assert [r["method"] for r in row["rows"]] == ["reprojection cache (ours)", "dynamic resolution",
                                                   "render cache (Walter 2002)"]
    assert row["rows"][0]["speedup"] == row["target_speedup"] > 0
    with pytest.raises(RRCacheError, match="no scene 'marble'"):
        bench.equal_time(resolve_scenes("marble")[0], bench_out, out)
    e3["parts"] = []
    (bench_out / "bench.json").write_text(json.dumps(doc))
    with pytest.raises(RRCacheError, match="no medium selection that caches"):
        bench.equal_time(resolve_scenes(f"{shader}:{session}")[0], bench_out, out)
