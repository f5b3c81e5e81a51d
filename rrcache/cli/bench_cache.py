"""``rrcache bench-cache SHADER SESSION --node ID``: one node cached at several periods, with the
three algorithms and three refresh block sizes, and the all-hit limit, side by side with the
original in one run (see :mod:`rrcache.bench.cache`).

``--breakdown`` measures only the all-hit frame, stage by stage (clears, each pass, the query
results, the read-back; each stage's fixed cost at 8×8 and its cost per covered pixel), for the
three-pass and two-pass algorithms in each of ``--formats`` (default rgba32f, rgba8: the colour
target timings used before and the one applications draw into), side by side with the original.

``--filters bilinear,edge,plane`` (the default) times the hit test and reconstruction filters at the
compared period, and ``--misses`` (on by default) sorts each one's misses by cause (refresh, the
depth-edge band, disocclusion, off screen), as shares of the covered pixels and of the 4×4 blocks
that hold a miss (see :mod:`rrcache.runtime.misses`).
"""
from __future__ import annotations

import json

import click
from rich.console import Console

from rrcache.budgets import MAX_PERIOD, check_period
from rrcache.cli.options import include_dirs_option, resolution_option as _resolution, vert_option
from rrcache.cli.progress import Reporter, quiet_option
from rrcache.gl.formats import COLOR_FORMATS, DEFAULT_TIMING_FORMAT


@click.command("bench-cache")
@click.argument("shader", type=click.Path(dir_okay=False))
@click.argument("session", type=click.Path(dir_okay=False))
@click.option("--node", required=True, metavar="ID", help="The node to cache (see `rrcache nodes --session`).")
@click.option("--periods", default="8,16,32", show_default=True, help="Refresh periods to compare.")
@click.option("--compare-period", default=16, show_default=True, type=click.IntRange(1, MAX_PERIOD),
              help="Δn for the algorithm and block comparisons.")
@click.option("--frames", default=60, show_default=True, type=click.IntRange(1, 100_000),
              help="Consecutive frames per configuration.")
@click.option("--repeats", default=3, show_default=True, type=click.IntRange(1, 50),
              help="Measurements of each configuration (rows show the median and the range).")
@click.option("--resolution", callback=_resolution, default=None, metavar="WxH")
@click.option("--timing-format", type=click.Choice(tuple(COLOR_FORMATS)), default=DEFAULT_TIMING_FORMAT,
              show_default=True, help="Colour target of every render, original and variants alike.")
@click.option("--breakdown", is_flag=True, help="Only the all-hit frame, stage by stage, per algorithm and format.")
@click.option("--formats", default="rgba32f,rgba8", show_default=True,
              help="Colour formats of --breakdown, side by side.")
@click.option("--payloads", default="f4", show_default=True,
              help="Payload layouts of --breakdown, side by side: f4, f2 (precision), and "
                   "f4-packed (32-bit with the inverse depth packed into the payload's free "
                   "channel: one render target and one fetch fewer).")
@click.option("--algorithms", default=None,
              help="Algorithms side by side ('' for none): default all three at the compared period, "
                   "three-pass,two-pass with --breakdown.")
@click.option("--blocks", default="1,2,4", show_default=True,
              help="Refresh block sizes compared at the compared period ('' for none).")
@click.option("--filters", default="bilinear,edge,plane", show_default=True,
              help="Hit test and reconstruction filters timed at the compared period ('' for none).")
@click.option("--misses/--no-misses", default=True, show_default=True,
              help="Sort each filter's misses by cause (refresh, depth-edge band, disocclusion, off screen) "
                   "in an untimed run that reads the hit maps.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@click.option("--markdown", is_flag=True, help="Print Markdown tables.")
@quiet_option
@vert_option
@include_dirs_option
def command(shader, session, node, periods, compare_period, frames, repeats, resolution, timing_format, breakdown,
            formats, payloads, algorithms, blocks, filters, misses, as_json, markdown, quiet, vert, include_dirs):
    """Measure the cache on one node of SHADER over SESSION."""
    from rrcache.bench.cache import PAYLOAD_LAYOUTS, breakdown as run_breakdown, run

    err = Console(stderr=True)
    try:
        period_list = [int(p) for p in periods.split(",") if p.strip()]
    except ValueError:
        raise click.BadParameter(f"{periods!r} is not a comma-separated list of integers", param_hint="--periods")
    period_list = [check_period(p, "--periods") for p in period_list]
    format_list = [f.strip() for f in formats.split(",") if f.strip()]
    bad = [f for f in format_list if f not in COLOR_FORMATS]
    if bad or not format_list:
        raise click.BadParameter(f"{formats!r}: give colour formats from {', '.join(COLOR_FORMATS)}",
                                 param_hint="--formats")
    payload_list = [p.strip() for p in payloads.split(",") if p.strip()]
    if not payload_list or any(p not in PAYLOAD_LAYOUTS for p in payload_list):
        raise click.BadParameter(f"{payloads!r}: give some of {', '.join(PAYLOAD_LAYOUTS)}", param_hint="--payloads")
    if algorithms is None:
        algorithms = "three-pass,two-pass" if breakdown else "three-pass,two-pass,one-pass"
    algorithm_list = [a.strip() for a in algorithms.split(",") if a.strip()]
    if (breakdown and not algorithm_list) or any(a not in ("three-pass", "two-pass", "one-pass") for a in algorithm_list):
        raise click.BadParameter(f"{algorithms!r}: give three-pass, two-pass and/or one-pass", param_hint="--algorithms")
    try:
        block_list = [int(b) for b in blocks.split(",") if b.strip()]
    except ValueError:
        raise click.BadParameter(f"{blocks!r} is not a comma-separated list of block sizes", param_hint="--blocks")
    from rrcache.runtime import BLOCK_SIZES

    if any(b not in BLOCK_SIZES for b in block_list):
        raise click.BadParameter(f"{blocks!r}: give block sizes from {', '.join(map(str, BLOCK_SIZES))}",
                                 param_hint="--blocks")
    from rrcache.runtime.glsl import FILTERS

    filter_list = [f.strip() for f in filters.split(",") if f.strip()]
    if any(f not in FILTERS for f in filter_list):
        raise click.BadParameter(f"{filters!r}: give some of {', '.join(FILTERS)}", param_hint="--filters")
    if not breakdown and not (period_list or algorithm_list or block_list or filter_list):
        # '' leaves a group of rows out; with every group out there is nothing to measure but the limit
        raise click.BadParameter("nothing to compare: give --periods, --algorithms, --blocks or --filters",
                                 param_hint="--periods")
    with Reporter(err, quiet=quiet) as reporter:
        if breakdown:
            bench = run_breakdown(shader, session, node, algorithms=tuple(algorithm_list), formats=tuple(format_list),
                                  payloads=tuple(payload_list), frames=frames,
                                  resolution=resolution, period=compare_period, repeats=repeats,
                                  progress=reporter.update, vertex=vert, include_dirs=include_dirs)
        else:
            bench = run(shader, session, node, period_list, compare_period, frames, resolution=resolution,
                        repeats=repeats, progress=reporter.update, color_format=timing_format, vertex=vert,
                        include_dirs=include_dirs, filters=tuple(filter_list), misses=misses,
                        algorithms=tuple(algorithm_list), blocks=tuple(block_list))
    if as_json:
        click.echo(json.dumps(bench.to_json()))
    else:
        click.echo(bench.markdown())
