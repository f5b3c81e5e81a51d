"""``rrcache accuracy PROFILE``: the models against measurements at held-out refresh periods.

    rrcache accuracy marble-marble.rrprofile
    rrcache accuracy marble-marble.rrprofile --periods 6,14,30 --nodes n2392,n958 --json

Measures the nodes that matter (the predicted Pareto front and the four selections, or
``--nodes``) at periods training did not use, as training measures, and prints predicted against
measured error and frame time per point, the mean relative error of the predicted frame time and
the error model's R² over the held-out points (``--json``: the whole report).
"""
from __future__ import annotations

import json

import click
from rich.console import Console

from rrcache.jsonable import finite_json
from rrcache.profiler.accuracy import DEFAULT_PERIODS, held_out
from rrcache.cli.options import include_dirs_option
from rrcache.cli.progress import Reporter, quiet_option
from rrcache.cli.tables import TextTable
from rrcache.profiles.document import load_profile
from rrcache.profiles.settings import parse_periods


@click.command("accuracy")
@click.argument("profile_path", metavar="PROFILE", type=click.Path())
@click.option("--periods", default=",".join(map(str, DEFAULT_PERIODS)), show_default=True,
              help="Held-out refresh periods, comma-separated.")
@click.option("--nodes", default=None, help="Node ids to measure (default: the Pareto front and the selections).")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
@include_dirs_option
@quiet_option
def command(profile_path, periods, nodes, as_json, include_dirs, quiet):
    """Check the profile's models at refresh periods they were not trained on."""
    prof = load_profile(profile_path)
    prof.include_dirs = list(include_dirs) + prof.include_dirs
    chosen = [n.strip() for n in nodes.split(",") if n.strip()] if nodes else None
    err_console = Console(stderr=True)
    with Reporter(err_console, quiet=quiet) as reporter:
        report = held_out(prof, parse_periods(periods, "--periods"), chosen, reporter.event)
    if as_json:
        click.echo(json.dumps(finite_json(report.to_json()), indent=2))
        return
    table = TextTable(f"held-out periods {report.periods} ({report.chosen_by})",
                      [(c, "right") for c in ("node", "Δn", "predicted error", "measured error", "predicted ms",
                                              "measured ms", "time error", "hit rate")])
    for p in report.points:
        table.add_row(p.node, str(p.period), f"{p.predicted_error:.5f}", f"{p.measured_error:.5f}",
                      f"{p.predicted_ms:.2f}", f"{p.measured_ms:.2f}", f"{p.time_relative_error:.1%}",
                      f"{p.hit_rate:.3f}")
    console = Console()
    table.print(console)
    for node in dict.fromkeys(p.node for p in report.points):
        console.print(f"{node}: {prof.node(node).text}", highlight=False, markup=False, soft_wrap=True)
    r2 = ", ".join(f"{k} {v:.3f}" for k, v in report.training_r2.items() if v is not None)
    console.print(f"frame time: mean relative error {report.time_mean_relative_error:.1%}, "
                  f"max {report.time_max_relative_error:.1%}; error model R² over the held-out points "
                  f"{report.error_r2:.3f}; R² on the training periods: {r2}", highlight=False)
