"""The profiler: train error and performance models of every cacheable node over a session,
select what to cache for an error threshold, and write the optimized shader (main paper §4).

>>> from rrcache.profile import profile, load_profile, TrainingSettings     # doctest: +SKIP
>>> p = profile("noise.frag", "orbit.json", "out/", TrainingSettings(periods=(2, 4, 8)))  # doctest: +SKIP
>>> load_profile("out/").select(0.01).period                                # doctest: +SKIP
8
"""
from rrcache.profile.profile import NodeProfile, Profile, SelectionReport, load_profile, profile, select  # noqa: F401
from rrcache.profile.settings import TrainingSettings, parse_periods  # noqa: F401
from rrcache.profile.store import ProfileStore, StoreKey, read_store  # noqa: F401
from rrcache.profile.train import ProgressEvent, TrainingResult, train  # noqa: F401
