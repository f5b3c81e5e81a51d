"""``rrcache render SHADER SESSION``: replay a session through a shader and report per frame.

    rrcache render marble.frag session.json --frames 10 --out frames/ -D OCTAVES=5
    rrcache render marble.frag session.json --resolution 64x48 --json
    rrcache render marble.frag session.json --node n2575 --period 16 --json

With ``--node`` the variant caching that node is rendered beside the original (``--node A --period
50 --node B --period 4``: several nodes, each at its own period, paired in order), frame by frame in
one run, and compared: error, PSNR (``psnr`` null and ``exact`` true for a variant equal to the
original on every summarized frame, "∞ (exact)" in the table), hit rate, and the speed-up as a ratio of median frame times
(the first frame, which has no cache, is left out of the summary), with its spread: a 95% bootstrap
interval over the frame pairs (``speedup_ci95``) and, with ``--repeats N``, the range of N whole
comparisons (``speedup_range``; the summary is the median repeat's). ``noise`` is the relative
frame-to-frame noise of the original's times (:mod:`rrcache.harness.timing`); above 10% a warning
says the machine's load made the timing unreliable (``reliable: false``).

Frames are drawn into ``--color-format`` (default: rgba8 for a ``--node`` comparison without
``--out``, as applications draw; rgba32f otherwise: exact images, and NaN/Inf can only be counted
in a float target). With ``--out`` each frame is written as ``frame_NNNN.exr`` and ``frame_NNNN.png``.
The summary is a table (or, with ``--json``, an object with ``frames``, ``resolution``,
``ms_per_frame``, ``frame_ms``, ``noise``, ``reliable``, ``color_format``, and per frame
``covered_pixels`` and ``nonfinite_pixels``: pixels with a NaN or an infinity); notes on the
session (uniforms the shader does not use) go to stderr.
"""
from __future__ import annotations

import json
import math
from typing import Optional
from pathlib import Path

import click
from rich.console import Console
from rich.table import Table

from rrcache.cli.options import PERIOD, include_dirs_option, pair_periods, parse_defines, resolution_option, vert_option
from rrcache.cli.progress import Reporter, quiet_option
from rrcache.gl.formats import COLOR_FORMATS, DEFAULT_TIMING_FORMAT, ERROR_FORMAT
from rrcache.harness.timing import frame_noise, load_warning
from rrcache.jsonable import finite_json
from rrcache.pipeline import all_include_dirs
from rrcache.harness.images import write_image
from rrcache.harness.metrics import nonfinite_count
from rrcache.compiler.prepared import prepare_file
from rrcache.harness.renderer import frame_indices, render
from rrcache.runtime import (ALGORITHMS, BLOCK_SIZES, DEFAULT_BLOCK, DEFAULT_DEPTH_EPSILON, DEFAULT_PERIOD,
                             DEFAULT_REFRESH, FILTERS, REFRESH_MODES)
from rrcache.session import load_session
from rrcache.cli.adaptive import adaptive_kwargs, adaptive_options, check_adaptive


@click.command("render")
@click.argument("shader", type=click.Path(dir_okay=False))
@click.argument("session", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Write every frame here as EXR and PNG.")
@click.option("--frames", "frame_count", type=click.IntRange(min=1), default=None,
              help="Render only the first N frames (default: all).")
@click.option("--resolution", callback=resolution_option, default=None, metavar="WxH",
              help="Render at this size instead of the session's.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("-D", "defines", multiple=True, metavar="NAME[=VALUE]", help="Define a preprocessor macro.")
@include_dirs_option
@click.option("--node", multiple=True, metavar="ID",
              help="Cache this node (an id from `rrcache nodes`); repeat it to cache several nodes.")
@click.option("--period", type=PERIOD, multiple=True, show_default=str(DEFAULT_PERIOD),
              help="Refresh period Δn; with several --node, one per node in the same order (or one for all).")
@click.option("--algorithm", type=click.Choice(ALGORITHMS), default="three-pass", show_default=True)
@click.option("--block", type=click.Choice([str(b) for b in BLOCK_SIZES]), default=str(DEFAULT_BLOCK),
              show_default=True, help="Refresh block size k (pixels).")
@click.option("--refresh", type=click.Choice(REFRESH_MODES), default=DEFAULT_REFRESH, show_default=True)
@click.option("--filter", "filter_", type=click.Choice(FILTERS), default="bilinear", show_default=True,
              help="Payload reconstruction filter.")
@click.option("--payload", type=click.Choice(["f4", "f2"]), default="f4", show_default=True,
              help="Cache precision: 32- or 16-bit float.")
@click.option("--depth-epsilon", type=float, default=DEFAULT_DEPTH_EPSILON, show_default=True,
              help="Relative tolerance of the reprojected depth test.")
@click.option("--color-format", type=click.Choice(("auto",) + tuple(COLOR_FORMATS)), default="auto",
              show_default=True,
              help="Colour target of every render: auto = rgba8 for a --node comparison without --out (as "
                   "applications draw; times depend on it), else rgba32f (exact images, NaN/Inf counted).")
@click.option("--repeats", type=click.IntRange(min=1, max=50), default=1, show_default=True,
              help="With --node: run the side-by-side comparison this many times (the speed-up is the "
                   "median repeat, with the range).")
@adaptive_options
@quiet_option
@vert_option
def command(shader, session, out_dir, frame_count, resolution, as_json, defines, include_dirs, node, period, algorithm,
            block, refresh, filter_, payload, depth_epsilon, color_format, repeats, adaptive, fast_period, spread,
            quiet, vert):
    """Render SESSION through the fragment shader SHADER and report time and coverage per frame;
    with --node, compare the cached variant of that node with the original."""
    err_console = Console(stderr=True)
    loaded = load_session(session)
    if color_format == "auto":
        # a replay is exact (its images, its NaN/Inf counts need floats); a comparison with
        # --node is a timing: as applications draw, unless its images are written
        color_format = DEFAULT_TIMING_FORMAT if node and not out_dir else ERROR_FORMAT
    check_adaptive(adaptive, node, algorithm)
    if node:
        periods = pair_periods(node, period, DEFAULT_PERIOD)
        if len(node) == 1:
            node, period = node[0], periods[0]
        else:
            period = periods
        _render_cached(shader, loaded, parse_defines(defines), include_dirs, node, out_dir, frame_count, resolution, as_json,
                       dict(period=period, algorithm=algorithm, block=int(block), refresh=refresh,
                            filter=filter_, payload=payload, depth_epsilon=depth_epsilon,
                            color_format=color_format, repeats=repeats, threshold=adaptive,
                            fast_period=fast_period, spread=spread), err_console, vert, quiet)
        return
    prepared = prepare_file(shader, loaded, parse_defines(defines), all_include_dirs(include_dirs, loaded), vertex=vert)
    indices = frame_indices(loaded, frame_count)
    out = Path(out_dir) if out_dir else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)

    with Reporter(err_console, quiet=quiet or len(indices) < 2) as reporter:
        nonfinite = []

        def done(frame):
            nonfinite.append(nonfinite_count(frame.image))
            if out is not None:
                stem = out / f"frame_{frame.index:04d}"
                write_image(stem.with_suffix(".exr"), frame.image)
                write_image(stem.with_suffix(".png"), frame.image)
            reporter.update("rendering", len(nonfinite), len(indices))

        # streamed: each frame's figures are taken (and its images written) as it is done
        result = render(prepared, loaded, indices, resolution=resolution, progress=done, keep_images=False,
                        color_format=color_format)

    noise = frame_noise([f.ms for f in result.frames])
    warning = load_warning(noise)
    if warning:
        err_console.print(f"warning: {warning}", highlight=False, markup=False)
    for note in result.notes:
        click.echo(f"note: {note}", err=True)  # one line each, never wrapped
    if as_json:
        click.echo(json.dumps({
            "frames": len(result.frames),
            "resolution": list(result.resolution),
            "ms_per_frame": result.ms_per_frame,
            "covered_pixels": [f.covered_pixels for f in result.frames],
            "nonfinite_pixels": nonfinite,
            "frame_ms": [f.ms for f in result.frames],
            "color_format": color_format,
            "noise": noise,
            "reliable": not warning,
        }))
        return
    table = Table(title=f"{prepared.path} × {loaded.path}  ({result.resolution[0]}×{result.resolution[1]})")
    table.add_column("frame", justify="right")
    table.add_column("covered pixels", justify="right")
    table.add_column("ms", justify="right")
    if any(nonfinite):
        table.add_column("NaN/Inf pixels", justify="right")
    for frame, bad in zip(result.frames, nonfinite):
        extra = [str(bad)] if any(nonfinite) else []
        table.add_row(str(frame.index), str(frame.covered_pixels), f"{frame.ms:.2f}", *extra)
    console = Console()
    console.print(table)
    console.print(f"median {result.ms_per_frame:.2f} ms per frame over {len(result.frames)} frames"
                  + (f"; images in {out}" if out is not None else ""), highlight=False)


def _render_cached(shader, loaded, defines, include_dirs, node, out_dir, frame_count, resolution, as_json, opts,
                   err_console, vert=None, quiet=False):
    from rrcache.harness.cached import compare
    from rrcache.pipeline import load_for_session, variant_for, variant_for_nodes

    work = load_for_session(shader, loaded, defines, include_dirs, vertex=vert)
    if not isinstance(node, str):  # several nodes, each with its period
        entries = [work.node(n) for n in node]
        variant = variant_for_nodes(work, list(node), opts["algorithm"], opts["filter"], opts["payload"])
        _render_nodes(work, loaded, node, entries, variant, out_dir, frame_count, resolution, as_json, opts,
                      err_console, quiet)
        return
    entry = work.node(node)
    adaptive = opts.get("threshold") is not None
    variant = variant_for(work, node, opts["algorithm"], opts["filter"], opts["payload"], adaptive=adaptive)
    indices = frame_indices(loaded, frame_count)
    out = Path(out_dir) if out_dir else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    repeats = opts["repeats"]
    runs = []
    with Reporter(err_console, quiet=quiet or len(indices) * repeats < 2) as reporter:
        for repeat in range(repeats):
            count = {"n": 0}

            def done(row, got, ref, repeat=repeat):
                if out is not None and repeat == 0:
                    stem = out / f"frame_{row.index:04d}"
                    write_image(stem.with_suffix(".exr"), got.image)
                    write_image(stem.with_suffix(".png"), got.image)
                    write_image(out / f"original_{row.index:04d}.png", ref.image)
                count["n"] += 1
                reporter.update(f"[{repeat + 1}/{repeats}] caching {node} at Δn={opts['period']}"
                                + (f", adaptive {opts['threshold']:g}" if adaptive else ""), count["n"],
                                len(indices))

            runs.append(compare(variant, loaded, work.prepared, indices, period=opts["period"], resolution=resolution,
                                block=opts["block"], refresh=opts["refresh"], depth_epsilon=opts["depth_epsilon"],
                                on_frame=done, color_format=opts["color_format"],
                                **adaptive_kwargs(opts)))
    # the median repeat by speed-up stands for the run; the range is every repeat's
    speedups = sorted(r.speedup for r in runs)
    result = sorted(runs, key=lambda r: r.speedup)[len(runs) // 2]
    for note in result.notes:
        click.echo(f"note: {note}", err=True)  # one line each, never wrapped
    summary = result.summary()
    summary.update(repeats=repeats, speedup_repeats=[r.speedup for r in runs],
                   speedup_range=[speedups[0], speedups[-1]])
    noisiest = max(runs, key=lambda r: r.noise)
    warning = load_warning(noisiest.noise)
    if warning:
        summary["reliable"] = False
        err_console.print(f"warning: {warning}", highlight=False, markup=False)
    if as_json:
        click.echo(json.dumps(finite_json(dict(
            frames=len(result.frames), resolution=list(result.resolution), node=node, period=opts["period"],
            algorithm=opts["algorithm"], filter=opts["filter"], covered_pixels=[f.covered for f in result.frames],
            **({"adaptive": adaptive_kwargs(opts)} if adaptive else {}), **summary))))
        return
    console = Console()
    table = Table(title=f"{work.prepared.path} caching {node} ({entry.type}, line {entry.line}) "
                        f"at Δn={opts['period']}, {opts['algorithm']}"
                        + (f", adaptive threshold {opts['threshold']:g} (fast period {opts['fast_period']})"
                           if adaptive else ""))
    for col in ("frame", "covered", "hit rate", "mean error", "PSNR dB", "ms", "original ms"):
        table.add_column(col, justify="right")
    for f in result.frames:
        rate = "n/a" if f.hits is None else f"{f.hits / f.covered if f.covered else 0.0:.3f}"
        table.add_row(str(f.index), str(f.covered), rate, f"{f.mean_error:.5f}",
                      _psnr(f.psnr, unit=""), f"{f.ms:.2f}", f"{f.original_ms:.2f}")
    console.print(table)
    console.print(f"node {node}: {entry.text}", highlight=False, markup=False)
    lo, hi = summary["speedup_ci95"]
    spread = (f"95% interval {lo:.2f}–{hi:.2f}" if repeats == 1 else
              f"{repeats} repeats {summary['speedup_range'][0]:.2f}–{summary['speedup_range'][1]:.2f}, "
              f"95% interval {lo:.2f}–{hi:.2f}")
    console.print(f"speed-up {summary['speedup']:.2f}× ({spread}; {summary['ms_per_frame']:.2f} ms vs "
                  f"{summary['original_ms_per_frame']:.2f} ms, medians), hit rate {summary['hit_rate']:.3f}, "
                  f"mean error {summary['mean_error']:.5f}, PSNR {_psnr(summary['psnr'])}", highlight=False)
    if summary["error_left_out_pixels"] or summary["nonfinite_pixels"]:
        console.print(f"NaN/Inf pixels: {summary['nonfinite_pixels']} in the variant, "
                      f"{summary['original_nonfinite_pixels']} in the original; the error leaves out "
                      f"{summary['error_left_out_pixels']} covered pixels", highlight=False)


def _psnr(value: Optional[float], unit: str = " dB") -> str:
    """A summary's PSNR (None: exact) as :func:`rrcache.model.psnr.psnr_text` shows it."""
    from rrcache.model.psnr import psnr_text

    text = psnr_text(math.inf if value is None else value)
    return text if text.startswith(("∞", "–")) else text + unit


def _render_nodes(work, loaded, nodes, entries, variant, out_dir, frame_count, resolution, as_json, opts,
                  err_console, quiet=False):
    """``render --node A --period 50 --node B --period 4``: the variant of several nodes beside
    the original, as for one node."""
    from rrcache.harness.cached import compare

    periods = list(opts["period"])
    label = " + ".join(f"{n} Δn={p}" for n, p in zip(nodes, periods))
    indices = frame_indices(loaded, frame_count)
    out = Path(out_dir) if out_dir else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    with Reporter(err_console, quiet=quiet or len(indices) < 2) as reporter:
        count = {"n": 0}

        def done(row, got, ref):
            if out is not None:
                stem = out / f"frame_{row.index:04d}"
                write_image(stem.with_suffix(".exr"), got.image)
                write_image(stem.with_suffix(".png"), got.image)
                write_image(out / f"original_{row.index:04d}.png", ref.image)
            count["n"] += 1
            reporter.update(f"caching {label}", count["n"], len(indices))

        result = compare(variant, loaded, work.prepared, indices, period=tuple(periods), resolution=resolution,
                         block=opts["block"], refresh=opts["refresh"], depth_epsilon=opts["depth_epsilon"],
                         on_frame=done, color_format=opts["color_format"])
    for note in result.notes:
        click.echo(f"note: {note}", err=True)
    summary = result.summary()
    if as_json:
        click.echo(json.dumps(finite_json(dict(
            frames=len(result.frames), resolution=list(result.resolution), node="+".join(nodes),
            nodes=list(nodes), period=periods, algorithm=opts["algorithm"],
            covered_pixels=[f.covered for f in result.frames], **summary))))
        return
    console = Console()
    table = Table(title=f"{work.prepared.path} caching {label}, {opts['algorithm']}")
    for col in ("frame", "covered", "hit rate", "mean error", "PSNR dB", "ms", "original ms"):
        table.add_column(col, justify="right")
    for f in result.frames:
        rate = "n/a" if f.hits is None else f"{f.hits / f.covered if f.covered else 0.0:.3f}"
        table.add_row(str(f.index), str(f.covered), rate, f"{f.mean_error:.5f}",
                      _psnr(f.psnr, unit=""), f"{f.ms:.2f}", f"{f.original_ms:.2f}")
    console.print(table)
    for n, e in zip(nodes, entries):
        console.print(f"node {n} ({e.type}, line {e.line}): {e.text}", highlight=False, markup=False)
    console.print(f"speed-up {summary['speedup']:.2f}× ({summary['ms_per_frame']:.2f} ms vs "
                  f"{summary['original_ms_per_frame']:.2f} ms, medians), hit rate "
                  f"{summary['hit_rate']:.3f}, mean error {summary['mean_error']:.5f}, PSNR {_psnr(summary['psnr'])}",
                  highlight=False)
