"""``rrcache instance SHADER --node ID --period N --out DIR``: write a cached variant's shaders.

``rrcache instance SHADER --estimator e1 --samples 4 --lambda 0.6 --out DIR`` writes an
amortized variant instead (:mod:`rrcache.compiler.amortize`; the manifest's ``amortized`` entry
gives m, N, λ and the phase cycle: run pass ``<pass>@<k>`` at frames ``k`` mod cycle, set
``rr_lambda`` to λ).

Writes ``<pass>.vert`` and ``<pass>.frag`` for every pass of the algorithm and ``manifest.json``
(node, period, algorithm, filter, payload precision, the uniforms and textures each pass expects
and the ``rr_`` uniforms the runtime sets). Load them in an application with
:class:`rrcache.runtime.CacheRuntime`.

``--node A --period 50 --node B --period 4`` caches several nodes, each at its own period (the
periods pair with the nodes in order); the manifest then lists ``"nodes"``, each with its period.
"""
from __future__ import annotations

import click

from rrcache.cli.adaptive import adaptive_kwargs, adaptive_options, check_adaptive
from rrcache.cli.options import PERIOD, include_dirs_option, pair_periods, parse_defines, vert_option
from rrcache.runtime import ALGORITHMS, DEFAULT_PERIOD, FILTERS
from rrcache.selection import AMORTIZE_PAYLOADS


@click.command("instance")
@click.argument("shader", type=click.Path(dir_okay=False))
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
@click.option("--algorithm", type=click.Choice(ALGORITHMS), default="three-pass", show_default=True)
@click.option("--filter", "filter_", type=click.Choice(FILTERS), default="bilinear", show_default=True)
@click.option("--payload", type=click.Choice(AMORTIZE_PAYLOADS), default="f4", show_default=True,
              help="32- or 16-bit floats; u8 (with --estimator and --history slots): 8 bits by the range of "
                   "the estimator's terms.")
@click.option("--session", type=click.Path(dir_okay=False), default=None,
              help="Take the MODEL_VERTEX_* defines from this session's meshes.")
@include_dirs_option
@click.option("-D", "defines", multiple=True, metavar="NAME[=VALUE]", help="Define a preprocessor macro.")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output folder.")
@adaptive_options
@vert_option
def command(shader, node, estimator, samples, blend, history, period, algorithm, filter_, payload, session, defines,
            include_dirs, out_dir, adaptive, fast_period, spread, vert):
    """Write the shaders of the variant of SHADER that caches --node (or amortizes --estimator),
    and a manifest."""
    from rrcache.pipeline import load_for_session, variant_for, variant_for_nodes
    from rrcache.session import load_session

    if (not node) == (estimator is None):
        raise click.UsageError("give either --node or --estimator")
    check_adaptive(adaptive, node, algorithm)
    loaded = load_session(session) if session else None
    work = load_for_session(shader, loaded, parse_defines(defines), include_dirs, vertex=vert)
    if payload == "u8" and estimator is None:
        raise click.UsageError("--payload u8 is for an amortized estimator's slots (--estimator, --history slots)")
    if estimator is not None:
        from rrcache.compiler.amortize import instance_amortized

        variant = instance_amortized(work.shader, estimator, algorithm, samples=samples, blend=blend,
                                     filter=filter_, payload_dtype=payload, history=history, vertex=work.vertex)
        written = variant.write(out_dir)
        a = variant.amortized
        click.echo(f"{estimator} ({variant.node_text}, {variant.node_loc}) amortized with {algorithm}: "
                   f"{a['samples']} of {a['of']} samples per frame, λ = {a['lambda']:g}, {a['history']}"
                   + (f", {variant.payload_dtype} payload" if variant.payload_dtype != "f4" else "") + ":")
        for path in written:
            click.echo(f"  {path}")
        return
    periods = pair_periods(node, period, DEFAULT_PERIOD)
    if len(node) > 1:
        entries = [work.node(n) for n in node]
        variant = variant_for_nodes(work, list(node), algorithm, filter_, payload)
        written = variant.write(out_dir, period=periods)
        click.echo(" + ".join(f"{n} ({e.type}, {shader}:{e.line}:{e.column}) at Δn={p}"
                              for n, e, p in zip(node, entries, periods)) + f" cached with {algorithm}:")
        for path in written:
            click.echo(f"  {path}")
        return
    node, period = node[0], periods[0]
    entry = work.node(node)
    runtime = adaptive_kwargs({"threshold": adaptive, "fast_period": fast_period, "spread": spread})
    variant = variant_for(work, node, algorithm, filter_, payload, adaptive=bool(runtime))
    written = variant.write(out_dir, period=period, runtime=runtime or None)
    click.echo(f"{node} ({entry.type}, {shader}:{entry.line}:{entry.column}) cached with {algorithm} at Δn={period}"
               + (f", adaptive threshold {adaptive:g}, fast period {fast_period}" if runtime else "") + ":")
    for path in written:
        click.echo(f"  {path}")
