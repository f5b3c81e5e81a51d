"""Front-end and analysis speed: `rrcache bench-frontend`.

``--generated LINES`` also measures node analysis of large generated shaders
(:mod:`rrcache.bench.large_shader`: a realistic library-shaped one and an ES-sketch-shaped one),
each in a fresh process (:mod:`rrcache.bench.probe`) so that its peak resident memory is its
own (:func:`run_generated`). Issue 14's target: any single shader under 5 s and 500 MB, linear
in the number of AST nodes.

Targets (issue 2): front-end plus analysis of Marble under 1 s; a 3,000-line shader under 3 s.
The large shader is synthetic but shaped like production code: ``copies`` renamed copies of a
real shader's functions (by default ``shaders/marble.glsl``), each called once from ``main`` and
summed, so inlining and unrolling have real work to do.
"""
from __future__ import annotations

import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from rrcache.analysis import cacheable_nodes
from rrcache.glsl.frontend import parse_shader


@dataclass
class FrontendTiming:
    name: str
    lines: int
    parse_s: float      # preprocess + lex + parse + type check (median)
    analyse_s: float    # inline + unroll + cacheable nodes (median)
    nodes: int

    @property
    def total_s(self) -> float:
        return self.parse_s + self.analyse_s


def synthetic_shader(template: str, target_lines: int = 3000) -> str:
    """Repeat ``template``'s functions (renamed per copy) until the source has about
    ``target_lines`` lines; ``main`` sums the copies' colours.

    The template must be a core shader whose ``main`` ends by writing ``fragColor``.
    """
    header, _, rest = template.partition("\n// ---- functions ----\n") if "// ---- functions ----" in template else ("", "", template)
    body_start = rest.index("void main()")
    declarations_end = _first_function(rest)
    globals_part, functions, main_part = rest[:declarations_end], rest[declarations_end:body_start], rest[body_start:]
    names = re.findall(r"^\s*(?:float|vec[234]|void|int|mat[234])\s+(\w+)\s*\(", functions, re.M)
    main_body = main_part[main_part.index("{") + 1: main_part.rindex("}")]
    per_copy = functions.count("\n") + main_body.count("\n") + 4
    copies = max(1, (target_lines - globals_part.count("\n")) // per_copy)
    out = [globals_part]
    calls = []
    for k in range(copies):
        renamed = functions
        body = main_body.replace("fragColor =", f"return").replace("vec4(color, 1.0)", "color")
        for name in sorted(names, key=len, reverse=True):
            renamed = re.sub(rf"\b{name}\b", f"{name}_{k}", renamed)
            body = re.sub(rf"\b{name}\b", f"{name}_{k}", body)
        out.append(renamed)
        out.append(f"vec3 shade_{k}() {{{body}}}\n")
        calls.append(f"shade_{k}()")
    out.append("void main() {\n    vec3 sum = vec3(0.0);\n")
    out.extend(f"    sum += {c};\n" for c in calls)
    out.append(f"    fragColor = vec4(sum / {float(copies)}, 1.0);\n}}\n")
    return "".join(out)


def _first_function(source: str) -> int:
    match = re.search(r"^(?:float|vec[234]|void|int|mat[234])\s+\w+\s*\([^;{]*\)\s*\{", source, re.M)
    return match.start() if match else 0


def time_shader(name: str, source: str, repeat: int = 3) -> FrontendTiming:
    """Median times of parsing and of analysis of ``source`` over ``repeat`` runs."""
    parse_times, analyse_times = [], []
    nodes = 0
    for _ in range(repeat):
        start = time.perf_counter()
        shader = parse_shader(source, name)
        mid = time.perf_counter()
        table = cacheable_nodes(shader)
        end = time.perf_counter()
        parse_times.append(mid - start)
        analyse_times.append(end - mid)
        nodes = len(table.nodes)
    return FrontendTiming(name, source.count("\n") + 1, statistics.median(parse_times),
                          statistics.median(analyse_times), nodes)


def run(shader_path: str | Path, lines: int = 3000, repeat: int = 3) -> list[FrontendTiming]:
    """Time the shader at ``shader_path`` and a ``lines``-line synthetic shader built from it."""
    from rrcache.glsl.preprocessor import read_source

    path = Path(shader_path)
    source, _ = read_source(str(path))
    return [time_shader(str(path), source, repeat),
            time_shader(f"synthetic-{lines}-lines.glsl", synthetic_shader(source, lines), repeat)]


def probe(path: str | Path, max_unroll: int | None = None) -> dict:
    """Node analysis of the shader at ``path`` in a fresh Python process
    (:mod:`rrcache.bench.probe`): its JSON line (lines, exprs, parse_s, analyse_s,
    rss_before_mb, rss_peak_mb, counts)."""
    cmd = [sys.executable, "-m", "rrcache.bench.probe", str(path)]
    if max_unroll is not None:
        cmd += ["--max-unroll", str(max_unroll)]
    done = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ))
    if done.returncode != 0:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"node analysis of {path} failed: {tail}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def run_generated(sizes, kinds=("realistic", "sketch"), repeat: int = 1) -> list[dict]:
    """Probe generated shaders of each size in ``sizes`` (lines) and kind; with ``repeat`` > 1
    the run of median analysis time is kept (each run a fresh process)."""
    from rrcache.bench.large_shader import realistic_shader, sketch_shader

    make = {"realistic": realistic_shader, "sketch": sketch_shader}
    rows = []
    with tempfile.TemporaryDirectory(prefix="rrcache-bench-") as tmp:
        for kind in kinds:
            for lines in sizes:
                path = Path(tmp) / f"{kind}-{lines}.frag"
                path.write_text(make[kind](int(lines)))
                runs = sorted((probe(path) for _ in range(max(1, repeat))),
                              key=lambda r: r["analyse_s"])
                row = dict(runs[len(runs) // 2])
                row["shader"] = f"{kind}-{lines}"
                rows.append(row)
    return rows
