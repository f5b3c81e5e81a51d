"""``rrcache bench``: the paper's scenes end to end (and the temple's PCF shadows) (see :mod:`rrcache.bench.paper`).

    rrcache bench                         # marble, trashcan, chess, temple at the sessions' resolution
    rrcache bench --quick                 # reduced sizes and budgets: a few minutes
    rrcache bench --scenes marble,my.frag:my.json --out bench-out --json

Writes ``bench.md`` and ``bench.json`` into ``--out`` after every scene, with each scene's
profile in ``<out>/<scene>.rrprofile`` (a rerun resumes the profiles). Progress goes to stderr
(:mod:`rrcache.cli.progress`: a bar on a terminal, a line per finished step elsewhere, none with
``--quiet``). ``--json`` prints the bench document; otherwise the Markdown is printed.
"""
from __future__ import annotations

import json
import sys

import click
from rich.console import Console

from rrcache.cli import interrupt
from rrcache.cli.progress import Reporter, quiet_option


@click.command("bench")
@click.option("--quick", is_flag=True, help="Reduced resolution, frames, training budget and searches.")
@click.option("--scenes", default="marble,trashcan,chess,temple", show_default=True, metavar="LIST",
              help="Comma-separated scene names, or SHADER:SESSION pairs.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="rrcache-bench", show_default=True,
              help="Folder for bench.md, bench.json and the profiles.")
@click.option("--json", "as_json", is_flag=True, help="Print the bench as JSON.")
@quiet_option
def command(quick, scenes, out_dir, as_json, quiet):
    """Profile each scene, measure its four selections, the cache algorithms, the speed-up limit,
    and dynamic resolution and simplification at equal time, side by side."""
    from rrcache.bench.paper import FULL, QUICK, run
    from rrcache.bench.paper_report import markdown
    from rrcache.bench.scenes import resolve_scenes

    chosen = resolve_scenes(scenes)
    err = Console(stderr=True)
    reporter = Reporter(err, quiet=quiet, width=60)

    def finished(scene):
        reporter.line(f"{scene.name}: done in {scene.wall_s:.0f} s; {out_dir}/bench.json updated")

    try:
        with reporter:
            result = run(chosen, QUICK if quick else FULL, out_dir, reporter.update, on_scene=finished)
    except KeyboardInterrupt:
        err.print(f"rrcache: {interrupt.word()}; finished scenes are in {out_dir}/bench.json and the profiles resume",
                  highlight=False)
        sys.exit(interrupt.exit_code())
    if as_json:
        click.echo(json.dumps(result.to_json(), ensure_ascii=False))
    else:
        click.echo(markdown(result))
