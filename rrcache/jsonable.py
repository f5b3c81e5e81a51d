"""JSON without NaN: what profiles, reports and benchmarks write.

JSON has no NaN or infinity (Python writes them as bare ``NaN``/``Infinity``, which other
readers refuse), so every non-finite float becomes ``null``; numpy scalars become Python
numbers and tuples lists.

>>> import numpy as np
>>> finite_json({"a": float("nan"), "b": (1.5, np.float32(2.0)), "c": [float("inf"), "x"]})
{'a': None, 'b': [1.5, 2.0], 'c': [None, 'x']}
"""
from __future__ import annotations

import json
import math


def finite_json(value):
    """``value`` with every non-finite float replaced by None (recursively, see the module)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: finite_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_json(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):  # numpy scalars
        return finite_json(value.item())
    return value


#: what a page's data block spells as escapes (report.html, the WebGL2 page): the HTML parser
#: reads a script's text looking for ``</script`` and, after ``<!--``, for ``<script`` (the
#: "script data escaped" states), so a shader comment ``<!--<script>`` left raw made the parser
#: swallow the report's own script
_SCRIPT_ESCAPES = {ord("<"): "\\u003c", ord(">"): "\\u003e", ord("&"): "\\u0026"}


def script_json(data) -> str:
    """``data`` as JSON safe inside ``<script type="application/json">``: no ``<``, ``>`` or ``&``
    appears raw (nor any non-ASCII character), so no text from a shader, a file name or a session
    can end or disable the script element; ``JSON.parse`` reads the escapes back as the same text.

    >>> print(script_json({"text": "<!--<script>a && b</script>"}))
    {"text":"\\u003c!--\\u003cscript\\u003ea \\u0026\\u0026 b\\u003c/script\\u003e"}
    """
    return json.dumps(data, separators=(",", ":"), allow_nan=False).translate(_SCRIPT_ESCAPES)
