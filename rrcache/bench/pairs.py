"""A pair of cached nodes against its single nodes, side by side, and the rule that predicts the
pair from the singles.

:func:`measure` renders, for each repeat, every configuration beside the original
(:func:`rrcache.harness.cached.compare`, the original and the variant alternating frame by frame):
the pair (outer O at Δn_O, inner I at Δn_I) and each single (O at Δn_O, I at Δn_I), so every
speed-up is a ratio measured in one run; the figures are medians over the repeats.

The combination rule (:func:`predict`), for an outer node O whose value depends on an inner
node I (nested in its expression, or through a variable), from the singles' measurements:

- **error**: ``e_pair ≈ e_O + e_I``. Per pixel the pair's colour differs from the original by at
  most (O's staleness: O reprojected where it hits) + (I's staleness reaching the colour where O
  is recomputed from I's cached value); the first is what O alone shows, the second at most what
  I alone shows (I alone recomputes O's outer part everywhere). So the sum is an upper bound of
  the mean error, tight when the two errors sit on different pixels.
- **time**: ``t_pair ≈ h_O · t_O^hit + (1 − h_O) · t_I``: a pixel where O hits costs what it
  costs when O alone hits everywhere (``t_O^hit``, O's all-hit time: the cached pipeline's best
  case, :meth:`rrcache.harness.cached.CachedRenderer.render_static`, or the profiler's timing
  model at hit rate 1); a pixel where O misses costs what it costs with I alone cached (O's
  outer part computed from I's cache, I recomputed where I misses): ``t_I``. ``h_O`` is O's hit
  rate as a single node. The second cache's own passes are in neither single, so the rule is
  optimistic by about their cost (on Marble at 320×240: predicted 3.42×, measured 2.00×;
  docs/multinode.md). This holds where a pixel that misses only O
  does not pay for I's computation: on hardware whose branches skip work for coherent pixels.
- **time, lock-step branches** (llvmpipe, whose fragment shader runs both sides of a branch for
  its SIMD lanes): every pixel where some node misses pays the whole pass 2, so
  ``t_pair ≈ h_U · t_O^hit + (1 − h_U) · T_0`` with ``h_U ≈ h_O · h_I`` the share of pixels where
  both hit (independent refresh phases; shared disocclusions make it a lower bound).

For two disjoint nodes A and B the same reasoning gives ``e ≈ e_A + e_B`` and
``t ≈ t_A + t_B − T_0`` (each saves what it saves alone); this module measures the nested kind.
"""
from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import Optional

from rrcache.harness.cached import compare
from rrcache.pipeline import load_for_session, variant_for, variant_for_nodes


@dataclass
class ConfigResult:
    """One configuration: ``label`` (``n12 Δn=4 + n40 Δn=50``), per repeat the error, ms,
    original ms, speed-up and hit rate; medians as properties."""

    label: str
    errors: list = field(default_factory=list)
    ms: list = field(default_factory=list)
    original_ms: list = field(default_factory=list)
    speedups: list = field(default_factory=list)
    hit_rates: list = field(default_factory=list)

    @property
    def error(self) -> float:
        return statistics.median(self.errors)

    @property
    def speedup(self) -> float:
        return statistics.median(self.speedups)

    @property
    def hit_rate(self) -> float:
        return statistics.median(self.hit_rates)

    def ratio_ms(self) -> float:
        """This configuration's ms as a fraction of the original's (1 / speed-up), median."""
        return 1.0 / self.speedup


@dataclass
class PairMeasurement:
    pair: ConfigResult
    outer: ConfigResult
    inner: ConfigResult
    outer_all_hit_ratios: list  # O's all-hit ms / the original's ms, per repeat (side by side)
    resolution: tuple
    frames: int
    repeats: int


def measure(shader, session, outer: str, inner: str, outer_period: int, inner_period: int,
            resolution=(320, 240), frames: int = 24, repeats: int = 3, algorithm: str = "three-pass",
            first_frame: int = 0) -> PairMeasurement:
    """Measure the pair and its singles (see the module docstring)."""
    from rrcache.session import load_session

    loaded = load_session(session) if isinstance(session, str) else session
    work = load_for_session(shader, loaded)
    variants = {
        "pair": (variant_for_nodes(work, [outer, inner], algorithm), (outer_period, inner_period),
                 f"{outer} Δn={outer_period} + {inner} Δn={inner_period}"),
        "outer": (variant_for(work, outer, algorithm), outer_period, f"{outer} Δn={outer_period}"),
        "inner": (variant_for(work, inner, algorithm), inner_period, f"{inner} Δn={inner_period}"),
    }
    results = {k: ConfigResult(label) for k, (_v, _p, label) in variants.items()}
    indices = range(first_frame, first_frame + frames)
    all_hit = []
    for _ in range(repeats):
        all_hit.append(_all_hit_ratio(variants["outer"][0], loaded, work, resolution, first_frame + frames // 2))
        for key, (variant, period, _label) in variants.items():
            r = compare(variant, loaded, work.prepared, indices, period=period, resolution=resolution)
            res = results[key]
            res.errors.append(r.mean_error)
            res.ms.append(r.ms_per_frame)
            res.original_ms.append(r.original_ms_per_frame)
            res.speedups.append(r.speedup)
            res.hit_rates.append(r.hit_rate)
    return PairMeasurement(results["pair"], results["outer"], results["inner"], all_hit, tuple(resolution),
                           frames, repeats)


def _all_hit_ratio(variant, session, work, resolution, index: int) -> float:
    """The variant's all-hit frame time over the original's, the original rendered between the
    cached frames (side by side)."""
    from rrcache.harness.cached import CachedRenderer
    from rrcache.harness.renderer import Renderer

    original_ms = []
    with Renderer(work.prepared, session, resolution) as original, \
            CachedRenderer(variant, session, work.prepared, resolution) as cached:
        original.render_frame(index)
        static = cached.render_static(index, repeats=5,
                                      between=lambda: original_ms.append(original.render_frame(index).ms))
    return static / statistics.median(original_ms)


def predict(outer_error: float, inner_error: float, outer_all_hit_ratio: float, inner_ratio: float,
            outer_hit_rate: float, inner_hit_rate: Optional[float] = None) -> tuple[float, float]:
    """The pair's (error, time as a fraction of the original's) from the singles' (see the module
    docstring; ``*_ratio`` = ms / the original's ms). With ``inner_hit_rate`` the time is the
    lock-step rule's.

    >>> predict(0.01, 0.002, 0.3, 0.7, 0.8)
    (0.012, 0.38)
    >>> predict(0.01, 0.002, 0.3, 0.7, 0.8, 0.5)
    (0.012, 0.72)
    """
    error = outer_error + inner_error
    if inner_hit_rate is None:
        ratio = outer_hit_rate * outer_all_hit_ratio + (1.0 - outer_hit_rate) * inner_ratio
    else:
        both = outer_hit_rate * inner_hit_rate
        ratio = both * outer_all_hit_ratio + (1.0 - both)
    return round(error, 12), round(ratio, 12)


def summary(m: PairMeasurement) -> dict:
    """The measured figures and the rule's prediction of the pair."""
    all_hit = statistics.median(m.outer_all_hit_ratios)
    pred_error, pred_ratio = predict(m.outer.error, m.inner.error, all_hit, m.inner.ratio_ms(), m.outer.hit_rate)
    _, lock_ratio = predict(m.outer.error, m.inner.error, all_hit, m.inner.ratio_ms(), m.outer.hit_rate,
                            m.inner.hit_rate)
    rows = {}
    for key, res in (("pair", m.pair), ("outer", m.outer), ("inner", m.inner)):
        rows[key] = {"label": res.label, "error": res.error, "speedup": res.speedup, "hit_rate": res.hit_rate,
                     "speedups": res.speedups, "errors": res.errors}
    return {"resolution": list(m.resolution), "frames": m.frames, "repeats": m.repeats, **rows,
            "outer_all_hit_speedup": 1.0 / all_hit, "outer_all_hit_ratios": m.outer_all_hit_ratios,
            "predicted_pair_error": pred_error, "predicted_pair_speedup": 1.0 / pred_ratio if pred_ratio > 0 else None,
            "predicted_pair_speedup_lockstep": 1.0 / lock_ratio if lock_ratio > 0 else None,
            "predicted_pair_hit_rate": m.outer.hit_rate * m.inner.hit_rate}


def main(argv: Optional[list] = None) -> None:  # pragma: no cover - a measurement, run by hand
    import argparse
    import json

    ap = argparse.ArgumentParser(description="a pair of cached nodes against its singles, side by side")
    ap.add_argument("shader")
    ap.add_argument("session")
    ap.add_argument("--outer", required=True)
    ap.add_argument("--inner", required=True)
    ap.add_argument("--outer-period", type=int, default=4)
    ap.add_argument("--inner-period", type=int, default=50)
    ap.add_argument("--resolution", default="320x240")
    ap.add_argument("--frames", type=int, default=24)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--algorithm", default="three-pass")
    a = ap.parse_args(argv)
    w, h = (int(v) for v in a.resolution.split("x"))
    m = measure(a.shader, a.session, a.outer, a.inner, a.outer_period, a.inner_period, (w, h), a.frames,
                a.repeats, a.algorithm)
    print(json.dumps(summary(m), indent=2))


if __name__ == "__main__":  # pragma: no cover
    main()
