"""The ``rrcache`` command line: a thin layer over the public API.

Each subcommand lives in its own module of this package and calls only the library. Known errors
(:class:`rrcache.errors.RRCacheError`) become one message on stderr and exit code 2; ``--debug``
shows the Python traceback as well.
"""
from __future__ import annotations

import contextlib
import errno
import importlib
import math
import os
import sys
import traceback

import click

from rrcache import watchdog
from rrcache.cli import interrupt
from rrcache.budgets import MAX_READ_BYTES, budget, reset_budget
from rrcache.errors import RRCacheError, printable

# subcommand name -> module in rrcache.cli (each module defines a click command named `command`)
_COMMANDS = {
    "nodes": "nodes",
    "bench-frontend": "bench_frontend",
    "instance": "instance",
    "bench-cache": "bench_cache",
    "bench-amortize": "bench_amortize",
    "bench-repeats": "bench_repeats",
    "bench": "bench",
    "profile": "profile",
    "profile-library": "profile_library",
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
@click.option("--max-ast-nodes", type=click.IntRange(min=1), default=None, metavar="N",
              help=f"Analysis budget: refuse shaders of more syntax nodes (default {budget.analysis_nodes:,}).")
@click.option("--max-depth", type=click.IntRange(min=1, max=250_000), default=None, metavar="N",
              help=f"Refuse expressions nested deeper (default {budget.expression_depth:,}).")
@click.option("--max-texture-pixels", type=click.IntRange(min=1), default=None, metavar="N",
              help=f"Refuse textures of more pixels, read from the header (default {budget.image_pixels:,}).")
@click.option("--max-source-bytes", type=click.IntRange(min=1, max=MAX_READ_BYTES), default=None, metavar="N",
              help=f"Refuse shaders whose sources (with includes) are larger (default {budget.source_bytes:,}).")
@click.option("--max-document-bytes", type=click.IntRange(min=1, max=MAX_READ_BYTES), default=None, metavar="N",
              help=f"Refuse larger session files and profile.json (default {budget.document_bytes:,}).")
@click.option("--max-asset-bytes", type=click.IntRange(min=1, max=MAX_READ_BYTES), default=None, metavar="N",
              help=f"Refuse larger mesh and texture files, measured before reading (default {budget.asset_bytes:,}).")
@click.option("--max-session-values", type=click.IntRange(min=1), default=None, metavar="N",
              help=f"Refuse sessions of more JSON values, keyframes mostly (default {budget.session_values:,}).")
@click.option("--max-session-objects", type=click.IntRange(min=1), default=None, metavar="N",
              help=f"Refuse sessions of more objects (default {budget.session_objects:,}).")
@click.option("--frame-timeout", type=click.FloatRange(min=0, min_open=True), default=None, metavar="S",
              help="Stop with an error when one frame takes longer than S seconds (what is done is kept).")
@click.option("--allow-outside-paths", is_flag=True,
              help="Let sessions name meshes, textures and include folders outside their own folder tree.")
@click.version_option(package_name="rrcache")
@click.pass_context
def cli(ctx, debug, max_ast_nodes, max_depth, max_texture_pixels, max_source_bytes, max_document_bytes,
        max_asset_bytes, max_session_values, max_session_objects, frame_timeout, allow_outside_paths):
    """rrcache: speed up expensive pixel shaders with a reverse reprojection cache."""
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug
    reset_budget()  # an in-process caller (tests, notebooks) starts from the defaults each time
    if max_ast_nodes is not None:
        budget.analysis_nodes = max_ast_nodes
    if max_depth is not None:
        budget.expression_depth = max_depth
    if max_texture_pixels is not None:
        budget.image_pixels = max_texture_pixels
    for name, value in (("source_bytes", max_source_bytes), ("document_bytes", max_document_bytes),
                        ("asset_bytes", max_asset_bytes), ("session_values", max_session_values),
                        ("session_objects", max_session_objects)):
        if value is not None:
            setattr(budget, name, value)
    budget.allow_outside_paths = allow_outside_paths
    if frame_timeout is not None and not math.isfinite(frame_timeout):
        raise click.BadParameter("must be a finite number of seconds", param_hint="--frame-timeout")
    watchdog.set_timeout(frame_timeout)
    if frame_timeout is not None and os.environ.get(watchdog.PIPE_ENV) is None and ctx.invoked_subcommand:
        # the command runs in a child process the watchdog can kill (a GL draw cannot be interrupted)
        sys.exit(watchdog.supervise(_ARGV if _ARGV is not None else sys.argv[1:], frame_timeout))


def _environment_error(err: OSError) -> None:
    """One line for an operating-system error (``[Errno 28] No space left on device``), exit 2.
    Output that cannot be written (``> /dev/full``) is dropped so the interpreter's own flush at
    exit does not fail a second time."""
    where = err.filename if err.filename is not None else "output"
    try:
        sys.stdout.flush()
    except OSError:
        pass
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    hint = {errno.ENOSPC: "free disk space and run the command again",
            errno.EBADF: "run it with its output open (a closing '>&-' leaves it none), or redirect it to a file",
            errno.EROFS: "write to a folder on a writable file system (--out)",
            errno.EACCES: "choose a folder you can write to (--out)",
            errno.EPIPE: "the reader of the output went away"}.get(err.errno, "check the path and the disk")
    click.echo(f"rrcache: error: {printable(str(where))}: {printable(err.strerror or str(err))} (hint: {hint})", err=True)
    sys.exit(2)


class _ClosedOutput:
    """``sys.stdout`` when the process started without descriptor 1: the first write is an
    ``OSError`` the command line reports in one line (exit 2) after the work is done and saved."""

    encoding = "utf-8"

    def write(self, text):
        raise OSError(errno.EBADF, "standard output is closed", "output")

    def flush(self):
        pass

    def isatty(self):
        return False

    def fileno(self):
        raise OSError(errno.EBADF, "standard output is closed", "output")


_ARGV = None  # the arguments main() was given (for the frame watchdog's child process)


def main(argv=None):
    """Entry point of the console script and ``python -m rrcache``."""
    global _ARGV
    _ARGV = list(argv) if argv is not None else None
    debug = "--debug" in (argv if argv is not None else sys.argv[1:])
    interrupt.install()
    if sys.stdout is None:  # started with its standard output closed ('>&-')
        sys.stdout = _ClosedOutput()
    try:
        cli.main(args=argv, prog_name="rrcache", standalone_mode=False)
        sys.stdout.flush()  # a full or closed output fails here, while we can still say so
    except RRCacheError as err:
        if debug:  # the traceback, then the same line and the same exit code as without --debug
            traceback.print_exc()
        click.echo(f"rrcache: error: {printable(str(err))}", err=True)
        sys.exit(2)
    except click.exceptions.Abort:
        click.echo("rrcache: aborted", err=True)
        sys.exit(130)
    except click.ClickException as err:
        if "\n" in err.format_message():  # 'rrcache' alone: click's help text, as click shows it
            err.show()
            sys.exit(err.exit_code)
        # one line, like every other error (click's own form adds the usage text)
        hint = ""
        ctx = getattr(err, "ctx", None)
        if isinstance(err, click.UsageError) and ctx is not None:
            hint = f" (hint: see '{ctx.command_path} --help')"
        click.echo(f"rrcache: error: {printable(err.format_message())}{hint}", err=True)
        sys.exit(err.exit_code)
    except KeyboardInterrupt:
        click.echo(f"rrcache: {interrupt.word()}", err=True)
        sys.exit(interrupt.exit_code())
    except SystemExit:
        raise
    except OSError as err:  # the machine's side: a full disk, a read-only folder, a closed pipe
        if debug:
            traceback.print_exc()
        _environment_error(err)
    except Exception as err:  # an internal error: say so plainly, traceback only with --debug
        if debug:
            raise
        click.echo(f"rrcache: internal error: {type(err).__name__}: {printable(str(err))} "
                   "(run with --debug for the traceback)", err=True)
        sys.exit(70)
