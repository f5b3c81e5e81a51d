"""``rrcache nodes SHADER``: list the cacheable nodes of a shader.

    rrcache nodes shaders/marble.glsl
    rrcache nodes shaders/marble.glsl --all -D OCTAVES=5
    rrcache nodes shaders/marble.glsl --json

The table shows each node's id (for ``rrcache`` commands that take a node), GLSL type, source
line:column, estimated cost (the work a cache hit saves, see ``rrcache.analysis.cost``), the
inlined call chain and the expression. ``--all`` adds the nodes left out, with the reason
(``type dynamic derivative uniform duplicate cheap``). ``--json`` prints
``{"shader", "nodes": [...], "excluded": [...]}``; ``excluded`` is empty unless ``--all``.
"""
from __future__ import annotations

import json

import click

from rrcache.cli.options import parse_defines
from rrcache.pipeline import load_for_session

_TEXT_WIDTH = 70


def _short(text: str, width: int = _TEXT_WIDTH) -> str:
    return text if len(text) <= width else text[: width - 3] + "..."


def _chain(chain: list[str], width: int = 36) -> str:
    text = ">".join(c.split(" (")[0] for c in chain) or "main"
    return text if len(text) <= width else "..." + text[-(width - 3):]


def format_table(table, show_all: bool) -> str:
    """The readable text table of a :class:`NodeTable` (with ``show_all``, the nodes left out
    too, in id order, with their reason)."""
    header = ["id", "type", "line:col", "cost"] + (["reason"] if show_all else []) + [
        "inlined from", "expression"]
    entries = [(n, "final" if n.final else "") for n in table.nodes]
    if show_all:
        entries += [(x, x.reason) for x in table.excluded]
        entries.sort(key=lambda p: int(p[0].id[1:]))
    rows = [header]
    for n, reason in entries:
        row = [n.id, n.type, f"{n.line}:{n.column}", str(n.cost)]
        if show_all:
            row.append(reason)
        elif reason:
            row[0] += "*"
        rows.append(row + [_chain(n.call_chain), _short(n.text)])
    widths = [max(len(r[i]) for r in rows) for i in range(len(header) - 1)]
    lines = ["  ".join(r[i].rjust(w) if i == 3 else r[i].ljust(w)
                       for i, w in enumerate(widths)) + "  " + r[-1] for r in rows]
    counts = table.counts()
    left = ", ".join(f"{counts[k]} {k}" for k in ("type", "dynamic", "derivative", "uniform",
                                                     "duplicate", "cheap") if counts[k])
    lines.append("")
    if not show_all and any(n.final for n in table.nodes):
        lines.append("* the final colour")
    lines.append(f"{counts['listed']} cacheable nodes" + (f"; left out: {left}" if left else "")
                 + ("" if show_all or not left else " (--all lists them)"))
    return "\n".join(lines)


@click.command("nodes")
@click.argument("shader", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.option("--all", "show_all", is_flag=True,
              help="Also show the nodes left out, with the reason.")
@click.option("-D", "define", multiple=True, metavar="NAME[=VALUE]",
              help="Define a preprocessor macro (repeatable).")
@click.option("--max-unroll", type=click.IntRange(min=0), default=64, show_default=True,
              help="Unroll constant loops of at most this many iterations.")
@click.option("--session", type=click.Path(dir_okay=False), default=None,
              help="Apply the MODEL_VERTEX_* defines of this session's meshes, as `rrcache render` "
                   "and `rrcache profile` do (node ids depend on the defines).")
def command(shader, as_json, show_all, define, max_unroll, session):
    """List the nodes of SHADER that a reprojection cache can hold."""
    loaded = None
    if session is not None:
        from rrcache.session import load_session

        loaded = load_session(session)
    table = load_for_session(shader, loaded, parse_defines(define), max_unroll=max_unroll).table
    if as_json:
        doc = table.to_json(shader)
        if not show_all:
            doc["excluded"] = []
        click.echo(json.dumps(doc, indent=2))
    else:
        click.echo(format_table(table, show_all))
