"""``rrcache bench-cache SHADER SESSION --node ID``: one node cached at several periods, with the
three algorithms and three refresh block sizes, and the all-hit limit, side by side with the
original in one run (see :mod:`rrcache.bench.cache`)."""
from __future__ import annotations

import json

import click
from rich.console import Console

from rrcache.cli.options import include_dirs_option, resolution_option as _resolution, vert_option


@click.command("bench-cache")
@click.argument("shader", type=click.Path(dir_okay=False))
@click.argument("session", type=click.Path(dir_okay=False))
@click.option("--node", required=True, metavar="ID", help="The node to cache (see `rrcache nodes --session`).")
@click.option("--periods", default="8,16,32", show_default=True, help="Refresh periods to compare.")
@click.option("--compare-period", default=16, show_default=True, help="Δn for the algorithm and block comparisons.")
@click.option("--frames", default=60, show_default=True, help="Consecutive frames per configuration.")
@click.option("--repeats", default=3, show_default=True, type=click.IntRange(1, 50),
              help="Measurements of each configuration (rows show the median and the range).")
@click.option("--resolution", callback=_resolution, default=None, metavar="WxH")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@click.option("--markdown", is_flag=True, help="Print Markdown tables.")
@vert_option
@include_dirs_option
def command(shader, session, node, periods, compare_period, frames, repeats, resolution, as_json, markdown, vert,
            include_dirs):
    """Measure the cache on one node of SHADER over SESSION."""
    from rrcache.bench.cache import run

    err = Console(stderr=True)
    try:
        period_list = [int(p) for p in periods.split(",") if p.strip()]
    except ValueError:
        raise click.BadParameter(f"{periods!r} is not a comma-separated list of integers", param_hint="--periods")
    bench = run(shader, session, node, period_list, compare_period, frames, resolution=resolution, repeats=repeats,
                include_dirs=include_dirs,
                progress=lambda msg: err.print(f"[dim]{msg}[/dim]"), vertex=vert)
    if as_json:
        click.echo(json.dumps(bench.to_json()))
    else:
        click.echo(bench.markdown())
