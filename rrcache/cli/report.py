"""``rrcache report PROFILE_DIR``: write a profile's self-contained HTML report again.

    rrcache report marble-marble.rrprofile
    rrcache report marble-marble.rrprofile --out marble.html

``rrcache profile`` writes ``report.html`` into the profile folder; this command rebuilds it from
the saved profile (``profile.json``) and the frames the profile rendered (``frames/``). A folder
without them (a profile from before they were kept), or ``--frames``, has them rendered first (the
shader and the session must still be where the profile names them). The page works offline: its
script, style and images are inside the file.
"""
from __future__ import annotations

from pathlib import Path

import click

from rrcache.cli.options import include_dirs_option
from rrcache.profiles.document import load_profile
from rrcache.report import REPORT_NAME, write_report
from rrcache.report.images import read_frames


@click.command("report")
@click.argument("profile_dir", metavar="PROFILE_DIR", type=click.Path())
@click.option("--out", "out_file", type=click.Path(dir_okay=False), default=None,
              help=f"The HTML file to write (default: PROFILE_DIR/{REPORT_NAME}).")
@click.option("--frames", "render_frames", is_flag=True, help="Render the selections' frames again first.")
@include_dirs_option
def command(profile_dir, out_file, render_frames, include_dirs):
    """Write the HTML report of a saved profile."""
    prof = load_profile(profile_dir)
    prof.include_dirs = list(include_dirs) + prof.include_dirs
    if prof.selections and (render_frames or not read_frames(prof.path)):
        from rrcache.choice import load_work
        from rrcache.profiler.frames import write_frames

        work, _session = load_work(prof, include_dirs)
        write_frames(prof, prof.path, work)
    target = Path(out_file) if out_file else Path(prof.path) / REPORT_NAME
    path = write_report(prof, target.parent, filename=target.name)
    click.echo(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)")
