"""The comparison figure of amortized sampling (Nehab et al. 2007 §7.3's figure): one frame
rendered several ways beside a many-sample reference, whole and magnified where the original
differs most from the reference, each labelled with its error against the reference.

:func:`write_sheet` takes ``(label, image)`` pairs (row 0 = top, as the harness renders) and the
reference; the magnified window is the ``crop``-sized square (a quarter of the frame's height by
default) where a chosen image's (the original's, for ``rrcache bench-amortize``) mean RGB distance from the reference is largest, found by a
summed-area table, so the figure shows the noisiest penumbra rather than a place chosen by hand.

>>> import numpy as np
>>> ref = np.zeros((8, 8, 4), np.float32); noisy = ref.copy(); noisy[4:8, 0:4, :3] = 0.5
>>> noisiest_window(noisy, ref, 4)
(4, 0)
"""
from __future__ import annotations

from typing import Optional, Sequence

import numpy as np

from rrcache.harness.metrics import mean_l2


def noisiest_window(image: np.ndarray, reference: np.ndarray, size: int) -> tuple[int, int]:
    """(row, column) of the top-left corner of the ``size``×``size`` window where ``image``'s RGB
    distance from ``reference`` sums highest (the first such window in row-major order)."""
    diff = np.sqrt(np.sum((np.asarray(image, np.float64)[..., :3] - np.asarray(reference, np.float64)[..., :3]) ** 2,
                          axis=-1))
    diff = np.nan_to_num(diff, nan=0.0)
    h, w = diff.shape
    size = max(1, min(int(size), h, w))
    table = np.zeros((h + 1, w + 1))
    table[1:, 1:] = diff.cumsum(0).cumsum(1)
    sums = table[size:, size:] - table[:-size, size:] - table[size:, :-size] + table[:-size, :-size]
    row, col = np.unravel_index(int(np.argmax(sums)), sums.shape)
    return int(row), int(col)


def write_sheet(path: str, panels: Sequence[tuple[str, np.ndarray]], reference: np.ndarray,
                mask: Optional[np.ndarray] = None, crop: Optional[int] = None, title: str = "",
                window_of: int = 0) -> dict:
    """Write the figure to ``path`` (PNG): a column per panel and the reference, the whole frame
    above and the magnified window below, each captioned with its mean RGB L2 error against the
    reference over ``mask`` (the covered pixels). Returns {"window": [row, col, size], "errors":
    {label: error}}."""
    from rrcache.report.agg import agg_pyplot, save_figure

    plt = agg_pyplot()
    h, w = reference.shape[:2]
    size = int(crop or max(8, h // 4))
    row, col = noisiest_window(panels[window_of][1], reference, size)
    columns = [(label, image, float(mean_l2(image, reference, mask)[0])) for label, image in panels]
    columns.append(("reference", reference, None))
    fig, axes = plt.subplots(2, len(columns), figsize=(3.2 * len(columns), 3.2 * (h / w) + 3.6), dpi=120,
                             squeeze=False, gridspec_kw={"height_ratios": [h / w, 1.0]})
    for k, (label, image, error) in enumerate(columns):
        rgb = np.clip(np.nan_to_num(np.asarray(image, np.float32)[..., :3]), 0.0, 1.0)
        top, bottom = axes[0][k], axes[1][k]
        top.imshow(rgb, interpolation="nearest")
        top.add_patch(plt.Rectangle((col - 0.5, row - 0.5), size, size, fill=False, edgecolor="red", linewidth=1.0))
        top.set_title(label if error is None else f"{label}\nerror {error:.5f}", fontsize=9)
        bottom.imshow(rgb[row:row + size, col:col + size], interpolation="nearest")
        for ax in (top, bottom):
            ax.set_xticks([])
            ax.set_yticks([])
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
    return {"window": [row, col, size], "errors": {label: error for label, _, error in columns if error is not None}}
