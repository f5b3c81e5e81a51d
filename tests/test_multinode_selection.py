"""A Selection of several CachedNode parts: compiled by pipeline.variant_for_selection, written
with its periods, and shown as ``n12 Δn=50 + n40 Δn=4`` by the report's data, plots and tables
and by ``rrcache select`` (the demo profile, with one multi-node selection put in)."""
from __future__ import annotations

import copy
import json

import pytest

from rrcache.pipeline import load_for_session, variant_for_selection
from rrcache.profiler.demo import demo_profile
from rrcache.profiles import load_profile
from rrcache.selection import CachedNode, Selection
from rrcache.session import load_session


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    return demo_profile(tmp_path_factory.getbasetemp() / "demo.rrprofile")


def _pair(prof):
    a, b = [n.id for n in prof.trained_nodes[:2]]
    return Selection((CachedNode(a, 50), CachedNode(b, 4)), 0.01, 2.0, 1.5, label="e5", max_error=0.02,
                     algorithm="three-pass")


def test_record_reads_nodes_periods_and_refuses_a_single_node(demo):
    sel = _pair(demo)
    a, b = sel.nodes
    assert sel.multi and sel.periods == (50, 4) and sel.kind == "nodes"
    assert sel.describe() == f"{a} Δn=50 + {b} Δn=4"
    with pytest.raises(Exception, match="no single node"):
        sel.node
    single = Selection((CachedNode(a, 16),), 0.01, 2.0, 1.5)
    assert not single.multi and single.nodes == (a,) and single.describe() == f"{a} Δn=16"


def test_variant_for_selection_compiles_several_nodes(gl_ctx, demo, tmp_path):
    sel = _pair(demo)
    work = load_for_session(demo.shader, load_session(demo.session), demo.defines)
    variant, periods = variant_for_selection(work, sel)
    assert periods == [50, 4] and [n["id"] for n in variant.nodes] == list(sel.nodes)
    variant.write(tmp_path, period=periods)
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert [(n["id"], n["period"]) for n in manifest["nodes"]] == [(sel.nodes[0], 50), (sel.nodes[1], 4)]


def test_report_pieces_show_a_multi_node_selection(demo, tmp_path):
    from rrcache.report.data import chart_data
    from rrcache.report.explore import selections_html, tradeoff_figure
    from rrcache.report.plots import write_plots

    sel = _pair(demo)
    prof = copy.copy(demo)
    prof.selections = list(demo.selections) + [sel]
    data = chart_data(prof)
    row = [s for s in data["selections"] if s["label"] == "e5"][0]
    assert row["node"] == "+".join(sel.nodes) and row["period"] == [50, 4] and row["what"] == sel.describe()
    table = selections_html(prof)
    assert f"{sel.nodes[0]} + {sel.nodes[1]}" in table and "50 + 4" in table
    assert write_plots(prof, tmp_path)
    tradeoff_figure(prof)
    from rrcache.report import write_report
    (tmp_path / "r").mkdir()
    write_report(prof, tmp_path / "r")
    text = (tmp_path / "r" / "report.html").read_text(encoding="utf-8")
    assert f"<b>{sel.nodes[0]}</b> every Δn = 50 frames" in text and "no frames are shown" in text
    # the document carries it: written and read back with its parts
    prof.write(tmp_path / "copy")
    back = load_profile(tmp_path / "copy")
    assert [s.describe() for s in back.selections][-1] == sel.describe()
