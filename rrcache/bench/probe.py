"""Time and peak memory of node analysis of one shader file, in this process.

    python -m rrcache.bench.probe SHADER [--max-unroll N]
    PYTHONPATH=OTHER_CHECKOUT python rrcache/bench/probe.py SHADER    # another version

Prints one JSON line: lines, AST expression nodes of the analysed program, parse seconds,
analysis seconds (inline + unroll + cacheable nodes; wall clock, and the process's CPU time,
which a loaded machine inflates less), the process's peak resident memory (MB)
before and after the analysis, and the table's counts. Only `parse_shader` and `cacheable_nodes`
are used, so the same file measures any version of rrcache put on PYTHONPATH (that is how
docs/bench_frontend.md compares before and after). ``rrcache bench-frontend --generated`` runs
it once per shader in a fresh process: peak resident memory only grows.
"""
from __future__ import annotations

import argparse
import json
import resource
import sys
import time


def _exprs_of(root):
    """The expression nodes under ``root``, for versions of rrcache without
    ``rrcache.glsl.ast.iter_exprs`` (a generic walk over the syntax fields)."""
    from rrcache.glsl import ast as A

    stack = [root]
    while stack:
        node = stack.pop()
        if isinstance(node, A.Expr):
            yield node
        for name, value in vars(node).items():
            if name in ("loc", "symbol", "type") or (name == "target" and isinstance(node, A.Call)):
                continue
            for item in (value if isinstance(value, (list, tuple)) else (value,)):
                for sub in (item if isinstance(item, tuple) else (item,)):
                    if isinstance(sub, A.Node):
                        stack.append(sub)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("shader")
    ap.add_argument("--max-unroll", type=int, default=None)
    args = ap.parse_args(argv)
    from rrcache.analysis import cacheable_nodes
    try:
        from rrcache.glsl.ast import iter_exprs
    except ImportError:      # versions before the AST traversal moved to glsl/ast.py
        iter_exprs = _exprs_of
    from rrcache.glsl.frontend import parse_shader

    from rrcache.glsl.preprocessor import read_source

    source, _ = read_source(args.shader)
    t0 = time.perf_counter()
    shader = parse_shader(source, args.shader)
    t1 = time.perf_counter()
    c1 = time.process_time()
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    kw = {} if args.max_unroll is None else {"max_iterations": args.max_unroll}
    table = cacheable_nodes(shader, **kw)
    t2 = time.perf_counter()
    c2 = time.process_time()
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    exprs = sum(1 for _ in iter_exprs(table.shader.unit))
    print(json.dumps({"shader": args.shader, "lines": source.count("\n") + 1, "exprs": exprs,
                      "parse_s": round(t1 - t0, 3), "analyse_s": round(t2 - t1, 3),
                      "analyse_cpu_s": round(c2 - c1, 3),
                      "rss_before_mb": round(rss0), "rss_peak_mb": round(rss1),
                      "counts": table.counts()}))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
