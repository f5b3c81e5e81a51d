"""``rrcache profile-library``: profile a library of shaders, one profile folder per (shader,
session), with a summary table.

    rrcache profile-library library.toml --out lib/
    rrcache profile-library --shaders 'shaders/*.glsl' --sessions sessions/orbit.json --out lib/ --budget 120

The pairs come from a JSON or TOML manifest (:mod:`rrcache.profiler.manifest`) or from
``--shaders`` and ``--sessions`` (paths or globs: every shader with every session). Each pair is
profiled into ``OUT/<name>/`` as ``rrcache profile`` would; the training options given here apply
to every pair, a manifest's ``settings`` over them. After each pair ``OUT/library.json``,
``OUT/library.csv`` and ``OUT/index.html`` (linking each ``report.html``) are rewritten; at the end
the table is printed: the verdict, the measured speed-up at each level e1..e4, the nodes trained
and the wall time. A pair that fails is reported in its row and the others are profiled (exit code
1 when any failed). Running the same command again resumes: finished profiles are kept, the others
resume from their stores. Ctrl-C stops after recording the pair in flight (exit 130).
"""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

import click
from rich.console import Console
from rich.table import Table

from rrcache.cli import interrupt
from rrcache.cli.options import cluster_options
from rrcache.cli.profile import _periods, _seconds
from rrcache.cli.progress import Reporter, quiet_option
from rrcache.cluster import maybe_cluster
from rrcache.profiles.settings import ALGORITHM_CHOICES, LEVEL_KINDS, TrainingSettings
from rrcache.report.library import LEVELS


@click.command("profile-library")
@click.argument("manifest", required=False, type=click.Path(dir_okay=False))
@click.option("--shaders", multiple=True, metavar="GLOB", help="Shader files or globs (repeatable), with --sessions.")
@click.option("--sessions", multiple=True, metavar="GLOB", help="Session files or globs (repeatable): every shader "
                                                               "is profiled over every session.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="library.rrlibrary", show_default=True,
              help="The library folder: a profile folder per pair, library.csv and index.html.")
@click.option("--budget", type=click.FloatRange(min=0, min_open=True), default=None, callback=_seconds,
              help=f"Seconds of node training per profile (default: {TrainingSettings.budget_s:g}).")
@click.option("--frames", type=click.IntRange(min=2), default=None, help="Error-run frames per profile.")
@click.option("--periods", callback=_periods, default=None, metavar="LIST", help="Training refresh periods.")
@click.option("--timing-frames", type=click.IntRange(min=1), default=None, help="Frames timed per node and period.")
@click.option("--timing-periods", callback=_periods, default=None, metavar="LIST",
              help="Refresh periods at which each node is timed.")
@click.option("--algorithm", type=click.Choice(ALGORITHM_CHOICES), default=None, help="Cache algorithm (default: auto).")
@click.option("--min-gain", type=click.FloatRange(min=0, max=100, max_open=True), default=None,
              help=f"The least speed-up worth having (default: {TrainingSettings.min_gain:g}).")
@click.option("--levels", type=click.Choice(LEVEL_KINDS), default=None, help="Selection levels (default: psnr).")
@click.option("--no-validate", is_flag=True, help="Do not measure the selections beside the original.")
@click.option("--no-plots", is_flag=True, help="Write no plots or report.html (faster).")
@click.option("--fresh", is_flag=True, help="Start every profile over (each store moved aside as .bak).")
@cluster_options
@quiet_option
def command(manifest, shaders, sessions, out_dir, budget, frames, periods, timing_frames, timing_periods, algorithm,
            min_gain, levels, no_validate, no_plots, fresh, workers, scheduler, quiet):
    """Profile every (shader, session) pair of MANIFEST (or of --shaders and --sessions) into OUT."""
    from rrcache.profiler.library import profile_library
    from rrcache.profiler.manifest import entries_from_globs, read_manifest

    if manifest is not None and (shaders or sessions):
        raise click.UsageError("give a manifest or --shaders/--sessions, not both")
    if manifest is None and not (shaders and sessions):
        raise click.UsageError("give a manifest, or both --shaders and --sessions")
    manifest_settings = {}
    if manifest is not None:
        entries, manifest_settings = read_manifest(manifest)
    else:
        entries = entries_from_globs(shaders, sessions)
    given = dict(budget_s=budget, frames=frames, periods=periods, timing_frames=timing_frames,
                 timing_periods=timing_periods, algorithm=algorithm, min_gain=min_gain, levels=levels)
    overrides = {k: v for k, v in given.items() if v is not None}
    if no_validate:
        overrides["validate"] = False
    err_console = Console(stderr=True)
    interrupted = False
    with Reporter(err_console, quiet=quiet) as reporter, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            # the command line's options win over the manifest's settings, the entries' own over both
            with maybe_cluster(workers, scheduler, announce=reporter.line) as cluster:
                rows = profile_library(entries, out_dir, None, {**manifest_settings, **overrides}, reporter.event,
                                       announce=reporter.line, fresh=fresh, plots=not no_plots, cluster=cluster)
        except KeyboardInterrupt:
            interrupted = True
            rows = None
        finally:
            for w in caught:
                err_console.print(f"warning: {w.message}", highlight=False, markup=False)
    if interrupted:
        err_console.print(f"rrcache: {interrupt.word()}; the summary so far is in {Path(out_dir) / 'index.html'}; "
                          "run the same command again to resume", highlight=False)
        sys.exit(interrupt.exit_code())
    console = Console()
    if not console.is_terminal:
        console = Console(width=140)
    console.print(table(rows))
    console.print(f"summary: {Path(out_dir) / 'index.html'}, {Path(out_dir) / 'library.csv'}", highlight=False)
    if any(r["status"] != "done" for r in rows):
        sys.exit(1)


def table(rows: list[dict]) -> Table:
    """The summary as a rich table."""
    out = Table(title="shader library")
    out.add_column("profile")
    out.add_column("verdict", overflow="fold")
    for level in LEVELS:
        out.add_column(level, justify="right")
    out.add_column("nodes", justify="right")
    out.add_column("wall", justify="right")
    for r in rows:
        speed = ["–" if r.get(f"{lv}_speedup") is None else f"{r[f'{lv}_speedup']:.2f}×" for lv in LEVELS]
        nodes = "–" if r.get("nodes") is None else f"{r['nodes_trained']}/{r['nodes']}"
        wall = "–" if r.get("wall_s") is None else f"{r['wall_s']:.0f} s"
        out.add_row(r["name"], r["verdict"], *speed, nodes, wall)
    return out
