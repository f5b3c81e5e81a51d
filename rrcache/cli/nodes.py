"""``rrcache nodes SHADER``: list the cacheable nodes of a shader.

    rrcache nodes shaders/marble.glsl
    rrcache nodes shaders/marble.glsl --all -D OCTAVES=5
    rrcache nodes shaders/marble.glsl --json

The table shows each node's id (for ``rrcache`` commands that take a node), GLSL type, source
line:column (``file:line:column`` for a line of an included file, the file relative to the
shader's folder: ``lygia/generative/fbm.glsl:13:15``), estimated cost (the work a cache hit
saves, see ``rrcache.analysis.cost``), the inlined call chain and the expression as written
(``sum + amp * snoise(p)``, not the inliner's temporaries; ``rrcache.analysis.source_text``).
Without ``--session``, a shader that tests ``MODEL_VERTEX_*`` macros gets a hint (a last line
``hint: ...``, ``"hint"`` in JSON, and in the error message when it fails): those branches are
off until a session's meshes (or ``-D``) define them. ``--all`` adds the nodes left out, with the reason
(``type dynamic screen derivative uniform duplicate cheap``). A node that only some cache
algorithms can hold (one that needs screen-space derivatives cannot be cached by one-pass) gets
an ``algorithms`` column naming those, with the reason for the others under the table. ``--json`` prints
``{"shader", "nodes": [...], "excluded": [...], "language": {...}}``; ``excluded`` is empty
unless ``--all``; every node has ``algorithms`` (the valid ones) and ``not_valid`` (algorithm ->
reason). The last line (``language`` in JSON: version, profile, ``es``, ``assumed``,
``text``) says which GLSL the shader was read as; a shader without ``#version`` is GLSL ES 1.00
when it has a ``precision`` statement or tests ``GL_ES`` (as ES sketch tools run it), else
desktop GLSL 1.10.

The JSON also has ``estimators``: the loops that sum independent samples (``{"id", "line",
"column", "samples", "text", "accumulators", "pragma", "term_range", "range_source"}`` and
``"range_reason"`` when the range is not known, see :mod:`rrcache.analysis.estimators`;
``#pragma rrcache estimator`` before a loop marks one the analysis cannot prove, and ``#pragma
rrcache estimator range(LO, HI)`` also declares the range of its terms) and
``not_estimators``, the other loops with the reason. The text table lists the estimators after
the nodes (with ``--all``, the other loops too).
"""
from __future__ import annotations

import json

import click

import re

from rrcache.analysis.cacheable import REASONS
from rrcache.analysis.estimators import display_name, find_estimators
from rrcache.analysis.source_text import display_file
from rrcache.cli.options import include_dirs_option, parse_defines, vert_option
from rrcache.budgets import budget
from rrcache.errors import RRCacheError
from rrcache.files import Refused, read_file
from rrcache.pipeline import load_for_session

_TEXT_WIDTH = 70


def _short(text: str, width: int = _TEXT_WIDTH) -> str:
    return text if len(text) <= width else text[: width - 3] + "..."


def _chain(chain: list[str], width: int = 36) -> str:
    text = ">".join(c.split(" (")[0] for c in chain) or "main"
    return text if len(text) <= width else "..." + text[-(width - 3):]


#: the orders ``--sort`` offers: id (source order of the analysis), cost (costliest first), line
SORT_KEYS = {
    "id": lambda n: int(n.id[1:]),
    "cost": lambda n: (-n.cost, int(n.id[1:])),
    "line": lambda n: (str(getattr(n, "file", None) or ""), n.line, n.column, int(n.id[1:])),
}

#: what the cost column counts, for the table's last lines
COST_UNIT = ("cost: the static estimate of the work one cache hit saves per pixel, in units of one scalar "
             "add or multiply (a sin costs 8, a texture fetch 16 or more), see rrcache/analysis/cost.py")


def format_table(table, show_all: bool, sort: str = "id") -> str:
    """The readable text table of a :class:`NodeTable` (with ``show_all``, the nodes left out
    too, with their reason), in the order ``sort`` names (:data:`SORT_KEYS`)."""
    restricted = any(n.invalid for n in table.nodes)
    header = ["id", "type", "line:col", "cost"] + (["reason"] if show_all else []) + (
        ["algorithms"] if restricted else []) + ["inlined from", "expression"]
    entries = [(n, "final" if n.final else "") for n in table.nodes]
    if show_all:
        entries += [(x, x.reason) for x in table.excluded]
    key = SORT_KEYS[sort]
    entries.sort(key=lambda p: key(p[0]))
    rows = [header]
    main_path = getattr(table.shader, "path", None)
    for n, reason in entries:
        where = display_file(getattr(n, "file", None), main_path)
        place = f"{where}:{n.line}:{n.column}" if where else f"{n.line}:{n.column}"
        row = [n.id, n.type, place, str(n.cost)]
        if show_all:
            row.append(reason)
        elif reason:
            row[0] += "*"
        if restricted:
            valid = getattr(n, "algorithms", [])
            row.append("all" if len(valid) == 3 else ",".join(valid) or "-")
        rows.append(row + [_chain(n.call_chain), _short(n.text)])
    widths = [max(len(r[i]) for r in rows) for i in range(len(header) - 1)]
    lines = ["  ".join(r[i].rjust(w) if i == 3 else r[i].ljust(w)
                       for i, w in enumerate(widths)) + "  " + r[-1] for r in rows]
    counts = table.counts()
    left = ", ".join(f"{counts[k]} {k}" for k in REASONS if counts[k])
    lines.append("")
    reasons = sorted({(a, why) for n in table.nodes for a, why in n.invalid.items()})
    for a, why in reasons:
        lines.append(f"not {a}: {why}")
    if not show_all and any(n.final for n in table.nodes):
        lines.append("* the final colour")
    lines.append(COST_UNIT)
    lines.append(f"{counts['listed']} cacheable nodes" + (f"; left out: {left}" if left else "")
                 + ("" if show_all or not left else " (--all lists them)"))
    return "\n".join(lines)


_MODEL_VERTEX_TEST = re.compile(
    r"^[ \t]*#[ \t]*(?:if|ifdef|ifndef|elif)\b[^\n]*?\b(MODEL_VERTEX_\w+)", re.M)


def model_vertex_tests(paths, defines) -> list[str]:
    """The ``MODEL_VERTEX_*`` macros the files test in ``#if``/``#ifdef`` lines that ``defines``
    leaves undefined (what a session's meshes would define)."""
    found: list[str] = []
    for path in paths:
        if not path or str(path).startswith("<"):
            continue
        try:
            text = read_file(path, budget.source_bytes).data.decode("utf-8", "replace")
        except Refused:
            continue
        for line in _MODEL_VERTEX_TEST.finditer(text):
            for name in re.findall(r"\bMODEL_VERTEX_\w+", line.group(0)):
                if name not in defines and name not in found:
                    found.append(name)
    return found


def _mesh_hint(tested: list[str]) -> str:
    names = ", ".join(tested)
    return (f"the shader tests {names}, which a session's meshes define (glslViewer defines them for the "
            f"model's attributes); without --session they are off, so those branches are left out and node "
            f"ids differ: give --session SESSION (or -D {tested[0]})")


def _check_vertex(loaded, user) -> None:
    """With a vertex shader (``--vert`` or the session's), check that it writes every input the
    fragment shader reads (the error names the declaration)."""
    if user is not None:
        user.check_inputs({n: str(t) for n, (t, _loc) in loaded.inputs.items()},
                          {n: loc for n, (_t, loc) in loaded.inputs.items()})


def format_estimators(estimators, show_all: bool) -> str:
    """The estimator lines of the text table (with ``show_all``, the other loops and why)."""
    lines = []
    for e in estimators.estimators:
        accs = ", ".join(display_name(a) for a in e.accumulators)
        terms = (f"terms in [{e.term_range[0]:g}, {e.term_range[1]:g}]"
                 + (" (declared)" if e.range_source == "pragma" else "")) if e.term_range else "terms unbounded"
        lines.append(f"estimator {e.id}  {e.line}:{e.column}  {e.samples} samples into {accs}, {terms}"
                     f"{'  (pragma)' if e.pragma else ''}  {_short(display_name(e.text))}")
    if show_all:
        for r in estimators.rejected:
            lines.append(f"loop {r.id}  {r.line}:{r.column}  not an estimator: {r.reason}  "
                         f"{_short(display_name(r.text))}")
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
@include_dirs_option
@click.option("--session", type=click.Path(dir_okay=False), default=None,
              help="Apply the MODEL_VERTEX_* defines of this session's meshes, as `rrcache render` "
                   "and `rrcache profile` do (node ids depend on the defines).")
@vert_option
@click.option("--sort", type=click.Choice(tuple(SORT_KEYS)), default="id", show_default=True,
              help="Order of the rows (and of the JSON's node lists): id, cost (costliest first) or line.")
def command(shader, as_json, show_all, define, max_unroll, include_dirs, session, vert, sort):
    """List the nodes of SHADER that a reprojection cache can hold."""
    defines = parse_defines(define)
    loaded_session = None
    if session is not None:
        from rrcache.session import load_session

        loaded_session = load_session(session)
    try:
        work = load_for_session(shader, loaded_session, defines, include_dirs, max_unroll=max_unroll,
                                vertex=vert)
    except RRCacheError as err:
        if loaded_session is None:
            tested = model_vertex_tests([shader, getattr(getattr(err, "loc", None), "file", None)], defines)
            if tested:
                err.hint = (f"{err.hint}; " if err.hint else "") + _mesh_hint(tested)
        raise
    loaded, table = work.shader, work.table
    mesh_hint = None
    if loaded_session is None:
        tested = model_vertex_tests(loaded.files or [shader], work.defines)
        mesh_hint = _mesh_hint(tested) if tested else None
    _check_vertex(loaded, work.vertex)
    estimators = find_estimators(loaded)
    if as_json:
        doc = table.to_json(shader)
        if not show_all:
            doc["excluded"] = []
        if sort != "id":
            order = {n.id: i for i, n in enumerate(sorted([*table.nodes, *table.excluded], key=SORT_KEYS[sort]))}
            for name in ("nodes", "excluded"):
                doc[name] = sorted(doc[name], key=lambda d: order.get(d.get("id"), len(order)))
        doc["language"] = {"version": loaded.version, "profile": loaded.profile, "es": loaded.es,
                           "assumed": loaded.assumed is not None, "text": loaded.language}
        doc["hint"] = mesh_hint
        doc.update(estimators.to_json())
        click.echo(json.dumps(doc, indent=2))
    else:
        click.echo(format_table(table, show_all, sort))
        lines = format_estimators(estimators, show_all)
        if lines:
            click.echo(lines)
        click.echo(f"read as {loaded.language}")
        if mesh_hint:
            click.echo(f"hint: {mesh_hint}")
