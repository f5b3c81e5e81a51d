"""``rrcache bench``: the paper's three scenes end to end (see :mod:`rrcache.bench.paper`).

    rrcache bench                         # marble, trashcan, chess at the sessions' resolution
    rrcache bench --quick                 # reduced sizes and budgets: a few minutes
    rrcache bench --scenes marble,my.frag:my.json --out bench-out --json

Writes ``bench.md`` and ``bench.json`` into ``--out`` after every scene, with each scene's
profile in ``<out>/<scene>.rrprofile`` (a rerun resumes the profiles). A progress bar runs on
stderr. ``--json`` prints the bench document; otherwise the Markdown is printed.
"""
from __future__ import annotations

import json
import sys

import click
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn


@click.command("bench")
@click.option("--quick", is_flag=True, help="Reduced resolution, frames, training budget and searches.")
@click.option("--scenes", default="marble,trashcan,chess", show_default=True, metavar="LIST",
              help="Comma-separated scene names, or SHADER:SESSION pairs.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="rrcache-bench", show_default=True,
              help="Folder for bench.md, bench.json and the profiles.")
@click.option("--json", "as_json", is_flag=True, help="Print the bench as JSON.")
def command(quick, scenes, out_dir, as_json):
    """Profile each scene, measure its four selections, the cache algorithms, the speed-up limit,
    and dynamic resolution and simplification at equal time, side by side."""
    from rrcache.bench.paper import FULL, QUICK, run
    from rrcache.bench.paper_report import markdown
    from rrcache.bench.scenes import resolve_scenes

    chosen = resolve_scenes(scenes)
    err = Console(stderr=True)
    bar = Progress(TextColumn("{task.description:<60}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   console=err, transient=True, disable=not err.is_terminal)
    task = bar.add_task("starting", total=None)

    def progress(stage, done, total):
        bar.update(task, description=stage[:60], completed=done or 0, total=total)

    def finished(scene):
        err.print(f"{scene.name}: done in {scene.wall_s:.0f} s; {out_dir}/bench.json updated", highlight=False)

    try:
        with bar:
            result = run(chosen, QUICK if quick else FULL, out_dir, progress, on_scene=finished)
    except KeyboardInterrupt:
        err.print(f"rrcache: interrupted; finished scenes are in {out_dir}/bench.json and the profiles resume",
                  highlight=False)
        sys.exit(130)
    if as_json:
        click.echo(json.dumps(result.to_json(), ensure_ascii=False))
    else:
        click.echo(markdown(result))
