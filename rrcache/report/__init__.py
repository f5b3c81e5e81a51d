"""Exploring a profile: the self-contained ``report.html`` (:mod:`rrcache.report.html`), the real
renders it shows (:mod:`rrcache.report.images`), the data behind its chart
(:mod:`rrcache.report.data`), the notebooks' figures and widgets (:mod:`rrcache.report.explore`)
and the demo profile they run on (:mod:`rrcache.report.demo`).

>>> from rrcache.report import write_report                                   # doctest: +SKIP
>>> write_report(rrcache.load_profile("marble-marble.rrprofile"), "marble-marble.rrprofile")  # doctest: +SKIP
PosixPath('marble-marble.rrprofile/report.html')
"""
from rrcache.report.demo import demo_profile  # noqa: F401
from rrcache.report.html import REPORT_NAME, write_report  # noqa: F401
