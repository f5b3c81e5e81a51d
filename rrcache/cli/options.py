"""Option parsing shared by the commands (``-D`` defines, ``--resolution``)."""
from __future__ import annotations

import click

from rrcache.budgets import MAX_PERIOD
from rrcache.harness.renderer import parse_resolution


#: the ``--period`` type of every command: Δn from 1 to :data:`rrcache.budgets.MAX_PERIOD`
PERIOD = click.IntRange(min=1, max=MAX_PERIOD)


def parse_defines(items) -> dict[str, str]:
    """``("A=1", "B")`` → ``{"A": "1", "B": "1"}``; a bad name is a ``click.BadParameter``.

    >>> parse_defines(["OCTAVES=5", "FAST"])
    {'OCTAVES': '5', 'FAST': '1'}
    """
    defines = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not name.isidentifier():
            raise click.BadParameter(f"{item!r} is not NAME or NAME=VALUE", param_hint="-D")
        defines[name] = value if sep else "1"
    return defines


def include_dirs_option(fn):
    """``-I DIR`` (repeatable): folders where ``#include`` files are looked up after the including
    file's own folder, as compilers do (a session's ``"include_dirs"`` come after these)."""
    return click.option("-I", "include_dirs", multiple=True, type=click.Path(file_okay=False), metavar="DIR",
                        help="Look for #include files in DIR too (repeatable); includes are read only from "
                             "the shader's folder tree and these folders.")(fn)


def resolution_option(ctx, param, value):
    """click callback: ``WxH`` → ``(w, h)`` (None stays None)."""
    if value is None:
        return None
    try:
        return parse_resolution(value)
    except ValueError as err:
        raise click.BadParameter(str(err)) from None


#: ``--vert FILE``: the user's vertex shader (glslViewer's .vert), on every command that renders or
#: compiles; it wins over a session's ``"vertex"``.
vert_option = click.option(
    "--vert", "vert", type=click.Path(dir_okay=False), default=None, metavar="FILE",
    help="The vertex shader paired with SHADER (a glslViewer .vert); default: the session's "
         "\"vertex\", else a generated one.")


def pair_periods(nodes, periods, default: int) -> list[int]:
    """The period of each ``--node``: the ``--period`` options paired with them in order (one
    ``--period`` serves every node; none: ``default``). Another count is a ``click.BadParameter``
    (exit 2).

    >>> pair_periods(("n1", "n2"), (50, 4), 8), pair_periods(("n1", "n2"), (), 8)
    ([50, 4], [8, 8])
    """
    periods = [int(p) for p in periods]
    if not periods:
        return [int(default)] * len(nodes)
    if len(periods) == 1:
        return periods * len(nodes)
    if len(periods) != len(nodes):
        raise click.BadParameter(
            f"{len(nodes)} --node but {len(periods)} --period: give one --period per --node, in the "
            "same order (or one for all)", param_hint="--period")
    return periods


def cluster_options(fn):
    """``--workers N`` and ``--scheduler ADDRESS``: where a profile's runs are made
    (:func:`rrcache.cluster.maybe_cluster`; neither: in this process)."""
    fn = click.option("--scheduler", metavar="ADDRESS", default=None,
                      help="Make the runs on the Dask cluster of this running scheduler (tcp://HOST:8786; "
                           "default: $RRCACHE_SCHEDULER). docs/distributed.md has a farm recipe.")(fn)
    return click.option("--workers", type=click.IntRange(min=1, max=512), default=None, metavar="N",
                        help="Make the runs on a Dask cluster of N worker processes started here (its "
                             "dashboard link is printed); more workers also train more nodes on more "
                             "frames (docs/distributed.md).")(fn)
