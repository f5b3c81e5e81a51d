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
    """One panel per profile, time as a share of the original's (each figure against the
    original it was measured beside: the models' and the training's against the training's
    original, a validation's against its own): the single-node front, the front with the trained
    sets, the sets (predicted, and trained joined to their prediction, numbered as listed under
    the panel) and the validated selections."""
    from rrcache.report.agg import agg_pyplot, save_figure

    plt = agg_pyplot()
    profiles = list(profiles)
    fig, axes = plt.subplots(1, len(profiles), figsize=(7 * len(profiles), 6.2), dpi=110, squeeze=False)
    for k, (ax, prof) in enumerate(zip(axes[0], profiles)):
        t0 = float(prof.original_ms)
        single, with_sets = fronts(prof)
        ax.plot([p[1] / t0 for p in single], [p[0] for p in single], "o-", color="black", lw=2, ms=2,
                label="single-node front (models)")
        ax.plot([p[1] / t0 for p in with_sets], [p[0] for p in with_sets], "--", color="darkorange", lw=1.6,
                label="front with the trained sets")
        listed = []
        for o in prof.sets:
            if not o.trained:
                ax.plot([o.predicted_ms / t0], [o.predicted_error], "D", color="darkorange", ms=3, mfc="none",
                        alpha=0.5)
                continue
            listed.append(o)
            n = len(listed)
            ax.plot([o.predicted_ms / t0, o.trained_ms / t0], [o.predicted_error, o.trained_error], ":",
                    color="darkorange", lw=1)
            ax.plot([o.predicted_ms / t0], [o.predicted_error], "D", color="darkorange", ms=4, mfc="none")
            ax.plot([o.trained_ms / t0], [o.trained_error], "D", color="darkorange", ms=6)
            ax.annotate(str(n), (o.trained_ms / t0, o.trained_error), textcoords="offset points", xytext=(5, 3),
                        fontsize=8, color="darkorange")
        for sel in prof.selections:
            if sel.measured_speedup and sel.parts:
                x = 1.0 / float(sel.measured_speedup)
                ax.plot([x], [sel.measured_error], sel.choice.marker if sel.parts else "s", color="crimson", ms=9, mfc="none")
                ax.annotate(sel.label, (x, sel.measured_error), textcoords="offset points", xytext=(-14, 4),
                            fontsize=7, color="crimson")
        ax.plot([], [], "D", color="darkorange", label="set: predicted (hollow) → trained (filled)")
        ax.plot([], [], "s", color="crimson", mfc="none", label="selection validated (star: a set)")
        ax.axvline(1.0, ls="--", color="gray", label="the original")
        ax.set_xlabel("time as a share of the original's")
        ax.set_ylabel("mean RGB L2 error per pixel")
        ax.set_ylim(bottom=0)
        ax.set_xlim(0, 1.25)
        ax.set_title(titles[k] if titles else Path(prof.shader).name)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
        text = "\n".join(f"{i + 1}: {o.describe()}" for i, o in enumerate(listed))
        ax.text(0.0, -0.13, text, transform=ax.transAxes, fontsize=7, va="top", color="darkorange")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
    return [str(path)]
