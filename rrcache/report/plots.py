"""The profile's figures (matplotlib, Agg backend; nothing opens a window).

- ``tradeoff.png`` / ``tradeoff.svg`` (main paper Fig. 7): error against ms per frame, one path
  per trained node over Δn = 1..50 from the models, the trained periods marked at their measured
  error, the original's frame time as a dashed vertical line, the Pareto front, and the four
  selections marked and labelled (e1..e4). Points left of the line are faster than the original.
- ``hitrate.png`` (Fig. 5): the measured hit rate per training period, every trained node, with
  the fitted γ(Δn) = μ(1 − 1/Δn).
- ``validation.png`` (Fig. 6): predicted against measured error and frame time for the four
  selections (the diagonal is a perfect prediction).

>>> write_plots(load_profile("marble-marble.rrprofile"), "out/")    # doctest: +SKIP
['out/tradeoff.png', 'out/tradeoff.svg', 'out/hitrate.png', 'out/validation.png']
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rrcache.report.agg import agg_pyplot, save_figure

PERIODS = np.arange(1, 51)


def _curves(prof):
    """Per trained node: (node, errors over Δn = 1..50, ms over Δn = 1..50)."""
    from rrcache.model import predict_ms

    errors, perfs, hit = prof.fits()
    out = []
    for node, ef, pf in zip(prof.trained_nodes, errors, perfs):
        out.append((node, np.asarray(ef.predict(PERIODS), float),
                    np.asarray(predict_ms(pf, hit.mu, prof.pixels, PERIODS), float)))
    return out, hit


def front_points(prof):
    """The Pareto front as ``(error, ms)`` pairs sorted by ms: one front over the cached nodes
    (the model table) and the amortized estimators' options."""
    from rrcache.model import pareto_front

    points = [(float(p.predicted_error), float(p.predicted_ms)) for p in pareto_front(prof.table)]
    amortized = [(float(o.predicted_error), float(o.predicted_ms)) for o in prof.amortized_options()]
    if amortized:  # one front over the cached nodes and the amortized estimators
        best, front = float("inf"), []
        for err, ms in sorted(points + amortized, key=lambda p: (p[1], p[0])):
            if err < best:
                front.append((err, ms))
                best = err
        points = front
    return sorted(points, key=lambda p: p[1])


#: the amortized options' colour per history
AMORTIZED_COLORS = {"blend": "darkorange", "slots": "firebrick"}


def draw_amortized(ax, prof, positive_only: bool = False) -> int:
    """Draw the amortized estimators' options on ``ax`` (ms per frame across, error up): one
    dotted line per estimator, history and m over λ, labelled, and one legend entry per history
    (``positive_only``: leave out options predicted at error 0, for a log error axis). Returns
    how many options were drawn (0 when the profile has none)."""
    amortized = [o for o in prof.amortized_options() if not positive_only or o.predicted_error > 0]
    for est in prof.estimators:  # amortized sampling: one line per history and m over λ
        options = [o for o in amortized if o.parts[0].estimator == est.id]
        for history, m in sorted({(o.parts[0].history, o.parts[0].samples) for o in options}):
            row = sorted((o for o in options if (o.parts[0].history, o.parts[0].samples) == (history, m)),
                         key=lambda o: o.parts[0].blend)
            ax.plot([o.predicted_ms for o in row], [o.predicted_error for o in row], "x:",
                    color=AMORTIZED_COLORS[history], ms=4, lw=1.0)
            ax.annotate(f"{est.id} m={m}" + (" slots" if history == "slots" else ""),
                        (row[0].predicted_ms, row[0].predicted_error), fontsize=7, color=AMORTIZED_COLORS[history],
                        textcoords="offset points", xytext=(4, 2))
    for history in sorted({o.parts[0].history for o in amortized}):
        what = "amortized estimator, slots history" if history == "slots" else "amortized estimator"
        ax.plot([], [], "x:", color=AMORTIZED_COLORS[history], ms=4, label=f"{what}, m samples, λ = 0..0.9")
    return len(amortized)


def plot_tradeoff(prof, out_dir) -> list[str]:
    """Write ``tradeoff.png`` and ``tradeoff.svg``; returns their paths."""
    plt = agg_pyplot()
    curves, _ = _curves(prof)
    fig, ax = plt.subplots(figsize=(8, 5.5), dpi=110)
    cmap = plt.get_cmap("viridis")
    for k, (node, err, ms) in enumerate(curves):
        color = cmap(k / max(1, len(curves) - 1))
        ax.plot(ms, err, "-", color=color, lw=1.0, alpha=0.75)
        trained = np.asarray(node.periods, float)
        if len(trained):
            from rrcache.model import predict_ms

            _, perfs, hit = prof.fits()
            idx = [n.id for n in prof.trained_nodes].index(node.id)
            tms = np.asarray(predict_ms(perfs[idx], hit.mu, prof.pixels, trained), float)
            ax.plot(tms, node.errors, "o", color=color, ms=3)
    draw_amortized(ax, prof)
    front = front_points(prof)
    if front:
        ax.plot([p[1] for p in front], [p[0] for p in front], "-", color="black", lw=2.2, alpha=0.55,
                label="Pareto front")
    from rrcache.report.sets_plot import draw_sets

    draw_sets(ax, prof)  # the sets of several nodes and the front with them (none: nothing drawn)
    if prof.original_ms:
        ax.axvline(prof.original_ms, ls="--", color="gray", label=f"original ({prof.original_ms:.2f} ms)")
    groups: dict = {}
    for sel in prof.selections:  # selections that coincide share one mark and one label
        groups.setdefault(sel.key, []).append(sel)
    for k, (_key, sels) in enumerate(sorted(groups.items(), key=lambda g: g[1][0].label)):
        first = sels[0]
        ax.plot([first.predicted_ms], [first.predicted_error], "s", color="crimson", ms=7, mfc="none", mew=1.8)
        labels = ",".join(s.label for s in sels)
        text = f"{labels}: " + (first.describe() if first.parts else "original")
        ax.annotate(text, (first.predicted_ms, first.predicted_error), textcoords="offset points",
                    xytext=(8, 4 + 11 * (k % 4)), fontsize=8, color="crimson")
    ax.plot([], [], "o-", color="gray", ms=3, lw=1.0, label="node over Δn = 1..50 (dots: trained Δn)")
    ax.plot([], [], "s", color="crimson", mfc="none", label="selections e1..e4")
    ax.set_xlabel("ms per frame (predicted, full resolution)")
    ax.set_ylabel("mean RGB L2 error per pixel")
    ax.set_title(f"{Path(prof.shader).name}: error against run time ({len(curves)} nodes)")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    paths = [str(Path(out_dir) / "tradeoff.png"), str(Path(out_dir) / "tradeoff.svg")]
    for path in paths:
        save_figure(fig, path)
    plt.close(fig)
    return paths


def plot_hitrate(prof, out_dir) -> list[str]:
    """Write ``hitrate.png``; returns its path."""
    plt = agg_pyplot()
    _, hit = _curves(prof)
    fig, ax = plt.subplots(figsize=(6, 4), dpi=110)
    for node in prof.trained_nodes:
        ax.plot(node.periods, node.hit_rates, "o", ms=3, alpha=0.5, color="tab:blue")
    ax.plot([], [], "o", ms=3, color="tab:blue", label="measured (each node)")
    ax.plot(PERIODS, np.asarray(hit.predict(PERIODS), float), "-", color="black",
            label=f"γ(Δn) = μ(1 − 1/Δn), μ = {hit.mu:.3f}")
    ax.set_xlabel("refresh period Δn")
    ax.set_ylabel("hit rate")
    ax.set_ylim(0, 1.02)
    ax.set_title("hit rate against refresh period")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    path = str(Path(out_dir) / "hitrate.png")
    save_figure(fig, path)
    plt.close(fig)
    return [path]


def plot_validation(prof, out_dir) -> list[str]:
    """Write ``validation.png`` (nothing when no selection was measured); returns its paths."""
    rows = [s for s in prof.selections if s.measured_error is not None]
    if not rows:
        return []
    plt = agg_pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 4), dpi=110)
    for ax, pred, meas, name in ((a, "predicted_error", "measured_error", "mean RGB L2 error"),
                                 (b, "predicted_ms", "measured_ms", "ms per frame")):
        pairs = [(getattr(s, pred), getattr(s, meas)) for s in rows
                 if getattr(s, pred) is not None and getattr(s, meas) is not None]
        xs, ys = [p[0] for p in pairs], [p[1] for p in pairs]
        top = max(xs + ys + [1e-9]) * 1.15
        ax.plot([0, top], [0, top], "--", color="gray", lw=1)
        ax.plot(xs, ys, "o", color="tab:red")
        for s, x, y in zip(rows, xs, ys):
            ax.annotate(s.label, (x, y), textcoords="offset points", xytext=(5, 4), fontsize=8)
        ax.set_xlim(0, top)
        ax.set_ylim(0, top)
        ax.set_xlabel(f"predicted {name}")
        ax.set_ylabel(f"measured {name}")
        ax.grid(alpha=0.3)
    a.set_title("error: model against render")
    b.set_title("time: model against render")
    fig.tight_layout()
    path = str(Path(out_dir) / "validation.png")
    save_figure(fig, path)
    plt.close(fig)
    return [path]


def write_plots(prof, out_dir) -> list[str]:
    """Every figure of a profile with trained nodes into ``out_dir``; returns the paths written."""
    if not prof.trained_nodes:
        return []
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    return plot_tradeoff(prof, out_dir) + plot_hitrate(prof, out_dir) + plot_validation(prof, out_dir)
