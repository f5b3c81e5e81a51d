#!/usr/bin/env python3
"""Measure the rrcache GLSL front-end on a directory of fragment shaders with known verdicts.

Meant for a GLSL compiler's own test suite laid out like glslang's ``Test/`` folder: each
``NAME.frag`` has an expected-result file ``NAME.frag.out`` (beside it, or in a baseResults
directory given with ``--results``). A test is *valid* when its ``.out`` has no line starting
with ``ERROR:``, *invalid* when it has one, and of *unknown* validity when no ``.out`` exists.

Each shader is run through :func:`rrcache.glsl.frontend.parse_shader` (preprocess, lex, parse,
type-check, and rrcache's fragment-only restrictions) and classified as

* ``ok``           accepted;
* ``unsupported``  rejected with :class:`~rrcache.errors.UnsupportedShaderError` (a construct
  or extension rrcache does not handle, named in the message: a product limit, not a bug);
* ``rejected``     rejected with another rrcache error (``ParseError``, ``SemanticError``,
  ``PreprocessorError``...): on a valid shader this is a front-end gap;
* ``crash``        any other exception escaped: always a bug.

With ``--frontend-only`` the fragment-only product checks of ``parse_shader`` (one colour output,
no other stage) are skipped: preprocess → parse → check, which measures the language coverage.

``--exclude`` leaves files out by glob (``--exclude 'hlsl.*'`` for glslang's HLSL tests);
``--verdicts FILE`` takes the expected verdicts from a list of ``NAME<TAB>valid|invalid`` lines
instead of ``.out`` files. Valid shaders are also counted per category: ``vulkan`` (glslang's
``spv.*``/``vulkan*`` tests, compiled with Vulkan semantics), ``extension`` (other files with an
``#extension`` directive) and ``core`` (GLSL 1.10–4.60, ES, compatibility, no extension).

Nothing here needs network access. Usage::

    python tools/glsl_conformance.py /tmp/glslang_tests
    python tools/glsl_conformance.py /tmp/glslang_tests --json report.json -v
    python tools/glsl_conformance.py glslang/Test --results glslang/Test/baseResults \
        --exclude 'hlsl.*' --frontend-only
"""
from __future__ import annotations

import argparse
import fnmatch
import glob
import json
import os
import re
import sys
import traceback
from collections import Counter

_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(_HERE))

from rrcache.errors import RRCacheError, UnsupportedShaderError  # noqa: E402
from rrcache.glsl.frontend import parse_shader  # noqa: E402
from rrcache.glsl.parser import parse_preprocessed  # noqa: E402
from rrcache.glsl.preprocessor import preprocess  # noqa: E402
from rrcache.glsl.semantic import check  # noqa: E402


def expected_validity(frag_path: str, results_dir: str | None) -> str:
    """``valid``, ``invalid`` or ``unknown`` from the ``.out`` file of ``frag_path``."""
    name = os.path.basename(frag_path)
    candidates = [frag_path + ".out"]
    if results_dir:
        candidates.insert(0, os.path.join(results_dir, name + ".out"))
    for out in candidates:
        if os.path.exists(out):
            with open(out, encoding="utf-8", errors="replace") as f:
                for line in f:
                    if line.startswith("ERROR:"):
                        return "invalid"
            return "valid"
    return "unknown"


def category(path: str) -> str:
    """``vulkan``, ``extension`` or ``core`` (see the module docstring)."""
    name = os.path.basename(path)
    if name.startswith(("spv.", "vulkan")):
        return "vulkan"
    with open(path, encoding="utf-8-sig", errors="replace") as f:
        text = f.read()
    return "extension" if re.search(r"^\s*#\s*extension\b", text, re.M) else "core"


def read_verdicts(path: str) -> dict[str, str]:
    """``NAME<TAB>valid|invalid[<TAB>how it was decided]`` lines -> {name: verdict}."""
    verdicts = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            parts = line.rstrip("\n").split("\t")
            if len(parts) >= 2 and parts[1] in ("valid", "invalid"):
                verdicts[parts[0]] = parts[1]
    return verdicts


def run_one(path: str, frontend_only: bool = False) -> tuple[str, str]:
    """Returns ``(outcome, message)``; outcome in ``ok unsupported rejected crash``."""
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as f:
            source = f.read()
        if frontend_only:
            pp = preprocess(source, path, {}, (os.path.dirname(path),))
            unit = parse_preprocessed(pp, path)
            check(unit, path)
        else:
            parse_shader(source, path, include_dirs=(os.path.dirname(path),))
        return "ok", ""
    except UnsupportedShaderError as e:
        return "unsupported", str(e)
    except RRCacheError as e:
        return "rejected", f"{type(e).__name__}: {e}"
    except RecursionError as e:  # still a bug, but report it without a giant traceback
        return "crash", f"RecursionError: {e}"
    except Exception as e:  # noqa: BLE001 - anything else escaping is what we look for
        tb = traceback.extract_tb(e.__traceback__)[-1]
        return "crash", (f"{type(e).__name__}: {e} (at {os.path.basename(tb.filename)}:"
                         f"{tb.lineno})")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("directory", help="folder holding *.frag files (and *.frag.out verdicts)")
    ap.add_argument("--results", help="folder of NAME.frag.out files (glslang baseResults)")
    ap.add_argument("--pattern", default="*.frag", help="file glob (default *.frag)")
    ap.add_argument("--exclude", action="append", default=[], metavar="GLOB",
                    help="leave out files matching GLOB (repeatable), e.g. 'hlsl.*'")
    ap.add_argument("--verdicts", metavar="FILE",
                    help="expected verdicts as NAME<TAB>valid|invalid lines (instead of .out)")
    ap.add_argument("--frontend-only", action="store_true",
                    help="skip parse_shader's fragment-only product checks")
    ap.add_argument("--json", metavar="FILE", help="also write the per-file results as JSON")
    ap.add_argument("-v", "--verbose", action="store_true", help="list every non-ok result")
    args = ap.parse_args(argv)

    files = sorted(p for p in glob.glob(os.path.join(args.directory, args.pattern))
                   if not any(fnmatch.fnmatch(os.path.basename(p), g) for g in args.exclude))
    verdicts = read_verdicts(args.verdicts) if args.verdicts else {}
    if not files:
        print(f"no files matching {args.pattern} in {args.directory}", file=sys.stderr)
        return 2
    rows = []
    for path in files:
        validity = verdicts.get(os.path.basename(path)) or expected_validity(path, args.results)
        outcome, message = run_one(path, args.frontend_only)
        rows.append({"file": os.path.basename(path), "expected": validity, "outcome": outcome,
                     "category": category(path), "message": message})

    table = Counter((r["expected"], r["outcome"]) for r in rows)
    outcomes = ["ok", "unsupported", "rejected", "crash"]
    print(f"{'expected':<10}" + "".join(f"{o:>13}" for o in outcomes) + f"{'total':>9}")
    for exp in ("valid", "invalid", "unknown"):
        n = sum(table[(exp, o)] for o in outcomes)
        if n:
            print(f"{exp:<10}" + "".join(f"{table[(exp, o)]:>13}" for o in outcomes)
                  + f"{n:>9}")
    valid = [r for r in rows if r["expected"] == "valid"]
    invalid = [r for r in rows if r["expected"] == "invalid"]
    crashes = [r for r in rows if r["outcome"] == "crash"]
    if valid:
        ok = sum(r["outcome"] == "ok" for r in valid)
        print(f"\nvalid shaders accepted: {ok}/{len(valid)}")
        for cat in ("core", "vulkan", "extension"):
            in_cat = [r for r in valid if r["category"] == cat]
            if in_cat:
                print(f"  {cat:<10} {sum(r['outcome'] == 'ok' for r in in_cat)}/{len(in_cat)}")
    if invalid:
        rej = sum(r["outcome"] in ("rejected", "unsupported") for r in invalid)
        print(f"invalid shaders also rejected: {rej}/{len(invalid)}")
    print(f"crashes (non-rrcache exceptions, bugs): {len(crashes)}")

    shown = [r for r in rows if r["outcome"] == "crash" or (
        r["outcome"] != "ok" and (args.verbose or r["expected"] != "invalid"))]
    if shown:
        print("\nnot accepted:" if args.verbose else "\nnot accepted (valid/unknown), crashes:")
        for r in shown:
            print(f"  [{r['expected']}/{r['outcome']}] {r['file']}: {r['message']}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"summary": {f"{e}/{o}": n for (e, o), n in sorted(table.items())},
                       "results": rows}, f, indent=1)
    return 1 if crashes else 0


if __name__ == "__main__":
    sys.exit(main())
