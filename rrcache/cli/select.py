"""``rrcache select PROFILE --max-error E``: choose what to cache from a trained profile.

    rrcache select marble-marble.rrprofile --max-error 0.02
    rrcache select marble-marble.rrprofile --max-error 0.02 --json
    rrcache select marble-marble.rrprofile --max-error 0.02 --out optimized/

From the models alone (nothing is rendered; milliseconds). ``--json`` prints ``{"node",
"period", "predicted_error", "predicted_ms", "predicted_speedup"}`` (node null: the original
shader is the best choice); ``--out`` writes the chosen variant's shader files.
"""
from __future__ import annotations

import json
import math

import click

from rrcache.profiles.document import load_profile


@click.command("select")
@click.argument("profile_path", metavar="PROFILE", type=click.Path())
@click.option("--max-error", required=True, type=float, help="Largest mean RGB L2 error per pixel to accept.")
@click.option("--json", "as_json", is_flag=True, help="Print the choice as JSON.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Write the chosen shader files here.")
def command(profile_path, max_error, as_json, out_dir):
    """Select the node and refresh period predicted fastest within --max-error."""
    prof = load_profile(profile_path)
    choice = prof.select(max_error)
    written = prof.write_variant(choice, out_dir) if out_dir else []
    if as_json:
        data = {"node": choice.node, "period": None if choice.period is None else int(choice.period),
                "predicted_error": float(choice.predicted_error), "predicted_ms": float(choice.predicted_ms),
                "predicted_speedup": float(choice.predicted_speedup)}
        click.echo(json.dumps({k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                               for k, v in data.items()}))
        return
    if choice.node is None:
        click.echo(f"the original shader: nothing is predicted faster within error {max_error:g} "
                   f"({choice.predicted_ms:.3f} ms per frame)")
    else:
        text = prof.node(choice.node).text
        click.echo(f"cache {choice.node} ({text}) every Δn = {int(choice.period)} frames: predicted error "
                   f"{choice.predicted_error:.4g}, {choice.predicted_ms:.3f} ms per frame, "
                   f"{choice.predicted_speedup:.2f}× the original")
    if written:
        click.echo(f"wrote {len(written)} files to {out_dir}")
