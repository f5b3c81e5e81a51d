"""A profile's data: the files of a profile folder and the records in them.

- :mod:`~rrcache.profiles.document`: ``profile.json``, its declared shape, :class:`Profile`,
  :func:`load_profile`, :func:`select`;
- :mod:`~rrcache.profiles.store`: ``profile.sqlite``, every measurement (:class:`ProfileStore`);
- :mod:`~rrcache.profiles.settings`: :class:`TrainingSettings`, what a profile measures.

The selection record they hold is :class:`rrcache.selection.Selection`. Writing a profile is the
profiler's job (:mod:`rrcache.profiler`); this package only defines, reads and writes the data.

>>> from rrcache.profiles import load_profile                     # doctest: +SKIP
>>> load_profile("out/").select(0.01).period                      # doctest: +SKIP
8
"""
from rrcache.profiles.document import (JSON_NAME, LABELS, PROFILE_VERSION, NodeProfile, Profile,  # noqa: F401
                                       algorithm_line, load_profile, select)
from rrcache.profiles.settings import TrainingSettings, parse_periods  # noqa: F401
from rrcache.profiles.store import STORE_NAME, ProfileStore, StoreKey, read_store  # noqa: F401
