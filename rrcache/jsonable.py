"""JSON without NaN: what profiles, reports and benchmarks write.

JSON has no NaN or infinity (Python writes them as bare ``NaN``/``Infinity``, which other
readers refuse), so every non-finite float becomes ``null``; numpy scalars become Python
numbers and tuples lists.

>>> import numpy as np
>>> finite_json({"a": float("nan"), "b": (1.5, np.float32(2.0)), "c": [float("inf"), "x"]})
{'a': None, 'b': [1.5, 2.0], 'c': [None, 'x']}
"""
from __future__ import annotations

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
