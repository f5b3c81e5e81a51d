"""Error runs over segments of a session: the warm-up that gives a later segment the cache a run
from frame 0 has there (docs/levels.md; the error frames are :mod:`rrcache.profiler.plan`'s).

Validation measures a session from an empty cache at frame 0. An error run over frames
0..N−1 does the same. A run over a later segment starting at frame s is preceded by
:data:`WARMUP_PERIODS` refresh periods of frames (rendered, not compared: :func:`warmup_frames`),
from an empty cache with the runtime's clock at the first of them (:func:`restart`): the refresh
schedule and an amortized variant's phase depend on the clock, which a run from frame 0 has at
that frame. By frame s every block has been refreshed since, on the same frames; values resampled
across block edges from before the warm-up have faded (one period of warm-up left them 2–6% of
the error on the tiny test scene at Δn = 4–16; two, under 0.1%).

>>> run_order([0, 1, 2, 6, 7], 1)
[[(0, True), (1, True), (2, True)], [(4, False), (5, False), (6, True), (7, True)]]
"""
from __future__ import annotations

#: refresh periods of warm-up before a later segment (see the module docstring)
WARMUP_PERIODS = 2
#: the settling time assumed of a variant without a refresh period (an amortized loop: its cycle of
#: subsets and its blend's memory), in frames: the default largest training period
SETTLE_FRAMES = 50


def warmup_frames(start: int, period: int) -> list[int]:
    """The frames rendered, not compared, before a segment starting at ``start``:
    :data:`WARMUP_PERIODS` × ``period`` frames (from frame 0 when there are fewer), none for a
    segment at frame 0.

    >>> warmup_frames(100, 2), warmup_frames(3, 10), warmup_frames(0, 10)
    ([96, 97, 98, 99], [0, 1, 2], [])
    """
    return list(range(max(0, int(start) - WARMUP_PERIODS * max(1, int(period))), int(start)))


def segments_of(indices) -> list[list[int]]:
    """``indices`` split into runs of consecutive frames.

    >>> segments_of([0, 1, 2, 10, 11])
    [[0, 1, 2], [10, 11]]
    """
    out: list[list[int]] = []
    for i in indices:
        if out and i == out[-1][-1] + 1:
            out[-1].append(i)
        else:
            out.append([i])
    return out


def run_order(indices, warmup: int) -> list[list[tuple[int, bool]]]:
    """The frames an error run renders to compare ``indices``: per segment of consecutive ones
    (each after a :func:`restart`), its warm-up frames (:func:`warmup_frames` for a refresh period
    or settling time ``warmup``; ``False``: rendered, not compared) and then its own frames
    (``True``). A run over frames 0..N−1 is one segment without warm-up."""
    return [[(i, False) for i in warmup_frames(seg[0], warmup)] + [(i, True) for i in seg]
            for seg in segments_of(indices)]


def warmup_of(variant_spec) -> int:
    """The refresh period a segment of ``variant_spec`` warms up over: its longest period, or
    :data:`SETTLE_FRAMES` for a variant without one."""
    periods = tuple(getattr(variant_spec, "periods", ()) or ())
    return max(periods) if periods else SETTLE_FRAMES


def restart(cached, frame: int) -> None:
    """Empty the cache of ``cached`` (a :class:`~rrcache.harness.cached.CachedRenderer`) before
    rendering session frame ``frame`` first, with the runtime's clock at ``frame``."""
    cached.reset()
    cached.runtime.clock = int(frame)
