"""A profile's choices reproduced: ``rrcache instance PROFILE --level eN`` writes the files of the
profile's ``optimized/eN``, ``rrcache render PROFILE --level eN`` measures that choice with the
profile's algorithm and options, and ``render``/``instance --node`` say which algorithm they use
(the profile's, when given one). Real profile (the demo scene, seconds), real GL renders."""
from __future__ import annotations

import filecmp
import json
from pathlib import Path

import pytest

from rrcache.cli import main
from rrcache.profiler import demo_profile
from rrcache.profiler.demo import DEMO_SESSION, DEMO_SHADER


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The demo profile, shared with the report tests of one run (made once, then loaded)."""
    return demo_profile(tmp_path_factory.getbasetemp() / "demo.rrprofile")


def _files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.is_file())


def test_instance_level_writes_the_profiles_optimized_files(demo, tmp_path, capsys):
    assert demo.selections, "the demo profile has no levels"
    for sel in demo.selections:
        out = tmp_path / sel.label
        main(["instance", str(demo.path), "--level", sel.label, "--out", str(out)])
        said = capsys.readouterr().out
        shipped = demo.path / sel.files
        assert _files(out) == _files(shipped)
        match, mismatch, errors = filecmp.cmpfiles(out, shipped, _files(shipped), shallow=False)
        assert mismatch == [] and errors == [], (sel.label, mismatch, errors)
        if sel.parts:
            manifest = json.loads((out / "manifest.json").read_text())
            assert manifest["algorithm"] == (sel.algorithm or demo.algorithm)
            assert manifest["period"] == sel.period
            assert manifest["runtime"] == demo.settings.cache_options()
            assert manifest["algorithm"] in said and sel.node in said


def test_instance_level_uses_the_profiles_algorithm_not_the_default(demo, tmp_path, capsys):
    """The demo profile measures two-pass faster (auto): a level is written with it, where
    ``instance SHADER --node`` would default to three-pass."""
    sel = next(s for s in demo.selections if s.parts)
    main(["instance", str(demo.path), "--level", sel.label, "--out", str(tmp_path / "level")])
    capsys.readouterr()
    level_algorithm = json.loads((tmp_path / "level" / "manifest.json").read_text())["algorithm"]
    assert level_algorithm == demo.algorithm
    main(["instance", str(DEMO_SHADER), "--node", sel.node, "--period", str(sel.period), "--session",
          str(DEMO_SESSION), "--out", str(tmp_path / "shader")])
    said = capsys.readouterr().out
    assert "three-pass (the default" in said
    main(["instance", str(demo.path), "--node", sel.node, "--period", str(sel.period), "--out",
          str(tmp_path / "node")])
    said = capsys.readouterr().out
    assert f"{demo.algorithm} (the profile's choice)" in said
    assert json.loads((tmp_path / "node" / "manifest.json").read_text())["algorithm"] == demo.algorithm


def test_render_level_measures_the_profiles_choice(demo, capsys):
    sel = next(s for s in demo.selections if s.parts)
    main(["render", str(demo.path), "--level", sel.label, "--frames", "4", "--json", "--quiet"])
    doc = json.loads(capsys.readouterr().out)
    assert doc["level"] == sel.label and doc["choice"] == sel.describe()
    assert doc["algorithm"] == (sel.algorithm or demo.algorithm) and doc["period"] == sel.period
    assert {k: doc[k] for k in ("block", "refresh", "depth_epsilon")} == demo.settings.cache_options()
    assert doc["color_format"] == demo.settings.timing_format and doc["frames"] == 4
    assert doc["hits"] > 0


def test_render_node_says_its_algorithm(demo, capsys):
    sel = next(s for s in demo.selections if s.parts)
    main(["render", str(DEMO_SHADER), str(DEMO_SESSION), "--node", sel.node, "--frames", "3", "--json"])
    captured = capsys.readouterr()
    assert json.loads(captured.out)["algorithm"] == "three-pass"
    assert "three-pass (the default" in captured.err
    main(["render", str(demo.path), "--node", sel.node, "--frames", "3", "--json"])
    captured = capsys.readouterr()
    assert json.loads(captured.out)["algorithm"] == demo.algorithm
    assert json.loads(captured.out)["filter"] == demo.filter  # the profile's cache filter too
    assert f"{demo.algorithm} (the profile's choice" in captured.err


@pytest.mark.parametrize("args, words", [
    (["--level", "e2", "--period", "3"], "leave out --period"),
    (["--level", "e2", "--algorithm", "one-pass"], "leave out --algorithm"),
    (["--level", "e9"], "no level 'e9'"),
])
def test_render_level_usage_errors(demo, args, words, capsys):
    with pytest.raises(SystemExit) as info:
        main(["render", str(demo.path), *args])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_level_needs_a_profile(tmp_path, capsys):
    for args in (["instance", str(DEMO_SHADER), "--level", "e2", "--out", str(tmp_path / "x")],
                 ["render", str(DEMO_SHADER), str(DEMO_SESSION), "--level", "e2"]):
        with pytest.raises(SystemExit) as info:
            main(args)
        assert info.value.code == 2
        assert "--level needs a PROFILE" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_a_level_takes_the_profiles_cache_filter(demo, tmp_path, capsys):
    """A profile trained with the other cache filter than the demo's (bilinear or plane, both
    real profiles): ``instance``/``render PROFILE --level`` and ``--node`` use the profile's
    filter, not the commands' default, and ``instance --level`` still writes its optimized/eN."""
    from rrcache.profiler.demo import DEMO_SETTINGS
    from rrcache.profiler.run import profile
    from rrcache.profiles import TrainingSettings

    other = "plane" if demo.filter != "plane" else "bilinear"
    prof = profile(DEMO_SHADER, DEMO_SESSION, tmp_path / "other.rrprofile",
                   TrainingSettings(**DEMO_SETTINGS, filter=other), plots=False)
    assert prof.filter == other
    sel = next((s for s in prof.selections if s.parts and len(s.parts) == 1), None)
    assert sel is not None, "the profile cached no single node at any level"
    out = tmp_path / "level"
    main(["instance", str(prof.path), "--level", sel.label, "--out", str(out)])
    assert f"{other} filter" in capsys.readouterr().out
    assert json.loads((out / "manifest.json").read_text())["filter"] == other
    match, mismatch, errors = filecmp.cmpfiles(out, prof.path / sel.files, _files(out), shallow=False)
    assert mismatch == [] and errors == []
    main(["render", str(prof.path), "--level", sel.label, "--frames", "3", "--json", "--quiet"])
    assert json.loads(capsys.readouterr().out)["filter"] == other
    main(["render", str(prof.path), "--node", sel.node, "--frames", "3", "--json", "--quiet"])
    assert json.loads(capsys.readouterr().out)["filter"] == other
