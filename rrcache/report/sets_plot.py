"""The sets of several cached nodes in a profile's figures: the single-node front against the
front with the sets (:mod:`rrcache.profiler.sets`).

:func:`fronts` gives both fronts of a profile as (error, ms) points: the single-node one from the
models (the original included), and the one with every *trained* set at its training
measurement added (predicted-only sets are candidates, not choices). :func:`draw_sets` marks the
sets on a tradeoff axis (hollow: predicted; filled: trained, joined to their prediction);
:func:`plot_fronts` draws one panel per profile (``docs/multinode_front.png``).

>>> plot_fronts([load_profile("marble.rrprofile")], "front.png")     # doctest: +SKIP
['front.png']
"""
from __future__ import annotations

from pathlib import Path


def _front(points):
    """The lower-left frontier of (error, ms) points, sorted by time."""
    out, best = [], float("inf")
    for e, ms in sorted(points, key=lambda p: (p[1], p[0])):
        if e < best:
            out.append((e, ms))
            best = e
    return out


def fronts(prof) -> tuple[list, list]:
    """(the single-node front, the front with the trained sets), each [(error, ms)] by time."""
    from rrcache.model import pareto_front

    single = [(float(p.predicted_error), float(p.predicted_ms)) for p in pareto_front(prof.table)]
    trained = [(float(o.trained_error), float(o.trained_ms)) for o in prof.sets
               if o.trained and o.trained_error is not None and o.trained_ms is not None]
    return _front(single), _front(single + trained)


def draw_sets(ax, prof) -> None:
    """Mark the profile's sets on ``ax`` (x: ms, y: error) and draw the front with them."""
    if not prof.sets:
        return
    for o in prof.sets:
        ax.plot([o.predicted_ms], [o.predicted_error], "D", color="darkorange", ms=4, mfc="none", alpha=0.7)
        if o.trained and o.trained_ms is not None:
            ax.plot([o.predicted_ms, o.trained_ms], [o.predicted_error, o.trained_error], ":", color="darkorange",
                    lw=1)
            ax.plot([o.trained_ms], [o.trained_error], "D", color="darkorange", ms=6)
            ax.annotate(o.describe(), (o.trained_ms, o.trained_error), textcoords="offset points", xytext=(6, -10),
                        fontsize=7, color="darkorange")
    _, with_sets = fronts(prof)
    ax.plot([p[1] for p in with_sets], [p[0] for p in with_sets], "--", color="darkorange", lw=1.6,
            label="front with the trained sets")
    ax.plot([], [], "D", color="darkorange", mfc="none", label="set of nodes: predicted (filled: trained)")


def plot_fronts(profiles, path, titles=None) -> list[str]:
    """One panel per profile: the single-node front, the front with the trained sets, the sets
    (predicted and trained) and the selections that stood (measured, where validated)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    profiles = list(profiles)
    fig, axes = plt.subplots(1, len(profiles), figsize=(6.5 * len(profiles), 5), dpi=110, squeeze=False)
    for k, (ax, prof) in enumerate(zip(axes[0], profiles)):
        single, _ = fronts(prof)
        ax.plot([p[1] for p in single], [p[0] for p in single], "o-", color="black", lw=2, ms=3,
                label="single-node front (models)")
        draw_sets(ax, prof)
        for sel in prof.selections:
            if sel.measured_ms is not None and sel.parts:
                marker = "*" if sel.multi else "s"
                ax.plot([sel.measured_ms], [sel.measured_error], marker, color="crimson", ms=9, mfc="none")
                ax.annotate(f"{sel.label} measured", (sel.measured_ms, sel.measured_error), textcoords="offset points",
                            xytext=(6, 4), fontsize=7, color="crimson")
        ax.plot([], [], "s", color="crimson", mfc="none", label="selection, validated (star: a set)")
        ax.axvline(float(prof.original_ms), ls="--", color="gray", label=f"original ({prof.original_ms:.1f} ms)")
        ax.set_xlabel("ms per frame")
        ax.set_ylabel("mean RGB L2 error per pixel")
        ax.set_ylim(bottom=0)
        ax.set_xlim(left=0)
        ax.set_title(titles[k] if titles else Path(prof.shader).name)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(str(path))
    plt.close(fig)
    return [str(path)]
