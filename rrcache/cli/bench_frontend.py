"""``rrcache bench-frontend``: front-end and analysis timings (issue 2 targets: 1 s and 3 s)."""
from __future__ import annotations

import json

import click
from rich.console import Console
from rrcache.cli.tables import TextTable


@click.command("bench-frontend")
@click.argument("shader", default="shaders/marble.glsl", type=click.Path(exists=True, dir_okay=False))
@click.option("--lines", default=3000, show_default=True, help="Size of the synthetic large shader.")
@click.option("--repeat", default=3, show_default=True, help="Runs per shader (the median is reported).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.option("--generated", "generated", multiple=True, type=click.IntRange(min=50), metavar="LINES",
              help="Also time node analysis, with its peak memory, of generated large shaders of this "
                   "many lines (a library-shaped and an ES-sketch-shaped one; repeatable), each in a "
                   "fresh process.")
def command(shader, lines, repeat, as_json, generated):
    """Time preprocessing+parsing+type checking and analysis of SHADER and of a large shader made
    from it."""
    from rrcache.bench.frontend import run, run_generated

    if generated:
        rows = run_generated(generated, repeat=repeat)
        if as_json:
            click.echo(json.dumps(rows))
            return
        table = TextTable("node analysis of generated shaders (fresh process each; median of %d)" % repeat,
                          [(col, "right" if col != "shader" else "left") for col in (
                              "shader", "lines", "AST exprs", "parse s", "analyse s", "CPU s", "µs/expr", "peak MB")])
        for r in rows:
            table.add_row(r["shader"], str(r["lines"]), str(r["exprs"]), f"{r['parse_s']:.2f}",
                          f"{r['analyse_s']:.2f}", f"{r['analyse_cpu_s']:.2f}",
                          f"{1e6 * r['analyse_cpu_s'] / max(1, r['exprs']):.0f}",
                          str(r["rss_peak_mb"]))
        table.print(Console())
        return
    timings = run(shader, lines, repeat)
    if as_json:
        click.echo(json.dumps([dict(name=t.name, lines=t.lines, parse_s=t.parse_s, analyse_s=t.analyse_s,
                                    total_s=t.total_s, nodes=t.nodes) for t in timings]))
        return
    table = TextTable("front-end + analysis (median of %d runs)" % repeat,
                      [(col, "right" if col != "shader" else "left")
                       for col in ("shader", "lines", "parse s", "analyse s", "total s", "nodes")])
    for t in timings:
        table.add_row(t.name, str(t.lines), f"{t.parse_s:.3f}", f"{t.analyse_s:.3f}", f"{t.total_s:.3f}", str(t.nodes))
    table.print(Console())
