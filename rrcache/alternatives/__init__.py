"""Other ways to cut pixel cost, for equal-time comparisons with the cache (main paper §5.4):

- :mod:`~rrcache.alternatives.dynres`: dynamic resolution (shade fewer pixels, upsample
  bilinearly);
- :mod:`~rrcache.alternatives.simplify`: automatic simplification after Pellacini 2005 (replace
  expressions by their mean over the session);
- :mod:`~rrcache.alternatives.render_cache`: the render cache of Walter et al. 2002 (forward
  reprojection of shaded points), a baseline to compare at equal time, never a profiler choice
  (docs/render_cache.md);
- :mod:`~rrcache.alternatives.search`: tuning them to a target speed-up;
- :mod:`~rrcache.alternatives.measure`: side-by-side measurement against the original.
"""
