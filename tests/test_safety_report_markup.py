"""report.html with markup everywhere a profile carries text (issue 30): a shader whose source and
file name hold ``<!--<script>``, ``</script>`` and ``&``, a session file named the same way and a
node text with a comment opener. The page is loaded in the real headless Chromium of
:mod:`rrcache.report.browser`: its own script must still run (the chart draws, a click shows a
node), the markup must show as text, and nothing in it may become an element.

Before the data block escaped ``<``, ``>`` and ``&``, ``<!--<script>`` in any of them put the
HTML parser in its "script data escaped" state: the report's own script was swallowed, the chart
stayed empty and hover and click were dead.
"""
from __future__ import annotations

import hashlib
import json
import shutil

import pytest

from rrcache.profiler import demo_profile
from rrcache.profiles import load_profile
from rrcache.report import write_report
from rrcache.report.browser import Chromium, find_chromium
from rrcache.report.html import script_json
from rrcache.session import load_session

pytestmark = pytest.mark.skipif(find_chromium() is None,
                                reason="chromium is not installed (Debian: apt-get install -y chromium; .ci/run does)")

#: the text that broke the page: a comment opener, a script tag, a script end tag, an entity
MARKUP = "<!--<script>document.title='pwned'</script> &amp; ]]> <b id=injected>x</b>"
#: file names cannot hold '/': the same markup without the end tag's slash
NAME_MARKUP = "<!--<script>&amp;<b id=injected2>"


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    return demo_profile(tmp_path_factory.getbasetemp() / "demo.rrprofile")


@pytest.fixture(scope="module")
def page(demo, tmp_path_factory):
    """The demo profile with markup in its shader's source and file name, its session's file
    name and name, and a node's text; its report written and loaded in Chromium."""
    folder = tmp_path_factory.mktemp("markup")
    shader = folder / f"shader {NAME_MARKUP}.glsl"
    shader.write_text(open(demo.shader, encoding="utf-8").read() + f"// {MARKUP}\n")
    doc = json.loads(open(demo.session, encoding="utf-8").read())
    doc["name"] = MARKUP
    session = folder / f"session {NAME_MARKUP}.json"
    session.write_text(json.dumps(doc))
    prof_dir = folder / "profile"
    shutil.copytree(demo.path, prof_dir)
    prof = load_profile(prof_dir)
    prof.shader, prof.session = str(shader), str(session)
    # the profile of that shader: its recorded content hash is the new file's
    prof.shader_files = [{"path": str(shader), "sha256": hashlib.sha256(shader.read_bytes()).hexdigest()}]
    prof.session_hash = load_session(session).hash
    node = prof.trained_nodes[0]
    node.text = f"{node.text} /* {MARKUP} */"
    path = write_report(prof, prof_dir)
    with Chromium(width=1280, height=1000) as chromium:
        chromium.open(path)
        yield chromium, prof, node, path


def test_data_block_has_no_raw_markup():
    text = script_json({"source": [MARKUP], "name": NAME_MARKUP})
    assert not set("<>&") & set(text)
    assert json.loads(text) == {"source": [MARKUP], "name": NAME_MARKUP}


def test_report_script_runs_with_markup_everywhere(page):
    browser, prof, node, path = page
    assert browser.evaluate("document.readyState") == "complete"
    assert browser.errors() == [] and browser.requests() == []
    # the report's own script ran: the chart has its points and the page its function
    assert browser.evaluate("document.querySelectorAll('#chart .pt').length") > 0
    assert browser.evaluate("typeof window.rrShowNode") == "function"
    # exactly the page's two scripts, and nothing from the markup became an element
    assert browser.evaluate("document.scripts.length") == 2
    assert browser.evaluate("document.querySelectorAll('#injected, #injected2').length") == 0
    assert "pwned" not in browser.evaluate("document.title")
    # the file names show as text in the title and the header
    assert NAME_MARKUP in browser.evaluate("document.title")
    header = browser.evaluate("document.querySelector('header').innerText")
    assert f"shader {NAME_MARKUP}.glsl" in header and f"session {NAME_MARKUP}.json" in header
    html = path.read_text(encoding="utf-8")
    data = html.split('<script id="rr-data" type="application/json">', 1)[1].split("</script>", 1)[0]
    assert "<" not in data and ">" not in data and "&" not in data


def test_markup_shows_as_text_in_source_and_details(page):
    browser, prof, node, _ = page
    last = len(open(prof.shader, encoding="utf-8").read().splitlines())
    assert MARKUP in browser.evaluate(f"document.getElementById('L{last}').innerText")
    browser.evaluate(f"window.rrShowNode({json.dumps(node.id)})")
    details = browser.evaluate("document.getElementById('details').innerText")
    assert MARKUP in details
    assert browser.evaluate("document.querySelectorAll('#injected, #injected2').length") == 0
    assert browser.errors() == []
