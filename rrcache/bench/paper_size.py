"""The bench's chosen selections measured again at the paper's size (main paper §5: 640×480, about
150 frames): ``python -m rrcache.bench.paper_size BENCH_OUT --scenes chess``.

``rrcache bench`` runs chess at 320×240 over its first 60 frames (a frame of the original costs
about a second and a half at 640×480 on two cores), so its speed-up and hit rate are those of the
reduced size. This takes the selections the bench shipped (``BENCH_OUT/bench.json``), compiles
them as the bench did (the scene's profile in ``BENCH_OUT/<scene>.rrprofile`` gives the cache
filter), and measures each beside the original over every frame of the scene's own session
(:data:`rrcache.bench.scenes.PAPER_SCENES`) at its own resolution, as the bench measures (the
original and the variant alternating frame by frame, ``rgba8`` colour targets, the speed-up the
ratio of median frame times), with the all-hit limit of a single cached node at that size too.
The table puts each figure beside the bench's, so what resolution does to the hit rate (the band
along silhouettes is a pixel or two wide at any size, so it is a smaller share of the pixels at
640×480) and to the speed-up can be read off.
"""
from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Optional

from rrcache.bench.scenes import PAPER_SCENES, default_root


@dataclass
class SizeRow:
    scene: str
    label: str
    what: str
    bench_resolution: tuple
    bench_frames: int
    bench_speedup: float
    bench_psnr: float
    bench_hit_rate: float
    resolution: tuple
    frames: int
    speedup: float
    psnr: float
    mean_error: float
    hit_rate: float
    ms: float
    original_ms: float
    speedup_ci95: tuple = ()
    noise: float = float("nan")
    limit_speedup: Optional[float] = None
    bench_limit_speedup: Optional[float] = None
    filter: str = "bilinear"


@dataclass
class SizeResult:
    bench_out: str
    started: str
    wall_s: float = 0.0
    rows: list = field(default_factory=list)

    def to_json(self) -> dict:
        from rrcache.jsonable import finite_json

        return finite_json({"bench_out": self.bench_out, "started": self.started, "wall_s": self.wall_s,
                            "rows": [asdict(r) for r in self.rows]})

    def markdown(self) -> str:
        lines = ["| scene | level | selection | filter | size, frames | speed-up | PSNR dB | hit rate | all-hit limit |",
                 "|---|---|---|---|---|---|---|---|---|"]
        for r in self.rows:
            bw, bh = r.bench_resolution
            w, h = r.resolution
            lim = f"{r.bench_limit_speedup:.2f}×" if r.bench_limit_speedup else "–"
            lines.append(f"| {r.scene} | {r.label} | `{r.what}` | {r.filter} | {bw}×{bh}, {r.bench_frames} (bench) | "
                         f"{r.bench_speedup:.2f}× | {r.bench_psnr:.1f} | {r.bench_hit_rate:.3f} | {lim} |")
            lim = f"{r.limit_speedup:.2f}×" if r.limit_speedup else "–"
            lo, hi = (r.speedup_ci95 or (float("nan"), float("nan")))
            lines.append(f"| {r.scene} | {r.label} | `{r.what}` | {r.filter} | {w}×{h}, {r.frames} | "
                         f"**{r.speedup:.2f}×** ({lo:.2f}–{hi:.2f}) | **{r.psnr:.1f}** | {r.hit_rate:.3f} | {lim} |")
        return "\n".join(lines)


def _selection(doc: dict):
    from rrcache.selection import Selection, parts_from_json

    parts = parts_from_json(doc["parts"], f"selections[{doc.get('label')}].parts")
    return Selection(parts, float("nan"), float("nan"), float("nan"), label=doc.get("label"),
                     algorithm=doc.get("algorithm"))


def run(bench_out, scenes=("chess",), labels=("e3",), frames: Optional[int] = None, progress=print,
        limit: bool = True) -> SizeResult:
    """Measure the bench's selections ``labels`` of ``scenes`` at their sessions' own size (see
    the module docstring); ``frames``: the first N frames instead of all."""
    from rrcache.harness.cached import compare
    from rrcache.harness.limit import all_hit_limit, probe_frames
    from rrcache.pipeline import load_for_session, variant_for_selection
    from rrcache.profiles import load_profile
    from rrcache.session import load_session

    bench_out = Path(bench_out)
    from rrcache.files import read_bytes

    doc = json.loads(read_bytes(bench_out / "bench.json", None))
    result = SizeResult(str(bench_out), time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()))
    t0 = time.time()
    root = default_root()
    for scene in doc["scenes"]:
        if scene["name"] not in scenes:
            continue
        # a paper scene's own session (the bench may have run a smaller copy); another scene's as benched
        shader, session_path = ((str(root / p) for p in PAPER_SCENES[scene["name"]]) if scene["name"] in PAPER_SCENES
                                else (scene["shader"], scene["session"]))
        prof = load_profile(scene["profile"])
        session = load_session(session_path)
        work = load_for_session(shader, session, term_scores=prof.term_scores)
        work.filter = prof.filter
        indices = list(range(session.frames if frames is None else min(frames, session.frames)))
        for sel_doc in scene["selections"]:
            if sel_doc.get("label") not in labels or not sel_doc.get("parts"):
                continue
            sel = _selection(sel_doc)
            variant, period = variant_for_selection(work, sel)
            progress(f"{scene['name']} {sel.label} {sel.describe()}: {len(indices)} frames at "
                     f"{session.resolution[0]}×{session.resolution[1]}")
            c = compare(variant, session, work.prepared, indices, period=period, color_format="rgba8",
                        **prof.settings.cache_options())
            row = SizeRow(scene["name"], sel.label, sel.describe(), tuple(scene["resolution"]), int(scene["frames"]),
                          float(sel_doc.get("measured_speedup") or math.nan), float(sel_doc.get("measured_psnr") or math.nan),
                          float(sel_doc.get("hit_rate") or math.nan), tuple(session.resolution), len(indices),
                          c.speedup, c.psnr, c.mean_error, c.hit_rate, c.ms_per_frame, c.original_ms_per_frame,
                          tuple(c.speedup_interval), c.noise, filter=prof.filter)
            if limit and sel.label == scene.get("medium"):
                row.bench_limit_speedup = scene.get("limit_speedup")
                lim = all_hit_limit(variant, session, work.prepared, probe_frames(indices), None, period=period,
                                    color_format="rgba8", **prof.settings.cache_options())
                row.limit_speedup = lim.original_median_ms / lim.limit_ms
            progress(f"  {row.speedup:.2f}× at {row.psnr:.1f} dB, hit rate {row.hit_rate:.3f} "
                     f"(bench: {row.bench_speedup:.2f}× at {row.bench_psnr:.1f} dB, {row.bench_hit_rate:.3f})")
            result.rows.append(row)
    result.wall_s = time.time() - t0
    return result


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m rrcache.bench.paper_size", description=__doc__.split("\n\n")[0])
    ap.add_argument("bench_out", help="the folder of a finished 'rrcache bench' (bench.json, <scene>.rrprofile)")
    ap.add_argument("--scenes", default="chess", help="comma-separated scene names (default: chess)")
    ap.add_argument("--labels", default="e3", help="comma-separated selection levels (default: e3)")
    ap.add_argument("--frames", type=int, default=None, help="only the first N frames (default: all)")
    ap.add_argument("--json", default=None, help="write the result here as JSON")
    args = ap.parse_args(argv)
    from rrcache.errors import RRCacheError

    if not (Path(args.bench_out) / "bench.json").is_file():
        print(f"{args.bench_out}: no bench.json here (give the --out folder of a finished 'rrcache bench')")
        return 2
    try:
        result = run(args.bench_out, tuple(args.scenes.split(",")), tuple(args.labels.split(",")), args.frames)
    except RRCacheError as err:
        print(str(err))
        return 2
    if args.json:
        from rrcache.atomic import write_text

        write_text(args.json, json.dumps(result.to_json(), indent=2) + "\n")
    print(result.markdown())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
