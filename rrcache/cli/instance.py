"""``rrcache instance SHADER --node ID --period N --out DIR``: write a cached variant's shaders.

Writes ``<pass>.vert`` and ``<pass>.frag`` for every pass of the algorithm and ``manifest.json``
(node, period, algorithm, filter, payload precision, the uniforms and textures each pass expects
and the ``rr_`` uniforms the runtime sets). Load them in an application with
:class:`rrcache.runtime.CacheRuntime`.
"""
from __future__ import annotations

import click

from rrcache.cli.options import parse_defines
from rrcache.runtime import ALGORITHMS, DEFAULT_PERIOD, FILTERS


@click.command("instance")
@click.argument("shader", type=click.Path(dir_okay=False))
@click.option("--node", required=True, metavar="ID", help="The node to cache (an id from `rrcache nodes`).")
@click.option("--period", type=click.IntRange(min=1), default=DEFAULT_PERIOD, show_default=True,
              help="Refresh period Δn.")
@click.option("--algorithm", type=click.Choice(ALGORITHMS), default="three-pass", show_default=True)
@click.option("--filter", "filter_", type=click.Choice(FILTERS), default="bilinear", show_default=True)
@click.option("--payload", type=click.Choice(["f4", "f2"]), default="f4", show_default=True)
@click.option("--session", type=click.Path(dir_okay=False), default=None,
              help="Take the MODEL_VERTEX_* defines from this session's meshes.")
@click.option("-D", "defines", multiple=True, metavar="NAME[=VALUE]", help="Define a preprocessor macro.")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Output folder.")
def command(shader, node, period, algorithm, filter_, payload, session, defines, out_dir):
    """Write the shaders of the variant of SHADER that caches --node, and a manifest."""
    from rrcache.pipeline import load_for_session, variant_for
    from rrcache.session import load_session

    loaded = load_session(session) if session else None
    work = load_for_session(shader, loaded, parse_defines(defines))
    entry = work.node(node)
    variant = variant_for(work, node, algorithm, filter_, payload)
    written = variant.write(out_dir, period=period)
    click.echo(f"{node} ({entry.type}, {shader}:{entry.line}:{entry.column}) cached with {algorithm} at Δn={period}:")
    for path in written:
        click.echo(f"  {path}")
