"""The render cache beside the original, and tuned to a target speed-up like dynamic resolution.

:func:`compare` renders consecutive frames with the original and with the render cache,
alternating frame by frame (:func:`rrcache.alternatives.measure.compare_renderers`); the first
frame, the render cache's cold start (every pixel shaded, as the reprojection cache's first frame
misses everywhere), is left out of the summary as the cached variants' is. ``stages`` of the
result has the median ms of each stage over the summarised frames.

:func:`tune_samples` finds the sample share whose measured speed-up matches a target, each step
measured side by side with the original over the same frames, searched by
:func:`rrcache.alternatives.search.match_scale` (the speed-up falls as the share grows). When even
the smallest share is slower than the target (the render cache's own work per frame costs more
than the target frame time), the result says so (``matched`` False) and holds the closest share.
"""
from __future__ import annotations

import statistics
from dataclasses import dataclass, field, fields, replace
from typing import Callable, Optional

from rrcache.alternatives.measure import compare_renderers
from rrcache.alternatives.render_cache.renderer import STAGES, RenderCacheRenderer
from rrcache.kinds.render_cache import RenderCacheSettings
from rrcache.alternatives.search import SearchResult, match_scale
from rrcache.gl.formats import ERROR_FORMAT
from rrcache.harness.cached import Comparison
from rrcache.harness.renderer import Renderer

#: the sample shares the equal-time search ranges over: from the bottom of the range where the
#: paper says the render cache works (1% to 10% of the pixels per frame) up to half the pixels
MIN_SAMPLES, MAX_SAMPLES = 0.01, 0.5


def compare(prepared, session, frames, settings: RenderCacheSettings, size=None, original: Optional[Renderer] = None,
            on_frame: Optional[Callable] = None, color_format: str = ERROR_FORMAT):
    """The render cache at ``settings`` against the original over consecutive ``frames``: a
    :class:`~rrcache.harness.cached.Comparison` (first frame left out of the summary) with
    ``stages`` (median ms per stage over the summarised frames), ``shaded`` (median pixels shaded
    per summarised frame) and ``budget`` added. ``on_frame(row, frame, reference)`` is called per
    frame (the render cache's :class:`~rrcache.alternatives.render_cache.renderer.RenderCacheFrame`
    and the original's frame). Both draw into ``color_format`` (``original``, when given, is
    used as it is)."""
    own = original is None
    ref = Renderer(prepared, session, size, color_format=color_format) if own else original
    try:
        with RenderCacheRenderer(prepared, session, size, settings, color_format=color_format) as rc:
            seen: list = []

            def keep(row, got, reference):
                seen.append(got)
                if on_frame is not None:
                    on_frame(row, got, reference)

            result = compare_renderers(ref, rc, frames, on_frame=keep)
            result.notes = list(dict.fromkeys(result.notes + list(rc.notes)))
            budget = rc.budget
    finally:
        if own:
            ref.release()
    steady = seen[1:] or seen
    result.color_format = color_format
    return RenderCacheComparison(
        **{f.name: getattr(result, f.name) for f in fields(Comparison) if f.name != "skip_first"}, skip_first=1,
        settings=settings, budget=budget, shaded=float(statistics.median(f.shaded for f in steady)),
        stages={stage: float(statistics.median(f.stages.get(stage, 0.0) for f in steady)) for stage in STAGES})


@dataclass
class RenderCacheComparison(Comparison):
    """A :class:`~rrcache.harness.cached.Comparison` of the render cache: its ``settings``, the
    per-frame pixel ``budget``, the median pixels ``shaded`` per summarised frame and the median
    ms of each stage (``stages``)."""

    settings: Optional[RenderCacheSettings] = None
    budget: int = 0
    shaded: float = 0.0
    stages: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """The figures ``rrcache render --method render-cache --json`` prints (those of a cached
        variant's comparison that apply: no hits, misses or payload)."""
        out = super().summary()
        for key in ("hit_rate", "hits", "misses", "payload_dtype"):
            out.pop(key, None)
        out.update(method="render-cache", samples=self.settings.samples if self.settings else None,
                   budget_pixels=self.budget, shaded_pixels=self.shaded, stage_ms=dict(self.stages),
                   settings=self.settings.to_json() if self.settings else None)
        return out


def measure_samples(prepared, session, frames, settings: RenderCacheSettings, size=None,
                    original: Optional[Renderer] = None):
    """A function ``share -> Comparison`` measuring the render cache at that sample share."""

    def run(share: float):
        return compare(prepared, session, frames, replace(settings, samples=float(share)), size, original)

    return run


def tune_samples(prepared, session, frames, target_speedup: float, settings: RenderCacheSettings = RenderCacheSettings(),
                 size=None, rel_tol: float = 0.05, max_steps: int = 8,
                 progress: Optional[Callable[[float, float], None]] = None) -> SearchResult:
    """The sample share (in [:data:`MIN_SAMPLES`, :data:`MAX_SAMPLES`]) whose measured speed-up over
    ``frames`` (consecutive, side by side with the original) matches ``target_speedup``;
    ``progress(share, speedup)`` after each step."""
    with Renderer(prepared, session, size) as original:
        run = measure_samples(prepared, session, frames, settings, size, original)

        def measure(share: float) -> float:
            speedup = run(share).speedup
            if progress is not None:
                progress(share, speedup)
            return speedup

        return match_scale(measure, target_speedup, lo=MIN_SAMPLES, hi=MAX_SAMPLES, rel_tol=rel_tol,
                           max_steps=max_steps)
