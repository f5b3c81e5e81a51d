"""The render cache (Walter, Drettakis, Parker 1999; Walter, Drettakis, Greenberg 2002): forward
reprojection of shaded points, the predecessor of the reverse reprojection cache, built over the
harness as a baseline to compare at equal frame time. It is an alternative to compare, not a
choice the profiler makes.

- the knobs and their defaults, :class:`RenderCacheSettings`, are the part of the registered kind
  ``render-cache`` (:mod:`rrcache.kinds.render_cache`): it is never a profiler choice;
- :mod:`~.points`: the fixed-size point cache (ring replacement, ageing, eviction);
- :mod:`~.projection`: projection into a frame, the z-buffer, the predicted occupancy image;
- :mod:`~.filters`: depth cull, the 3×3 interpolation with the priority image, the 7×7 prefilter;
- :mod:`~.sampling`: error-diffusion dithering under the sample budget, predictive requests;
- :mod:`~.shading`: the renderer: the user's shader at the requested pixels only;
- :mod:`~.renderer`: :class:`RenderCacheRenderer`, a frame of all of it, timed stage by stage;
- :mod:`~.tune`: measured beside the original, and tuned to a target speed-up.

docs/render_cache.md describes the choices and what was measured.
"""
from rrcache.alternatives.render_cache.renderer import RenderCacheFrame, RenderCacheRenderer, STAGES
from rrcache.kinds.render_cache import RenderCacheSettings

__all__ = ["RenderCacheFrame", "RenderCacheRenderer", "RenderCacheSettings", "STAGES"]
