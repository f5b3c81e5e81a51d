"""``rrcache report PROFILE_DIR``: write a profile's self-contained HTML report again.

    rrcache report marble-marble.rrprofile
    rrcache report marble-marble.rrprofile --out marble.html

``rrcache profile`` writes ``report.html`` into the profile folder; this command rebuilds it from
the saved profile (``profile.json``), rendering the four selections' frames again (the shader and
the session must still be where the profile names them). The page works offline: its script,
style and images are inside the file.
"""
from __future__ import annotations

from pathlib import Path

import click

from rrcache.cli.options import include_dirs_option
from rrcache.profiles.document import load_profile
from rrcache.report import REPORT_NAME, write_report


@click.command("report")
@click.argument("profile_dir", metavar="PROFILE_DIR", type=click.Path())
@click.option("--out", "out_file", type=click.Path(dir_okay=False), default=None,
              help=f"The HTML file to write (default: PROFILE_DIR/{REPORT_NAME}).")
@include_dirs_option
def command(profile_dir, out_file, include_dirs):
    """Write the HTML report of a saved profile."""
    prof = load_profile(profile_dir)
    prof.include_dirs = list(include_dirs) + prof.include_dirs
    target = Path(out_file) if out_file else Path(prof.path) / REPORT_NAME
    path = write_report(prof, target.parent, filename=target.name)
    click.echo(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)")
