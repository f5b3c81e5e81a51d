"""The import graph of ``rrcache/``: every module imports, no cycle, each package only above the
packages it uses (docs/architecture.md, "Layers"), and the public names never shadowed.

The graph is read from the source with :mod:`ast`: an edge for every ``import`` and ``from …
import`` anywhere in a module (inside functions too: a lazy import still runs the other module,
and the cycle this test was written for, profile → report → profile, went through one), plus an
edge to each package an import passes through (``import rrcache.a.b`` runs ``rrcache/a/__init__.py``),
except the importer's own packages.
"""
from __future__ import annotations

import ast
import importlib
import inspect
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
    {"selection", "glsl", "session", "gl"},
    {"analysis", "runtime", "model"},
    {"harness"},
    {"compiler"},
    {"pipeline"},
    {"alternatives", "profiles", "cluster", "webgl"},
    {"report"},
    {"profiler"},
    {"bench"},
    {"cli"},
    {"__main__", "rrcache"},
]


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _imports(name: str, path: Path) -> set[str]:
    """The rrcache modules ``name`` imports (see the module docstring)."""
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
                found.add(sub if sub in MODULES else module)
    own = {".".join(name.split(".")[:i]) for i in range(1, name.count(".") + 1)}
    edges = set()
    for target in found:
        if target not in MODULES:
            continue
        edges.add(target)
        pieces = target.split(".")
        edges.update(".".join(pieces[:i]) for i in range(2, len(pieces)) if ".".join(pieces[:i]) in MODULES)
    return edges - own - {name}


GRAPH = {name: _imports(name, path) for name, path in MODULES.items()}


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
    assert "rrcache.profiles" not in GRAPH["rrcache.profiles.document"]  # not its own package


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


def test_each_package_imports_only_lower_layers():
    wrong = sorted(f"{a} imports {b}" for a, targets in GRAPH.items() for b in targets
                   if a.split(".")[:2] != b.split(".")[:2] and _layer(b) >= _layer(a))
    assert not wrong, "\n".join(wrong)


def test_the_report_only_reads_documents():
    """The report never runs the profiler or the bench (they write the report)."""
    for name, targets in GRAPH.items():
        if name.startswith("rrcache.report"):
            assert not {t for t in targets if t.startswith(("rrcache.profiler", "rrcache.bench", "rrcache.cli"))}, name


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
