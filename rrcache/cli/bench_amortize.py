"""``rrcache bench-amortize SHADER SESSION --estimator ID``: an estimator amortized over frames
(``m`` of its ``N`` samples per frame, blend ``λ``) against the original, both measured against
a many-sample reference (see :mod:`rrcache.bench.amortize`).

    rrcache bench-amortize shaders/pcf_shadows.glsl sessions/temple.json --estimator e1 \\
        --samples 4 --lambda 0.6 --reference PCF_SAMPLES=256 --frames 60 --repeats 3

``--images DIR`` writes, at the last frame of the first repeat, the original, the amortized
frame and the reference as PNG (and ``--also NAME=VALUE``: the shader with that define, e.g.
``PCF_SAMPLES=1``).
"""
from __future__ import annotations

import json
import os

import click
from rich.console import Console

from rrcache.cli.options import parse_defines, resolution_option as _resolution
from rrcache.cli.progress import Reporter, quiet_option
from rrcache.runtime.glsl import FILTERS
from rrcache.selection import AMORTIZE_PAYLOADS


@click.command("bench-amortize")
@click.argument("shader", type=click.Path(dir_okay=False))
@click.argument("session", type=click.Path(dir_okay=False))
@click.option("--estimator", required=True, metavar="ID", help="The estimator (see `rrcache nodes --json`).")
@click.option("--samples", default=4, show_default=True, type=click.IntRange(1), help="m: samples per frame at hits.")
@click.option("--lambda", "blend", default=0.6, show_default=True, type=click.FloatRange(0.0, 1.0, max_open=True),
              help="λ: weight of the reprojected estimate.")
@click.option("--history", type=click.Choice(["blend", "slots"]), default="blend", show_default=True)
@click.option("--filter", "filter_", type=click.Choice(list(FILTERS)),
              default="bilinear", show_default=True, help="How the previous frame's estimate is resampled.")
@click.option("--phase", type=click.Choice(["frame", "pixel"]), default="frame", show_default=True)
@click.option("--payload", type=click.Choice(AMORTIZE_PAYLOADS), default="f4", show_default=True,
              help="The cache's payload format: 32- or 16-bit floats, or u8, 8 bits by the range of the "
                   "estimator's terms (slots history only; rrcache.compiler.payload_encoding).")
@click.option("--algorithm", type=click.Choice(["three-pass", "two-pass", "one-pass"]), default="two-pass",
              show_default=True)
@click.option("--reference", "reference", multiple=True, metavar="NAME=VALUE",
              help="Define(s) that make the shader the reference (e.g. PCF_SAMPLES=256); none: the original.")
@click.option("--also", multiple=True, metavar="NAME=VALUE", help="Another define for an extra image.")
@click.option("--frames", default=60, show_default=True, type=click.IntRange(2))
@click.option("--repeats", default=3, show_default=True, type=click.IntRange(1, 50))
@click.option("--error-every", default=5, show_default=True, type=click.IntRange(1),
              help="Render the reference (untimed) every this many frames.")
@click.option("--resolution", callback=_resolution, default=None, metavar="WxH")
@click.option("--images", type=click.Path(file_okay=False), default=None, help="Write comparison PNGs here.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@quiet_option
def command(shader, session, estimator, samples, blend, history, filter_, phase, payload, algorithm, reference, also, frames,
            repeats, error_every, resolution, images, as_json, quiet):
    """Measure amortized sampling of one estimator of SHADER over SESSION."""
    from rrcache.bench.amortize import run, write_images

    err = Console(stderr=True)
    ref_defines = parse_defines(reference)
    kept = {}
    done = {"n": 0}

    with Reporter(err, quiet=quiet) as reporter:
        def on_frame(repeat, index, original, amortized, ref):
            done["n"] += 1
            reporter.update(f"[{repeat + 1}/{repeats}] {estimator} amortized beside the original", done["n"],
                            frames * repeats)
            if repeat == 0 and images and index == frames - 1:
                kept.update(original=original.image, amortized=amortized.image)

        result = run(shader, session, estimator, samples, blend, ref_defines, frames=frames, repeats=repeats,
                     error_every=error_every, algorithm=algorithm, phase=phase, history=history, filter=filter_,
                     payload=payload, resolution=resolution, on_frame=on_frame)
    summary = result.summary()
    if images:
        os.makedirs(images, exist_ok=True)
        summary["images"] = write_images(images, shader, session, result, kept, parse_defines(also))
    if as_json:
        click.echo(json.dumps(summary, indent=2))
        return
    s = summary
    click.echo(f"{estimator}: {s['samples']} of {s['of']} samples per frame, λ = {s['lambda']}, "
               f"{s['history']} history, {s['phase']} phase, {s['payload']} payload, {s['algorithm']}, {s['frames']} frames "
               f"at {s['resolution'][0]}x{s['resolution'][1]}, {s['repeats']} repeats")
    if s.get("payload_note"):
        click.echo(f"note: {s['payload_note']}")
    ratio = f" ({s['amortized_error'] / s['original_error']:.2f}x)" if s["original_error"] > 0 else ""
    click.echo(f"error against the reference ({s['error_frames']} frames): original {s['original_error']:.6f}, "
               f"amortized {s['amortized_error']:.6f}{ratio}; PSNR {s['original_psnr']:.1f} / "
               f"{s['amortized_psnr']:.1f} dB")
    click.echo(f"speed-up (wall): {s['speedup']:.2f}x (range {s['speedup_range'][0]:.2f}-{s['speedup_range'][1]:.2f}); "
               f"{s['original_ms']:.1f} / {s['amortized_ms']:.1f} ms")
    click.echo(f"speed-up (CPU time): {s['cpu_speedup']:.2f}x (range {s['cpu_speedup_range'][0]:.2f}-"
               f"{s['cpu_speedup_range'][1]:.2f}); {s['original_cpu_ms']:.1f} / {s['amortized_cpu_ms']:.1f} ms")
