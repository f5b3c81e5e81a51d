"""The layout counts of a checkout's rrcache/ package: big modules, long signatures, class ladders.

    python tools/layout_counts.py [ROOT] [-v]

Reads the source only (nothing of ROOT is imported), so it counts any revision: unpack one with
``git archive REV | tar -x -C DIR`` and give DIR. It prints

- modules over 600 lines;
- functions with 12 parameters or more (``self``/``cls`` not counted, ``*args``/``**kw`` counted);
- ``isinstance`` ladders on GLSL syntax classes (as ``tools/ast_ladders.py`` counts them);
- branches on the kind of a choice outside ``rrcache/kinds/``: an ``isinstance`` on a part class
  (a class with a ``KIND`` tag) or on ``MultiVariant``/``MultiCacheRuntime``, and a comparison of
  ``X.kind``/``X.choice``/``X.KIND`` with a kind's name ("cache", "nodes", "amortize", ...);
- tests of the per-kind flags ``.multi``, ``.amortized``, ``.adaptive`` outside ``rrcache/kinds/``.

``-v`` lists where each stands.
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path

from ast_ladders import count as count_ladders

LIMIT_LINES = 600
LIMIT_PARAMS = 12
#: the names a choice's kind has had (``Selection.kind``, the part tags, the registry's names)
KIND_NAMES = {"cache", "nodes", "amortize", "adaptive", "original", "render-cache"}
KIND_CLASSES = {"MultiVariant", "MultiCacheRuntime"}
FLAGS = {"multi", "amortized", "adaptive"}


def _modules(root: Path):
    for path in sorted((root / "rrcache").rglob("*.py")):
        text = path.read_text()
        yield path.relative_to(root).as_posix(), text, ast.parse(text)


def part_classes(root: Path) -> set[str]:
    """Classes of rrcache/ with a class-level ``KIND`` tag (the parts of a choice)."""
    out = set()
    for _, _, tree in _modules(root):
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef) and any(
                    (isinstance(s, ast.Assign) and any(getattr(t, "id", None) == "KIND" for t in s.targets))
                    or (isinstance(s, ast.AnnAssign) and getattr(s.target, "id", None) == "KIND")
                    for s in node.body):
                out.add(node.name)
    return out


def _params(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args]
    n = len(names) + len(a.kwonlyargs) + (a.vararg is not None) + (a.kwarg is not None)
    return n - 1 if names and names[0] in ("self", "cls") else n


def _kind_string(node: ast.expr) -> bool:
    items = node.elts if isinstance(node, (ast.Tuple, ast.List, ast.Set)) else [node]
    return any(isinstance(i, ast.Constant) and i.value in KIND_NAMES for i in items)


def _kind_subject(node: ast.expr) -> bool:
    return isinstance(node, ast.Attribute) and node.attr in ("kind", "choice", "KIND")


def kind_branches(tree: ast.AST, classes: set[str]) -> list[tuple[int, str]]:
    """``(line, text)`` of every isinstance on a kind's class and every comparison with a kind's name."""
    found = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "isinstance"
                and len(node.args) == 2):
            tested = node.args[1].elts if isinstance(node.args[1], ast.Tuple) else [node.args[1]]
            if any(ast.unparse(t).split(".")[-1] in classes for t in tested):
                found.append((node.lineno, ast.unparse(node)))
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(_kind_subject(s) for s in sides) and any(_kind_string(s) for s in sides):
                found.append((node.lineno, ast.unparse(node)))
    return found


def flag_tests(tree: ast.AST) -> list[tuple[int, str]]:
    """``(line, text)`` of every ``if``/conditional/boolean test reading ``.multi``/``.amortized``/``.adaptive``."""
    tests = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.If, ast.IfExp, ast.While, ast.Assert)):
            tests.append(node.test)
        elif isinstance(node, ast.comprehension):
            tests.extend(node.ifs)
    found = []
    for test in tests:
        for sub in ast.walk(test):
            if isinstance(sub, ast.Attribute) and sub.attr in FLAGS:
                found.append((sub.lineno, ast.unparse(test)))
                break
    return found


def counts(root: Path) -> dict[str, dict[str, list]]:
    """Every count by name: ``{count: {file: [where, ...]}}``."""
    classes = part_classes(root) | KIND_CLASSES
    out: dict[str, dict[str, list]] = {"big modules": {}, "long signatures": {}, "kind branches": {},
                                       "flag tests": {}}
    for rel, text, tree in _modules(root):
        lines = text.count("\n")
        if lines > LIMIT_LINES:
            out["big modules"][rel] = [(0, f"{lines} lines")]
        long = [(f.lineno, f"{f.name}: {_params(f)} parameters") for f in ast.walk(tree)
                if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)) and _params(f) >= LIMIT_PARAMS]
        if long:
            out["long signatures"][rel] = long
        if not rel.startswith("rrcache/kinds/"):
            for name, got in (("kind branches", kind_branches(tree, classes)), ("flag tests", flag_tests(tree))):
                if got:
                    out[name][rel] = got
    out["AST isinstance ladders"] = {path: [(line, f"on {subject} ({n} classes)") for line, subject, n in items]
                                     for path, items in count_ladders(root).items()}
    return out


def main(argv: list[str]) -> int:
    args = [a for a in argv if not a.startswith("-")]
    root = Path(args[0]) if args else Path(__file__).resolve().parents[1]
    for name, files in counts(root).items():
        total = sum(len(v) for v in files.values())
        print(f"{name}: {total} in {len(files)} files")
        if "-v" in argv:
            for path, items in sorted(files.items()):
                for line, text in items:
                    print(f"    {path}:{line}: {text}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
