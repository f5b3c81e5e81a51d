"""``rrcache profile SHADER SESSION``: train the models and write the profile folder.

    rrcache profile marble.frag marble.json
    rrcache profile marble.frag marble.json --out marble.rrprofile --budget 900 -D OCTAVES=5
    rrcache profile noise.frag orbit.json --resolution 32x24 --periods 2,4,8 --timing-frames 6

The ceiling (:mod:`rrcache.profiler.ceiling`) is measured first, in seconds: when no cached variant
can reach ``--min-gain`` (default 1.1×) the command stops there and says so, with the measured
ceiling, why, and what would change it. Progress goes to stderr (:mod:`rrcache.cli.progress`: a bar
on a terminal, a line per finished step elsewhere; ``--quiet`` for none). Rerunning
the same command resumes: every stored run is skipped (the summary says how many). Ctrl-C stops
after the run in flight is dropped: what is stored stays, it is listed, and the exit code is 130.
The closing summary gives the nodes trained, μ, the overhead, the original's frame time and the
four selections (node, Δn, predicted/measured speed-up and error, PSNR).
"""
from __future__ import annotations

import math
import sys
import warnings

import click
from rich.console import Console

from rrcache.cli import interrupt
from rrcache.cli.options import (cluster_options, include_dirs_option, parse_defines, resolution_option as _resolution,
                                 vert_option)
from rrcache.cli.progress import Reporter, quiet_option
from rrcache.cluster import maybe_cluster
from rrcache.cli.tables import TextTable
from rrcache.gl.formats import COLOR_FORMATS
from rrcache.harness.timing import CLOCKS, DEFAULT_CLOCK, UNRELIABLE_NOISE
from rrcache.model.psnr import psnr_text
from rrcache.errors import RRCacheError
from rrcache.profiler.run import default_out_dir, profile
from rrcache.profiles.document import algorithm_line, filter_line
from rrcache.profiles.notices import ceiling_noise, run_warnings
from rrcache.profiles.store import STORE_NAME
from rrcache.profiles.settings import (ALGORITHM_CHOICES, DEFAULT_PERIODS, FILTER_CHOICES, LEVEL_KINDS, TrainingSettings,
                                      parse_periods)


def _periods(ctx, param, value):
    if value is None:
        return None
    return parse_periods(value, param.opts[0])  # the option given: --periods or --timing-periods


def _thresholds(ctx, param, value):
    """``0.005,0.01`` → (0.005, 0.01): finite numbers >= 0."""
    if value is None:
        return None
    try:
        out = tuple(float(v) for v in value.split(",") if v.strip())
    except ValueError:
        raise click.BadParameter(f"{value!r} is not a comma-separated list of numbers (e.g. 0.005,0.01,0.02)") from None
    if not out or any(not math.isfinite(v) or v < 0 for v in out):
        raise click.BadParameter(f"{value!r}: give finite thresholds >= 0 (e.g. 0.005,0.01,0.02)")
    return out


def _seconds(ctx, param, value):
    if value is not None and not math.isfinite(value):
        raise click.BadParameter(f"{value} is not a finite number of seconds (e.g. 480)")
    return value


def _fmt(value, spec=".3g", none="–"):
    if value is None:
        return none
    try:
        return format(value, spec)
    except (TypeError, ValueError):
        return str(value)


@click.command("profile")
@click.argument("shader", type=click.Path(dir_okay=False))
@click.argument("session", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", type=click.Path(), default=None,
              help="Profile folder (default: <shader>-<session>.rrprofile here).")
@click.option("--resolution", callback=_resolution, default=None, metavar="WxH",
              help="Render the error runs at this reduced size instead (default: the session's, in a window; "
                   "a smaller size overstates the error).")
@click.option("--error-window", type=click.FloatRange(min=0, max=1, min_open=True), default=None,
              help="Share of the frame the error runs render at full resolution (default: chosen from the "
                   "original's cost, at most 0.25; 1: the whole frame).")
@click.option("--frames", type=click.IntRange(min=2), default=None,
              help="Train the error on N frames, spread over the session in segments (default: 150, all of a "
                   "shorter session).")
@click.option("--periods", callback=_periods, default=None, metavar="LIST",
              help=f"Training refresh periods (default: {','.join(map(str, DEFAULT_PERIODS))}).")
@click.option("--timing-frames", type=click.IntRange(min=1), default=None,
              help=f"Frames L timed per node and timing period, at full resolution (default: {TrainingSettings.timing_frames}).")
@click.option("--timing-periods", callback=_periods, default=None, metavar="LIST",
              help="Refresh periods at which each node is timed (default: 2,8,50).")
@click.option("--algorithm", type=click.Choice(ALGORITHM_CHOICES), default="auto", show_default=True,
              help="auto: time three-pass and two-pass on the first node and keep the faster.")
@click.option("--filter", "filter_", type=click.Choice(FILTER_CHOICES), default="auto", show_default=True,
              help="The cache's hit test and payload reconstruction: auto measures bilinear against plane on "
                   "the first node and keeps plane where faster at about the same PSNR (docs/misses.md).")
@click.option("--measure-terms", is_flag=True,
              help="Before training, order the terms of sums whose weights do not fold by what caching each "
                   "alone costs in error (docs/sums.md).")
@click.option("--budget", type=click.FloatRange(min=0, min_open=True), default=None, callback=_seconds,
              help=f"Seconds of node training; no new node is started once spent (default: {TrainingSettings.budget_s:g}).")
@click.option("--min-saving", type=click.FloatRange(min=0, max=1, max_open=True), default=None,
              help=f"Skip nodes whose static cost is below this share of the costliest node's "
                   f"(default: {TrainingSettings.min_saving:g}).")
@click.option("--validation-frames", type=click.IntRange(min=2), default=None,
              help="Render each selection over the first N frames (default: all).")
@click.option("--no-validate", is_flag=True, help="Do not render the four selections against the original.")
@click.option("--fresh", is_flag=True, help="Move an existing profile.sqlite aside (.bak) and start over.")
@click.option("--min-gain", type=click.FloatRange(min=0, max=100, max_open=True), default=None,
              help=f"The least speed-up worth having (default: {TrainingSettings.min_gain:g}): the ceiling is "
                   "measured first and the profile stops with the answer 'the original' when nothing can "
                   "reach it; nodes whose best case is below it are not trained. 0: never stop.")
@click.option("--timing-format", type=click.Choice(tuple(COLOR_FORMATS)), default=None,
              help="Colour target of every timed run, original and variants alike (default: "
                   f"{TrainingSettings.timing_format}, as applications draw); error runs use rgba32f.")
@click.option("--levels", type=click.Choice(LEVEL_KINDS), default="psnr", show_default=True,
              help="The four selection levels e1..e4: psnr = predicted PSNR against the original >= 45, 40, 35, "
                   "30 dB; relative = the paper's error thresholds (fractions of the largest error seen).")
@click.option("--wait", is_flag=True,
              help="If another rrcache process is profiling into the same --out, wait for it (default: exit 2).")
@click.option("--sets", "max_sets", type=click.IntRange(min=0, max=64), default=None,
              help="Train at most this many sets of several cached nodes predicted to improve the front "
                   "(default 3; 0: single nodes only).")
@click.option("-D", "defines", multiple=True, metavar="NAME[=VALUE]", help="Define a preprocessor macro.")
@click.option("--adaptive", "adaptive", default=None, metavar="LIST", callback=_thresholds,
              help="After validation, measure each selection's node with adaptive refresh at these "
                   "thresholds (e.g. 0.005,0.01,0.02) and keep it where faster at the same level "
                   "(docs/adaptive.md).")
@click.option("--max-flip", type=click.FloatRange(min=0, min_open=True), default=None, metavar="F",
              help="Add a level 'flip': the fastest choice measured at mean FLIP <= F against the original "
                   "(docs/levels.md).")
@click.option("--clock", type=click.Choice(sorted(CLOCKS)), default=DEFAULT_CLOCK, show_default=True,
              help="The frame clock of every timed run: wall = wall time around glFinish (the only one that "
                   "means anything on a software rasterizer); gl-timer = GL timer queries (real GPUs). "
                   "Recorded in the profile.")
@cluster_options
@quiet_option
@vert_option
@include_dirs_option
def command(shader, session, out_dir, resolution, error_window, frames, periods, timing_frames, timing_periods,
            algorithm, filter_, measure_terms, budget, min_saving, validation_frames, no_validate, fresh, min_gain,
            timing_format, levels, wait, max_sets, defines, adaptive, clock, workers, scheduler, max_flip, quiet, vert,
            include_dirs):
    """Train error and performance models of the cacheable nodes of SHADER over SESSION, select
    what to cache at four error levels, and write the profile folder."""
    err_console = Console(stderr=True)
    kwargs = dict(resolution=resolution, error_window=error_window, frames=frames, algorithm=algorithm, filter=filter_,
                  measure_terms=measure_terms,
                  validate=not no_validate, validation_frames=validation_frames, levels=levels, clock=clock)
    for name, value in (("timing_frames", timing_frames), ("budget_s", budget), ("min_saving", min_saving),
                        ("min_gain", min_gain), ("timing_format", timing_format),
                        ("max_sets", max_sets)):
        if value is not None:
            kwargs[name] = value
    if periods is not None:
        kwargs["periods"] = periods
    if timing_periods is not None:
        kwargs["timing_periods"] = timing_periods
    settings = TrainingSettings(**kwargs)
    out = out_dir if out_dir is not None else default_out_dir(shader, session)

    try:
        with Reporter(err_console, quiet=quiet) as reporter, warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                with maybe_cluster(workers, scheduler, announce=reporter.line) as cluster:
                    prof = profile(shader, session, out, settings, parse_defines(defines), reporter.event, fresh=fresh,
                                   vertex=vert, include_dirs=include_dirs, wait=wait, adaptive=adaptive,
                                   executor=cluster, max_flip=max_flip)
            finally:
                for w in caught:
                    err_console.print(f"warning: {w.message}", highlight=False, markup=False)
    except KeyboardInterrupt:
        _interrupted(out, err_console)
        sys.exit(interrupt.exit_code())
    console = Console()
    if not console.is_terminal:  # a pipe, a file: whole lines, never wrapped or cut
        console = Console(soft_wrap=True)
    _summary(prof, console)


def _interrupted(out, err_console) -> None:
    from pathlib import Path

    from rrcache.profiles.store import read_store

    err_console.print(f"rrcache: {interrupt.word()}; the run in flight was dropped", highlight=False)
    path = Path(out) / STORE_NAME
    try:
        with read_store(path) as store:
            c = store.counts()
        err_console.print(f"stored in {path}: {c['error_runs']} error runs over {c['nodes']} nodes, "
                          f"{c['timing_runs']} timing runs, {c['validations']} validations; "
                          "run the same command again to resume", highlight=False)
    except RRCacheError as err:
        err_console.print(f"nothing readable is stored ({err})", highlight=False, markup=False)


def _verdict(prof, console: Console) -> None:
    v, ceiling = prof.verdict, prof.measured_ceiling
    console.print(f"profile: {prof.path}", highlight=False)
    console.print(f"answer: {v['answer']}", highlight=False)
    if ceiling is not None:
        console.print(f"ceiling: {ceiling.summary()}", highlight=False)
    for line in ceiling_noise(ceiling):
        console.print(f"warning: {line}", highlight=False, markup=False, soft_wrap=True)
    console.print(f"why: {v['reason']}", highlight=False)
    console.print("what would change it:", highlight=False)
    for change in v["changes"]:
        console.print(f"  - {change}", highlight=False)


def _summary(prof, console: Console) -> None:
    if prof.verdict is not None:
        _verdict(prof, console)
        return
    c = prof.counts
    trained = len(prof.trained_nodes)
    console.print(f"profile: {prof.path}", highlight=False)
    pruned = sum(1 for n in prof.nodes if not n.trained and n.note and "best case" in n.note)
    cheap = sum(1 for n in prof.nodes if not n.trained and n.note and "static cost" in n.note
                and "best case" not in n.note)
    late = sum(1 for n in prof.nodes if not n.trained and n.note and "budget" in n.note)
    console.print(f"nodes trained: {trained} of {len(prof.nodes)}; {cheap} too cheap to win (static cost under "
                  f"{prof.settings.min_saving:.0%} of the costliest), {pruned} whose best case under the measured "
                  f"ceiling is below {prof.settings.min_gain:.2f}×, {late} not reached within the budget",
                  highlight=False)
    console.print(f"runs: {c.get('error_runs_computed', 0)} error and {c.get('timing_runs_computed', 0)} timing runs "
                  f"computed; {c.get('error_runs_skipped', 0)} error and {c.get('timing_runs_skipped', 0)} timing "
                  "runs were stored and skipped", highlight=False)
    console.print(f"μ = {_fmt(prof.mu)} ({prof.mu_quality}); overhead {_fmt(prof.overhead_ms, '.3f')} ms; "
                  f"original {_fmt(prof.original_ms, '.3f')} ms per frame over {prof.pixels:,.0f} covered pixels; "
                  f"training {_fmt(prof.training_wall_s, '.1f')} s", highlight=False)
    console.print(f"algorithm: {algorithm_line(prof)}", highlight=False)
    console.print(f"filter: {filter_line(prof)}", highlight=False)
    if prof.plan:
        from rrcache.profiler.plan import Plan

        console.print(Plan.from_json(prof.plan).describe(prof.settings.resolution, prof.settings.frames),
                      highlight=False)
    for line in _estimator_lines(prof):
        console.print(line, highlight=False)
    ceiling = prof.measured_ceiling
    if ceiling is not None:
        console.print(f"ceiling: {ceiling.summary()}", highlight=False)
    _table(prof).print(console)
    for line in calibration_lines(prof):
        console.print(line, highlight=False, markup=False, soft_wrap=True)
    # what the measurements imply (the run's own warnings were printed as they came)
    for line in run_warnings(prof, stored=False):
        console.print(f"warning: {line}", highlight=False, markup=False, soft_wrap=True)
    level = next((s.label for s in prof.selections if s.parts), None)
    if level is not None:
        console.print(f"next: {prof.path / 'report.html'} says what each level's files are and how to run them; "
                      f"'rrcache instance {prof.path} --level {level} --out DIR' writes a level's shaders again "
                      "(--target webgl2: a page that runs them in a browser)", highlight=False, markup=False,
                      soft_wrap=True)


def calibration_lines(prof) -> list[str]:
    """What validation said of the PSNR predictions: their error on the measured choices, raw and
    calibrated, and the calibration the profile now predicts with (docs/levels.md)."""
    cal = prof.calibration or {}
    raw, calibrated = cal.get("raw") or {}, cal.get("calibrated") or {}
    if not raw.get("n"):
        return []
    return [f"PSNR predicted against measured on {raw['n']} validated choices: |error| mean {raw['mean']:.1f} dB, "
            f"worst {raw['worst']:.1f} dB (models alone); mean {calibrated['mean']:.1f}, worst "
            f"{calibrated['worst']:.1f} dB (calibrated by the choices measured before each); the profile now "
            f"predicts a measured node with its own shift, another cached node with a "
            f"{cal.get('shift', 0.0):+.1f} dB calibration (± {cal.get('spread', 0.0):.1f} dB)"]


def _estimator_lines(prof) -> list[str]:
    """One line per estimator (amortized sampling): trained or why not, and its options' best
    predicted speed-up with the PSNR there."""
    out = []
    options = prof.amortized_options()
    for est in prof.estimators:
        if not est.trained and not (est.slots is not None and est.slots.trained):
            out.append(f"estimator {est.id} (line {est.line}, {est.samples} terms): {est.note or 'not trained'}")
            continue
        mine = [o for o in options if o.parts[0].estimator == est.id]
        text = f"estimator {est.id} (line {est.line}, {est.samples} terms): amortization trained at m = "
        parts = []
        for history in ("blend", "slots"):
            runs = est.runs(history)
            if runs is None:
                continue
            if not runs.trained:
                parts.append(f"{history} history {runs.note or 'not trained'}")
                continue
            fit = runs.error_fit
            r2 = fit.get("r2")
            part = (f"{', '.join(str(m) for m in runs.timed_samples)} (error fit R² "
                    f"{r2 if r2 is not None else float('nan'):.2f})")
            parts.append(part if history == "blend" else f"slots history at m = {part}")
        text += "; ".join(parts)
        best = max(mine, key=lambda o: o.predicted_speedup, default=None)
        if best is not None:
            text += (f"; fastest option {best.describe()} {best.predicted_speedup:.2f}× at "
                     f"{_fmt(best.predicted_psnr, '.1f')} dB (predicted)")
        out.append(text)
    return out


def _level(s) -> str:
    if s.min_psnr is not None:
        return f"≥ {s.min_psnr:g} dB"
    if s.max_flip is not None:
        return f"FLIP ≤ {s.max_flip:g}"
    return f"error ≤ {_fmt(s.max_error)}"


def _speedup(s) -> str:
    if s.measured_speedup is None:
        return "–"
    if len(s.speedups) > 1:
        lo, hi = s.speedup_range
        return f"{s.measured_speedup:.2f} ({lo:.2f}–{hi:.2f})"
    return f"{s.measured_speedup:.2f}"


def _predicted_speedup(s) -> str:
    if not s.parts or len(s.predicted_speedup_range) != 2:
        return _fmt(s.predicted_speedup, ".2f")
    lo, hi = s.predicted_speedup_range
    return f"{s.predicted_speedup:.2f} ({lo:.2f}–{hi:.2f})"


def _predicted_psnr(s) -> str:
    if s.exact or not s.parts:
        return psnr_text(math.inf)
    if s.predicted_psnr is None:
        return "–"
    return f"{psnr_text(s.predicted_psnr)} ± {s.predicted_psnr_uncertainty or 0:.1f}"


def _measured_psnr(s) -> str:
    if s.measured_error is None:
        return "–"
    if s.exact or not s.parts:
        return psnr_text(math.inf)
    text = psnr_text(s.measured_psnr)
    if s.measured_psnr_uncertainty:
        text += f" ± {s.measured_psnr_uncertainty:.1f}"
    return text


def _flip(s) -> str:
    """The measured mean FLIP ('0' for an exact image), marked where it shows visible artifacts."""
    if s.exact or (not s.parts and s.measured_error is not None):
        return "0"
    if s.measured_flip is None:
        return "–"
    return f"{s.measured_flip:.3f}" + (" (visible)" if s.visible_artifacts else "")


def level_status(s) -> str:
    """The table's word on a selection's level: ``met``, ``met, try N`` (the N-th candidate
    measured stood), ``original`` (nothing measured met it: see the fallback line), ``MISSED``
    (shipped below its level: only where validation was told not to fall back), or ``–``
    (not measured).

    >>> from rrcache.selection import Selection
    >>> level_status(Selection.original(1.0, level_met=True, tries=2, fallback="..."))
    'original (2 tried)'
    """
    if s.level_met is None:
        return "–"
    if not s.level_met:
        return "MISSED"
    if not s.parts:
        return f"original ({s.tries} tried)" if s.tries else ("original" if s.fallback else "met")
    return f"met, try {s.tries}" if s.tries > 1 else "met"


def _table(prof) -> TextTable:
    table = TextTable("selections (pred. = predicted by the models, meas. = measured by validation)",
                      [(name, "left" if name in ("level", "node") else "right") for name in (
                          "level", "node", "Δn", "speed-up pred.", "speed-up meas.", "PSNR pred.", "PSNR meas.",
                          "FLIP meas.", "level met")])
    for s in prof.selections:
        node, period = s.choice.cells(s, prof) if s.parts else ("(original)", "–")
        if s.fallback:
            node = "↩ " + node
        table.add_row(f"{s.label} {_level(s)}", node, period, _predicted_speedup(s), _speedup(s),
                      _predicted_psnr(s), _measured_psnr(s), _flip(s), level_status(s))
    return table
