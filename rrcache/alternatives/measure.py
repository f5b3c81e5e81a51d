"""Side-by-side measurement of an alternative against the original.

:func:`compare_renderers` is :func:`rrcache.harness.cached.compare` for renderers that hold no
cache (a simplified shader, dynamic resolution): the original and the alternative render each
frame in turn, so machine noise touches both alike, and the result is the harness'
:class:`~rrcache.harness.cached.Comparison` (mean RGB L2 error over the original's covered
pixels, PSNR, speed-up as a ratio of median frame times). Every frame counts (there is no
empty first frame to leave out).
"""
from __future__ import annotations

from typing import Callable, Iterable, Optional

from rrcache.harness.cached import Comparison, FrameComparison
from rrcache.harness.metrics import mean_l2, nonfinite_count, psnr


def compare_renderers(original, other, frames: Iterable[int],
                      on_frame: Optional[Callable[[FrameComparison, object, object], None]] = None) -> Comparison:
    """Render ``frames`` with ``original`` and ``other`` (anything with ``render_frame(index)``
    returning an image, a mask and ``ms``), alternating frame by frame, at the same size;
    ``on_frame(row, other's frame, original's frame)`` after each."""
    result = Comparison(skip_first=0)
    result.resolution = tuple(original.size)
    result.notes = list(getattr(original, "notes", []))
    for index in frames:
        ref = original.render_frame(index)
        got = other.render_frame(index)
        err, left_out = mean_l2(got.image, ref.image, ref.mask)
        result.frames.append(FrameComparison(index, float(err), float(psnr(got.image, ref.image)), None, None,
                                             int(ref.covered_pixels), float(got.ms), float(ref.ms),
                                             nonfinite_count(got.image), int(left_out)))
        if on_frame is not None:
            on_frame(result.frames[-1], got, ref)
    return result
