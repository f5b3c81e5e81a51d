"""matplotlib for files: every figure rrcache writes is drawn on the Agg backend, so nothing
opens a window and a machine without a display draws them too (the notebooks' explorer keeps
its own inline display, :mod:`rrcache.report.explore`)."""
from __future__ import annotations


def agg_pyplot():
    """matplotlib's pyplot on the Agg backend."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt
