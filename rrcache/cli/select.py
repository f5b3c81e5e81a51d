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
    written = choice_write(prof, choice, out_dir) if out_dir else []
    level = f"error {max_error:g}" if max_error is not None else f"PSNR ≥ {min_psnr:g} dB"
    if as_json:
        figures = {"predicted_error": float(choice.predicted_error), "predicted_ms": float(choice.predicted_ms),
                   "predicted_speedup": float(choice.predicted_speedup),
                   "predicted_speedup_range": list(choice.predicted_speedup_range),
                   "predicted_psnr": choice.predicted_psnr,
                   "predicted_psnr_uncertainty": choice.predicted_psnr_uncertainty,
                   "exact": choice.exact, "visible_artifacts": choice.visible_artifacts}
        # what is chosen, as its kind of choice says it (rrcache.kinds); the original: node null
        what = choice.choice.summary(choice, prof) if choice.parts else {"node": None, "period": None}
        click.echo(json.dumps(finite_json({**what, **figures})))
        return
    if not choice.parts:
        reason = prof.verdict["answer"] if prof.verdict is not None else f"nothing is predicted faster within {level}"
        click.echo(f"the original shader: {reason} ({choice.predicted_ms:.3f} ms per frame)")
    else:
        lo, hi = choice.predicted_speedup_range or (choice.predicted_speedup, choice.predicted_speedup)
        click.echo(f"{choice.choice.sentence(choice, prof)}: predicted error "
                   f"{choice.predicted_error:.4g}, PSNR {psnr_text(choice.predicted_psnr)} ± "
                   f"{choice.predicted_psnr_uncertainty or 0:.1f} dB, {choice.predicted_ms:.3f} ms per frame, "
                   f"{choice.predicted_speedup:.2f}× ({lo:.2f}–{hi:.2f}) the original")
        if choice.visible_artifacts:
            click.echo(f"note: below {VISIBLE_DB:.0f} dB: expect visible artifacts")
    if written:
        click.echo(f"wrote {len(written)} files to {out_dir}")


from rrcache.kinds.amortize import history_words as _history  # noqa: E402,F401 (the words, the kind's)
from rrcache.choice import write as choice_write
