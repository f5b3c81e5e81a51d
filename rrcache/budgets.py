"""Resource budgets: the limits that keep any input, however large or hostile, from taking the
machine down. Each is checked before the work it bounds, in one place here, and an input beyond
one is refused with an :class:`~rrcache.errors.RRCacheError` that names the file, the place, the
limit and the way to raise it.

* :data:`MAX_PERIOD`: the largest refresh period Δn (the runtime's phase uniforms are 32-bit and
  a period longer than any session is meaningless); :func:`check_period`.
* :data:`budget.image_pixels`: decoded pixels of one texture (``--max-texture-pixels``), checked
  on the image's header before it is decoded (:mod:`rrcache.session.textures`).
* :data:`budget.analysis_nodes`: syntax-tree nodes of a shader before analysis
  (``--max-ast-nodes``), and :data:`budget.expression_depth`, the deepest expression nesting the
  recursive passes accept (:mod:`rrcache.deep` gives them the stack for it).
* :data:`budget.source_bytes`: the size of a shader file and of everything it includes.
* :data:`budget.document_bytes`: the size of a session file or a ``profile.json``
  (``--max-document-bytes``); :data:`budget.asset_bytes`: of one mesh or texture file
  (``--max-asset-bytes``). Every file is measured on its open descriptor before a byte is read
  (:mod:`rrcache.files`): a sparse 100 GB file is refused at once.
* :data:`budget.session_values` and :data:`budget.session_objects`: a session's JSON values
  (keyframes are most of them) and objects (``--max-session-values``,
  ``--max-session-objects``), counted before the schema validates anything: a schema-valid
  session of 10⁶ keyframes or 10⁵ objects is refused at once instead of loading for minutes.

The command line's global options (``rrcache --max-ast-nodes N ...``) set :data:`budget`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from rrcache.errors import RRCacheError

#: the largest any byte budget may be raised to (a file is read into memory whole: 16 GiB)
MAX_READ_BYTES = 16 * 1024 ** 3
#: the largest refresh period Δn a user may ask for (2^20 frames: over 4 hours at 60 fps)
MAX_PERIOD = 2 ** 20
#: the largest the runtime's signed 32-bit phase uniforms hold with room for frame arithmetic
#: (its "never refresh" mode for the all-hit limit uses 2^30)
MAX_RUNTIME_PERIOD = 2 ** 30


@dataclass
class Budget:
    """The adjustable limits (see the module docstring)."""

    image_pixels: int = 64 * 1024 * 1024      # 8192 x 8192
    analysis_nodes: int = 1_000_000    # ~2 GB of analysis (a 100k-term chain: 200k nodes, 400 MB)
    expression_depth: int = 125_000   # a 100,000-term chain nests ~100,010 deep
    source_bytes: int = 16 * 1024 * 1024
    document_bytes: int = 16 * 1024 * 1024
    session_values: int = 250_000      # JSON values: ~25,000 camera keyframes
    session_objects: int = 2_000
    asset_bytes: int = 1024 * 1024 * 1024
    #: not a size: whether session paths may leave the session's folder tree (the opt-out)
    allow_outside_paths: bool = False


#: the limits in force (the CLI's global options change them)
budget = Budget()


def reset_budget() -> None:
    """Put every limit back to its default."""
    for name, value in vars(Budget()).items():
        setattr(budget, name, value)


def check_period(value, where: str, limit: int = MAX_PERIOD) -> int:
    """``value`` as a refresh period: an integer in 1 .. :data:`MAX_PERIOD`, else an error naming
    ``where`` (an option or a file's key path).

    >>> check_period(16, "--period")
    16
    >>> check_period(3_000_000_000, "--period")
    Traceback (most recent call last):
    ...
    rrcache.errors.RRCacheError: --period: refresh period 3000000000 is larger than 1048576 (2^20), the largest rrcache supports (hint: use a period of at most 1048576 frames)
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)) or (
            isinstance(value, float) and (not math.isfinite(value) or value != int(value))):
        raise RRCacheError(f"refresh period {value!r} is not a whole number", where,
                           hint=f"use an integer from 1 to {limit}")
    value = int(value)
    if value < 1:
        raise RRCacheError(f"refresh period {value} is below 1", where, hint="Δn = 1 recomputes every frame")
    if value > limit:
        raise RRCacheError(f"refresh period {value} is larger than {limit} (2^{limit.bit_length() - 1}), the "
                           "largest rrcache supports", where, hint=f"use a period of at most {limit} frames")
    return value
