"""The bench's figure per scene: measured error against run time (matplotlib, Agg backend).

``<out>/<scene>-error-time.png``: x is the frame time as a fraction of the original's (1 /
speed-up, each measured side by side with the original, so machine noise cancels), y the mean
RGB L2 error. The original sits at (1, 0); the four selections e1..e4 are joined in order; the
cache algorithms on the medium node and the equal-time alternatives are marked beside them,
and the speed-up limit is a dotted vertical line. The profiler's own model-based trade-off plot
is in the scene's profile folder (``tradeoff.png``) when plots are on.
"""
from __future__ import annotations

from pathlib import Path

from rrcache.report.agg import agg_pyplot, save_figure


def _x(speedup):
    return 1.0 / speedup if speedup and speedup > 0 else None


def write_scene_plot(scene, out) -> str:
    """Write the figure of one :class:`~rrcache.bench.paper.SceneResult`; returns its path."""
    plt = agg_pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=110)
    try:
        ax.scatter([1.0], [0.0], color="black", zorder=3, label="original")
        sel = [(r.label, _x(r.measured_speedup), r.measured_error) for r in scene.selections
               if _x(r.measured_speedup) is not None]
        if sel:
            ax.plot([s[1] for s in sel], [s[2] for s in sel], "o-", color="tab:blue", zorder=3,
                    label="our selections")
            for label, x, y in sel:
                ax.annotate(label, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8)
        markers = {"three-pass": "s", "two-pass": "D", "one-pass": "v"}
        for r in scene.algorithms:
            if _x(r.speedup) is not None:
                ax.scatter([_x(r.speedup)], [r.mean_error], marker=markers.get(r.method, "x"), facecolors="none",
                           edgecolors="tab:gray", zorder=2, label=f"{r.method} ({scene.medium} node)")
        colours = {"dynamic resolution": "tab:orange", "simplification (Pellacini 2005)": "tab:green",
                   "render cache (Walter 2002)": "tab:purple"}
        for r in scene.equal_time[1:]:
            if _x(r.speedup) is not None:
                ax.scatter([_x(r.speedup)], [r.mean_error], marker="*", s=120, color=colours.get(r.method, "tab:red"),
                           zorder=4, label=f"{r.method} (equal time)")
        styles = [("P", "darkorange"), ("X", "tab:purple"), ("D", "tab:brown"), ("v", "tab:pink")]
        for k, r in enumerate(getattr(scene, "amortized", [])):
            if _x(r.speedup) is not None:
                marker, colour = styles[k % len(styles)]
                ax.scatter([_x(r.speedup)], [r.mean_error], marker=marker, s=70, color=colour, zorder=4,
                           label=f"amortized ({r.setting})")
        if scene.limit_speedup:
            ax.axvline(1.0 / scene.limit_speedup, color="tab:blue", linestyle=":", linewidth=1,
                       label=f"cache limit ({scene.limit_speedup:.1f}×)")
        ax.set_xlabel("frame time / original frame time")
        ax.set_ylabel("mean RGB L2 error")
        xs = [x for x in ([s[1] for s in sel] + [_x(r.speedup) for r in scene.algorithms + scene.equal_time
                                                  + list(getattr(scene, "amortized", []))])
              if x is not None]
        ax.set_xlim(0, 1.05 * max([1.0] + xs))
        ax.set_ylim(bottom=0)
        w, h = scene.resolution
        ax.set_title(f"{scene.name}: {w}×{h}, {scene.frames} frames", fontsize=10)
        ax.legend(fontsize=7, loc="best")
        ax.grid(alpha=0.3)
        fig.tight_layout()
        path = Path(out) / f"{scene.name}-error-time.png"
        save_figure(fig, path)
    finally:
        plt.close(fig)
    return str(path)
