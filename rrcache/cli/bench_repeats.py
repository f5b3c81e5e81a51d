"""``rrcache bench-repeats PROFILE...``: what repeated profiles shipped, and whether any was slower.

    rrcache profile shaders/marble.glsl sessions/marble.json --out runs/marble-r1.rrprofile
    rrcache profile shaders/marble.glsl sessions/marble.json --out runs/marble-r2.rrprofile
    rrcache bench-repeats runs/*.rrprofile
    rrcache bench-repeats --predictions runs/*.rrprofile     # the PSNR predictions against validation
    rrcache bench-repeats --by-scene runs/*.rrprofile        # a line per scene, a column per level

One line per shipped selection (:mod:`rrcache.bench.repeats`); exits 1 when a profile shipped a
selection measured slower than the original in every repeat.
"""
from __future__ import annotations

import json

import click


@click.command("bench-repeats")
@click.argument("profiles", nargs=-1, required=True, type=click.Path(exists=True, file_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print the rows as JSON.")
@click.option("--summary", is_flag=True, help="One line per scene and level over all the runs.")
@click.option("--by-scene", is_flag=True,
              help="One line per scene, a column per level: each run's measured PSNR, speed-up, FLIP and level.")
@click.option("--predictions", is_flag=True,
              help="The PSNR predictions' error on every validated choice, per profile and pooled (docs/levels.md).")
def command(profiles, as_json, summary, predictions, by_scene):
    """Tabulate the shipped selections of PROFILES (folders of repeated 'rrcache profile' runs):
    speed-ups measured beside the original (median and range of the repeats), PSNR, fallbacks,
    and whether any shipped a measured slowdown."""
    from rrcache.bench.repeats import markdown, rows, scenes_markdown, slowdowns, summary_markdown

    from pathlib import Path

    done = [p for p in profiles if (Path(p) / "profile.json").is_file()]
    for p in sorted(set(profiles) - set(done)):
        click.echo(f"note: {p}: skipped, no profile.json yet (still running, or interrupted)", err=True)
    if not done:
        raise click.UsageError("none of the folders holds a profile.json")
    if predictions:
        from rrcache.bench.repeats import predictions as prediction_rows, predictions_markdown

        found = prediction_rows(done)
        click.echo(json.dumps(found) if as_json else predictions_markdown(found))
        return
    table = rows(done)
    if as_json:
        click.echo(json.dumps(table))
    else:
        click.echo(scenes_markdown(table) if by_scene else summary_markdown(table) if summary else markdown(table))
    if slowdowns(table):
        raise SystemExit(1)
