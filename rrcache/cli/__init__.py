"""The ``rrcache`` command line: a thin layer over the public API.

Each subcommand lives in its own module of this package and calls only the library. Known errors
(:class:`rrcache.errors.RRCacheError`) become one message on stderr and exit code 2; ``--debug``
shows the Python traceback as well.
"""
from __future__ import annotations

import importlib
import sys

import click

from rrcache.errors import RRCacheError

# subcommand name -> module in rrcache.cli (each module defines a click command named `command`)
_COMMANDS = {
    "nodes": "nodes",
    "bench-frontend": "bench_frontend",
    "instance": "instance",
    "bench-cache": "bench_cache",
    "bench-amortize": "bench_amortize",
    "bench": "bench",
    "profile": "profile",
    "select": "select",
    "accuracy": "accuracy",
    "render": "render",
    "report": "report",
}


class _LazyGroup(click.Group):
    def list_commands(self, ctx):
        return sorted(_COMMANDS)

    def get_command(self, ctx, name):
        module = _COMMANDS.get(name)
        if module is None:
            return None
        return importlib.import_module(f"rrcache.cli.{module}").command


@click.group(cls=_LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Show Python tracebacks for errors.")
@click.version_option(package_name="rrcache")
@click.pass_context
def cli(ctx, debug):
    """rrcache: speed up expensive pixel shaders with a reverse reprojection cache."""
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug


def main(argv=None):
    """Entry point of the console script and ``python -m rrcache``."""
    debug = "--debug" in (argv if argv is not None else sys.argv[1:])
    try:
        cli.main(args=argv, prog_name="rrcache", standalone_mode=False)
    except RRCacheError as err:
        if debug:
            raise
        click.echo(f"rrcache: error: {err}", err=True)
        sys.exit(2)
    except click.exceptions.Abort:
        click.echo("rrcache: aborted", err=True)
        sys.exit(130)
    except click.ClickException as err:
        err.show()
        sys.exit(err.exit_code)
    except KeyboardInterrupt:
        click.echo("rrcache: interrupted", err=True)
        sys.exit(130)
    except SystemExit:
        raise
    except Exception as err:  # an internal error: say so plainly, traceback only with --debug
        if debug:
            raise
        click.echo(f"rrcache: internal error: {type(err).__name__}: {err} (run with --debug for the traceback)", err=True)
        sys.exit(70)
