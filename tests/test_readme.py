"""README.md stays true: its complete CacheRuntime loop runs as printed on a level's files, every
command of its reference exists with the options it shows, and every figure of its results table is
in the page it cites."""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

from rrcache.cli import main
from rrcache.profiler.demo import DEMO_SESSION, DEMO_SHADER

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README, re.S)


def test_the_complete_loop_runs_on_a_levels_files(tmp_path, capsys):
    loop = next(b for b in _blocks("python") if "cache.frame(draw)" in b)
    script = tmp_path / "run_level.py"
    script.write_text(loop)
    main(["nodes", str(DEMO_SHADER), "--session", str(DEMO_SESSION), "--json", "--sort", "cost"])
    node = json.loads(capsys.readouterr().out)["nodes"][0]["id"]
    for algorithm in ("two-pass", "three-pass"):
        folder = tmp_path / algorithm
        main(["instance", str(DEMO_SHADER), "--node", node, "--period", "4", "--algorithm", algorithm,
              "--session", str(DEMO_SESSION), "--out", str(folder)])
        capsys.readouterr()
        env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        done = subprocess.run([sys.executable, str(script), str(folder), str(DEMO_SESSION)], cwd=tmp_path,
                              capture_output=True, text=True, env=env, timeout=300)
        assert done.returncode == 0, done.stderr[-2000:]
        frames = json.loads(Path(DEMO_SESSION).read_text())["frames"]
        found = re.search(r"(\d+) frames; the last: (\d+) of (\d+) covered pixels from the cache", done.stdout)
        assert found, done.stdout
        assert int(found.group(1)) == frames and 0 < int(found.group(2)) < int(found.group(3))


def _reference() -> list[str]:
    """The commands of the README's command reference (its first shell block), comments left out."""
    block = re.findall(r"```sh\n(.*?)```", README.split("## Command reference", 1)[1], re.S)[0]
    return [line.split("#")[0].strip() for line in block.splitlines() if line.strip()]


def test_every_command_of_the_reference_exists_with_its_options(capsys):
    lines = _reference()
    assert len(lines) >= 10
    helps: dict[str, str] = {}
    for line in lines:
        words = line.split()
        assert words[0] == "rrcache", line
        command = words[1]
        if command not in helps:
            try:
                main([command, "--help"])
            except SystemExit as stop:
                assert stop.code in (0, None), line
            helps[command] = capsys.readouterr().out
            assert f"Usage: rrcache {command}" in helps[command], line
        for option in re.findall(r"(?<![\w-])(--[a-z][a-z-]*)", line):
            assert option in helps[command], f"{line}: {option} is not an option of rrcache {command}"


def test_the_results_table_cites_its_figures():
    section = README.split("## Results", 1)[1].split("\n## ", 1)[0]
    cited = re.search(r"\((docs/[\w.]+\.md), with the command", section).group(1)
    record = (ROOT / cited).read_text(encoding="utf-8")
    paper = (ROOT / "docs" / "design.md").read_text(encoding="utf-8")
    rows = [r for r in section.splitlines() if r.startswith("| ") and "---" not in r][1:]
    assert len(rows) == 4
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        ours = re.findall(r"\d+\.\d+", cells[3])
        assert ours and all(f in record for f in ours), (row, cited)
        if cells[2] != "—":
            assert cells[2] in paper, row


def test_the_library_table_is_the_run_recorded_in_docs():
    section = README.split("## A shader library", 1)[1].split("\n## ", 1)[0]
    cited = re.search(r"\((docs/[\w.]+\.md), with the command\)", section).group(1)
    record = (ROOT / cited).read_text(encoding="utf-8")
    rows = [r for r in section.splitlines() if r.startswith("| ") and "---" not in r]
    assert len(rows) >= 7 and all(row in record for row in rows)


def test_the_levels_table_is_the_run_recorded_in_docs():
    """The README's 'Do the levels hold?' table is the measured run docs/levels.md records with
    its commands (issue 29): every row of it, as written there."""
    section = README.split("## Do the levels hold?", 1)[1].split("\n## ", 1)[0]
    cited = re.search(r"\((docs/[\w.]+\.md), with the commands", section).group(1)
    record = (ROOT / cited).read_text(encoding="utf-8")
    rows = [r for r in section.splitlines() if r.startswith("| ") and "---" not in r]
    assert len(rows) >= 2 and all(row in record for row in rows)


#: a figure: a number (with its uncertainty, '37.3 ± 2.7 dB') and the unit of a speed-up, a PSNR or a
#: time (not a size such as 640×480 or 4×4)
FIGURE = re.compile(r"(?<![\w.×])(\d+(?:\.\d+)?)(?: ± \d+(?:\.\d+)?)? ?(×|dB|ms|s|min|minutes|seconds|h|hours)"
                    r"(?![\w×\d])")


def _settings() -> dict:
    """The README's figures that are defaults, not measurements, each with the code's value."""
    import inspect

    from rrcache.cli.progress import Reporter
    from rrcache.model.psnr import DEFAULT_LEVELS_DB
    from rrcache.profiles import TrainingSettings

    defaults = TrainingSettings()
    levels = {f"{db:g} dB": db for db in DEFAULT_LEVELS_DB}  # e1 ≥ 45 dB … e4 ≥ 30 dB
    return {**levels, "1.1×": defaults.min_gain, "360 s": defaults.budget_s,
            "10 seconds": inspect.signature(Reporter).parameters["interval"].default}


def test_every_figure_comes_from_a_run_recorded_in_the_docs_it_cites():
    """Each section's figures (speed-ups, PSNRs, times) are in a docs/ page the section cites (the
    run, with its command), or are defaults whose values the code has: a figure added without
    its record fails here."""
    settings = _settings()
    for name, value in settings.items():
        assert float(FIGURE.match(name).group(1)) == float(value), (name, value)
    checked = 0
    for section in re.split(r"\n(?=## )", README):
        prose = re.sub(r"```.*?```", "", section, flags=re.S)
        title = section.splitlines()[0]
        cited = sorted(set(re.findall(r"docs/[\w-]+\.md", prose)))
        records = [" ".join((ROOT / c).read_text(encoding="utf-8").split()) for c in cited]
        for found in FIGURE.finditer(prose):
            figure = found.group(0)
            if figure in settings:
                continue
            assert cited, f"{title}: {figure} is stated, but the section cites no docs/ page recording it"
            assert any(figure in record for record in records), \
                f"{title}: {figure} is in none of the pages the section cites ({', '.join(cited)})"
            checked += 1
    assert checked >= 40  # the results and library tables, the set-up's times, re-selection


def test_the_session_example_loads_with_its_files_in_place(tmp_path):
    """The README's session, copied as printed beside a mesh and a texture at the paths it
    names, is a valid session: its camera, light, object, keyframed uniform and texture."""
    import numpy as np
    from PIL import Image

    from rrcache.session import load_session

    block = _blocks("json")[0]
    (tmp_path / "meshes").mkdir()
    (tmp_path / "textures").mkdir()
    (tmp_path / "meshes" / "statue.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    Image.fromarray(np.full((4, 4, 3), 128, np.uint8)).save(tmp_path / "textures" / "albedo.png")
    (tmp_path / "my.json").write_text(block)
    session = load_session(tmp_path / "my.json")
    assert session.resolution == (640, 480) and session.frames == 150
    assert [o.name for o in session.objects] == ["statue"] and list(session.textures) == ["u_albedo"]
    values = session.uniform_values(149)
    assert values["u_roughness"] == 0.4 and values["u_wave"] == 1.0
    assert not np.allclose(session.camera_at(0).eye, session.camera_at(10).eye)  # the orbit moves
