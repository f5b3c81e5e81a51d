"""Compare the node tables two versions of rrcache give for the same shaders.

    python tools/compare_node_tables.py BEFORE_ROOT AFTER_ROOT [SHADER ...]

Runs ``python -m rrcache nodes SHADER --all --json`` with ``PYTHONPATH`` set to each root (a
checkout, or ``git archive REV | tar -x -C DIR``) for every shader (default: shaders/*.glsl and
tests/corpus/*.glsl), and prints one line per shader (same / DIFF) and the number of
differences: the parsed JSON (ids, costs, texts, reasons, call chains), the exit status and
stderr must all be equal. Exit status 1 when any differ. Used to check that a speed-up of the
analysis changes no output (docs/bench_frontend.md).

Each run starts in its root's folder (``python -m`` puts the current folder before
``PYTHONPATH``: run from a checkout, both sides would otherwise import that checkout's
rrcache), with the shaders' absolute paths, and the tool first checks that each root's rrcache
is the one imported.
"""
from __future__ import annotations

import glob
import json
import os
import subprocess
import sys


def _env(root: str) -> dict:
    return dict(os.environ, PYTHONPATH=os.path.abspath(root))


def _imports_its_own(root: str) -> bool:
    p = subprocess.run([sys.executable, "-c", "import rrcache; print(rrcache.__file__)"],
                       capture_output=True, text=True, env=_env(root), cwd=os.path.abspath(root))
    return p.stdout.strip().startswith(os.path.join(os.path.abspath(root), "rrcache"))


def _table(root: str, shader: str) -> tuple:
    p = subprocess.run([sys.executable, "-m", "rrcache", "nodes", os.path.abspath(shader), "--all", "--json"],
                       capture_output=True, text=True, env=_env(root), cwd=os.path.abspath(root))
    try:
        out = json.loads(p.stdout)
    except ValueError:
        out = p.stdout
    return out, p.returncode, p.stderr


def main(argv: list[str]) -> int:
    if len(argv) < 2:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    before, after, shaders = argv[0], argv[1], argv[2:]
    shaders = shaders or sorted(glob.glob("shaders/*.glsl")) + sorted(glob.glob("tests/corpus/*.glsl"))
    for root in (before, after):
        if not _imports_its_own(root):
            print(f"{root}: has no rrcache package of its own to compare", file=sys.stderr)
            return 2
    diffs = 0
    for shader in shaders:
        same = _table(before, shader) == _table(after, shader)
        diffs += not same
        print(("same " if same else "DIFF ") + shader, flush=True)
    print(f"{len(shaders)} shaders compared, {diffs} differences")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
