"""CI runs the README's test command, lists the slowest tests, and every test has a time limit."""
from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_ci_runs_the_readmes_test_command_and_lists_the_slowest_tests():
    readme = (ROOT / "README.md").read_text()
    block = re.search(r"Install and run the tests:\s*```sh\n(.+?)\n```", readme, re.S)
    assert block, "README.md: the 'Install and run the tests' command block"
    command = block.group(1).strip()
    ci = (ROOT / ".ci" / "run").read_text()
    assert command in ci.splitlines()
    assert re.search(r"PYTEST_ADDOPTS=.*--durations=\d+", ci)


def test_every_test_has_a_time_limit():
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    limit = project["tool"]["pytest"]["ini_options"]["timeout"]
    assert 60 <= int(limit) <= 1200
    assert any(dep.startswith("pytest-timeout") for dep in project["project"]["optional-dependencies"]["test"])
