"""``rrcache render SHADER SESSION`` (or ``rrcache render PROFILE``): replay a session through a
shader and report per frame.

    rrcache render marble.frag session.json --frames 10 --out frames/ -D OCTAVES=5
    rrcache render marble.frag session.json --resolution 64x48 --json
    rrcache render marble.frag session.json --node n2575 --period 16 --json
    rrcache render marble.rrprofile --level e2            # the profile's e2 choice, as it chose it
    rrcache render marble.rrprofile --node n74 --period 8 # another choice, with the profile's options
    rrcache render marble.frag session.json --method render-cache --samples 0.05   # the render cache

With ``--node`` the variant caching that node is rendered beside the original (``--node A --period
50 --node B --period 4``: several nodes, each at its own period, paired in order), frame by frame in
one run, and compared: error, PSNR (``psnr`` null and ``exact`` true for a variant equal to the
original on every summarized frame, "∞ (exact)" in the table), hit rate, and the speed-up as a ratio of median frame times
(the first frame, which has no cache, is left out of the summary), with its spread: a 95% bootstrap
interval over the frame pairs (``speedup_ci95``) and, with ``--repeats N``, the range of N whole
comparisons (``speedup_range``; the summary is the median repeat's). ``noise`` is the relative
frame-to-frame noise of the original's times (:mod:`rrcache.harness.timing`); above 10% a warning
says the machine's load made the timing unreliable (``reliable: false``).

The cache algorithm and options are said before the comparison starts (stderr) and in the
summary: with a SHADER, ``--algorithm`` defaults to three-pass; with a PROFILE, to the one the
profile chose, and the refresh block, pattern and depth tolerance to the profile's.
``--level eN`` renders a level's choice with every option the profile chose (its algorithm, period,
adaptive threshold or amortized m and λ), over the profile's validation frames, drawn into the
profile's timing colour format (``--color-format rgba32f`` for the exact error): what the profile
measured when it validated the level, again.

``--method render-cache --samples F`` compares the render cache of Walter et al. 2002 (forward
reprojection, F of the pixels shaded per frame) with the original instead: a baseline at equal
time, never a choice the profiler makes (:mod:`rrcache.cli.method`).

Frames are drawn into ``--color-format`` (default: rgba8 for a comparison without ``--out``, as
applications draw; rgba32f otherwise: exact images, and NaN/Inf can only be counted in a float
target). With ``--out`` each frame is written as ``frame_NNNN.exr`` and ``frame_NNNN.png``.
The summary is a table (plain text when stdout is not a terminal, every cell whole) or, with
``--json``, an object with ``frames``, ``resolution``, ``ms_per_frame``, ``frame_ms``, ``noise``,
``reliable``, ``color_format``, and per frame ``covered_pixels`` and ``nonfinite_pixels``: pixels
with a NaN or an infinity; a comparison adds ``algorithm``, ``block``, ``refresh``,
``depth_epsilon`` and, with ``--level``, ``level`` and ``choice``. Notes on the session (uniforms
the shader does not use) go to stderr; so does progress (a line every 10 s off a terminal).
"""
from __future__ import annotations

import json
import math
from typing import Optional

import click
from rich.console import Console

from rrcache.cli.options import PERIOD, include_dirs_option, pair_periods, parse_defines, resolution_option, vert_option
from rrcache.cli.progress import Reporter, quiet_option
from rrcache.cli.sources import describe_selection, given, refuse_with_level, resolve
from rrcache.cli.tables import TextTable
from rrcache.gl.formats import COLOR_FORMATS, DEFAULT_TIMING_FORMAT, ERROR_FORMAT
from rrcache.harness.timing import frame_noise, load_warning
from rrcache.jsonable import finite_json
from rrcache.harness.images import write_image
from rrcache.harness.metrics import nonfinite_count
from rrcache.harness.renderer import render
from rrcache.runtime import (ALGORITHMS, BLOCK_SIZES, DEFAULT_BLOCK, DEFAULT_DEPTH_EPSILON, DEFAULT_FILTER, DEFAULT_PERIOD,
                             DEFAULT_REFRESH, FILTERS, REFRESH_MODES)
from rrcache.session import load_session
from rrcache.cli.adaptive import adaptive_kwargs, adaptive_options, check_adaptive
from rrcache.cli.method import check_method, method_option, render_cache, samples_option
from rrcache.cli.repeats import frames_and_folder, run_repeats

#: the options --level takes from the profile (parameter name -> option as typed)
_LEVEL_OWNS = {"node": "--node", "period": "--period", "algorithm": "--algorithm", "block": "--block",
               "refresh": "--refresh", "filter_": "--filter", "payload": "--payload",
               "depth_epsilon": "--depth-epsilon", "adaptive": "--adaptive", "fast_period": "--fast-period",
               "spread": "--spread"}


@click.command("render")
@click.argument("shader", metavar="SHADER|PROFILE", type=click.Path())
@click.argument("session", required=False, type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Write every frame here as EXR and PNG.")
@click.option("--frames", "frame_count", type=click.IntRange(min=1), default=None,
              help="Render only the first N frames (default: all; with --level, the profile's validation frames).")
@click.option("--resolution", callback=resolution_option, default=None, metavar="WxH",
              help="Render at this size instead of the session's.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("-D", "defines", multiple=True, metavar="NAME[=VALUE]", help="Define a preprocessor macro.")
@include_dirs_option
@click.option("--level", default=None, metavar="eN",
              help="With a PROFILE: render the choice of this level (e1..e4) with every option the profile chose.")
@click.option("--node", multiple=True, metavar="ID",
              help="Cache this node (an id from `rrcache nodes`); repeat it to cache several nodes.")
@click.option("--period", type=PERIOD, multiple=True, show_default=str(DEFAULT_PERIOD),
              help="Refresh period Δn; with several --node, one per node in the same order (or one for all).")
@click.option("--algorithm", type=click.Choice(ALGORITHMS), default=None,
              help="Cache algorithm (default: the profile's with a PROFILE, else three-pass).")
@click.option("--block", type=click.Choice([str(b) for b in BLOCK_SIZES]), default=None,
              help=f"Refresh block size k in pixels (default: the profile's, else {DEFAULT_BLOCK}).")
@click.option("--refresh", type=click.Choice(REFRESH_MODES), default=None,
              help=f"Refresh pattern (default: the profile's, else {DEFAULT_REFRESH}).")
@click.option("--filter", "filter_", type=click.Choice(FILTERS), default=None,
              help=f"The cache's hit test and payload reconstruction (default: the profile's with a PROFILE, else "
                   f"{DEFAULT_FILTER}).")
@click.option("--payload", type=click.Choice(["f4", "f2"]), default="f4", show_default=True,
              help="Cache precision: 32- or 16-bit float.")
@click.option("--depth-epsilon", type=float, default=None,
              help=f"Relative tolerance of the reprojected depth test (default: the profile's, else "
                   f"{DEFAULT_DEPTH_EPSILON:g}).")
@click.option("--color-format", type=click.Choice(("auto",) + tuple(COLOR_FORMATS)), default="auto",
              show_default=True,
              help="Colour target of every render: auto = rgba8 (a PROFILE's timing format) for a comparison "
                   "without --out (as applications draw; times depend on it), else rgba32f (exact images, "
                   "NaN/Inf counted).")
@click.option("--repeats", type=click.IntRange(min=1, max=50), default=1, show_default=True,
              help="With --node or --level: run the side-by-side comparison this many times (the speed-up is "
                   "the median repeat, with the range).")
@adaptive_options
@method_option
@samples_option
@quiet_option
@vert_option
@click.pass_context
def command(ctx, shader, session, out_dir, frame_count, resolution, as_json, defines, include_dirs, level, node,
            period, algorithm, block, refresh, filter_, payload, depth_epsilon, color_format, repeats, adaptive,
            fast_period, spread, method, samples, quiet, vert):
    """Render SESSION through the fragment shader SHADER (or a PROFILE's shader and session) and
    report time and coverage per frame; with --node or --level, compare a cached variant with the
    original."""
    err_console = Console(stderr=True)
    source = resolve(ctx, shader, session, parse_defines(defines), include_dirs, vert, session_required=True)
    prof = source.prof
    if level is not None and prof is None:
        raise click.UsageError("--level needs a PROFILE folder as the first argument (rrcache render PROFILE "
                               "--level e2)")
    if level is not None:
        refuse_with_level(ctx, _LEVEL_OWNS)
    check_method(method, samples, {"--node": bool(node), "--level": level is not None})
    loaded = load_session(source.session)
    cached = bool(node) or level is not None or method == "render-cache"
    if color_format == "auto":
        # a replay is exact (its images, its NaN/Inf counts need floats); a comparison is a
        # timing: as applications draw (as the profile timed it), unless its images are written
        timing = prof.settings.timing_format if prof is not None else DEFAULT_TIMING_FORMAT
        color_format = timing if cached and not out_dir else ERROR_FORMAT
    if method == "render-cache":
        render_cache(source, loaded, samples, out_dir, frame_count, resolution, as_json, color_format, repeats,
                     err_console, quiet)
        return
    if level is not None:
        from rrcache import choice

        sel = choice.level(prof, level)
        if not sel.parts:
            err_console.print(f"{sel.label} keeps the original shader ({choice.original_note(prof, sel)}): "
                              "rendering the original", highlight=False, markup=False)
            _replay(source, loaded, out_dir, frame_count, resolution, as_json, color_format, err_console, quiet)
            return
        if frame_count is None and prof.settings.validation_frames is not None:
            frame_count = prof.settings.validation_frames
        work, _ = choice.load_work(prof, include_dirs)
        variant, run_period = choice.variant_of(prof, sel, work)
        opts = choice.runtime_options(prof, sel)
        what = f"{sel.label} of {prof.path}: {describe_selection(prof, sel)}"
        setup = dict(algorithm=choice.algorithm_of(prof, sel), period=run_period, options=opts,
                     said=choice.describe_options(prof, sel), level=sel.label, choice=sel.describe())
        _compare(work, loaded, variant, what, setup, out_dir, frame_count, resolution, as_json, color_format,
                 repeats, err_console, quiet)
        return
    if not node:
        _replay(source, loaded, out_dir, frame_count, resolution, as_json, color_format, err_console, quiet)
        return
    # a node (or several) given: the profile's algorithm and options when a profile is given
    settings = prof.settings if prof is not None else None
    if algorithm is None:
        algorithm = prof.algorithm if prof is not None else "three-pass"
        why = (f"the profile's choice; --algorithm for another" if prof is not None else
               "the default; --algorithm two-pass or one-pass for another, or give a PROFILE for its choice")
    else:
        why = "--algorithm"
    check_adaptive(adaptive, node, algorithm)
    options = {"block": int(block) if block is not None else (settings.block if settings else DEFAULT_BLOCK),
               "refresh": refresh or (settings.refresh if settings else DEFAULT_REFRESH),
               "depth_epsilon": depth_epsilon if depth_epsilon is not None else (
                   settings.depth_epsilon if settings else DEFAULT_DEPTH_EPSILON)}
    options.update(adaptive_kwargs({"threshold": adaptive, "fast_period": fast_period, "spread": spread}))
    if filter_ is None:
        filter_ = getattr(prof, "filter", None) or DEFAULT_FILTER
    from rrcache.pipeline import load_for_session, variant_for, variant_for_nodes

    work = load_for_session(source.shader, loaded, source.defines, source.include_dirs, vertex=source.vertex)
    periods = pair_periods(node, period, DEFAULT_PERIOD)
    entries = [work.node(n) for n in node]
    if len(node) == 1:
        variant = variant_for(work, node[0], algorithm, filter_, payload, adaptive=adaptive is not None)
        run_period = periods[0]
    else:
        variant = variant_for_nodes(work, list(node), algorithm, filter_, payload)
        run_period = periods
    what = " + ".join(f"{n} ({e.type}, line {e.line}: {e.text}) at Δn={p}" for n, e, p in zip(node, entries, periods))
    said = (f"{algorithm} ({why}), {filter_} filter, refresh block {options['block']}, {options['refresh']} "
            f"refresh, depth tolerance {options['depth_epsilon']:g}"
            + (f", adaptive threshold {adaptive:g} (fast period {fast_period})" if adaptive is not None else ""))
    setup = dict(algorithm=algorithm, period=run_period if len(node) > 1 else periods[0], options=options,
                 said=said, filter=filter_)
    if not given(ctx, "period") and prof is None:
        said_period = f" (Δn={DEFAULT_PERIOD}: the default; --period for another)"
        setup["said"] += said_period
    _compare(work, loaded, variant, what, setup, out_dir, frame_count, resolution, as_json, color_format, repeats,
             err_console, quiet, nodes=list(node))


def _replay(source, loaded, out_dir, frame_count, resolution, as_json, color_format, err_console, quiet) -> None:
    """The shader alone over the session: time and coverage per frame."""
    prepared = source.prepare(loaded)
    indices, out = frames_and_folder(loaded, frame_count, out_dir)

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
        err_console.print(f"warning: {warning}", highlight=False, markup=False, soft_wrap=True)
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
    columns = [("frame", "right"), ("covered pixels", "right"), ("ms", "right")]
    if any(nonfinite):
        columns.append(("NaN/Inf pixels", "right"))
    table = TextTable(f"{prepared.path} × {loaded.path}  ({result.resolution[0]}×{result.resolution[1]})", columns)
    for frame, bad in zip(result.frames, nonfinite):
        extra = [str(bad)] if any(nonfinite) else []
        table.add_row(str(frame.index), str(frame.covered_pixels), f"{frame.ms:.2f}", *extra)
    console = Console()
    table.print(console)
    console.print(f"median {result.ms_per_frame:.2f} ms per frame over {len(result.frames)} frames"
                  + (f"; images in {out}" if out is not None else ""), highlight=False, markup=False)


def _compare(work, loaded, variant, what: str, setup: dict, out_dir, frame_count, resolution, as_json,
             color_format, repeats, err_console, quiet, nodes=None) -> None:
    """A cached variant beside the original, ``repeats`` times; the table and summary (or JSON).
    ``setup``: ``algorithm``, ``period``, ``options`` (the runtime's keyword arguments), ``said``
    (them in words) and, for a level, ``level`` and ``choice``."""
    from rrcache.harness.cached import compare

    indices, out = frames_and_folder(loaded, frame_count, out_dir)
    if not quiet:
        err_console.print(f"{what}\n  with {setup['said']}; colour target {color_format}, {len(indices)} frames",
                          highlight=False, markup=False, soft_wrap=True)
    label = setup.get("level") or " + ".join(nodes or [])
    runs = run_repeats(lambda done: compare(variant, loaded, work.prepared, indices, period=setup["period"],
                                            resolution=resolution, on_frame=done, color_format=color_format,
                                            **setup["options"]),
                       len(indices), repeats, out, label, err_console, quiet)
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
        err_console.print(f"warning: {warning}", highlight=False, markup=False, soft_wrap=True)
    options = setup["options"]
    if as_json:
        doc = dict(frames=len(result.frames), resolution=list(result.resolution),
                   node=None if variant.amortized else "+".join(nodes) if nodes else
                   (str(variant.node_id) if variant.node_id is not None else None),
                   period=setup["period"], algorithm=setup["algorithm"], filter=variant.filter,
                   block=options["block"], refresh=options["refresh"], depth_epsilon=options["depth_epsilon"],
                   covered_pixels=[f.covered for f in result.frames])
        if nodes and len(nodes) > 1:
            doc["nodes"] = list(nodes)
        if "threshold" in options:
            doc["adaptive"] = {k: options[k] for k in ("threshold", "fast_period", "spread")}
        if setup.get("level"):
            doc.update(level=setup["level"], choice=setup["choice"])
        click.echo(json.dumps(finite_json(dict(doc, **summary))))
        return
    console = Console()
    table = TextTable(f"{work.prepared.path}: {what}, {setup['algorithm']}",
                      [(c, "right") for c in ("frame", "covered", "hit rate", "mean error", "PSNR dB", "ms",
                                              "original ms")])
    for f in result.frames:
        rate = "n/a" if f.hits is None else f"{f.hits / f.covered if f.covered else 0.0:.3f}"
        table.add_row(str(f.index), str(f.covered), rate, f"{f.mean_error:.5f}",
                      _psnr(f.psnr, unit=""), f"{f.ms:.2f}", f"{f.original_ms:.2f}")
    table.print(console)
    console.print(f"cache: {setup['said']}", highlight=False, markup=False, soft_wrap=True)
    lo, hi = summary["speedup_ci95"]
    spread = (f"95% interval {lo:.2f}–{hi:.2f}" if repeats == 1 else
              f"{repeats} repeats {summary['speedup_range'][0]:.2f}–{summary['speedup_range'][1]:.2f}, "
              f"95% interval {lo:.2f}–{hi:.2f}")
    console.print(f"speed-up {summary['speedup']:.2f}× ({spread}; {summary['ms_per_frame']:.2f} ms vs "
                  f"{summary['original_ms_per_frame']:.2f} ms, medians), hit rate {summary['hit_rate']:.3f}, "
                  f"mean error {summary['mean_error']:.5f}, PSNR {_psnr(summary['psnr'])}", highlight=False,
                  markup=False, soft_wrap=True)
    if summary["error_left_out_pixels"] or summary["nonfinite_pixels"]:
        console.print(f"NaN/Inf pixels: {summary['nonfinite_pixels']} in the variant, "
                      f"{summary['original_nonfinite_pixels']} in the original; the error leaves out "
                      f"{summary['error_left_out_pixels']} covered pixels", highlight=False, markup=False)


def _psnr(value: Optional[float], unit: str = " dB") -> str:
    """A summary's PSNR (None: exact) as :func:`rrcache.model.psnr.psnr_text` shows it."""
    from rrcache.model.psnr import psnr_text

    text = psnr_text(math.inf if value is None else value)
    return text if text.startswith(("∞", "–")) else text + unit
