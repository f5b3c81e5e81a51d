#!/usr/bin/env python3
"""Measure the rrcache GLSL front-end and node analysis on a folder of fragment shaders with known verdicts.

Meant for a GLSL compiler's own test suite laid out like glslang's ``Test/`` folder: each
``NAME.frag`` has an expected-result file ``NAME.frag.out`` (beside it, or in a baseResults
directory given with ``--results``). A test is *valid* when its ``.out`` has no line starting
with ``ERROR:`` (glslang's own rule: compile and link the file alone), *invalid* when it has one,
and of *unknown* validity when it has no ``.out`` of its own (glslang's multi-file link tests).

Every shader runs in a fresh worker process (``--jobs`` at a time, one shader per process) under
a time limit (``--timeout``, a SIGALRM in the worker) and an address-space limit (``--memory``),
so one slow or huge shader cannot stall or sink the run. Each goes through four stages, each one
only public functions that every revision of rrcache has had:

* ``parse``   :func:`rrcache.glsl.preprocessor.preprocess` + :func:`rrcache.glsl.parser.parse_preprocessed`;
* ``check``   :func:`rrcache.glsl.semantic.check` on that tree (the language: types, scopes, built-ins);
* ``accept``  :func:`rrcache.glsl.frontend.parse_shader` (the whole front-end, with rrcache's
  fragment-only product checks: one colour output, no other stage);
* ``nodes``   :func:`rrcache.analysis.cacheable_nodes` on the accepted shader (inlining, unrolling,
  def-use, costs); the number of cacheable nodes it lists is recorded.

A stage's result is ``ok``; ``unsupported`` (:class:`~rrcache.errors.UnsupportedShaderError`, a
product limit named in the message); ``rejected`` (another :class:`~rrcache.errors.RRCacheError`);
``timeout`` / ``memory`` (the limits above); or ``crash`` (any other exception: always a bug,
listed with the exception and where it was raised). A stage after a failed one is ``skipped``.

The old ``outcome`` of a file (``ok unsupported rejected crash``) is the ``accept`` stage, or with
``--frontend-only`` the ``check`` stage (language coverage without the product checks).

``--opengl`` keeps only glslang's OpenGL fragment tests (see :data:`VULKAN_OR_HLSL` and
:data:`VULKAN_ONLY_FILES`); ``--exclude`` leaves out files by glob; ``--verdicts FILE`` takes the
expected verdicts from ``NAME<TAB>valid|invalid`` lines instead of ``.out`` files. Valid shaders
are also counted per category: ``vulkan`` (``spv.*``/``vulkan*``), ``extension`` (an
``#extension`` directive) and ``core``.

Nothing here needs network access. Usage::

    python tools/glsl_conformance.py glslang/Test --results glslang/Test/baseResults --opengl \\
        --json report.json -v
"""
from __future__ import annotations

import argparse
import fnmatch
import glob
import json
import multiprocessing
import os
import re
import sys
import time
import traceback
from collections import Counter

_HERE = os.path.dirname(os.path.abspath(__file__))
if not os.environ.get("PYTHONPATH"):  # an explicit PYTHONPATH picks the rrcache to measure
    sys.path.insert(0, os.path.dirname(_HERE))

#: Name globs of glslang tests that are not OpenGL GLSL: HLSL, and the suites glslang compiles
#: for Vulkan (or WebGPU through Vulkan) by name.
VULKAN_OR_HLSL = ("hlsl.*", "spv.*", "vk.*", "vulkan*", "*.vk.*", "web.*")
#: OpenGL-looking names whose only driver in glslang compiles them for Vulkan: ``Test/runtests``
#: runs them with ``-V``/``-H`` (Vulkan SPIR-V), or ``gtests/Spv.FromFile.cpp`` lists them only
#: under a Vulkan target (``CompileVulkanToSpirvTest``, ``VulkanSemantics``).
VULKAN_ONLY_FILES = ("enhanced.*.frag", "glsl.versionOverride.frag",
                     "glsl.autosampledtextures.frag", "link.crossStageOptimization.frag",
                     "rayQuery-allOps.frag", "samplerlessTextureFunctions.frag")

STAGES = ("parse", "check", "accept", "nodes")


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


class _TimeLimit(BaseException):
    """Raised by the worker's alarm; a BaseException so no ``except Exception`` swallows it."""


def _on_alarm(signum, frame):  # noqa: ARG001
    raise _TimeLimit()


def _where(e: BaseException) -> str:
    tb = traceback.extract_tb(e.__traceback__)
    if not tb:
        return ""
    last = tb[-1]
    return f" (at {os.path.basename(last.filename)}:{last.lineno} in {last.name})"


def run_one(path: str, timeout: float = 0, memory_mb: int = 0) -> dict:
    """Run the four stages on ``path``; returns ``{stage: result, "message", "listed", "stage",
    "seconds"}``: ``listed`` is the number of cacheable nodes, ``stage`` the first stage that did
    not succeed (``None`` when all did)."""
    from rrcache.errors import RRCacheError, UnsupportedShaderError

    if memory_mb:
        import resource
        limit = memory_mb * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    if timeout:
        import signal
        signal.signal(signal.SIGALRM, _on_alarm)
        signal.setitimer(signal.ITIMER_REAL, timeout)
    row: dict = {s: "skipped" for s in STAGES}
    row.update(message="", listed=None, stage=None)
    start = time.perf_counter()
    stage = "parse"
    try:
        from rrcache.analysis import cacheable_nodes
        from rrcache.glsl.frontend import parse_shader
        from rrcache.glsl.parser import parse_preprocessed
        from rrcache.glsl.preprocessor import preprocess
        from rrcache.glsl.semantic import check

        with open(path, encoding="utf-8-sig", errors="replace") as f:
            source = f.read()
        include_dirs = (os.path.dirname(path),)
        pp = preprocess(source, path, {}, include_dirs)
        unit = parse_preprocessed(pp, path)
        row["parse"] = "ok"
        stage = "check"
        check(unit, path)
        row["check"] = "ok"
        stage = "accept"
        shader = parse_shader(source, path, include_dirs=include_dirs)
        row["accept"] = "ok"
        stage = "nodes"
        table = cacheable_nodes(shader)
        row["listed"] = len(table.nodes)
        row[stage] = "ok"
        stage = None
    except _TimeLimit:
        row[stage] = "timeout"
        row["message"] = f"over the {timeout:g} s limit in {stage}"
    except UnsupportedShaderError as e:
        row[stage], row["message"] = "unsupported", str(e)
    except RRCacheError as e:
        row[stage], row["message"] = "rejected", f"{type(e).__name__}: {e}"
    except MemoryError as e:
        row[stage], row["message"] = "memory", f"MemoryError over {memory_mb} MB{_where(e)}"
    except RecursionError as e:  # a bug, reported without a giant traceback
        row[stage], row["message"] = "crash", f"RecursionError: {e}{_where(e)}"
    except Exception as e:  # noqa: BLE001 - anything else escaping is what we look for
        row[stage], row["message"] = "crash", f"{type(e).__name__}: {e}{_where(e)}"
    finally:
        if timeout:
            signal.setitimer(signal.ITIMER_REAL, 0)
    row["stage"] = stage
    row["seconds"] = round(time.perf_counter() - start, 3)
    return row


def _job(args: tuple) -> dict:
    return run_one(*args)


def outcome(row: dict, frontend_only: bool) -> str:
    """The file's front-end verdict: ``ok unsupported rejected crash`` (timeouts count as crash)."""
    for s in (("parse", "check") if frontend_only else ("parse", "check", "accept")):
        if row[s] != "ok":
            return row[s] if row[s] in ("unsupported", "rejected") else "crash"
    return "ok"


def select_files(directory: str, pattern: str, exclude: list[str], opengl: bool) -> list[str]:
    globs = list(exclude) + (list(VULKAN_OR_HLSL + VULKAN_ONLY_FILES) if opengl else [])
    return sorted(p for p in glob.glob(os.path.join(directory, pattern))
                  if not any(fnmatch.fnmatch(os.path.basename(p), g) for g in globs))


def stage_table(rows: list[dict]) -> list[str]:
    """One line per verdict: files, parse, check, accept, nodes, >=1 node, crashes."""
    head = ["files", "parse", "check", "accept", "nodes", ">=1 node", "crash", "timeout"]
    lines = [f"{'expected':<10}" + "".join(f"{h:>10}" for h in head)]
    for exp in ("valid", "invalid", "unknown", "all"):
        sel = [r for r in rows if exp in ("all", r["expected"])]
        if not sel:
            continue
        counts = [len(sel)] + [sum(r[s] == "ok" for r in sel) for s in STAGES] + [
            sum(bool(r["listed"]) for r in sel),
            sum(any(r[s] == "crash" for s in STAGES) for r in sel),
            sum(any(r[s] in ("timeout", "memory") for s in STAGES) for r in sel)]
        lines.append(f"{exp:<10}" + "".join(f"{c:>10}" for c in counts))
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("directory", help="folder holding *.frag files (and *.frag.out verdicts)")
    ap.add_argument("--results", help="folder of NAME.frag.out files (glslang baseResults)")
    ap.add_argument("--pattern", default="*.frag", help="file glob (default *.frag)")
    ap.add_argument("--exclude", action="append", default=[], metavar="GLOB",
                    help="leave out files matching GLOB (repeatable), e.g. 'hlsl.*'")
    ap.add_argument("--opengl", action="store_true",
                    help="keep only glslang's OpenGL tests (no HLSL, Vulkan or WebGPU ones)")
    ap.add_argument("--verdicts", metavar="FILE",
                    help="expected verdicts as NAME<TAB>valid|invalid lines (instead of .out)")
    ap.add_argument("--frontend-only", action="store_true",
                    help="the summary's outcome is the type check, without parse_shader's "
                         "fragment-only product checks")
    ap.add_argument("--timeout", type=float, default=20.0,
                    help="seconds per shader, all stages (default 20; 0: none)")
    ap.add_argument("--memory", type=int, default=4096,
                    help="address-space limit per shader in MB (default 4096, of which rrcache's "
                         "deep-recursion thread reserves 1024 of stack; 0: none)")
    ap.add_argument("-j", "--jobs", type=int, default=1, help="shaders at a time (default 1)")
    ap.add_argument("--json", metavar="FILE", help="also write the per-file results as JSON")
    ap.add_argument("-v", "--verbose", action="store_true", help="list every non-ok result")
    args = ap.parse_args(argv)

    files = select_files(args.directory, args.pattern, args.exclude, args.opengl)
    verdicts = read_verdicts(args.verdicts) if args.verdicts else {}
    if not files:
        print(f"no files matching {args.pattern} in {args.directory}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    jobs = [(p, args.timeout, args.memory) for p in files]
    # one shader per process: a fresh analysis each, and a worker that ran out of memory or time
    # takes nothing of the next shader with it
    with multiprocessing.get_context("fork").Pool(max(1, args.jobs), maxtasksperchild=1) as pool:
        results = pool.map(_job, jobs, chunksize=1)
    elapsed = time.perf_counter() - start
    rows = []
    for path, res in zip(files, results):
        validity = verdicts.get(os.path.basename(path)) or expected_validity(path, args.results)
        rows.append({"file": os.path.basename(path), "expected": validity,
                     "outcome": outcome(res, args.frontend_only), "category": category(path),
                     **res})

    print(f"{len(rows)} shaders in {elapsed:.1f} s ({args.jobs} at a time, "
          f"{args.timeout:g} s and {args.memory} MB each)\n")
    print("\n".join(stage_table(rows)))
    print("\n(parse: preprocess+parse; check: type check; accept: parse_shader; nodes: "
          "cacheable_nodes ran; >=1 node: it listed one or more)\n")

    table = Counter((r["expected"], r["outcome"]) for r in rows)
    valid = [r for r in rows if r["expected"] == "valid"]
    invalid = [r for r in rows if r["expected"] == "invalid"]
    crashes = [r for r in rows if any(r[s] == "crash" for s in STAGES)]
    if valid:
        ok = sum(r["outcome"] == "ok" for r in valid)
        print(f"valid shaders accepted: {ok}/{len(valid)}")
        for cat in ("core", "vulkan", "extension"):
            in_cat = [r for r in valid if r["category"] == cat]
            if in_cat:
                print(f"  {cat:<10} {sum(r['outcome'] == 'ok' for r in in_cat)}/{len(in_cat)}")
    if invalid:
        rej = sum(r["outcome"] in ("rejected", "unsupported") for r in invalid)
        print(f"invalid shaders also rejected: {rej}/{len(invalid)}")
    print(f"crashes (non-rrcache exceptions, bugs): {len(crashes)}")

    def failed(r: dict) -> bool:
        return r["stage"] is not None

    shown = [r for r in rows if r in crashes or (failed(r) and (
        args.verbose or r["expected"] != "invalid"))]
    if shown:
        print("\nstopped before the end (stage, result):" if args.verbose else
              "\nstopped before the end (valid/unknown), crashes:")
        for r in shown:
            print(f"  [{r['expected']}] {r['file']}: {r['stage']} {r[r['stage']]}: {r['message']}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"seconds": round(elapsed, 1), "stages": stage_table(rows),
                       "summary": {f"{e}/{o}": n for (e, o), n in sorted(table.items())},
                       "results": rows}, f, indent=1)
    return 1 if crashes else 0


if __name__ == "__main__":
    sys.exit(main())
