"""The WebGL2 target (``rrcache instance ... --target webgl2``) in a real browser: Debian's
headless Chromium with WebGL2 on the CPU (ANGLE over SwiftShader, :data:`rrcache.report.browser.
WEBGL_FLAGS`), driven over the DevTools protocol.

For each algorithm the page compiles every pass, draws non-blank frames, makes no network
request, and at Δn = 1 (every pixel recomputed each frame) the cached image equals the original;
at a longer period the cache hits and the image stays close. A profile's level is written with
the profile's algorithm, and Marble's e3 choice (its node, period and algorithm recorded in
docs/webgl_marble_e3.json by the profile run of docs/webgl.md) renders like the original. What
the page cannot run is refused with one line.

CI installs Chromium (.ci/run); without it these tests skip and say so.
"""
from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from rrcache.cli import main
from rrcache.profiler import demo_profile
from rrcache.profiler.demo import DEMO_SESSION, DEMO_SHADER
from rrcache.report.browser import Chromium, find_chromium

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"

pytestmark = pytest.mark.skipif(find_chromium() is None,
                                reason="chromium is not installed (Debian: apt-get install -y chromium; .ci/run does)")


@pytest.fixture(scope="module")
def browser():
    with Chromium(width=1100, height=700, webgl=True, timeout=120) as chromium:
        yield chromium


def _node(shader, session, capsys) -> str:
    """The costliest cacheable node of ``shader``."""
    main(["nodes", str(shader), "--session", str(session), "--json", "--sort", "cost"])
    return json.loads(capsys.readouterr().out)["nodes"][0]["id"]


def _page(out: Path, browser, query: str):
    browser.open(out / "index.html", query)
    assert browser.evaluate("window.rrcache && window.rrcache.ready") is True, browser.evaluate(
        "window.rrcache ? window.rrcache.errors.join('\\n') : 'no runtime'")
    assert browser.evaluate("window.rrcache.errors") == []
    return browser.evaluate("window.rrcache.size")


def _frames(browser, size, frames):
    """Render ``frames`` in order; the (original, cached) RGBA8 images of each."""
    w, h = size
    out = []
    for f in frames:
        browser.evaluate(f"window.rrcache.step({f}) && 0")
        images = [np.array(browser.evaluate(f"window.rrcache.pixels('{which}')"), np.uint8).reshape(h, w, 4)
                  for which in ("original", "cached")]
        out.append(images)
    return out


def _psnr(original: np.ndarray, cached: np.ndarray) -> float:
    """PSNR of the cached RGB against the original's (inf when equal)."""
    mse = float(((original[..., :3] / 255.0 - cached[..., :3] / 255.0) ** 2).mean())
    return math.inf if mse == 0 else 10.0 * math.log10(1.0 / mse)


def _harness_image(shader, session_path, size, frame: int) -> np.ndarray:
    """Frame ``frame`` as ``rrcache render`` draws it (rgba8, row 0 = the bottom, as readPixels)."""
    from rrcache.harness.renderer import render
    from rrcache.pipeline import load_for_session
    from rrcache.session import load_session

    session = load_session(session_path)
    prepared = load_for_session(shader, session).prepared
    result = render(prepared, session, [frame], resolution=tuple(size), color_format="rgba8")
    return np.round(np.clip(result.frames[0].image, 0, 1) * 255).astype(np.uint8)[::-1]


def _non_blank(image: np.ndarray, background) -> float:
    """The share of pixels that are not the background (what the geometry covered)."""
    bg = np.round(np.asarray(background[:3]) * 255)
    return float((np.abs(image[..., :3].astype(int) - bg).max(axis=-1) > 2).mean())


@pytest.mark.parametrize("algorithm", ["three-pass", "two-pass", "one-pass"])
def test_page_matches_the_original_at_period_one(algorithm, browser, tmp_path, capsys):
    node = _node(DEMO_SHADER, DEMO_SESSION, capsys)
    out = tmp_path / algorithm
    main(["instance", str(DEMO_SHADER), "--node", node, "--period", "6", "--algorithm", algorithm, "--session",
          str(DEMO_SESSION), "--target", "webgl2", "--out", str(out)])
    said = capsys.readouterr().out
    assert "index.html" in said
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["target"] == "webgl2" and manifest["algorithm"] == algorithm and manifest["period"] == 6
    for name in list(manifest["passes"]) + ["original"]:
        for ext in ("vert", "frag"):
            assert (out / f"{name}.{ext}").read_text().startswith("#version 300 es\nprecision highp float;")
    size = _page(out, browser, "?autoplay=0&size=64x48&period=1")
    assert size == [64, 48]
    background = json.loads((ROOT / DEMO_SESSION).read_text()).get("background", [0, 0, 0, 0])
    frames = _frames(browser, size, range(4))
    if algorithm == "three-pass":  # the page draws what rrcache render draws (another rasterizer: close)
        assert _psnr(_harness_image(DEMO_SHADER, DEMO_SESSION, size, 3), frames[3][0]) >= 30.0
    for original, cached in frames:
        assert _non_blank(original, background) > 0.1
        assert len(np.unique(original.reshape(-1, 4), axis=0)) > 50  # shaded, not flat
        diff = np.abs(original.astype(int) - cached.astype(int))
        assert diff.max() <= 2 and diff.mean() < 0.05, (diff.max(), diff.mean())
    assert browser.errors() == [] and browser.requests() == []


def test_page_draws_what_the_harness_draws_with_textures(browser, tmp_path, capsys):
    """examples/wood: an 8-bit RGB texture with mipmaps (WebGL2 makes no mipmaps of RGB8: the
    page uploads RGBA), an include, a struct, an animated uniform: the page's original is the
    harness's frame, and the cached image the original at Δn = 1."""
    shader, session = ROOT / "examples/wood/wood.frag", ROOT / "examples/wood/wood.json"
    node = _node(shader, session, capsys)
    out = tmp_path / "wood"
    main(["instance", str(shader), "--node", node, "--session", str(session), "--target", "webgl2",
          "--out", str(out)])
    capsys.readouterr()
    size = _page(out, browser, "?autoplay=0&size=80x60&period=1")
    frames = _frames(browser, size, range(3))
    assert _psnr(_harness_image(shader, session, size, 2), frames[2][0]) >= 30.0
    assert all(np.abs(o.astype(int) - c.astype(int)).max() <= 2 for o, c in frames)
    assert browser.errors() == [] and browser.requests() == []
    # each label over its half of a canvas narrower than the page (the labels spread over the
    # page's width before)
    left = browser.evaluate("[document.getElementById('view').getBoundingClientRect()]"
                            ".concat([...document.querySelectorAll('.labels span')].map(s => s.getBoundingClientRect()))"
                            ".map(r => [r.left, r.width])")
    (canvas_left, canvas_width), (original_left, _), (cached_left, _) = left
    assert canvas_width == 160 and original_left == canvas_left
    assert abs(cached_left - (canvas_left + canvas_width / 2)) <= 1


def test_page_caches_at_a_longer_period(browser, tmp_path, capsys):
    node = _node(DEMO_SHADER, DEMO_SESSION, capsys)
    out = tmp_path / "p6"
    main(["instance", str(DEMO_SHADER), "--node", node, "--period", "6", "--session", str(DEMO_SESSION),
          "--target", "webgl2", "--out", str(out)])
    capsys.readouterr()
    size = _page(out, browser, "?autoplay=0&size=64x48")
    assert browser.evaluate("window.rrcache.stats().period") == 6
    frames = _frames(browser, size, range(6))
    first = np.abs(frames[0][0].astype(int) - frames[0][1].astype(int))
    assert first.max() <= 2  # frame 0 has no cache: computed everywhere
    # reused values: the image is not the original's exactly, but close to it
    psnrs = [_psnr(o, c) for o, c in frames[1:]]
    assert all(math.isfinite(p) for p in psnrs) and min(psnrs) >= 28.0, psnrs
    browser.evaluate("window.rrcache.setPeriod(1)")
    assert browser.evaluate("window.rrcache.stats().period") == 1


def test_profile_level_page_uses_the_profiles_algorithm(browser, tmp_path_factory, tmp_path, capsys):
    demo = demo_profile(tmp_path_factory.getbasetemp() / "demo.rrprofile")
    sel = next(s for s in demo.selections if s.parts)
    out = tmp_path / "level"
    main(["instance", str(demo.path), "--level", sel.label, "--target", "webgl2", "--out", str(out)])
    capsys.readouterr()
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["algorithm"] == (sel.algorithm or demo.algorithm) and manifest["period"] == sel.period
    assert manifest["runtime"] == demo.settings.cache_options()
    size = _page(out, browser, "?autoplay=0&size=64x48&period=1")
    for original, cached in _frames(browser, size, range(2)):
        assert np.abs(original.astype(int) - cached.astype(int)).max() <= 2


def test_marble_e3_page(browser, tmp_path, capsys):
    """Marble's e3 choice as its profile chose it (docs/webgl_marble_e3.json): the page compiles,
    draws the marble, equals the original at Δn = 1 and stays close at the chosen period; its
    screenshot is docs/webgl_marble_e3.png (RRCACHE_DOCS_SCREENSHOTS=1 writes it again, at the
    session's full size)."""
    record = json.loads((DOCS / "webgl_marble_e3.json").read_text())
    out = tmp_path / "marble-e3"
    main(["instance", "shaders/marble.glsl", "--node", record["node"], "--period", str(record["period"]),
          "--algorithm", record["algorithm"], "--session", "sessions/marble.json", "--target", "webgl2",
          "--out", str(out)])
    capsys.readouterr()
    docs = os.environ.get("RRCACHE_DOCS_SCREENSHOTS") == "1"
    size = _page(out, browser, "?autoplay=0&period=1" + ("" if docs else "&size=160x120"))
    background = json.loads((ROOT / "sessions/marble.json").read_text())["background"]
    frames = _frames(browser, size, range(2))
    assert _psnr(_harness_image("shaders/marble.glsl", "sessions/marble.json", size, 1), frames[1][0]) >= 30.0
    for original, cached in frames:
        assert _non_blank(original, background) > 0.1
        assert np.abs(original.astype(int) - cached.astype(int)).max() <= 2
    browser.evaluate(f"window.rrcache.setPeriod({record['period']})")
    frames = _frames(browser, size, range(6))  # back to frame 0: the cache starts empty
    psnrs = [_psnr(o, c) for o, c in frames[1:]]
    # the cache is used (the image is not the original's) and stays close to it (at 160×120 the
    # reprojection blur is four times the session's: 30 dB after 5 frames where 640×480 keeps 36)
    assert all(math.isfinite(p) for p in psnrs) and min(psnrs) >= 28.0, psnrs
    browser.evaluate("window.scrollTo(0, 0)")
    shot = browser.screenshot(tmp_path / "webgl_marble_e3.png")
    image = Image.open(shot)
    assert len(np.unique(np.asarray(image.convert("L").resize((110, 70))))) > 20  # not a blank page
    if docs:
        shutil.copyfile(shot, DOCS / "webgl_marble_e3.png")
    assert browser.errors() == [] and browser.requests() == []


def test_what_the_page_cannot_run_is_refused(tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        main(["instance", "shaders/pcf_shadows.glsl", "--estimator", "e1", "--session", "sessions/temple.json",
              "--target", "webgl2", "--out", str(tmp_path / "amortized")])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "WebGL2" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    with pytest.raises(SystemExit) as info:
        main(["instance", str(DEMO_SHADER), "--node", "n1", "--target", "webgl2", "--out", str(tmp_path / "x")])
    assert info.value.code == 2 and "needs --session" in capsys.readouterr().err
