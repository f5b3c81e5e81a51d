"""``rrcache render ... --method render-cache``: an alternative method beside the original.

``--method`` says what ``rrcache render`` compares with the original: ``reprojection-cache`` (the
default: ``--node`` or ``--level``, or a plain replay without them) or ``render-cache``, the
forward-reprojection render cache of Walter et al. 2002
(:mod:`rrcache.alternatives.render_cache`), with ``--samples F`` (the share of the pixels the
renderer may shade per frame). It is a baseline to compare against at the same frame time, not
something the profiler ever chooses.

The comparison is run as a cached variant's is: frame by frame beside the original, ``--repeats``
times (the median repeat by speed-up stands for the run), the first frame (the render cache's
cold start, every pixel shaded) left out of the summary; the same error metrics, the same
``--json`` keys where they apply, ``--out`` writes each frame (``frame_NNNN.exr/png``) and the
original's (``original_NNNN.png``). The summary adds the budget, the pixels shaded and the
median ms of each stage of a frame.
"""
from __future__ import annotations

import json
import math

import click
from rich.console import Console

from rrcache.cli.repeats import frames_and_folder, run_repeats
from rrcache.cli.tables import TextTable
from rrcache.harness.timing import load_warning
from rrcache.jsonable import finite_json

#: the methods ``rrcache render --method`` compares with the original
METHODS = ("reprojection-cache", "render-cache")
#: what ``--samples`` defaults to (3% of the pixels per frame: inside the paper's 1–10%)
DEFAULT_SAMPLES = 0.03


def samples_option(f):
    return click.option("--samples", type=float, default=None, metavar="F",
                        help=f"With --method render-cache: the share of the pixels shaded per frame "
                             f"(0 < F <= 1; default {DEFAULT_SAMPLES}).")(f)


def method_option(f):
    return click.option("--method", type=click.Choice(METHODS), default="reprojection-cache", show_default=True,
                        help="What to compare with the original: the reprojection cache (--node, --level) or "
                             "the render cache of Walter et al. 2002 (--samples), a baseline at equal time.")(f)


def check_method(method: str, samples, conflicting: dict) -> None:
    """Usage errors: ``--samples`` without the render cache; a reprojection-cache option (name →
    whether given) with it."""
    if method != "render-cache":
        if samples is not None:
            raise click.UsageError("--samples is the render cache's budget: give it with --method render-cache")
        return
    for name, given in conflicting.items():
        if given:
            raise click.UsageError(f"{name} chooses a reprojection-cache variant; --method render-cache compares the "
                                   "render cache (leave out " + name + ")")


def render_cache(source, loaded, samples, out_dir, frame_count, resolution, as_json, color_format, repeats,
                 err_console, quiet) -> None:
    """The render cache at ``samples`` beside the original: table and summary (or JSON)."""
    from rrcache.alternatives.render_cache import RenderCacheSettings
    from rrcache.alternatives.render_cache.tune import compare

    settings = RenderCacheSettings(samples=DEFAULT_SAMPLES if samples is None else samples).checked()
    prepared = source.prepare(loaded)
    indices, out = frames_and_folder(loaded, frame_count, out_dir)
    said = (f"{settings.describe().replace('render cache', 'render cache (Walter et al. 2002)', 1)}, a cache of "
            f"{settings.points_per_pixel:g}× the pixels in points, prediction {'on' if settings.predict else 'off'}")
    if not quiet:
        err_console.print(f"{prepared.path}: {said}; colour target {color_format}, {len(indices)} frames",
                          highlight=False, markup=False, soft_wrap=True)
    runs = run_repeats(lambda done: compare(prepared, loaded, indices, settings, resolution, on_frame=done,
                                            color_format=color_format),
                       len(indices), repeats, out, "render cache", err_console, quiet)
    speedups = sorted(r.speedup for r in runs)
    result = sorted(runs, key=lambda r: r.speedup)[len(runs) // 2]
    for note in result.notes:
        click.echo(f"note: {note}", err=True)
    summary = result.summary()
    summary.update(repeats=repeats, speedup_repeats=[r.speedup for r in runs],
                   speedup_range=[speedups[0], speedups[-1]])
    warning = load_warning(max(r.noise for r in runs))
    if warning:
        summary["reliable"] = False
        err_console.print(f"warning: {warning}", highlight=False, markup=False, soft_wrap=True)
    if as_json:
        click.echo(json.dumps(finite_json(dict(
            frames=len(result.frames), resolution=list(result.resolution),
            covered_pixels=[f.covered for f in result.frames], frame_ms=[f.ms for f in result.frames],
            original_frame_ms=[f.original_ms for f in result.frames], **summary))))
        return
    console = Console()
    table = TextTable(f"{prepared.path}: {said}",
                      [(c, "right") for c in ("frame", "mean error", "PSNR dB", "ms", "original ms")])
    for f in result.frames:
        table.add_row(str(f.index), f"{f.mean_error:.5f}", _db(f.psnr), f"{f.ms:.2f}", f"{f.original_ms:.2f}")
    table.print(console)
    lo, hi = summary["speedup_ci95"]
    console.print(f"speed-up {summary['speedup']:.2f}× (95% interval {lo:.2f}–{hi:.2f}; {summary['ms_per_frame']:.2f} "
                  f"ms vs {summary['original_ms_per_frame']:.2f} ms, medians), mean error {summary['mean_error']:.5f}, "
                  f"PSNR {_db(summary['psnr'])} dB; budget {summary['budget_pixels']} pixels per frame, "
                  f"{summary['shaded_pixels']:.0f} shaded (median; the first frame, a cold start, shades all)",
                  highlight=False, markup=False, soft_wrap=True)
    stages = ", ".join(f"{k} {v:.2f}" for k, v in summary["stage_ms"].items())
    console.print(f"ms per stage (medians): {stages}", highlight=False, markup=False, soft_wrap=True)


def _db(value) -> str:
    return "∞" if value is None or (isinstance(value, float) and math.isinf(value)) else f"{value:.2f}"
