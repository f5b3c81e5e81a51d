"""The estimator analysis (rrcache.analysis.estimators): loops summing independent samples."""
from __future__ import annotations

import json
import math

import pytest
from click.testing import CliRunner

from estimator_corpus import ESTIMATORS, NOT_ESTIMATORS, PRAGMA
from rrcache.analysis.estimators import find_estimators
from rrcache.errors import RRCacheError
from rrcache.glsl.frontend import parse_shader


@pytest.mark.parametrize("name", sorted(ESTIMATORS))
def test_corpus_estimators_are_found(name):
    source, samples = ESTIMATORS[name]
    table = find_estimators(parse_shader(source, f"{name}.frag"))
    assert [e.samples for e in table.estimators] == samples
    assert not table.rejected


def test_accumulators_and_place():
    table = find_estimators(parse_shader(ESTIMATORS["weighted"][0], "w.frag"))
    (e,) = table.estimators
    assert e.accumulators == ["acc", "wsum"] and e.types == ["vec3", "float"] and e.components == 4
    assert (e.line, e.column) == (12, 5) and (e.start, e.step) == (1, 1)
    down = find_estimators(parse_shader(ESTIMATORS["conditional"][0], "c.frag")).estimators[0]
    assert (down.start, down.step, down.samples) == (15, -1, 16)


@pytest.mark.parametrize("name", sorted(NOT_ESTIMATORS))
def test_loops_that_are_not_estimators_say_why(name):
    source, why = NOT_ESTIMATORS[name]
    table = find_estimators(parse_shader(source, f"{name}.frag"))
    assert not table.estimators
    (r,) = table.rejected
    assert why in r.reason
    with pytest.raises(RRCacheError, match="not an estimator"):
        table.find(r.id)


def test_nested_loops_the_outer_one_is_the_estimator():
    src = ESTIMATORS["blur"][0].replace(
        "s += bump(v_texcoord + o);",
        "for (int j = 0; j < 3; j++) { s += bump(v_texcoord + o * float(j)); }")
    table = find_estimators(parse_shader(src, "n.frag"))
    assert [(e.id, e.samples) for e in table.estimators] == [("e1", 8)]
    assert [(r.id, "inside another loop" in r.reason) for r in table.rejected] == [("e2", True)]


def test_pragma_marks_a_loop_the_analysis_cannot_prove():
    unmarked = find_estimators(parse_shader(PRAGMA.replace("#pragma rrcache estimator", ""), "p.frag"))
    assert not unmarked.estimators and "reads an accumulator" in unmarked.rejected[0].reason
    marked = find_estimators(parse_shader(PRAGMA, "p.frag"))
    (e,) = marked.estimators
    assert e.pragma and e.samples == 6 and e.accumulators == ["s"]


def test_cli_nodes_json_lists_estimators(tmp_path):
    from rrcache.cli import cli as main

    path = tmp_path / "weighted.frag"
    path.write_text(ESTIMATORS["weighted"][0])
    out = CliRunner().invoke(main, ["nodes", str(path), "--json"])
    assert out.exit_code == 0, out.output
    doc = json.loads(out.output)
    assert doc["estimators"] == [{"id": "e1", "line": 12, "column": 5, "samples": 12,
                                  "text": "for (int i = 1; i <= 12; i += 1)",
                                  "accumulators": ["acc", "wsum"], "pragma": False,
                                  "term_range": [0.0, pytest.approx(math.exp(-0.1))],
                                  "range_source": "analysis"}]
    assert doc["not_estimators"] == []
    text = CliRunner().invoke(main, ["nodes", str(path)]).output
    assert "estimator e1" in text and "12 samples" in text
