"""Count the isinstance ladders on GLSL syntax classes in a checkout's rrcache/ package.

    python tools/ast_ladders.py [ROOT] [--min-classes N] [-v]

A *ladder* is a chain of tests ``isinstance(X, C)`` on the same subject ``X`` with ``C`` a node
class of ``rrcache/glsl/ast.py`` (or a tuple of them): the branches of one ``if``/``elif`` chain,
or consecutive ``if`` statements of one block, two tests or more. With ``--min-classes N`` only
ladders naming N different classes or more count. ``-v`` lists where each stands. A pass that
switches on node classes this way must be edited whenever a node class is added; one written as
a :class:`rrcache.glsl.visitor.NodeVisitor` need not. ROOT defaults to this checkout (give
another, for instance ``git archive REV | tar -x -C DIR``, to count an older revision).
"""
from __future__ import annotations

import ast
import os
import sys
from collections import Counter
from pathlib import Path


def node_classes(root: Path) -> set[str]:
    """The class names defined in ``rrcache/glsl/ast.py`` of ``root``."""
    tree = ast.parse((root / "rrcache" / "glsl" / "ast.py").read_text())
    return {n.name for n in tree.body if isinstance(n, ast.ClassDef) and not n.name.startswith("_")}


def _tested(test: ast.expr, classes: set[str]):
    """``(subject, class names)`` when ``test`` is (or starts with) an isinstance on node classes."""
    if isinstance(test, ast.BoolOp) and isinstance(test.op, ast.And):
        test = test.values[0]
    if not (isinstance(test, ast.Call) and isinstance(test.func, ast.Name)
            and test.func.id == "isinstance" and len(test.args) == 2):
        return None
    kinds = test.args[1].elts if isinstance(test.args[1], ast.Tuple) else [test.args[1]]
    names = [ast.unparse(k).split(".")[-1] for k in kinds]
    if not names or not all(n in classes for n in names):
        return None
    return ast.unparse(test.args[0]), names


def _chain(node: ast.If, classes: set[str]) -> list:
    out = []
    while True:
        out.append(_tested(node.test, classes))
        if len(node.orelse) == 1 and isinstance(node.orelse[0], ast.If):
            node = node.orelse[0]
        else:
            return out


def ladders(path: Path, classes: set[str]) -> list[tuple[int, str, int]]:
    """``(line, subject, number of classes)`` of every ladder in one file."""
    tree = ast.parse(path.read_text())
    found = []
    elifs = {id(n.orelse[0]) for n in ast.walk(tree)
             if isinstance(n, ast.If) and len(n.orelse) == 1 and isinstance(n.orelse[0], ast.If)}
    for node in ast.walk(tree):
        for name in ("body", "orelse", "finalbody"):
            block = getattr(node, name, None)
            if not isinstance(block, list):
                continue
            run: list = []       # consecutive single ``if isinstance`` tests on one subject

            def close() -> None:
                if len(run) >= 2:
                    found.append((run[0][0], run[0][1], len({c for _, _, cs in run for c in cs})))
                run.clear()

            for stmt in block:
                if not isinstance(stmt, ast.If) or id(stmt) in elifs:
                    close()
                    continue
                chain = _chain(stmt, classes)
                tests = Counter(t[0] for t in chain if t is not None)
                if len(chain) > 1 and tests and tests.most_common(1)[0][1] >= 2:
                    close()
                    subject = tests.most_common(1)[0][0]
                    names = {c for t in chain if t is not None and t[0] == subject for c in t[1]}
                    found.append((stmt.lineno, subject, len(names)))
                elif len(chain) == 1 and chain[0] is not None:
                    subject, names = chain[0]
                    if run and run[-1][1] != subject:
                        close()
                    run.append((stmt.lineno, subject, names))
                else:
                    close()
            close()
    return found


def count(root: Path, min_classes: int = 1) -> dict[str, list[tuple[int, str, int]]]:
    """Every file of ``root``'s rrcache/ package with its ladders of ``min_classes`` or more."""
    classes = node_classes(root)
    out = {}
    for path in sorted((root / "rrcache").rglob("*.py")):
        got = [x for x in ladders(path, classes) if x[2] >= min_classes]
        if got:
            out[str(path.relative_to(root))] = got
    return out


def main(argv: list[str]) -> int:
    args = [a for a in argv if not a.startswith("-")]
    min_classes = 1
    if "--min-classes" in argv:
        min_classes = int(argv[argv.index("--min-classes") + 1])
        args.remove(str(min_classes))
    root = Path(args[0]) if args else Path(__file__).resolve().parents[1]
    found = count(root, min_classes)
    for path, items in sorted(found.items(), key=lambda kv: -len(kv[1])):
        print(f"{len(items):4d} {path}")
        if "-v" in argv:
            for line, subject, n in items:
                print(f"       {path}:{line} on {subject} ({n} class{'es' if n > 1 else ''})")
    print(f"{sum(len(v) for v in found.values())} ladders in {len(found)} files")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
