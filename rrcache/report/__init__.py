"""Showing a profile: the self-contained ``report.html`` (:mod:`rrcache.report.html`), the real
renders it shows (:mod:`rrcache.report.images`), the data behind its chart
(:mod:`rrcache.report.data`), the plots (:mod:`rrcache.report.plots`) and the notebooks' figures
and widgets (:mod:`rrcache.report.explore`).

The report only reads: a :class:`rrcache.profiles.Profile` (the document) in, files and figures
out. It never runs the profiler (:mod:`rrcache.profiler` writes the report at the end of a run;
the notebooks' demo profile is :func:`rrcache.profiler.demo_profile`).

>>> from rrcache.report import write_report                                   # doctest: +SKIP
>>> write_report(rrcache.load_profile("marble-marble.rrprofile"), "marble-marble.rrprofile")  # doctest: +SKIP
PosixPath('marble-marble.rrprofile/report.html')
"""
from rrcache.report.html import REPORT_NAME, write_report  # noqa: F401
