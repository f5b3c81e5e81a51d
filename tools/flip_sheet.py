"""The validated selections nearest FLIP's visible-artifact threshold, as images (docs/levels.md).

    python tools/flip_sheet.py runs/*.rrprofile --out docs/levels_flip_threshold.png --json docs/levels_flip.json

Reads every choice the profiles' validation measured (``profile.json``: ``measured``, with its
mean FLIP), lists them with PSNR and FLIP side by side (``--json``), picks the two nearest
:data:`rrcache.model.levels.VISIBLE_FLIP` on each side, and renders each at full resolution on a
frame of the session where the cache has run (the session's middle, at least two refresh periods
in): the original, the cached frame and FLIP's error map (magma, as its authors show it), one row
per selection, labelled.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def validated(folders) -> list[dict]:
    """Every distinct measured (cached) choice of ``folders`` with its FLIP, PSNR and speed-up."""
    from rrcache.profiles import load_profile

    out = []
    for folder in folders:
        prof = load_profile(folder)
        seen = set()
        for sel in list(prof.measured) + list(prof.selections):
            if not sel.parts or sel.measured_flip is None or sel.key in seen or sel.multi:
                continue
            seen.add(sel.key)
            out.append({"profile": str(folder), "scene": Path(prof.shader).stem, "run": Path(folder).name,
                        "choice": sel.describe(), "kind": sel.kind, "label": sel.label,
                        "psnr": sel.measured_psnr, "psnr_uncertainty": sel.measured_psnr_uncertainty,
                        "flip": sel.measured_flip, "flip_uncertainty": sel.measured_flip_uncertainty,
                        "temporal_psnr": sel.measured_temporal_psnr, "speedup": sel.measured_speedup,
                        "predicted_psnr": sel.predicted_psnr, "visible": bool(sel.visible_artifacts),
                        "key": json.dumps(sel.key)})
    return out


def nearest(rows: list[dict], threshold: float, each: int = 2) -> list[dict]:
    """The ``each`` rows just below ``threshold`` and the ``each`` just above it (distinct
    scenes and choices), lowest FLIP first."""
    below = sorted((r for r in rows if r["flip"] < threshold), key=lambda r: threshold - r["flip"])[:each]
    above = sorted((r for r in rows if r["flip"] >= threshold), key=lambda r: r["flip"] - threshold)[:each]
    return sorted(below + above, key=lambda r: r["flip"])


def render_row(row: dict, at: int = None) -> tuple[np.ndarray, float, int]:
    """(original | cached | FLIP map) of one validated choice at its shown frame (``at``, else the
    session's middle; at least two refresh periods in), and the frame's mean FLIP and index."""
    import flip_evaluator

    from rrcache.harness.cached import CachedRenderer
    from rrcache.harness.renderer import Renderer
    from rrcache.pipeline import variant_for_selection
    from rrcache.profiles import load_profile
    from rrcache.choice import load_work

    prof = load_profile(row["profile"])
    sel = next(s for s in list(prof.measured) + list(prof.selections) if json.dumps(s.key) == row["key"])
    work, session = load_work(prof)
    variant, period = variant_for_selection(work, sel.replace(algorithm=sel.algorithm or prof.algorithm))
    start = int(session.frames) // 2 if at is None else int(at)
    frame = min(int(session.frames) - 1, max(start, 2 * int(period or 1) + 2))
    with CachedRenderer(variant, session, work.prepared, session.resolution, period=period,
                        **prof.settings.cache_options()) as cached, \
            Renderer(work.prepared, session, session.resolution) as original:
        cached.reset()
        for index in range(frame + 1):
            got = cached.render_frame(index)
        ref = original.render_frame(frame)
    a = np.ascontiguousarray(np.clip(ref.image[..., :3], 0, 1), dtype=np.float32)
    b = np.ascontiguousarray(np.clip(got.image[..., :3], 0, 1), dtype=np.float32)
    fmap, mean, _ = flip_evaluator.evaluate(a, b, "LDR", applyMagma=True)
    return np.concatenate([a, b, np.clip(fmap, 0, 1)], axis=1), float(mean), frame


def sheet(rows: list[dict], out: Path, threshold: float, at: int = None) -> list[dict]:
    """Write the rows' images as one PNG (each row labelled) and return the rows with their frame
    (``at``: see :func:`render_row`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    images = [render_row(r, at) for r in rows]
    fig, axes = plt.subplots(len(rows), 1, figsize=(12, 3.6 * len(rows)), squeeze=False)
    for ax, row, (image, frame_flip, frame) in zip(axes[:, 0], rows, images):
        ax.imshow(image, interpolation="nearest")
        ax.set_axis_off()
        side = "at or above" if row["flip"] >= threshold else "below"
        ax.set_title(f"{row['scene']} {row['choice']} ({row['run']}): mean FLIP {row['flip']:.3f} over the session "
                     f"({side} {threshold:g}), PSNR {row['psnr']:.1f} dB; frame {frame} (FLIP {frame_flip:.3f}): "
                     "original | cached | FLIP map", fontsize=9)
        row["frame"], row["frame_flip"] = frame, frame_flip
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=80)
    plt.close(fig)
    # a 256-colour palette (no dithering) keeps a four-row sheet near 250 KB for docs/
    from PIL import Image

    with Image.open(out) as image:
        small = image.convert("RGB").quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    small.save(out, optimize=True)
    return rows


def main(argv=None) -> int:
    from rrcache.model.levels import VISIBLE_FLIP

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("profiles", nargs="+", type=Path)
    parser.add_argument("--out", type=Path, default=Path("docs/levels_flip_threshold.png"))
    parser.add_argument("--json", type=Path, default=None, help="write every validated choice's figures here")
    parser.add_argument("--no-sheet", action="store_true", help="only the table: render no images")
    parser.add_argument("--frame", type=int, default=None,
                        help="the frame shown (at least two refresh periods in; default: the session's middle); "
                             "an earlier one renders fewer frames of a costly shader")
    args = parser.parse_args(argv)
    done = [p for p in args.profiles if (p / "profile.json").is_file()]
    for p in args.profiles:
        if p not in done:
            print(f"note: {p}: skipped, no profile.json yet (still running, or interrupted)", file=sys.stderr)
    rows = validated(done)
    picked = nearest(rows, VISIBLE_FLIP)
    if not args.no_sheet:
        picked = sheet(picked, args.out, VISIBLE_FLIP, args.frame)
    if args.json is not None:
        args.json.write_text(json.dumps({"threshold": VISIBLE_FLIP, "validated": rows, "shown": picked}, indent=1))
    print(markdown(rows, picked))
    return 0


def markdown(rows: list[dict], picked: list[dict]) -> str:
    """Every validated choice, lowest mean FLIP first, as a Markdown table (PSNR and FLIP side
    by side, each with its uncertainty); the ones the sheet shows marked."""
    def pm(value, u, fmt):
        return "–" if value is None else fmt.format(value) + ("" if not u else " ± " + fmt.format(u))

    shown = {(r["profile"], r["key"]) for r in picked}
    lines = ["| scene | run | level | choice | PSNR dB (predicted) | mean FLIP | temporal PSNR dB | speed-up | "
             "in the sheet |", "|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: r["flip"]):
        psnr = pm(r["psnr"], r["psnr_uncertainty"], "{:.1f}") + (
            "" if r["predicted_psnr"] is None else f" ({r['predicted_psnr']:.1f})")
        lines.append(f"| {r['scene']} | {r['run']} | {r['label']} | {r['choice']} | {psnr} | "
                     f"{pm(r['flip'], r['flip_uncertainty'], '{:.3f}')}{' (visible)' if r['visible'] else ''} | "
                     f"{'–' if r['temporal_psnr'] is None else format(r['temporal_psnr'], '.1f')} | "
                     f"{'–' if r['speedup'] is None else format(r['speedup'], '.2f') + '×'} | "
                     f"{'yes' if (r['profile'], r['key']) in shown else ''} |")
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
