"""Running the recursive passes on deeply nested programs.

The front-end, the analysis and the compiler walk the syntax tree recursively. A generated shader
can nest an expression thousands of levels deep (``u_time + 1.0 + 1.0 + ...``: every ``+`` is one
level), far beyond Python's default recursion limit of 1,000 frames. :func:`deep` runs such a pass
in a worker thread with a large stack and a raised recursion limit, so that any program within
:data:`rrcache.budgets.MAX_EXPRESSION_DEPTH` goes through every pass; a deeper one is refused
after parsing with a clear error (``rrcache.glsl.frontend``), never a ``RecursionError``.

>>> @deep
... def depth(n):
...     return 0 if n == 0 else 1 + depth(n - 1)
>>> depth(20_000)
20000
"""
from __future__ import annotations

import functools
import sys
import threading

#: the worker thread's stack; only the pages used are committed
STACK_BYTES = 1024 * 1024 * 1024
#: Python frames allowed inside the worker (each syntax level costs a handful; the CLI caps
#: ``--max-depth`` at 250,000 levels)
RECURSION_LIMIT = 2_000_000

_local = threading.local()
_lock = threading.Lock()


def deep(fn):
    """Decorator: call ``fn`` in a big-stack thread (directly when already inside one); its
    result or exception comes back to the caller."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if getattr(_local, "inside", False):
            return fn(*args, **kwargs)
        box: dict = {}

        def run():
            _local.inside = True
            try:
                box["result"] = fn(*args, **kwargs)
            except BaseException as err:  # handed to the caller's thread as it is
                box["error"] = err

        with _lock:
            old_stack = threading.stack_size()
            old_limit = sys.getrecursionlimit()
            # the new thread takes the limit in force when it starts
            sys.setrecursionlimit(max(old_limit, RECURSION_LIMIT))
            try:
                threading.stack_size(STACK_BYTES)
                worker = threading.Thread(target=run, name=f"rrcache-deep-{fn.__name__}", daemon=True)
                worker.start()
            finally:
                threading.stack_size(old_stack)
            try:
                worker.join()
            finally:
                if not worker.is_alive():
                    sys.setrecursionlimit(old_limit)
        if "error" in box:
            err = box.pop("error")
            raise err.with_traceback(err.__traceback__)
        return box.get("result")

    return wrapper
