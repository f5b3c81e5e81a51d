"""The profiler: train error and performance models of every cacheable node over a session,
select what to cache for four error thresholds, validate, and write the profile folder (main
paper §4). It is the orchestrator: it uses the data package (:mod:`rrcache.profiles`) and the
report (:mod:`rrcache.report`), and neither imports it.

- :mod:`~rrcache.profiler.run`: :func:`profile` (``rrcache.profile``), the whole run;
- :mod:`~rrcache.profiler.train`: the measurements and the fits;
- :mod:`~rrcache.profiler.order`, :mod:`~rrcache.profiler.plan`: which nodes, which windows;
- :mod:`~rrcache.profiler.validate`: the selections measured beside the original;
- :mod:`~rrcache.profiler.accuracy`: held-out accuracy (``rrcache accuracy``);
- :mod:`~rrcache.profiler.demo`: the notebooks' demo profile.

>>> from rrcache.profiler import profile                                               # doctest: +SKIP
>>> p = profile("noise.frag", "orbit.json", "out/", TrainingSettings(periods=(2, 4, 8)))  # doctest: +SKIP
"""
from rrcache.profiler.demo import demo_profile  # noqa: F401
from rrcache.profiler.run import default_out_dir, profile  # noqa: F401
from rrcache.profiler.train import ProgressEvent, TrainingResult, train  # noqa: F401
