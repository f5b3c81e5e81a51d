"""Windows: a rectangle of a render target that a renderer restricts its work to.

A window is ``(x, y, width, height)`` in pixels of the target, origin at the bottom left as in
GL. Rendering through a window uses the scissor test, so the pixels inside it are shaded at the
target's full density and nothing outside is touched; read-backs return only the window, top row
first like every image in rrcache.

>>> import numpy as np
>>> rows = np.arange(12).reshape(4, 3)          # GL order: row 0 is the bottom of the image
>>> crop_rows(rows, (1, 0, 2, 2)).tolist()      # the bottom two rows, columns 1-2, top first
[[4, 5], [1, 2]]
>>> check_window((0, 0, 4, 4), (3, 3))
Traceback (most recent call last):
    ...
ValueError: window (0, 0, 4, 4) is not inside the 3x3 frame
"""
from __future__ import annotations

from typing import Optional

import numpy as np

Window = tuple[int, int, int, int]


def check_window(window, size) -> Optional[Window]:
    """``window`` as four ints when it lies inside ``size`` (w, h); None stays None."""
    if window is None:
        return None
    x, y, w, h = (int(v) for v in window)
    if w < 1 or h < 1 or x < 0 or y < 0 or x + w > size[0] or y + h > size[1]:
        raise ValueError(f"window {tuple(window)} is not inside the {size[0]}x{size[1]} frame")
    return (x, y, w, h)


def crop_rows(data: np.ndarray, window: Optional[Window]) -> np.ndarray:
    """GL rows (bottom first) of a whole target → the window's rows (all when None), top first."""
    if window is not None:
        x, y, w, h = window
        data = data[y:y + h, x:x + w]
    return data[::-1]
