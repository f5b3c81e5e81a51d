"""``rrcache instance SHADER --node ID --period N --out DIR``: write a cached variant's shaders.

    rrcache instance shaders/marble.glsl --node n74 --period 8 --session sessions/marble.json --out v/
    rrcache instance marble.rrprofile --level e3 --out e3/                  # the profile's choice
    rrcache instance marble.rrprofile --level e3 --target webgl2 --out e3-web/

``rrcache instance PROFILE --level eN`` writes exactly the files of the profile's
``optimized/eN`` (the level's choice with its algorithm, period and every cache option;
:mod:`rrcache.choice`). With a PROFILE and ``--node``, the algorithm defaults to the
profile's; with a SHADER, to three-pass (the command says which it used).

``rrcache instance SHADER --estimator e1 --samples 4 --lambda 0.6 --out DIR`` writes an
amortized variant instead (:mod:`rrcache.compiler.amortize`; the manifest's ``amortized`` entry
gives m, N, λ and the phase cycle: run pass ``<pass>@<k>`` at frames ``k`` mod cycle, set
``rr_lambda`` to λ).

Writes ``<pass>.vert`` and ``<pass>.frag`` for every pass of the algorithm and ``manifest.json``
(node, period, algorithm, filter, payload precision, the uniforms and textures each pass expects
and the ``rr_`` uniforms the runtime sets). Load them in an application with
:class:`rrcache.runtime.CacheRuntime`. ``--target webgl2`` writes the passes in GLSL ES 3.00 and
``index.html``, a page that runs the original and the cached variant side by side in a browser
over the session's first object and camera path (:mod:`rrcache.webgl`).

``--node A --period 50 --node B --period 4`` caches several nodes, each at its own period (the
periods pair with the nodes in order); the manifest then lists ``"nodes"``, each with its period.
"""
from __future__ import annotations

import click

from rrcache.cli.adaptive import adaptive_kwargs, adaptive_options, check_adaptive
from rrcache.cli.options import PERIOD, include_dirs_option, pair_periods, parse_defines, vert_option
from rrcache.cli.sources import describe_selection, refuse_with_level, resolve
from rrcache.runtime import ALGORITHMS, DEFAULT_FILTER, DEFAULT_PERIOD, FILTERS
from rrcache.selection import AMORTIZE_PAYLOADS
from rrcache.choice import write as choice_write

#: what --target writes: GLSL 3.30 core files, or WebGL2 (GLSL ES 3.00 and a page)
TARGETS = ("glsl", "webgl2")
#: the options --level takes from the profile (parameter name -> option as typed)
_LEVEL_OWNS = {"node": "--node", "estimator": "--estimator", "samples": "--samples", "blend": "--lambda",
               "history": "--history", "period": "--period", "algorithm": "--algorithm", "filter_": "--filter",
               "payload": "--payload", "session": "--session", "adaptive": "--adaptive",
               "fast_period": "--fast-period", "spread": "--spread"}


@click.command("instance")
@click.argument("shader", metavar="SHADER|PROFILE", type=click.Path())
@click.option("--level", default=None, metavar="eN",
              help="With a PROFILE: write the choice of this level (e1..e4) as the profile wrote optimized/eN.")
@click.option("--node", multiple=True, metavar="ID",
              help="The node to cache (an id from `rrcache nodes`); repeat it to cache several nodes.")
@click.option("--estimator", default=None, metavar="ID",
              help="Amortize this estimator instead (an id from `rrcache nodes --json`).")
@click.option("--samples", type=click.IntRange(min=1), default=4, show_default=True,
              help="With --estimator: samples evaluated per frame at hits (m).")
@click.option("--lambda", "blend", type=click.FloatRange(0.0, 1.0, max_open=True), default=0.6, show_default=True,
              help="With --estimator: weight of the reprojected estimate (λ).")
@click.option("--history", type=click.Choice(["blend", "slots"]), default="blend", show_default=True)
@click.option("--period", type=PERIOD, multiple=True, show_default=str(DEFAULT_PERIOD),
              help="Refresh period Δn; with several --node, one per node in the same order (or one for all).")
@click.option("--algorithm", type=click.Choice(ALGORITHMS), default=None,
              help="Cache algorithm (default: the profile's with a PROFILE, else three-pass).")
@click.option("--filter", "filter_", type=click.Choice(FILTERS), default=None,
              help=f"The cache's hit test and payload reconstruction (default: the profile's with a PROFILE, else "
                   f"{DEFAULT_FILTER}).")
@click.option("--payload", type=click.Choice(AMORTIZE_PAYLOADS), default="f4", show_default=True,
              help="32- or 16-bit floats; u8 (with --estimator and --history slots): 8 bits by the range of "
                   "the estimator's terms.")
@click.option("--session", type=click.Path(dir_okay=False), default=None,
              help="Take the MODEL_VERTEX_* defines from this session's meshes (with --target webgl2: the scene "
                   "the page draws).")
@click.option("--target", type=click.Choice(TARGETS), default="glsl", show_default=True,
              help="glsl: GLSL 3.30 core passes; webgl2: GLSL ES 3.00 passes and index.html, the original and the "
                   "cached variant side by side in a browser.")
@include_dirs_option
@click.option("-D", "defines", multiple=True, metavar="NAME[=VALUE]", help="Define a preprocessor macro.")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output folder.")
@adaptive_options
@vert_option
@click.pass_context
def command(ctx, shader, level, node, estimator, samples, blend, history, period, algorithm, filter_, payload, session,
            target, defines, include_dirs, out_dir, adaptive, fast_period, spread, vert):
    """Write the shaders of the variant of SHADER that caches --node (or amortizes --estimator),
    or of a PROFILE's --level, and a manifest."""
    from rrcache.pipeline import load_for_session, variant_for, variant_for_nodes
    from rrcache.session import load_session

    source = resolve(ctx, shader, session, parse_defines(defines), include_dirs, vert, session_required=False,
                     session_name="--session")
    prof = source.prof
    if level is not None:
        if prof is None:
            raise click.UsageError("--level needs a PROFILE folder as the first argument (rrcache instance "
                                   "PROFILE --level e2 --out DIR)")
        refuse_with_level(ctx, _LEVEL_OWNS)
        _write_level(prof, level, include_dirs, out_dir, target)
        return
    if (not node) == (estimator is None):
        raise click.UsageError("give --node or --estimator" + (" (or --level with a PROFILE)" if prof else ""))
    if algorithm is None:
        algorithm = prof.algorithm if prof is not None else "three-pass"
        why = "the profile's choice" if prof is not None else "the default; --algorithm for another"
    else:
        why = "--algorithm"
    check_adaptive(adaptive, node, algorithm)
    if filter_ is None:
        filter_ = getattr(prof, "filter", None) or DEFAULT_FILTER
    loaded = load_session(source.session) if source.session else None
    if target == "webgl2" and loaded is None:
        raise click.UsageError("--target webgl2 needs --session SESSION (the scene the page draws)")
    work = load_for_session(source.shader, loaded, source.defines, source.include_dirs, vertex=source.vertex)
    runtime_opts = prof.settings.cache_options() if prof is not None else None
    if payload == "u8" and estimator is None:
        raise click.UsageError("--payload u8 is for an amortized estimator's slots (--estimator, --history slots)")
    if estimator is not None:
        from rrcache.compiler.amortize import instance_amortized

        variant = instance_amortized(work.shader, estimator, algorithm, samples=samples, blend=blend,
                                     filter=filter_, payload_dtype=payload, history=history, vertex=work.vertex)
        written = _write(variant, out_dir, target, loaded, work, DEFAULT_PERIOD, runtime_opts)
        a = variant.amortized
        click.echo(f"{estimator} ({variant.node_text}, {variant.node_loc}) amortized with {algorithm} ({why}): "
                   f"{a['samples']} of {a['of']} samples per frame, λ = {a['lambda']:g}, {a['history']}"
                   + (f", {variant.payload_dtype} payload" if variant.payload_dtype != "f4" else "") + ":")
        for path in written:
            click.echo(f"  {path}")
        return
    periods = pair_periods(node, period, DEFAULT_PERIOD)
    if len(node) > 1:
        entries = [work.node(n) for n in node]
        variant = variant_for_nodes(work, list(node), algorithm, filter_, payload)
        written = _write(variant, out_dir, target, loaded, work, periods, runtime_opts)
        click.echo(" + ".join(f"{n} ({e.type}, {source.shader}:{e.line}:{e.column}: {e.text}) at Δn={p}"
                              for n, e, p in zip(node, entries, periods)) + f" cached with {algorithm} ({why}):")
        for path in written:
            click.echo(f"  {path}")
        return
    node, period = node[0], periods[0]
    entry = work.node(node)
    runtime = adaptive_kwargs({"threshold": adaptive, "fast_period": fast_period, "spread": spread})
    variant = variant_for(work, node, algorithm, filter_, payload, adaptive=bool(runtime))
    written = _write(variant, out_dir, target, loaded, work, period, dict(runtime_opts or {}, **runtime) or None)
    click.echo(f"{node} ({entry.type}, {source.shader}:{entry.line}:{entry.column}: {entry.text}) cached with "
               f"{algorithm} ({why}) at Δn={period}"
               + (f", adaptive threshold {adaptive:g}, fast period {fast_period}" if runtime else "") + ":")
    for path in written:
        click.echo(f"  {path}")


def _write(variant, out_dir, target, session, work, period, runtime) -> list:
    """Write ``variant`` for ``target``: the GLSL files, or the WebGL2 page and its passes; each
    pass is compiled and linked by the driver first (:func:`_compile`), so nothing is written
    for a variant the driver refuses."""
    _compile(variant)
    if target == "webgl2":
        from rrcache.webgl import write_page

        return write_page(variant, session, work, out_dir, period=period, runtime=runtime)
    return variant.write(out_dir, period=period, runtime=runtime)


def _compile(variant) -> None:
    """Compile and link every pass of ``variant`` with this machine's driver and release the
    programs: a refused pass is the driver's one-line error naming the node and the pass (exit 2,
    nothing written). Without OpenGL here the files are written unchecked, and the command says so."""
    from rrcache.errors import GLError
    from rrcache.gl.context import get_context

    try:
        ctx = get_context()
    except GLError as err:
        click.echo(f"note: the passes were not compiled here (no OpenGL: {err.message})", err=True)
        return
    for program in variant.build_programs(ctx).values():
        program.release()


def _write_level(prof, level, include_dirs, out_dir, target) -> None:
    """``instance PROFILE --level eN``: the level's choice, as the profile wrote optimized/eN."""
    from rrcache import choice

    sel = choice.level(prof, level)
    if not sel.parts:
        written = choice_write(prof, sel, out_dir)
        click.echo(f"{sel.label} keeps the original shader ({choice.original_note(prof, sel)}):")
    else:
        work, session = choice.load_work(prof, include_dirs)
        if target == "webgl2":
            variant, period = choice.variant_of(prof, sel, work)
            written = _write(variant, out_dir, target, session, work, period, choice.runtime_options(prof, sel))
        else:
            written = choice.write(prof, sel, out_dir, work)
        click.echo(f"{sel.label} of {prof.path}: {describe_selection(prof, sel)}, with "
                   f"{choice.describe_options(prof, sel)}:")
    for path in written:
        click.echo(f"  {path}")
