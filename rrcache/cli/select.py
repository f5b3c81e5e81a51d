"""``rrcache select PROFILE --max-error E`` or ``--min-psnr DB``: choose what to cache from a
trained profile.

    rrcache select marble-marble.rrprofile --min-psnr 40
    rrcache select marble-marble.rrprofile --max-error 0.02 --json
    rrcache select marble-marble.rrprofile --max-error 0.02 --out optimized/

From the models alone (nothing is rendered; milliseconds). ``--min-psnr`` asks for a predicted
PSNR against the original of at least that many dB (the PSNR model of :mod:`rrcache.model.psnr`);
``--max-error`` for a mean RGB L2 error. ``--json`` prints ``{"node", "period",
"predicted_error", "predicted_ms", "predicted_speedup", "predicted_speedup_range",
"predicted_psnr", "predicted_psnr_uncertainty", "exact", "visible_artifacts"}`` (node null: the
original shader is the best choice; PSNR null with ``exact`` true: the original's image; an
amortized estimator adds ``"kind": "amortize", "estimator", "samples", "of", "blend", "history"``
(``blend``: the paper's running estimate; ``slots``: the N/m subset sums kept apart),
``"phase"``, ``"filter"`` and ``"payload"`` (``u8``: the slots in 8 bits) with node null);
``--out`` writes the chosen variant's shader files.
"""
from __future__ import annotations

import click

from rrcache.cli.options import include_dirs_option
from rrcache.jsonable import finite_json
from rrcache.model.psnr import VISIBLE_DB, psnr_text
from rrcache.profiles.document import load_profile


@click.command("select")
@click.argument("profile_path", metavar="PROFILE", type=click.Path())
@click.option("--max-error", type=float, default=None, help="Largest mean RGB L2 error per pixel to accept.")
@click.option("--min-psnr", type=float, default=None, help="Least predicted PSNR against the original (dB).")
@click.option("--json", "as_json", is_flag=True, help="Print the choice as JSON.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Write the chosen shader files here.")
@include_dirs_option
def command(profile_path, max_error, min_psnr, as_json, out_dir, include_dirs):
    """Select the node and refresh period predicted fastest within --max-error or --min-psnr."""
    import json

    if (max_error is None) == (min_psnr is None):
        raise click.UsageError("give one of --max-error and --min-psnr")
    prof = load_profile(profile_path)
    prof.include_dirs = list(include_dirs) + prof.include_dirs
    choice = prof.select(max_error) if max_error is not None else prof.select_psnr(min_psnr)
    written = prof.write_variant(choice, out_dir) if out_dir else []
    level = f"error {max_error:g}" if max_error is not None else f"PSNR ≥ {min_psnr:g} dB"
    if as_json:
        if choice.kind == "amortize":  # amortized sampling: the estimator, m and λ
            part = choice.parts[0]
            data = {"node": None, "period": None, "kind": "amortize", "estimator": part.estimator,
                    "samples": part.samples, "of": prof.estimator(part.estimator).samples, "blend": part.blend,
                    "history": part.history, "phase": part.phase, "filter": part.filter, "payload": part.payload,
                    "predicted_error": float(choice.predicted_error), "predicted_ms": float(choice.predicted_ms),
                    "predicted_speedup": float(choice.predicted_speedup),
                    "predicted_speedup_range": list(choice.predicted_speedup_range),
                    "predicted_psnr": choice.predicted_psnr,
                    "predicted_psnr_uncertainty": choice.predicted_psnr_uncertainty,
                    "exact": choice.exact, "visible_artifacts": choice.visible_artifacts}
            click.echo(json.dumps(finite_json(data)))
            return
        if choice.multi:  # several nodes: "n12+n40" and one period each
            data = {"node": "+".join(choice.nodes), "period": list(choice.periods), "nodes": list(choice.nodes),
                    "predicted_error": float(choice.predicted_error), "predicted_ms": float(choice.predicted_ms),
                    "predicted_speedup": float(choice.predicted_speedup)}
            click.echo(json.dumps(finite_json(data)))
            return
        data = {"node": choice.node, "period": None if choice.period is None else int(choice.period),
                "predicted_error": float(choice.predicted_error), "predicted_ms": float(choice.predicted_ms),
                "predicted_speedup": float(choice.predicted_speedup),
                "predicted_speedup_range": list(choice.predicted_speedup_range),
                "predicted_psnr": choice.predicted_psnr, "predicted_psnr_uncertainty": choice.predicted_psnr_uncertainty,
                "exact": choice.exact, "visible_artifacts": choice.visible_artifacts}
        click.echo(json.dumps(finite_json(data)))
        return
    if choice.kind == "amortize":
        part = choice.parts[0]
        click.echo(f"amortize {part.estimator} ({part.text}): {part.samples} of "
                   f"{prof.estimator(part.estimator).samples} terms per frame, {_history(part)}, λ = {part.blend:g}: "
                   f"predicted "
                   f"error {choice.predicted_error:.4g}, PSNR {psnr_text(choice.predicted_psnr)} ± "
                   f"{choice.predicted_psnr_uncertainty or 0:.1f} dB, {choice.predicted_ms:.3f} ms per frame, "
                   f"{choice.predicted_speedup:.2f}× the original")
    elif choice.multi:
        texts = "; ".join(prof.node(n).text for n in choice.nodes)
        click.echo(f"cache {choice.describe()} ({texts}): predicted error {choice.predicted_error:.4g}, "
                   f"{choice.predicted_ms:.3f} ms per frame, {choice.predicted_speedup:.2f}× the original")
    elif choice.node is None:
        reason = prof.verdict["answer"] if prof.verdict is not None else f"nothing is predicted faster within {level}"
        click.echo(f"the original shader: {reason} ({choice.predicted_ms:.3f} ms per frame)")
    else:
        text = prof.node(choice.node).text
        lo, hi = choice.predicted_speedup_range or (choice.predicted_speedup, choice.predicted_speedup)
        click.echo(f"cache {choice.node} ({text}) every Δn = {int(choice.period)} frames: predicted error "
                   f"{choice.predicted_error:.4g}, PSNR {psnr_text(choice.predicted_psnr)} ± "
                   f"{choice.predicted_psnr_uncertainty or 0:.1f} dB, {choice.predicted_ms:.3f} ms per frame, "
                   f"{choice.predicted_speedup:.2f}× ({lo:.2f}–{hi:.2f}) the original")
        if choice.visible_artifacts:
            click.echo(f"note: below {VISIBLE_DB:.0f} dB: expect visible artifacts")
    if written:
        click.echo(f"wrote {len(written)} files to {out_dir}")


def _history(part) -> str:
    """How the amortized choice keeps its history, in words."""
    if part.history == "slots":
        return ("slots history (the N/m subset sums kept apart, each blended with its own"
                + (", in 8 bits by the terms' range)" if part.payload == "u8" else ")"))
    return "blend history (one running estimate)"
