"""``rrcache select PROFILE --max-error E`` or ``--min-psnr DB``: choose what to cache from a
trained profile.

    rrcache select marble-marble.rrprofile --min-psnr 40
    rrcache select marble-marble.rrprofile --max-error 0.02 --json
    rrcache select marble-marble.rrprofile --max-error 0.02 --out optimized/
    rrcache select marble-marble.rrprofile --max-flip 0.05

Nothing is rendered (milliseconds). Where the profile's validation measured a choice, its
measured figures answer (:mod:`rrcache.profiles.measured`): a measured choice that meets the
level, or the models' choice with its measurement; where it did not, the models predict (their
PSNR calibrated by validation). Every figure says whether it was measured or predicted, and a
warning says when the models' choice was measured below the asked level (docs/levels.md).
``--min-psnr`` asks for a PSNR against the original of at least that many dB, ``--max-error``
for a mean RGB L2 error, ``--max-flip`` for a mean FLIP (measured choices; else the PSNR the
measured ones relate to it). ``--json`` prints ``{"node", "period",
"predicted_error", "predicted_ms", "predicted_speedup", "predicted_speedup_range",
"predicted_psnr", "predicted_psnr_uncertainty", "exact", "visible_artifacts", "source",
"note", "warnings", "measured_error", "measured_psnr", "measured_psnr_uncertainty",
"measured_speedup", "speedups", "measured_flip", "measured_temporal_psnr"}`` (``source``
``measured`` or ``predicted``; measured figures null when not measured; node null: the
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
@click.option("--min-psnr", type=float, default=None, help="Least PSNR against the original (dB).")
@click.option("--max-flip", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Largest mean FLIP against the original (measured choices; docs/levels.md).")
@click.option("--json", "as_json", is_flag=True, help="Print the choice as JSON.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Write the chosen shader files here.")
@include_dirs_option
def command(profile_path, max_error, min_psnr, max_flip, as_json, out_dir, include_dirs):
    """Select what to cache within --min-psnr, --max-error or --max-flip: from validation's
    measurements where the profile has them, else the models' prediction (each figure says which)."""
    import json

    from rrcache.profiles.measured import choose

    if sum(v is not None for v in (max_error, min_psnr, max_flip)) != 1:
        raise click.UsageError("give one of --max-error, --min-psnr and --max-flip")
    prof = load_profile(profile_path)
    prof.include_dirs = list(include_dirs) + prof.include_dirs
    if max_error is not None:
        prof.select(max_error)  # the threshold's own checks (a located error for a bad one)
    answer = choose(prof, min_psnr=min_psnr, max_error=max_error, max_flip=max_flip)
    choice = answer.selection
    written = choice_write(prof, choice, out_dir) if out_dir else []
    level = (f"error {max_error:g}" if max_error is not None else f"PSNR ≥ {min_psnr:g} dB" if min_psnr is not None
             else f"mean FLIP ≤ {max_flip:g}")
    if as_json:
        click.echo(json.dumps(finite_json(_json(prof, choice, answer))))
        return
    if not choice.parts:
        reason = (prof.verdict["answer"] if prof.verdict is not None else
                  answer.warnings[0] if answer.warnings else f"nothing is predicted faster within {level}")
        click.echo(f"the original shader: {reason} ({choice.predicted_ms:.3f} ms per frame)")
    else:
        click.echo(f"{choice.choice.sentence(choice, prof)}: {_figures(choice)}")
    if choice.parts and answer.note:
        click.echo(f"({answer.note})")
    said = 1 if not choice.parts and prof.verdict is None and answer.warnings else 0  # the reason above
    for warning in answer.warnings[said:]:
        click.echo(f"warning: {warning}")
    if choice.visible_artifacts:
        click.echo("note: " + ("its measured mean FLIP shows visible artifacts" if choice.measured_flip is not None
                               else f"below {VISIBLE_DB:.0f} dB (predicted): expect visible artifacts"))
    if written:
        click.echo(f"wrote {len(written)} files to {out_dir}")


def _figures(choice) -> str:
    """Its figures, each said measured or predicted."""
    out = []
    if choice.measured_error is not None:
        unc = f" ± {choice.measured_psnr_uncertainty:.1f}" if choice.measured_psnr_uncertainty else ""
        psnr = psnr_text(float("inf") if choice.exact else choice.measured_psnr)
        out.append(f"measured PSNR {psnr}{unc} dB")
        if choice.measured_flip is not None:
            out.append(f"measured mean FLIP {choice.measured_flip:.4f}")
        lo, hi = choice.speedup_range or (choice.measured_speedup, choice.measured_speedup)
        out.append(f"measured {choice.measured_speedup:.2f}× ({lo:.2f}–{hi:.2f}) the original")
        out.append(f"(predicted PSNR {psnr_text(choice.predicted_psnr)} dB, {choice.predicted_speedup:.2f}×)")
        return ", ".join(out)
    lo, hi = choice.predicted_speedup_range or (choice.predicted_speedup, choice.predicted_speedup)
    return (f"predicted error {choice.predicted_error:.4g}, predicted PSNR {psnr_text(choice.predicted_psnr)} ± "
            f"{choice.predicted_psnr_uncertainty or 0:.1f} dB, predicted {choice.predicted_ms:.3f} ms per frame, "
            f"predicted {choice.predicted_speedup:.2f}× ({lo:.2f}–{hi:.2f}) the original (not validated)")


def _json(prof, choice, answer) -> dict:
    """The --json record (see the module docstring): what is chosen as its kind of choice says it
    (rrcache.kinds; the original: node null), its predicted and measured figures, and which."""
    data = dict(choice.choice.summary(choice, prof) if choice.parts else {"node": None, "period": None})
    data.update({"predicted_error": float(choice.predicted_error), "predicted_ms": float(choice.predicted_ms),
                 "predicted_speedup": float(choice.predicted_speedup),
                 "predicted_speedup_range": list(choice.predicted_speedup_range),
                 "predicted_psnr": choice.predicted_psnr, "predicted_psnr_uncertainty": choice.predicted_psnr_uncertainty,
                 "exact": choice.exact, "visible_artifacts": choice.visible_artifacts,
                 "source": answer.source, "note": answer.note, "warnings": list(answer.warnings),
                 "measured_error": choice.measured_error, "measured_psnr": choice.measured_psnr,
                 "measured_psnr_uncertainty": choice.measured_psnr_uncertainty,
                 "measured_speedup": choice.measured_speedup, "speedups": list(choice.speedups),
                 "measured_flip": choice.measured_flip, "measured_temporal_psnr": choice.measured_temporal_psnr})
    return data


from rrcache.kinds.amortize import history_words as _history  # noqa: E402,F401 (the words, the kind's)
from rrcache.choice import write as choice_write
