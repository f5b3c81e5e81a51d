"""Front-end and analysis speed: `rrcache bench-frontend`.

Targets (issue 2): front-end plus analysis of Marble under 1 s; a 3,000-line shader under 3 s.
The large shader is synthetic but shaped like production code: ``copies`` renamed copies of a
real shader's functions (by default ``shaders/marble.glsl``), each called once from ``main`` and
summed, so inlining and unrolling have real work to do.
"""
from __future__ import annotations

import re
import statistics
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
    path = Path(shader_path)
    source = path.read_text()
    return [time_shader(str(path), source, repeat),
            time_shader(f"synthetic-{lines}-lines.glsl", synthetic_shader(source, lines), repeat)]
