"""Resource budgets (issue 16): deep expressions go through every pass (no RecursionError), a
program beyond the analysis budgets is refused with one clear line, textures are decoded only
when sampled, ``render`` streams its frames, and the per-frame watchdog stops a runaway shader
with what was done kept."""
from __future__ import annotations

import json
import tracemalloc

import numpy as np
import pytest

from rrcache.analysis.cacheable import cacheable_nodes
from rrcache.budgets import budget, reset_budget
from rrcache.errors import GLSLError
from rrcache.glsl.frontend import parse_shader
from rrcache.glsl.parser import parse_source
from rrcache.glsl.printer import print_glsl
from safety_cli import SESSION, one_error_line, rrcache, session, write_case

AREA = "safety: resource budgets"


def _chain(n: int, first: str = "u_time") -> str:
    return ("#version 330\nuniform float u_time;\nin vec3 v_normal;\nout vec4 c;\nvoid main() {\n"
            f"  float a = {first}" + " + 1.0" * n + ";\n  c = vec4(a);\n}\n")


@pytest.fixture(autouse=True)
def _defaults():
    reset_budget()
    yield
    reset_budget()


def test_100k_term_chain_parses_and_prints(stability_case):
    source = _chain(100_000)
    case = stability_case("100,000-term left-associative chain: parse and print", AREA,
                          "float a = u_time + 1.0 + ... (100,000 terms)")
    unit = parse_source(source, "chain.frag")
    text = print_glsl(unit)
    again = print_glsl(parse_source(text, "again.frag"))  # (== on the trees would recurse 100k deep)
    case.observe(printed_chars=len(text), reprint_identical=again == text)
    assert text.count("+ 1.0") == 100_000 and again == text


def test_deep_chain_through_every_pass():
    """5,000 levels (five times Python's default recursion limit) through the front-end, the
    analysis and the compiler; the node texts are abbreviated, not quadratic."""
    from rrcache.compiler import instance

    shader = parse_shader(_chain(5_000, "v_normal.x"), "deep.frag")
    table = cacheable_nodes(shader)
    assert table.nodes, "the chain depends on v_normal: some node is cacheable"
    node = max(table.nodes, key=lambda n: n.cost)
    assert len(node.text) < 200 and "nodes ...)" in node.text
    variant = instance(table, node.id, "three-pass")
    assert variant.passes["payload"].fragment.count("+ 1.0") > 4_000  # the cached chain, printed whole


def test_100k_chain_through_rrcache_nodes(tmp_path, stability_case):
    (tmp_path / "chain.frag").write_text(_chain(100_000, "v_normal.x"))
    case = stability_case("100,000-term chain through rrcache nodes", AREA, "rrcache nodes chain.frag --json")
    code, out, lines = rrcache(tmp_path, "nodes", "chain.frag", "--json")
    assert code == 0, lines
    doc = json.loads(out)
    case.observe(exit=code, nodes=len(doc["nodes"]))
    assert doc["nodes"]


def test_depth_and_size_budgets_are_clear_errors(tmp_path, stability_case):
    (tmp_path / "chain.frag").write_text(_chain(3_000))
    case = stability_case("expression depth and analysis size over budget", AREA,
                          "a 3,000-term chain with --max-depth 1000; with --max-ast-nodes 2000; "
                          "--max-source-bytes 1000")
    seen = {}
    for option, value, expected in (("--max-depth", "1000", "nested 3,00"),
                                    ("--max-ast-nodes", "2000", "syntax nodes"),
                                    ("--max-source-bytes", "1000", "larger than 1,000 bytes")):
        code, _, lines = rrcache(tmp_path, option, value, "nodes", "chain.frag")
        line = one_error_line(code, lines)
        seen[option] = line.replace(str(tmp_path), "TMP")
        assert expected in line and option in line and "chain.frag" in line
    case.observe(**seen)


def test_budget_in_process():
    budget.analysis_nodes = 50
    with pytest.raises(GLSLError, match="analysis budget"):
        parse_shader(_chain(40), "b.frag")
    reset_budget()
    budget.expression_depth = 10
    with pytest.raises(GLSLError, match="nested"):
        parse_shader(_chain(40), "b.frag")


# ----------------------------------------------------------------------------- textures

def _png(path, size=(8, 8)):
    import OpenImageIO as oiio
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(size[0], size[1], 3, oiio.UINT8))
    out.write_image(np.full((size[1], size[0], 3), 0.5, np.float32))
    out.close()


def test_textures_decode_only_when_sampled(tmp_path, gl_ctx, stability_case):
    from rrcache.harness.renderer import render
    from rrcache.session import load_session

    _png(tmp_path / "used.png")
    _png(tmp_path / "unused.png")
    shader = ("#version 330\nuniform sampler2D u_used;\nout vec4 c;\n"
              "void main() { c = texture(u_used, vec2(0.5)); }\n")
    frag, sess = write_case(tmp_path, session(textures={"u_used": "used.png", "u_unused": "unused.png"}),
                            shader=shader)
    loaded = load_session(sess)
    case = stability_case("only sampled textures are decoded", AREA, "two textures listed, one sampled")
    before = {n: t.loaded for n, t in loaded.textures.items()}
    result = render(str(frag), loaded, frames=1)
    after = {n: t.loaded for n, t in loaded.textures.items()}
    case.observe(before=str(before), after=str(after))
    assert not any(before.values())
    assert after == {"u_unused": False, "u_used": True}
    assert result.frames[0].image[..., 0].max() == pytest.approx(128 / 255, abs=1e-3)
    budget.image_pixels = 63
    with pytest.raises(Exception, match="texture budget"):
        load_session(sess)


def test_render_streams_frames(tmp_path, gl_ctx, stability_case):
    """Memory of ``render(keep_images=False)`` does not grow with the frame count: 48 frames
    peak no higher than 4 frames plus a little (each 64×64 frame's image and mask are ~70 KB)."""
    from rrcache.harness.renderer import render
    from rrcache.session import load_session

    frag, sess = write_case(tmp_path, session(resolution=[64, 64], frames=48))
    loaded = load_session(sess)
    seen = []
    peaks = {}
    for frames in (4, 48):
        tracemalloc.start()
        result = render(str(frag), loaded, frames=frames, keep_images=False,
                        progress=lambda f: seen.append(f.image.shape))
        peaks[frames] = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert all(f.image is None and f.mask is None for f in result.frames)
        assert len(result.frames) == frames
    case = stability_case("render streams frames", AREA, "render(keep_images=False), 4 and 48 frames at 64×64")
    case.observe(peak_4_frames=peaks[4], peak_48_frames=peaks[48])
    assert len(seen) == 52 and seen[0] == (64, 64, 4)
    assert peaks[48] < peaks[4] + 48 * 70_000 / 4


# ----------------------------------------------------------------------------- watchdog

def test_frame_watchdog_stops_a_runaway_frame(tmp_path, stability_case):
    """Frames 0 and 1 are quick; frame 2 runs a long loop at every pixel of a 512×512 frame (the
    loop count is a session uniform keyframed to 2e9; llvmpipe stops a loop after 65,535
    iterations, which still takes tens of seconds here): the watchdog stops the run after 2 s
    of that frame; frames 0 and 1 stay written."""
    shader = ("#version 330\nuniform float u_n;\nout vec4 c;\nvoid main() {\n  float s = 0.0;\n"
              "  for (int i = 0; i < int(u_n); i++) { s = sin(s + float(i)); }\n  c = vec4(s, 0.5, 0.5, 1.0);\n}\n")
    doc = session(resolution=[512, 512], frames=4,
                  uniforms={"u_n": {"keyframes": [{"frame": 1, "value": 1.0}, {"frame": 2, "value": 2e9}]}})
    write_case(tmp_path, doc, shader=shader)
    case = stability_case("per-frame watchdog", AREA,
                          "rrcache --frame-timeout 2 render, 512×512, frame 2 loops 65,535 times per pixel")
    code, _, lines = rrcache(tmp_path, "--frame-timeout", "2", "render", "scene.frag", "scene.json",
                             "--out", "frames")
    line = one_error_line(code, lines)
    written = sorted(p.name for p in (tmp_path / "frames").iterdir())
    case.observe(exit=code, stderr=line, written=written)
    assert "frame 2" in line and "--frame-timeout" in line and "after 2 finished frames" in line
    assert written == ["frame_0000.exr", "frame_0000.png", "frame_0001.exr", "frame_0001.png"]
