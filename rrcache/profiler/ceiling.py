"""Measuring the ceiling before training (:mod:`rrcache.model.ceiling` holds what it means).

:func:`measure_ceiling` caches the costliest node to train with each algorithm the profile may
use and measures its all-hit frame beside the original (:func:`rrcache.harness.limit.all_hit_limit`)
on a few of the timing frames, at the session's resolution (in the timing window when the
shader is timed in one) and at 8×8 pixels (the fixed per-frame cost), in the settings' timing
format; the best algorithm's figures make the :class:`~rrcache.model.ceiling.Ceiling`.
"""
from __future__ import annotations

import time

from rrcache.harness.limit import all_hit_limit, probe_frames
from rrcache.model.ceiling import Ceiling, relative_noise

#: the resolution of the fixed-cost (geometry) measurement
FIXED_SIZE = (8, 8)
#: probe frames and hitting repeats of the ceiling's measurement (a few seconds)
PROBE_FRAMES = 3
REPEATS = 5


def measure_ceiling(work, session, settings, node, algorithms, timing_frames, pixels: float, window=None,
                    step=None) -> Ceiling:
    """Measure the :class:`Ceiling` of ``work`` over ``session`` by caching ``node`` (a node
    table entry: the costliest node to train) with each of ``algorithms`` (see the module
    docstring): the all-hit frame beside the original on up to :data:`PROBE_FRAMES` of
    ``timing_frames`` at the session's resolution (inside ``window`` if given) and at
    :data:`FIXED_SIZE`, in ``settings.timing_format``. ``pixels``: a full frame's covered
    pixels. ``step(detail)`` after each measurement."""
    from rrcache.pipeline import variant_for

    start = time.perf_counter()
    frames = probe_frames(timing_frames, PROBE_FRAMES)
    period = settings.timing_periods[len(settings.timing_periods) // 2]
    common = dict(period=period, block=settings.block, refresh=settings.refresh,
                  depth_epsilon=settings.depth_epsilon, color_format=settings.timing_format, repeats=REPEATS,
                  clock=settings.clock)
    full = tuple(int(v) for v in session.resolution)
    results, noise = {}, []
    for algorithm in algorithms:
        variant = variant_for(work, node.id, algorithm)
        big = all_hit_limit(variant, session, work.prepared, frames, full, window=window, **common)
        if step is not None:
            step(f"{algorithm} all hits")
        small = all_hit_limit(variant, session, work.prepared, frames[:2], FIXED_SIZE, **common)
        if step is not None:
            step(f"{algorithm} at {FIXED_SIZE[0]}×{FIXED_SIZE[1]}")
        results[algorithm] = (big, small)
        per = len(big.samples) // max(1, len(big.frames))
        noise += [big.samples[i * per:(i + 1) * per] for i in range(len(big.frames))]
    best = min(results, key=lambda a: results[a][0].limit_ms / results[a][0].original_median_ms)
    big, small = results[best]
    # the fixed costs are small and a loaded machine only adds time: the fastest frames stand
    ceiling = Ceiling(node.id, node.text, best, float(pixels), big.covered_pixels, big.original_median_ms,
                      big.limit_ms, small.fastest_original_ms, small.fastest_limit_ms, settings.min_gain,
                      windowed=window is not None, noise=relative_noise(noise), color_format=settings.timing_format,
                      frames=list(frames))
    for algorithm, (b, s) in results.items():
        other = Ceiling(node.id, node.text, algorithm, float(pixels), b.covered_pixels, b.original_median_ms,
                        b.limit_ms, s.fastest_original_ms, s.fastest_limit_ms, windowed=window is not None)
        ceiling.algorithms[algorithm] = other.speedup
    ceiling.wall_s = time.perf_counter() - start
    return ceiling
