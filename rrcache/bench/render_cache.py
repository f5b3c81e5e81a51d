"""The render cache's measurements (issue 26; docs/render_cache.md): the equal-time comparison
on the bench scenes with its contact sheet and per-stage times, what a scattered sample mask
costs llvmpipe, and the tiled against the untiled z-buffer.

    python -m rrcache.bench.render_cache equal-time --choice marble=n2442:50 --out OUT
    python -m rrcache.bench.render_cache equal-time --bench BENCH_OUT --scene marble --out OUT
    python -m rrcache.bench.render_cache mask --scene marble --out OUT
    python -m rrcache.bench.render_cache zbuffer --scene marble --out OUT
    python -m rrcache.bench.render_cache sweep --scene marble --config block=1 --config block=2 --out OUT
    python -m rrcache.bench.render_cache projection --scene marble --out OUT
    python -m rrcache.bench.render_cache filters --scene marble --out OUT

``equal-time``: per scene, the reprojection cache's choice (``--choice NAME=NODE:PERIOD[+NODE:PERIOD]
[@ALGORITHM[/FILTER]]``: a bench profile's medium selection, e.g. from ``rrcache bench``'s table; or
``--bench BENCH_OUT --scene NAME``: the medium selection that run measured, compiled as it
compiled it, with its profile's filter) measured beside the original over the scene's frames; dynamic resolution and the render cache tuned to
its measured speed-up over the first ``--search-frames`` frames and measured beside the original
over the same frames (:func:`rrcache.bench.paper.dynres_row`,
:func:`rrcache.bench.paper.render_cache_row`, as ``rrcache bench`` does); one frame of each
(``--sheet-frame``, default the middle one) kept with its error for the contact sheet. Writes
``equal_time.json``, ``equal_time.md`` (the table, the render cache's per-stage times) and
``contact_sheet.png`` into ``--out`` after every scene, adding to the scenes already there (a
scene measured again replaces its row), so scenes can be measured one run each. Scenes are sized like ``rrcache bench``
(chess at 320×240 over its first 60 frames; the others at the session's size).

``mask``: the renderer's cost on llvmpipe: a frame shaded through a sample mask of a given
density (single pixels, 2×2 or 4×4 blocks) against the whole frame, side by side, repeated.

``zbuffer``: the z-buffer of a real point cache (the scene's first frames through the render cache)
untiled and bucket-sorted into tiles first (the paper's §3.2), side by side, repeated.

``projection``: where the projection and z-buffer of a real point cache run fastest here: numpy
(what the render cache uses), GL points drawn with the depth test, and a GL 4.3 compute shader
with image atomics (two passes: nearest depth, then the owner), side by side, repeated; every
variant checked to find the same nearest depth per pixel.

``filters``: where the depth cull, the 3×3 interpolation with the priority image and the 7×7
prefilter run fastest here: numpy (what the render cache uses) against the same filters as GL
fragment passes (the projected points uploaded, the cull, the interpolation writing the image and
the priority, the prefilter as two separable 7-tap passes composed where the 3×3 filter found
nothing, the priority read back for the dither), on the projected points of a real frame, side by
side, repeated; the GL image is checked against numpy's.

``sweep``: the render cache's own settings compared: each ``--config`` (settings given as
``key=value,...``) at each ``--shares`` share, beside the original over the first ``--frames``
frames: error and speed-up per point (``sweep.json``, ``sweep.png``: error against frame time),
which is how its defaults were chosen (docs/render_cache.md).

Timings are ratios measured side by side in one run; the machine's load is recorded beside them.
"""
from __future__ import annotations

import argparse
import io
import json
import os
import statistics
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from rrcache.bench.scenes import resolve_scenes, scaled_session
from rrcache.errors import RRCacheError
from rrcache.gl.program import fullscreen_vertex
from rrcache.report.agg import save_figure

#: how ``rrcache bench`` sizes each scene (its FULL settings): chess smaller and shorter
SCENE_SIZES = {"chess": ((320, 240), 60)}


@dataclass
class Choice:
    """The reprojection cache's choice for a scene: nodes with their periods, the algorithm and the
    cache filter (None: the default)."""

    nodes: list
    periods: list
    algorithm: str = "two-pass"
    filter: Optional[str] = None

    @classmethod
    def parse(cls, text: str) -> "Choice":
        """``NODE:PERIOD[+NODE:PERIOD...][@ALGORITHM[/FILTER]]``.

        >>> Choice.parse("n215:50+n108:50@three-pass")
        Choice(nodes=['n215', 'n108'], periods=[50, 50], algorithm='three-pass', filter=None)
        >>> Choice.parse("n324:3@three-pass/plane").describe()
        'n324 Δn=3, three-pass, plane filter'
        """
        from rrcache.runtime.glsl import FILTERS

        body, _, tail = text.partition("@")
        algorithm, _, filter_ = tail.partition("/")
        nodes, periods = [], []
        for part in body.split("+"):
            node, sep, period = part.partition(":")
            if not sep or not node.strip() or not period.strip().isdigit():
                raise RRCacheError(f"{text!r} is not a choice", "--choice",
                                   hint="give NAME=NODE:PERIOD, several nodes joined by +, optionally "
                                        "@ALGORITHM or @ALGORITHM/FILTER")
            nodes.append(node.strip())
            periods.append(int(period))
        filter_ = filter_.strip() or None
        if filter_ is not None and filter_ not in FILTERS:
            raise RRCacheError(f"{text!r}: {filter_!r} is not a cache filter", "--choice",
                               hint=f"give one of {', '.join(FILTERS)}")
        return cls(nodes, periods, algorithm.strip() or "two-pass", filter_)

    def describe(self) -> str:
        return (" + ".join(f"{n} Δn={p}" for n, p in zip(self.nodes, self.periods)) + f", {self.algorithm}"
                + (f", {self.filter} filter" if self.filter else ""))


@dataclass
class SceneComparison:
    name: str
    resolution: tuple
    frames: int
    choice: str
    texts: list
    target_speedup: float
    rows: list = field(default_factory=list)
    sheet_frame: int = 0
    sheet: dict = field(default_factory=dict)  # method -> (error, psnr) of the sheet frame
    load: str = ""
    wall_s: float = 0.0


def _sizes(scene, out) -> str:
    """The session the comparison runs: the scene's own, or chess as ``rrcache bench`` runs it
    (a scaled copy in ``out/sessions``)."""
    from rrcache.session import load_session

    if scene.name not in SCENE_SIZES:
        return scene.session
    size, frames = SCENE_SIZES[scene.name]
    session = load_session(scene.session)
    return str(scaled_session(scene.session, Path(out) / "sessions" / f"{scene.name}.json", size,
                              min(frames, session.frames)))


def _side_by_side(variants: list, repeats: int) -> dict:
    """Median ms of each ``(name, function)`` in ``variants``, run in turn ``repeats`` times (after
    one untimed call each)."""
    for _, fn in variants:
        fn()
    times = {name: [] for name, _ in variants}
    for _ in range(repeats):
        for name, fn in variants:
            start = time.perf_counter()
            fn()
            times[name].append((time.perf_counter() - start) * 1000.0)
    return {name: statistics.median(t) for name, t in times.items()}


def _load() -> str:
    try:
        return " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "unknown"


@dataclass
class _Cached:
    """What the reprojection cache runs in an equal-time comparison: the session and work it
    renders, its compiled variant and period(s), its description, the cached nodes' texts and the
    cache's run-time options."""

    session: object
    work: object
    variant: object
    period: object
    describe: str
    texts: list
    options: dict = field(default_factory=dict)


def _from_choice(scene, choice: Choice, out) -> _Cached:
    """The reprojection cache of ``--choice``: compiled with its filter (else the default)."""
    from rrcache.pipeline import load_for_session, variant_for, variant_for_nodes
    from rrcache.session import load_session

    session = load_session(_sizes(scene, out))
    work = load_for_session(scene.shader, session)
    if choice.filter is not None:
        work.filter = choice.filter
    texts = [work.node(n).text for n in choice.nodes]
    if len(choice.nodes) == 1:
        variant, period = variant_for(work, choice.nodes[0], choice.algorithm), choice.periods[0]
    else:
        variant, period = variant_for_nodes(work, choice.nodes, choice.algorithm), tuple(choice.periods)
    return _Cached(session, work, variant, period, choice.describe(), texts)


def _from_bench(bench_out, scene) -> _Cached:
    """The medium selection ``rrcache bench`` measured for scene ``name`` (``BENCH_OUT/bench.json``),
    compiled as the bench compiled it: over the session it ran (chess: its smaller copy), with the
    scene profile's cache filter, term order and cache options."""
    from rrcache.bench.paper_size import _selection
    from rrcache.files import read_bytes
    from rrcache.pipeline import load_for_session, variant_for_selection
    from rrcache.profiles import load_profile
    from rrcache.session import load_session

    bench_out = Path(bench_out)
    doc = json.loads(read_bytes(bench_out / "bench.json", None))
    name = scene.name
    record = next((s for s in doc.get("scenes", []) if s.get("name") == name), None)
    if record is None:
        raise RRCacheError(f"no scene {name!r} in the bench's results (yet)", str(bench_out / "bench.json"),
                           hint="wait until rrcache bench has finished the scene, or give --choice")
    medium = record.get("medium")
    sel_doc = next((s for s in record.get("selections", []) if medium and s.get("label") == medium), None)
    if sel_doc is None or not sel_doc.get("parts"):
        raise RRCacheError(f"scene {name!r} has no medium selection that caches something",
                           str(bench_out / "bench.json"), hint="give --choice NAME=NODE:PERIOD instead")
    prof = load_profile(_bench_path(bench_out, record["profile"]))
    session = load_session(_bench_path(bench_out, record["session"], scene.session))
    shader = _bench_path(bench_out, record["shader"], scene.shader)
    work = load_for_session(shader, session, term_scores=prof.term_scores)
    work.filter = prof.filter
    sel = _selection(sel_doc)
    variant, period = variant_for_selection(work, sel)
    texts = [work.node(n).text for n in sel.nodes]
    measured = sel_doc.get("measured_speedup")
    describe = (f"{medium}: {sel.describe()}, {sel.algorithm or 'three-pass'}, {prof.filter} filter"
                + (f" (the bench measured {measured:.2f}×)" if measured else ""))
    return _Cached(session, work, variant, period, describe, texts, dict(prof.settings.cache_options()))


def _bench_path(bench_out: Path, text: str, fallback=None) -> str:
    """A file the bench recorded (``text``: as it wrote it, maybe relative to where it ran): as
    written when it exists, else the same name in ``bench_out`` (a profile) or
    ``bench_out/sessions`` (a session it scaled), else ``fallback`` (the scene's own file)."""
    path = Path(text)
    if path.exists():
        return str(path)
    inside = bench_out / path.name if path.suffix == ".rrprofile" else bench_out / "sessions" / path.name
    if inside.exists() or fallback is None:
        return str(inside)
    return str(fallback)


def equal_time(scene, choice, out, search_frames: int = 24, sheet_frame: Optional[int] = None,
               progress=print) -> tuple[SceneComparison, dict]:
    """The equal-time comparison of one scene (see the module docstring); ``choice``: a
    :class:`Choice`, or the folder of an ``rrcache bench`` run whose medium selection of the scene
    is measured. Returns it and the sheet frame's images (method → H×W×4)."""
    from rrcache.bench.paper import BenchSettings, MethodRow, dynres_row, render_cache_row
    from rrcache.harness.cached import compare

    started = time.time()
    cached_setup = _from_choice(scene, choice, out) if isinstance(choice, Choice) else _from_bench(choice, scene)
    session, work = cached_setup.session, cached_setup.work
    frames = list(range(session.frames))
    keep = frames[len(frames) // 2] if sheet_frame is None else min(int(sheet_frame), frames[-1])
    images: dict = {}

    def capture(method):
        def on_frame(row, got, ref):
            if row.index == keep:
                images[method] = got.image.copy()
                images["original"] = ref.image.copy()
                result.sheet[method] = (float(row.mean_error), float(row.psnr))
        return on_frame

    result = SceneComparison(scene.name, tuple(session.resolution), len(frames), cached_setup.describe,
                             cached_setup.texts, 0.0, sheet_frame=keep, load=_load())
    progress(f"{scene.name}: reprojection cache {cached_setup.describe}")
    cached = compare(cached_setup.variant, session, work.prepared, frames, period=cached_setup.period,
                     on_frame=capture("reprojection cache"), **cached_setup.options)
    target = cached.speedup
    result.target_speedup = target
    result.rows.append(MethodRow("reprojection cache (ours)", cached_setup.describe, cached.speedup,
                                 cached.mean_error, min(cached.psnr, 100.0), cached.ms_per_frame,
                                 cached.original_ms_per_frame, True))
    settings = BenchSettings(search_frames=search_frames)
    search = frames[:search_frames]
    say = lambda stage, done=None, total=None: progress(f"{scene.name}: {stage}")  # noqa: E731
    result.rows.append(dynres_row(work, session, frames, search, target, settings, say,
                                  on_frame=capture("dynamic resolution")))
    result.rows.append(render_cache_row(work, session, frames, search, target, settings, say,
                                        on_frame=capture("render cache")))
    result.wall_s = time.time() - started
    return result, images


def _markdown(results: list) -> str:
    from rrcache.bench.paper_report import _f

    lines = ["# The render cache at equal time", "",
             "Each row measured beside the original in the same run (speed-up: ratio of median frame times); "
             "error: mean RGB L2 over the original's covered pixels; PSNR over the whole frame. Dynamic resolution "
             "and the render cache are tuned to the reprojection cache's measured speed-up.", "",
             "| scene | method | setting | speed-up | mean error | PSNR dB | ms | original ms |",
             "|---|---|---|---|---|---|---|---|"]
    for r in results:
        w, h = r.resolution
        for row in r.rows:
            flag = "" if row.matched in (None, True) else " (not within 5% of the target)"
            lines.append(f"| {r.name} ({w}×{h}, {r.frames} frames) | {row.method}{flag} | {row.setting} | "
                         f"{_f(row.speedup, '.2f')}× | {_f(row.mean_error, '.4f')} | {_f(row.psnr, '.1f')} | "
                         f"{_f(row.ms, '.2f')} | {_f(row.original_ms, '.2f')} |")
    lines += ["", "## The render cache's time per stage (median ms per frame at the tuned share)", ""]
    stages = None
    for r in results:
        row = next((x for x in r.rows if getattr(x, "stages", None)), None)
        if row is None:
            continue
        if stages is None:
            stages = list(row.stages)
            lines += ["| scene | " + " | ".join(stages) + " | total |", "|---" * (len(stages) + 2) + "|"]
        total = sum(row.stages.values())
        lines.append(f"| {r.name} | " + " | ".join(f"{row.stages[s]:.2f}" for s in stages) + f" | {total:.2f} |")
    lines += ["", "Load averages (1, 5, 15 min) when each scene started: "
              + "; ".join(f"{r.name} {r.load}" for r in results) + "."]
    for r in results:
        lines.append(f"- {r.name}: the reprojection cache caches {' and '.join('`' + t + '`' for t in r.texts)}; "
                     f"{r.wall_s:.0f} s.")
    return "\n".join(lines) + "\n"


#: the error maps' gain: |image − original| × this, per channel
ERROR_GAIN = 4.0


def contact_sheet(results: list, images: dict, path) -> str:
    """Two rows per scene: the original, the reprojection cache, the render cache and dynamic
    resolution at the scene's sheet frame, each titled with its error and PSNR; under each
    method its error map (``|image − original| ×`` :data:`ERROR_GAIN`)."""
    from rrcache.report.agg import agg_pyplot

    plt = agg_pyplot()
    methods = ["original", "reprojection cache", "render cache", "dynamic resolution"]
    fig, axes = plt.subplots(2 * len(results), len(methods), figsize=(3.2 * len(methods), 5.0 * len(results)),
                             dpi=100, squeeze=False)
    try:
        for i, r in enumerate(results):
            shots = images.get(r.name, {})
            original = shots.get("original")
            for j, method in enumerate(methods):
                top, bottom = axes[2 * i][j], axes[2 * i + 1][j]
                for ax in (top, bottom):
                    ax.set_xticks([])
                    ax.set_yticks([])
                image = shots.get(method)
                if image is None:
                    top.set_title(f"{method}: not measured", fontsize=8)
                    bottom.axis("off")
                    continue
                top.imshow(np.clip(np.nan_to_num(image[..., :3]), 0, 1), interpolation="nearest")
                if method == "original":
                    top.set_title(f"{r.name}, frame {r.sheet_frame}: original", fontsize=8)
                    bottom.axis("off")
                    continue
                err, db = r.sheet[method]  # an exact image's PSNR is infinite (null once written)
                db_text = "∞" if db is None or db == float("inf") else f"{db:.1f}"
                top.set_title(f"{method}: error {err:.4f}, {db_text} dB", fontsize=8)
                diff = np.abs(np.nan_to_num(image[..., :3]) - np.nan_to_num(original[..., :3])) * ERROR_GAIN
                bottom.imshow(np.clip(diff, 0, 1), interpolation="nearest")
                bottom.set_title(f"|{method} − original| × {ERROR_GAIN:g}", fontsize=7)
        fig.tight_layout()
        save_figure(fig, path)
    finally:
        plt.close(fig)
    return str(path)


def _write(out: Path, result: SceneComparison, shots: dict) -> list:
    """Add ``result`` (replacing a scene of the same name) to ``equal_time.json`` in ``out``, keep
    its sheet frame's images (``sheet/<scene>.npz``), and rewrite the table and the contact sheet
    from every scene there (so runs of one scene each add up, and an interrupted run keeps what
    it finished). Returns the scenes."""
    from rrcache.atomic import write_bytes, write_text
    from rrcache.bench.paper import MethodRow
    from rrcache.jsonable import finite_json

    from rrcache.files import read_bytes

    path = out / "equal_time.json"
    scenes = json.loads(read_bytes(path, None))["scenes"] if path.is_file() else []
    record = dict(name=result.name, resolution=list(result.resolution), frames=result.frames, choice=result.choice,
                  texts=result.texts, target_speedup=result.target_speedup, sheet_frame=result.sheet_frame,
                  sheet=result.sheet, load=result.load, wall_s=result.wall_s, rows=[vars(row) for row in result.rows])
    scenes = [s for s in scenes if s["name"] != result.name] + [finite_json(record)]
    write_text(path, json.dumps({"rrcache_render_cache_bench": 1, "scenes": scenes}, indent=2, ensure_ascii=False)
               + "\n")
    (out / "sheet").mkdir(exist_ok=True)
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **{k.replace(" ", "_"): v for k, v in shots.items()})
    write_bytes(out / "sheet" / f"{result.name}.npz", buffer.getvalue())
    results, images = [], {}
    for s in scenes:
        rows = [MethodRow(**row) for row in s["rows"]]
        results.append(SceneComparison(s["name"], tuple(s["resolution"]), s["frames"], s["choice"], s["texts"],
                                       s["target_speedup"], rows, s["sheet_frame"],
                                       {k: tuple(v) for k, v in s["sheet"].items()}, s["load"], s["wall_s"]))
        stored = out / "sheet" / f"{s['name']}.npz"
        if stored.is_file():
            with np.load(io.BytesIO(read_bytes(stored, None)), allow_pickle=False) as data:
                images[s["name"]] = {k.replace("_", " "): data[k] for k in data.files}
    write_text(out / "equal_time.md", _markdown(results))
    contact_sheet(results, images, out / "contact_sheet.png")
    return results


_POINTS_VERTEX = """#version 330 core
in vec3 a_position;
uniform mat4 rr_viewProjection;
out float v_slot;
void main() {
    gl_Position = rr_viewProjection * vec4(a_position, 1.0);
    gl_PointSize = 1.0;
    v_slot = float(gl_VertexID);
}
"""
_POINTS_FRAGMENT = """#version 330 core
in float v_slot;
out vec4 rr_out;
void main() { rr_out = vec4(v_slot); }
"""
_COMPUTE = """#version 430
layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer Points { vec4 p[]; };
layout(r32ui, binding = 0) uniform uimage2D rr_depth;
layout(r32i, binding = 1) uniform iimage2D rr_owner;
uniform mat4 rr_screen;
uniform int rr_count;
uniform int rr_pass;
uniform ivec2 rr_size;
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= rr_count) return;
    vec4 c = rr_screen * vec4(p[i].xyz, 1.0);
    if (!(c.w > 0.0)) return;
    ivec2 px = ivec2(floor(c.xy / c.w));
    if (px.x < 0 || px.y < 0 || px.x >= rr_size.x || px.y >= rr_size.y) return;
    uint d = floatBitsToUint(c.w);
    if (rr_pass == 0) imageAtomicMin(rr_depth, px, d);
    else if (imageLoad(rr_depth, px).x == d) imageStore(rr_owner, px, ivec4(i));
}
"""


def projection_cost(scene, out, repeats: int = 9, frames: int = 8, samples: float = 0.03) -> dict:
    """numpy, GL points and a compute shader projecting and z-buffering one point cache (see the
    module docstring)."""
    import moderngl

    from rrcache.alternatives.render_cache import RenderCacheRenderer, RenderCacheSettings
    from rrcache.alternatives.render_cache.projection import zbuffer
    from rrcache.gl.resources import GLScope
    from rrcache.compiler.prepared import prepare_file
    from rrcache.session import load_session

    session = load_session(_sizes(scene, out))
    prepared = prepare_file(scene.shader, session)
    with RenderCacheRenderer(prepared, session, settings=RenderCacheSettings(samples=samples)) as rc, GLScope() as scope:
        for i in range(frames):
            rc.render_frame(i)
        ctx, cache, (w, h) = rc.ctx, rc.cache, rc.size
        if rc.shader.moving:
            raise RRCacheError("the projection comparison takes a scene whose objects stand still", scene.name)
        live = np.flatnonzero(cache.live())
        points = np.stack([cache.x[live], cache.y[live], cache.z[live]], axis=1).astype(np.float32)
        cam = session.camera_at(frames - 1)
        view_projection = cam.projection(w / h) @ cam.view
        screen, moving = rc._matrices(frames - 1)

        def numpy_way():
            pix, depth, slots = rc.projector.project(cache, screen, rc.size, moving)
            return zbuffer(pix, depth, slots, w * h)[1]

        program = scope.own(ctx.program(vertex_shader=_POINTS_VERTEX, fragment_shader=_POINTS_FRAGMENT))
        program["rr_viewProjection"].write(view_projection.T.astype("f4").tobytes())
        vbo = scope.own(ctx.buffer(points.tobytes()))
        vao = scope.own(ctx.vertex_array(program, [(vbo, "3f", "a_position")]))
        target = scope.own(ctx.texture((w, h), 4, dtype="f4"))
        depth_texture = scope.own(ctx.depth_texture((w, h)))
        fbo = scope.own(ctx.framebuffer([target], depth_texture))

        def points_way():
            fbo.use()
            fbo.viewport = (0, 0, w, h)
            fbo.clear(depth=1.0)
            ctx.enable(moderngl.DEPTH_TEST)
            ctx.depth_func = "<"
            vao.render(moderngl.POINTS)
            ctx.finish()

        variants = [("numpy (project + z-buffer)", numpy_way), ("GL points, depth test", points_way)]
        if ctx.version_code >= 430:
            compute = scope.own(ctx.compute_shader(_COMPUTE))
            compute["rr_screen"].write(screen_matrix4(screen).T.astype("f4").tobytes())
            compute["rr_count"].value = len(points)
            compute["rr_size"].value = (w, h)
            ssbo = scope.own(ctx.buffer(np.c_[points, np.ones(len(points), np.float32)].astype(np.float32).tobytes()))
            depth_image = scope.own(ctx.texture((w, h), 1, dtype="u4"))
            owner_image = scope.own(ctx.texture((w, h), 1, dtype="i4"))
            far = np.full(w * h, 0xFFFFFFFF, np.uint32).tobytes()
            nobody = np.full(w * h, -1, np.int32).tobytes()
            groups = (len(points) + 63) // 64

            def compute_way():
                ssbo.bind_to_storage_buffer(0)
                depth_image.bind_to_image(0, read=True, write=True)
                owner_image.bind_to_image(1, read=False, write=True)
                depth_image.write(far)
                owner_image.write(nobody)
                compute["rr_pass"].value = 0
                compute.run(groups)
                ctx.memory_barrier()
                compute["rr_pass"].value = 1
                compute.run(groups)
                ctx.finish()
                return np.frombuffer(depth_image.read(), np.uint32).view(np.float32)

            variants.append(("GL compute, image atomics", compute_way))
            expected = numpy_way()
            got = compute_way()
            found = np.where(got.view(np.uint32) == 0xFFFFFFFF, np.inf, got)
            if not np.allclose(found, expected, rtol=1e-5, equal_nan=True):
                raise AssertionError("the compute shader's z-buffer differs from numpy's")
        ms = _side_by_side(variants, repeats)
    return {"scene": scene.name, "resolution": [w, h], "points": int(len(points)), "load": _load(), "ms": ms}


# the projected points: rgb = colour (0 where none), a = depth (0 where none; negative: shaded this
# frame, exempt from the cull)
_CULL = """#version 330 core
uniform sampler2D rr_points;
uniform float rr_tolerance;
out vec4 rr_kept;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 c = texelFetch(rr_points, p, 0);
    float total = 0.0, count = 0.0;
    for (int j = -1; j <= 1; j++)
        for (int i = -1; i <= 1; i++) {
            float d = abs(texelFetch(rr_points, p + ivec2(i, j), 0).a);
            if (d > 0.0) { total += d; count += 1.0; }
        }
    bool keep = c.a < 0.0 || (c.a > 0.0 && c.a * count <= (1.0 + rr_tolerance) * total);
    rr_kept = keep ? vec4(c.rgb, 1.0) : vec4(0.0);
}
"""
_INTERPOLATE = """#version 330 core
uniform sampler2D rr_kept;
uniform sampler2D rr_ages;
layout(location = 0) out vec4 rr_image;
layout(location = 1) out float rr_priority;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 own = texelFetch(rr_kept, p, 0);
    vec4 sum = vec4(0.0);
    for (int j = -1; j <= 1; j++)
        for (int i = -1; i <= 1; i++)
            sum += float((2 - abs(i)) * (2 - abs(j))) * texelFetch(rr_kept, p + ivec2(i, j), 0);
    rr_image = own.a > 0.0 ? vec4(own.rgb, 1.0) : (sum.a > 0.0 ? vec4(sum.rgb / sum.a, 1.0) : vec4(0.0));
    rr_priority = own.a > 0.0 ? texelFetch(rr_ages, p, 0).r / 255.0 : 1.0;
}
"""
_BOX_ROWS = """#version 330 core
uniform sampler2D rr_kept;
out vec4 rr_sum;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 s = vec4(0.0);
    for (int i = -3; i <= 3; i++) s += texelFetch(rr_kept, p + ivec2(i, 0), 0);
    rr_sum = s;
}
"""
_BOX_COLUMNS = """#version 330 core
uniform sampler2D rr_rows;
uniform sampler2D rr_image;
uniform sampler2D rr_previous;
out vec4 rr_final;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 image = texelFetch(rr_image, p, 0);
    if (image.a > 0.0) { rr_final = image; return; }
    vec4 s = vec4(0.0);
    for (int j = -3; j <= 3; j++) s += texelFetch(rr_rows, p + ivec2(0, j), 0);
    rr_final = s.a > 0.0 ? vec4(s.rgb / s.a, 1.0) : texelFetch(rr_previous, p, 0);
}
"""


def filters_cost(scene, out, repeats: int = 9, frames: int = 8, samples: float = 0.03) -> dict:
    """numpy against GL fragment passes for the depth cull, interpolation and prefilter (see the
    module docstring)."""
    import moderngl

    from rrcache.alternatives.render_cache import RenderCacheRenderer, RenderCacheSettings
    from rrcache.alternatives.render_cache.filters import depth_cull, reconstruct
    from rrcache.alternatives.render_cache.projection import zbuffer
    from rrcache.gl.resources import GLScope
    from rrcache.compiler.prepared import prepare_file
    from rrcache.session import load_session

    session = load_session(_sizes(scene, out))
    prepared = prepare_file(scene.shader, session)
    settings = RenderCacheSettings(samples=samples)
    with RenderCacheRenderer(prepared, session, settings=settings) as rc, GLScope() as scope:
        for i in range(frames):
            rc.render_frame(i)
        ctx, cache, (w, h) = rc.ctx, rc.cache, rc.size
        screen, moving = rc._matrices(frames - 1)
        pix, depth, slots = rc.projector.project(cache, screen, rc.size, moving)
        owner, nearest = zbuffer(pix, depth, slots, w * h)
        has = owner >= 0
        safe = np.where(has, owner, 0)
        colors = np.where(has, cache.color[:, safe], 0).astype(np.float32).reshape(3, h, w)
        ages_all = np.where(has, cache.age[safe], 0).astype(np.float32)
        exempt = (has & (cache.frame[safe] == frames - 1)).reshape(h, w)
        previous = rc._previous.copy()
        depth_image = np.where(has, nearest, 0).astype(np.float32).reshape(h, w)

        def numpy_way():
            keep = depth_cull(depth_image, has.reshape(h, w), settings.cull, exempt)
            kept_colors = colors * keep
            ages = np.where(keep, ages_all.reshape(h, w), 0).astype(np.float32)
            return reconstruct(kept_colors, keep, ages, previous)

        def target(components=4):
            t = scope.own(ctx.texture((w, h), components, dtype="f4"))
            t.filter = (moderngl.NEAREST, moderngl.NEAREST)
            t.repeat_x = t.repeat_y = False
            t.border_color = (0.0, 0.0, 0.0, 0.0)
            return t

        def program(fragment):
            return scope.own(ctx.program(vertex_shader=fullscreen_vertex(0.0), fragment_shader=fragment))

        points_tex, kept_tex, image_tex, rows_tex, final_tex, previous_tex = (target() for _ in range(6))
        ages_tex, priority_tex = target(1), target(1)
        cull, interpolate, box_rows, box_columns = (program(f) for f in (_CULL, _INTERPOLATE, _BOX_ROWS, _BOX_COLUMNS))
        cull["rr_tolerance"].value = settings.cull
        interpolate["rr_kept"].value, interpolate["rr_ages"].value = 0, 1
        box_columns["rr_rows"].value, box_columns["rr_image"].value, box_columns["rr_previous"].value = 0, 1, 2
        fbos = [scope.own(ctx.framebuffer(t)) for t in ([kept_tex], [image_tex, priority_tex], [rows_tex], [final_tex])]
        vaos = [scope.own(ctx.vertex_array(p, [])) for p in (cull, interpolate, box_rows, box_columns)]
        packed = np.empty((h, w, 4), np.float32)
        packed[..., :3] = np.moveaxis(colors, 0, -1)
        packed[..., 3] = np.where(exempt, -depth_image, depth_image)
        previous_rgba = np.ones((h, w, 4), np.float32)
        previous_rgba[..., :3] = np.moveaxis(previous, 0, -1)
        previous_tex.write(previous_rgba)

        def gl_way():
            ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
            points_tex.write(packed)
            ages_tex.write(ages_all)
            steps = [(0, [points_tex]), (1, [kept_tex, ages_tex]), (2, [kept_tex]), (3, [rows_tex, image_tex, previous_tex])]
            for (k, inputs), fbo in zip(steps, fbos):
                fbo.use()
                fbo.viewport = (0, 0, w, h)
                for unit, tex in enumerate(inputs):
                    tex.use(location=unit)
                vaos[k].render(moderngl.TRIANGLES, vertices=3)
            priority = np.frombuffer(priority_tex.read(), np.float32)
            ctx.finish()
            return priority

        image_np, priority_np, _ = numpy_way()
        priority_gl = gl_way()
        image_gl = np.frombuffer(final_tex.read(), np.float32).reshape(h, w, 4)[..., :3]
        if not (np.allclose(np.moveaxis(image_np, 0, -1), image_gl, atol=1e-4)
                and np.allclose(priority_np.reshape(-1), priority_gl, atol=1e-6)):
            raise AssertionError("the GL filters' image differs from numpy's")
        variants = [("numpy (cull, interpolate, prefilter)", numpy_way),
                    ("GL passes (upload, cull, interpolate, prefilter, read the priority)", gl_way)]
        ms = _side_by_side(variants, repeats)
    return {"scene": scene.name, "resolution": [w, h], "load": _load(), "ms": ms}


def screen_matrix4(screen: np.ndarray) -> np.ndarray:
    """The 3×4 screen matrix as a 4×4 whose third row is zero (the compute shader's ``c.w`` is row 4)."""
    m = np.zeros((4, 4))
    m[0], m[1], m[3] = screen[0], screen[1], screen[2]
    return m


def _config(text: str) -> dict:
    """``block=1,points_per_pixel=2`` → the settings' keyword arguments (typed as the defaults)."""
    from rrcache.alternatives.render_cache import RenderCacheSettings

    defaults = RenderCacheSettings()
    out = {}
    for item in filter(None, (t.strip() for t in text.split(","))):
        key, _, value = item.partition("=")
        if not hasattr(defaults, key):
            raise RRCacheError(f"{key!r} is not a render cache setting", "--config")
        kind = type(getattr(defaults, key))
        out[key] = value.lower() in ("1", "true", "yes") if kind is bool else kind(value)
    return out


def sweep(scene, out, configs: list, shares, frames: int = 40) -> dict:
    """Each config at each share beside the original (see the module docstring)."""
    from rrcache.alternatives.render_cache import RenderCacheSettings
    from rrcache.alternatives.render_cache.tune import compare
    from rrcache.compiler.prepared import prepare_file
    from rrcache.harness.renderer import Renderer
    from rrcache.session import load_session

    session = load_session(_sizes(scene, out))
    prepared = prepare_file(scene.shader, session)
    indices = list(range(min(frames, session.frames)))
    points = []
    with Renderer(prepared, session) as original:
        for config in configs:
            for share in shares:
                settings = RenderCacheSettings(**dict(config, samples=float(share))).checked()
                r = compare(prepared, session, indices, settings, original=original)
                points.append(dict(config=config, samples=share, speedup=r.speedup, mean_error=r.mean_error,
                                   psnr=r.psnr, ms=r.ms_per_frame, original_ms=r.original_ms_per_frame,
                                   stages=r.stages))
                print(f"{scene.name} {config} {share:g}: {r.speedup:.2f}× error {r.mean_error:.4f} "
                      f"{r.psnr:.1f} dB", flush=True)
    return {"scene": scene.name, "resolution": list(session.resolution), "frames": len(indices), "load": _load(),
            "points": points}


def _sweep_plot(doc: dict, path) -> None:
    from rrcache.report.agg import agg_pyplot

    plt = agg_pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=110)
    try:
        configs = []
        for p in doc["points"]:
            if p["config"] not in configs:
                configs.append(p["config"])
        for config in configs:
            pts = [p for p in doc["points"] if p["config"] == config]
            label = ", ".join(f"{k}={v}" for k, v in config.items()) or "defaults"
            ax.plot([1 / p["speedup"] for p in pts], [p["mean_error"] for p in pts], "o-", label=label)
            for p in pts:
                ax.annotate(f"{p['samples']:g}", (1 / p["speedup"], p["mean_error"]), fontsize=6,
                            textcoords="offset points", xytext=(3, 3))
        ax.set_xlabel("frame time / original frame time")
        ax.set_ylabel("mean RGB L2 error")
        w, h = doc["resolution"]
        ax.set_title(f"render cache settings on {doc['scene']} ({w}×{h}, {doc['frames']} frames; labels: share)",
                     fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        save_figure(fig, path)
    finally:
        plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m rrcache.bench.render_cache", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="what", required=True)
    eq = sub.add_parser("equal-time", help="the equal-time table, per-stage times and contact sheet")
    eq.add_argument("--choice", action="append", default=[], metavar="NAME=NODE:PERIOD",
                    help="a scene (a bench name or SHADER:SESSION) and the reprojection cache's choice for it")
    eq.add_argument("--bench", metavar="BENCH_OUT", default=None,
                    help="an rrcache bench output folder: measure its medium selection of each --scene")
    eq.add_argument("--scene", action="append", default=[], metavar="NAME",
                    help="with --bench: a scene of the bench's results (repeat for several)")
    eq.add_argument("--search-frames", type=int, default=24)
    eq.add_argument("--sheet-frame", type=int, default=None)
    eq.add_argument("--out", required=True)
    for name in ("mask", "zbuffer", "sweep", "projection", "filters"):
        p = sub.add_parser(name)
        p.add_argument("--scene", default="marble")
        p.add_argument("--out", required=True)
        if name == "sweep":
            p.add_argument("--config", action="append", default=None, metavar="KEY=VALUE,...")
            p.add_argument("--shares", default="0.005,0.01,0.02,0.04,0.08")
            p.add_argument("--frames", type=int, default=40)
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.what == "equal-time":
        if not args.choice and not (args.bench and args.scene):
            parser.error("give --choice NAME=NODE:PERIOD, or --bench BENCH_OUT with --scene NAME")
        if args.scene and not args.bench:
            parser.error("--scene takes --bench BENCH_OUT")
        jobs = []
        for item in args.choice:
            name, sep, spec = item.partition("=")
            if not sep:
                parser.error(f"--choice {item!r}: give NAME=NODE:PERIOD")
            jobs.append((name, Choice.parse(spec)))
        jobs += [(name, Path(args.bench)) for name in args.scene]
        for name, choice in jobs:
            (scene,) = resolve_scenes(name)
            result, shots = equal_time(scene, choice, out, args.search_frames, args.sheet_frame)
            _write(out, result, shots)
            print(f"{result.name}: done in {result.wall_s:.0f} s; {out / 'equal_time.md'} updated", flush=True)
        return 0
    (scene,) = resolve_scenes(args.scene)
    from rrcache.atomic import write_text

    if args.what == "sweep":
        doc = sweep(scene, out, [_config(c) for c in (args.config or [""])],
                    [float(x) for x in args.shares.split(",")], args.frames)
        _sweep_plot(doc, out / "sweep.png")
    else:
        doc = {"mask": mask_cost, "zbuffer": zbuffer_cost, "projection": projection_cost,
               "filters": filters_cost}[args.what](scene, out)

    write_text(out / f"{args.what}.json", json.dumps(doc, indent=2) + "\n")
    print(json.dumps(doc, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
