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


def save_figure(fig, path) -> str:
    """Draw ``fig`` into memory in the format of ``path``'s extension and write it to ``path`` by
    :mod:`rrcache.atomic`'s rule (matplotlib would open the path itself, following any link);
    returns the path."""
    import io
    import os

    from rrcache.atomic import write_bytes

    buffer = io.BytesIO()
    fig.savefig(buffer, format=os.path.splitext(os.fspath(path))[1].lstrip(".").lower() or "png")
    return write_bytes(path, buffer.getvalue())
