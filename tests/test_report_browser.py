"""report.html in a real browser: Debian's headless Chromium driven over the DevTools protocol
(:mod:`rrcache.report.browser`), networking features off and a fresh profile folder.

- the page loads with no console error, no exception and no network request;
- the chart draws one SVG point per predicted (node, Δn) (the log axis leaves out Δn = 1, whose
  error is 0; the linear axis shows all);
- hovering a point shows the tooltip with its node and Δn; clicking it shows that node's details
  (α, λ, t_hit, t_miss, its source line, measured runs) and marks its line in the source;
- a screenshot is saved as a test artifact (and copied to docs/report.png when
  ``RRCACHE_DOCS_SCREENSHOTS=1``).

CI installs Chromium (.ci/run); without it these tests skip and say so.
"""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from rrcache.profiler import demo_profile
from rrcache.report import REPORT_NAME
from rrcache.report.browser import Chromium, find_chromium

DOCS = Path(__file__).resolve().parent.parent / "docs"

pytestmark = pytest.mark.skipif(find_chromium() is None,
                                reason="chromium is not installed (Debian: apt-get install -y chromium; .ci/run does)")


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The demo profile, shared by the report modules of one test run (made once, then loaded)."""
    return demo_profile(tmp_path_factory.getbasetemp() / "demo.rrprofile")


@pytest.fixture(scope="module")
def browser(demo):
    with Chromium(width=1280, height=1000) as chromium:
        chromium.open(demo.path / REPORT_NAME)
        yield chromium


def _center(browser, selector: str):
    box = browser.evaluate(f"(function () {{ var e = document.querySelector({json.dumps(selector)});"
                           "e.scrollIntoView({block: 'center'}); var r = e.getBoundingClientRect();"
                           "return [r.x + r.width / 2, r.y + r.height / 2]; })()")
    return box


def test_loads_offline_without_errors(browser):
    assert browser.evaluate("document.readyState") == "complete"
    assert browser.errors() == []
    assert browser.requests() == []
    # every image decoded (a broken data URI has naturalWidth 0)
    assert browser.evaluate("Array.from(document.images).every(function (i) { return i.naturalWidth > 0; })")


def test_chart_draws_a_point_per_prediction(browser, demo):

    table = demo.table
    finite = np.isfinite(table.E) & np.isfinite(table.T)
    positive = int((finite & (table.E > 0)).sum())
    assert browser.evaluate("document.querySelectorAll('#chart .pt').length") == positive
    assert browser.evaluate("document.querySelectorAll('#chart .selmark').length") >= 1
    from rrcache.model import pareto_front

    front = browser.evaluate("document.getElementById('front').getAttribute('points').trim().split(' ').length")
    assert front == len(pareto_front(table))
    browser.evaluate("document.querySelector('#yscale button[data-scale=linear]').click()")
    assert browser.evaluate("document.querySelectorAll('#chart .pt').length") == int(finite.sum())
    browser.evaluate("document.querySelector('#yscale button[data-scale=log]').click()")
    assert browser.errors() == []


def test_hover_shows_the_tooltip_and_click_the_node(browser, demo, tmp_path):
    # the 8th point of a path is Δn = 8 (points are Δn = 1..50, all with error > 0 here); two nodes
    # whose curves coincide draw points on top of each other, so hover the first node whose point
    # is the topmost element at its own centre (the one a user's mouse reaches)
    for index, node in enumerate(demo.trained_nodes):
        period = 8
        selector = f'#chart .pt[data-node="{index}"][data-point="{period - 1}"]'
        x, y = _center(browser, selector)
        if browser.evaluate(f"document.elementFromPoint({x}, {y}) === document.querySelector({json.dumps(selector)})"):
            break
    else:
        pytest.fail("every node's Δn = 8 point is covered by another node's point")
    browser.mouse("move", x, y)
    tip = browser.evaluate("[getComputedStyle(document.getElementById('tooltip')).display,"
                           " document.getElementById('tooltip').textContent]")
    assert tip[0] == "block" and node.id in tip[1] and f"Δn = {period}" in tip[1] and "ms" in tip[1]
    browser.mouse("click", x, y)
    details = browser.evaluate("document.getElementById('details').innerText")
    assert browser.evaluate("document.getElementById('details').getAttribute('data-node')") == node.id
    for label in ("α", "λ", "t_hit", "t_miss", "call chain", "measured error runs"):
        assert label in details
    source_line = Path(demo.shader).read_text().splitlines()[node.line - 1].strip()
    assert source_line in details
    assert browser.evaluate(f"document.getElementById('L{node.line}').classList.contains('focus')")
    rows = browser.evaluate("document.querySelectorAll('#details table.runs tr').length")
    assert rows == len(node.periods) + 1
    # the screenshot: chart with the tooltip and the details, the summary above
    browser.evaluate("window.scrollTo(0, 0)")
    box = browser.evaluate(f"(function () {{ var r = document.querySelector({json.dumps(selector)})"
                           ".getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]; })()")
    browser.mouse("move", *box)
    shot = browser.screenshot(tmp_path / "report.png")
    image = Image.open(shot)
    assert image.size == (1280, 1000)
    assert len(np.unique(np.asarray(image.convert("L").resize((64, 50))))) > 20  # not a blank page
    if os.environ.get("RRCACHE_DOCS_SCREENSHOTS") == "1":
        shutil.copyfile(shot, DOCS / "report.png")
    assert browser.errors() == [] and browser.requests() == []


def test_source_line_click_shows_its_node(browser, demo):
    node = demo.trained_nodes[-1]
    line = browser.evaluate(f"document.getElementById('L{node.line}').getAttribute('data-node')")
    x, y = _center(browser, f"#L{node.line}")
    browser.mouse("click", x, y)
    assert browser.evaluate("document.getElementById('details').getAttribute('data-node')") == line
    assert line in {n.id for n in demo.nodes if n.line == node.line}
