"""The examples in the docstrings of every ``rrcache`` module run, and pass (``python -m pytest
-q`` runs them with the other tests; pyproject's ``testpaths`` is ``tests``). They run from the
repository root, so an example may read ``shaders/marble.glsl`` or ``sessions/marble.json``.
An example marked ``# doctest: +SKIP`` is one that cannot run quickly here (a whole session
rendered, a file that is not in the repository).

Also here: the documentation is self-contained (it cites ``docs/`` files, never a file outside
the repository)."""
from __future__ import annotations

import doctest
import importlib
import pkgutil
import re
from pathlib import Path

import pytest

import rrcache

ROOT = Path(__file__).resolve().parents[1]
MODULES = ["rrcache"] + sorted(m.name for m in pkgutil.walk_packages(rrcache.__path__, "rrcache.")
                              if not m.name.endswith("__main__"))
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def test_every_module_is_found():
    assert "rrcache.glsl.ast" in MODULES and "rrcache.compiler.hoist" in MODULES
    assert len(MODULES) == len(list(ROOT.joinpath("rrcache").rglob("*.py"))) - 1  # __main__


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name, monkeypatch, gl_ctx):
    """Every module's examples pass and leave the shared GL context without an error (the
    ``gl_ctx`` fixture checks the flag before and after, as for any GL test)."""
    monkeypatch.chdir(ROOT)
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    tests = [t for t in finder.find(module, name) if t.examples]
    for test in tests:
        runner.run(test)
    results = runner.summarize(verbose=False)
    assert results.failed == 0, f"{results.failed} of {results.attempted} examples failed in {name}"


DOC_FILES = sorted([*ROOT.joinpath("rrcache").rglob("*.py"), *ROOT.joinpath("docs").glob("*.md"),
                    ROOT / "README.md", *ROOT.joinpath("tests").rglob("*.py"),
                    *ROOT.joinpath("tests").rglob("*.md"), *ROOT.joinpath("notebooks").glob("*.ipynb")])


def test_docs_cite_only_files_in_the_repository():
    outside = re.compile(r"DESIGN\.md|\.\./shared|/work/shared|seeds/")
    bad = [f"{p.relative_to(ROOT)}:{i}" for p in DOC_FILES if p.name != Path(__file__).name
           for i, line in enumerate(p.read_text(errors="replace").splitlines(), 1) if outside.search(line)]
    assert not bad, bad
    cited = {m for p in DOC_FILES for m in re.findall(r"docs/[\w.-]+\.md", p.read_text(errors="replace"))}
    assert "docs/design.md" in cited
    assert all((ROOT / c).exists() for c in cited), sorted(c for c in cited if not (ROOT / c).exists())
