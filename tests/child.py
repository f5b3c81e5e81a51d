"""A Python child process set up without ``preexec_fn``.

``subprocess``'s ``preexec_fn`` runs Python in the forked child before ``exec``; the test process
has GL driver threads running, and a fork of a threaded process can deadlock in the child on a
lock another thread held at the fork (Python's documentation warns of it; the suite hung once so
in a forked worker pool). Here a fresh interpreter applies the set-up and ``exec``s the command:
signal dispositions that are ignored or default, resource limits and closed descriptors all
survive ``exec``.

>>> python_argv(["-m", "rrcache", "--help"], sigint_default=True)[4:]
['-m', 'rrcache', '--help']
"""
from __future__ import annotations

import json
import sys

_PROLOGUE = """
import json, os, resource, signal, sys
o = json.loads(sys.argv[1])
if o["sigint_default"]:
    signal.signal(signal.SIGINT, signal.SIG_DFL)
if o["file_size"] is not None:
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (o["file_size"], o["file_size"]))
if o["close_stdout"]:
    os.close(1)
os.execv(sys.executable, [sys.executable, *sys.argv[2:]])
"""


def python_argv(args, *, sigint_default: bool = False, file_size: int | None = None,
                close_stdout: bool = False) -> list:
    """``[python, ...]`` running ``python ARGS`` after: SIGINT back to its default (a test run
    started in the background by a non-interactive shell inherits SIGINT ignored, and Python then
    installs no KeyboardInterrupt handler), a file-size limit of ``file_size`` bytes (writes past
    it fail with EFBIG instead of a SIGXFSZ kill), stdout closed."""
    options = dict(sigint_default=sigint_default, file_size=file_size, close_stdout=close_stdout)
    return [sys.executable, "-c", _PROLOGUE, json.dumps(options), *map(str, args)]
