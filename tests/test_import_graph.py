"""The import graph of ``rrcache/``: every module imports, no cycle (inside a package either),
each package only above the packages it uses (docs/architecture.md, "Layers"), none of the
imports the rooms forbid (:data:`FORBIDDEN`), and the public names never shadowed.

The graph is read from the source with :mod:`ast`: an edge for every ``import`` and ``from …
import`` anywhere in a module (inside functions too: a lazy import still runs the other module,
and the cycle this test was written for, profile → report → profile, went through one), to
modules of the importer's own package too, plus an edge to each package an import passes through
(``import rrcache.a.b`` runs ``rrcache/a/__init__.py``), except the importer's own packages.
"""
from __future__ import annotations

import ast
import importlib
import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

import rrcache

ROOT = Path(rrcache.__file__).resolve().parent

#: every package (or top-level module) of rrcache, lowest layer first: a module may import from
#: its own package and from lower layers only (the same table is in docs/architecture.md)
LAYERS = [
    {"errors", "jsonable", "files"},
    {"budgets", "deep", "atomic", "stdio", "watchdog"},
    {"glsl", "session", "gl"},
    {"analysis", "runtime"},
    {"compiler", "runs"},
    {"kinds"},
    {"selection"},
    {"model", "harness"},
    {"pipeline"},
    {"alternatives", "profiles", "cluster", "webgl"},
    {"report", "choice"},
    {"profiler"},
    {"bench", "explorer"},
    {"cli"},
    {"__main__", "rrcache"},
]


#: imports the layers allow but the rooms forbid: (importer, imported, why). A package name
#: stands for every module in it (docs/architecture.md, "Forbidden imports", is this table)
FORBIDDEN = [
    ("report", "harness", "the report only reads the profile folder: the profiler renders its frames"),
    ("report", "pipeline", "the report only reads the profile folder: it compiles nothing"),
    ("report", "compiler", "the report only reads the profile folder: it compiles nothing"),
    ("report", "gl", "the report only reads the profile folder: it needs no GL context"),
    ("profiles", "pipeline", "a profile's data compiles nothing (rrcache.choice writes a choice's files)"),
    ("profiles", "compiler", "a profile's data compiles nothing"),
    ("model", "harness", "the models are pure maths over measurements"),
    ("model", "gl", "the models are pure maths over measurements"),
    ("model", "pipeline", "the models are pure maths over measurements"),
    ("kinds", "gl", "a kind compiles and plans; the harness runs it"),
    ("runs", "harness", "a run is a plain record; the harness executes it"),
]


def _modules(root: Path = ROOT) -> dict[str, Path]:
    """Module name → file, for every ``.py`` under the package folder ``root``."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _imports(name: str, path: Path, modules: dict = MODULES) -> set[str]:
    """The modules of ``modules`` that module ``name`` imports (see the module docstring): every
    module an import names, inside its own package too (``from pkg import f`` in ``pkg/b.py``
    depends on ``pkg/__init__.py``: that is how a cycle inside a package shows), and the packages an
    import passes through (``import pkg.a.b`` runs ``pkg/a/__init__.py``) except the importer's
    own, which are running already."""
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module
            for alias in node.names:
                sub = f"{module}.{alias.name}"
                found.add(sub if sub in modules else module)
    own = {".".join(name.split(".")[:i]) for i in range(1, name.count(".") + 1)}
    root = name.split(".")[0]  # the root package runs before any of its modules (rrcache: lazy names)
    named, passed = set(), set()
    for target in found:
        if target not in modules:
            continue
        named.add(target)
        pieces = target.split(".")
        passed.update(".".join(pieces[:i]) for i in range(2, len(pieces)) if ".".join(pieces[:i]) in modules)
    return (named | (passed - own)) - {name, root}


def _graph(modules: dict) -> dict[str, set[str]]:
    return {name: _imports(name, path, modules) for name, path in modules.items()}


GRAPH = _graph(MODULES)


def _package(module: str) -> str:
    """``rrcache.report.html`` → ``report`` (a top-level module is its own package)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def forbidden_imports(graph: dict, table=FORBIDDEN) -> list[str]:
    """Each edge of ``graph`` that ``table`` forbids, with why."""
    rules = {(a, b): why for a, b, why in table}
    return sorted(f"{a} imports {b}: {rules[(_package(a), _package(b))]}" for a, targets in graph.items()
                  for b in targets if (_package(a), _package(b)) in rules)


def _cycle(graph: dict) -> list[str]:
    """One cycle of ``graph`` as a list of modules (first == last), or []."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state:
                found = visit(nxt)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return []

    for start in sorted(graph):
        if start not in state:
            found = visit(start)
            if found:
                return found
    return []


def _layer(module: str) -> int:
    key = module.split(".")[1] if "." in module else module
    for i, names in enumerate(LAYERS):
        if key in names:
            return i
    raise AssertionError(f"{module}: its package is in no layer of LAYERS (add it there and to docs/architecture.md)")


def test_the_graph_is_read():
    """The reader sees the imports it must: lazy ones inside functions and relative ones."""
    assert "rrcache.report.plots" in GRAPH["rrcache.profiler.run"]  # imported inside a function
    assert "rrcache.profiles.document" in GRAPH["rrcache.report.html"]
    assert "rrcache.profiles" in GRAPH["rrcache.report.html"]  # the package the import runs
    assert "rrcache.profiles" not in GRAPH["rrcache.profiles.document"]  # not its own package, passed through
    assert "rrcache.kinds.base" in GRAPH["rrcache.kinds.single"]  # inside a package


def _write_package(root: Path, files: dict) -> dict:
    """A package ``pkg`` under ``root`` with ``files`` (relative path → source); its modules."""
    for rel, text in {"__init__.py": "", **files}.items():
        path = root / "pkg" / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return _modules(root / "pkg")


def test_a_cycle_inside_a_package_is_found(tmp_path):
    """A package's ``__init__`` importing one of its modules that imports a name from the
    ``__init__`` is a cycle (the compiler's ``__init__`` and its ``multi`` were one, unseen while
    the reader dropped edges inside a package); a module importing a sibling is not."""
    modules = _write_package(tmp_path / "a", {"sub/__init__.py": "from pkg.sub.b import g\ndef f(): pass\n",
                                              "sub/b.py": "def g():\n    from pkg.sub import f\n    return f\n",
                                              "sub/c.py": "from pkg.sub.b import g\n"})
    graph = _graph(modules)
    assert graph["pkg.sub.b"] == {"pkg.sub"} and graph["pkg.sub.c"] == {"pkg.sub.b"}
    assert _cycle(graph) == ["pkg.sub", "pkg.sub.b", "pkg.sub"]
    fixed = _write_package(tmp_path / "b", {"sub/__init__.py": "from pkg.sub.b import g\nfrom pkg.sub.a import f\n",
                                            "sub/a.py": "def f(): pass\n",
                                            "sub/b.py": "def g():\n    from pkg.sub.a import f\n    return f\n"})
    assert _cycle(_graph(fixed)) == []


def test_each_forbidden_import_fails_the_check():
    """Every row of FORBIDDEN fails the check on a graph that has that import (and only that row),
    and the check passes the graph without it."""
    for importer, imported, why in FORBIDDEN:
        graph = {f"rrcache.{importer}.x": {f"rrcache.{imported}.y"}, f"rrcache.{imported}.y": set()}
        assert forbidden_imports(graph) == [f"rrcache.{importer}.x imports rrcache.{imported}.y: {why}"]
        assert forbidden_imports({f"rrcache.{importer}.x": set()}) == []


def test_every_module_imports():
    """Each module imports in a fresh interpreter, in its own (an import-order cycle fails there)."""
    names = [n for n in MODULES if not n.endswith("__main__")]
    code = "import importlib, sys\nfor n in sys.argv[1:]:\n    importlib.import_module(n)\n"
    proc = subprocess.run([sys.executable, "-c", code, *names], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr


def test_a_cycle_is_found():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle():
    cycle = _cycle(GRAPH)
    assert not cycle, "import cycle: " + " -> ".join(cycle)


def upward_imports(graph: dict) -> list[str]:
    """Each edge of ``graph`` from a package to one in its own layer or above."""
    return sorted(f"{a} imports {b}" for a, targets in graph.items() for b in targets
                  if a.split(".")[:2] != b.split(".")[:2] and _layer(b) >= _layer(a))


def test_each_package_imports_only_lower_layers():
    wrong = upward_imports(GRAPH)
    assert not wrong, "\n".join(wrong)
    assert upward_imports({"rrcache.model.x": {"rrcache.harness.y"}, "rrcache.harness.y": set()}) == [
        "rrcache.model.x imports rrcache.harness.y"]


def test_no_forbidden_import():
    wrong = forbidden_imports(GRAPH)
    assert not wrong, "\n".join(wrong)


def _doc_rows(heading: str) -> list[list[str]]:
    """The cells of the table under ``## heading`` in docs/architecture.md."""
    text = (ROOT.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    section = text.split(f"## {heading}\n", 1)[1].split("\n## ", 1)[0]
    return [[c.strip() for c in line.strip().strip("|").split("|")] for line in section.splitlines()
            if line.startswith("|") and not set(line) <= set("|- ")][1:]


def _names(cell: str) -> set[str]:
    """``errors.py``, ``glsl/``, ``rrcache/__init__.py`` → the package names the test uses."""
    return {"rrcache" if n == "rrcache/__init__.py" else n.removesuffix(".py").rstrip("/")
            for n in re.findall(r"`([^`]+)`", cell)}


def test_the_documented_tables_are_the_tested_ones():
    """docs/architecture.md's "Layers" and "Forbidden imports" tables say what LAYERS and
    FORBIDDEN hold, row for row."""
    layers: dict[int, set] = {}
    for number, package, _ in _doc_rows("Layers"):
        layers.setdefault(int(number), set()).update(_names(package))
    assert [layers[i] for i in sorted(layers)] == LAYERS
    documented = {(i, f) for importer, forbidden, _ in _doc_rows("Forbidden imports")
                  for i in _names(importer) for f in _names(forbidden)}
    assert documented == {(a, b) for a, b, _ in FORBIDDEN}


def test_public_names_survive_importing_every_module():
    """``rrcache.profile`` and the other lazily exported names stay what they are after every
    submodule is imported (a package of the same name once replaced the function)."""
    for name in MODULES:
        if not name.endswith("__main__"):
            importlib.import_module(name)
    for name, module in rrcache._LAZY.items():
        assert f"rrcache.{name}" not in MODULES, f"a module rrcache.{name} would shadow the public name"
        value = getattr(rrcache, name)
        assert not inspect.ismodule(value), name
        assert value is getattr(importlib.import_module(module), name), name
    assert inspect.isfunction(rrcache.profile) and rrcache.profile.__module__ == "rrcache.profiler.run"
    assert list(inspect.signature(rrcache.profile).parameters)[:3] == ["shader_path", "session_path", "out_dir"]
    assert inspect.isclass(rrcache.TrainingSettings) and callable(rrcache.select)
    with pytest.raises(rrcache.RRCacheError, match="no profile here"):
        rrcache.load_profile(ROOT)


def test_public_profile_function_runs_after_the_packages_are_imported(tmp_path):
    """Calling ``rrcache.profile`` after importing ``rrcache.profiler.*`` and
    ``rrcache.profiles.*`` reaches the function (a bad session path: its located error, not a
    TypeError from calling a module)."""
    code = ("import rrcache, rrcache.profiler.train, rrcache.profiles.store, rrcache.profiles.document\n"
            "try:\n    rrcache.profile('s.glsl', 'missing.json', 'out')\n"
            "except rrcache.RRCacheError as err:\n    print('located:', err)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("located:") and "missing.json" in proc.stdout, proc.stdout
