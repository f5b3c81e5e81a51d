"""Compare the node tables two versions of rrcache give for the same shaders.

    python tools/compare_node_tables.py BEFORE_ROOT AFTER_ROOT [SHADER ...]

Runs ``python -m rrcache nodes SHADER --all --json`` with ``PYTHONPATH`` set to each root (a
checkout, or ``git archive REV | tar -x -C DIR``) for every shader (default: shaders/*.glsl and
tests/corpus/*.glsl), and prints one line per shader (same / DIFF) and the number of
differences: the parsed JSON (ids, costs, texts, reasons, call chains), the exit status and
stderr must all be equal. Exit status 1 when any differ. Used to check that a speed-up of the
analysis changes no output (docs/bench_frontend.md).
"""
from __future__ import annotations

import glob
import json
import os
import subprocess
import sys


def _table(root: str, shader: str) -> tuple:
    env = dict(os.environ, PYTHONPATH=os.path.abspath(root))
    p = subprocess.run([sys.executable, "-m", "rrcache", "nodes", shader, "--all", "--json"],
                       capture_output=True, text=True, env=env)
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
    diffs = 0
    for shader in shaders:
        same = _table(before, shader) == _table(after, shader)
        diffs += not same
        print(("same " if same else "DIFF ") + shader, flush=True)
    print(f"{len(shaders)} shaders compared, {diffs} differences")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
