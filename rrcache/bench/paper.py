"""``rrcache bench``: the paper's results on its three scenes, end to end (issue 8; main paper
§5, Table 1, Figs. 7–10).

Per scene (:func:`run_scene`):

1. **Profile** (:func:`rrcache.profile`) into ``<out>/<scene>.rrprofile``; a second run with the
   same settings resumes from its store (``precompute_resumed`` says so). The precomputation
   time is the profile's ``precompute_s`` (the wall time of every invocation on its store added
   up, so earlier invocations count); ``training_s`` the seconds of its stored training runs. The profile is not validated (``validate=False``): the bench measures the four
   selections itself, below, in the same run as everything else.
2. **Size of the problem**: the static cost of the shader (our cost model,
   :mod:`rrcache.analysis.cost`, summed over every expression that contributes to the output
   colour of the analysed program, each counted once: :func:`rrcache.alternatives.simplify.static_cost`;
   the paper gives instruction counts instead) and the number of cacheable nodes.
3. **The four selections** e1..e4 rendered side by side with the original
   (:func:`rrcache.harness.cached.compare`) over the bench frames, ``repeats`` times: speed-up
   = median over the repeats of the ratio of median frame times; mean error (mean RGB L2 over
   covered pixels) and PSNR from the first repeat (the images do not depend on timing).
4. On the **medium selection** (e3, the threshold of the paper's Fig. 10; the nearest cached
   selection when e3 caches nothing): the three cache algorithms side by side and the cache's
   speed-up limit (every pixel hitting), through :func:`rrcache.bench.cache.run`.
5. **Equal time** (§5.4): dynamic resolution, the render cache of Walter et al. 2002 (its
   sample share) and simplification tuned to the medium selection's measured speed-up
   (:mod:`rrcache.alternatives`), then measured over the bench frames beside the original; error
   and PSNR of all of them. The simplification's candidates
   are the ``candidates`` costliest nodes whose cost is at most what the target allows to save
   (static cost taken as proportional to time, keeping at least half of ``cost / target``);
   a medium selection no faster than the original gets no equal-time comparison.

:func:`run` does every scene and rewrites ``bench.json`` and ``bench.md`` in ``out`` as each
scene finishes, so an interruption loses only the scene in flight (and its profile resumes).
``QUICK`` shrinks sessions, training and searches so the whole bench fits in a few minutes on
a two-core machine; its figures are not the paper's full run.
"""
from __future__ import annotations

import json
import math
import os
import statistics
import time
import warnings
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from rrcache import atomic
from rrcache.bench.scenes import Scene, scaled_session
from rrcache.errors import RRCacheError
from rrcache.jsonable import finite_json as _finite
from rrcache.selection import Selection

ProgressFn = Callable[[str, Optional[int], Optional[int]], None]
PSNR_CAP = 100.0
MEDIUM = "e3"


@dataclass(frozen=True)
class BenchSettings:
    """How much the bench does.

    - ``resolution``/``frames``: the session is scaled down to fit this size (aspect ratio kept)
      and cut to this frame count (None: as it is); ``scene_overrides`` per scene name (quick:
      chess smaller).
    - ``training``: keyword arguments of :class:`rrcache.profiles.TrainingSettings`.
    - ``repeats``: side-by-side runs per selection (speed-up: the median).
    - ``candidates``: the costliest nodes considered by the simplification; ``probe_frames``
      sample frames for its node means and errors, at ``probe_resolution`` (None: a quarter).
    - ``search_frames``: frames per equal-time search step; ``tolerance`` the relative speed-up
      tolerance; ``max_steps`` of the dynamic-resolution search; ``min_scale`` its lower end.
    - ``plots``: let the profiler write its plots; ``figures``: write the bench's own figure
      per scene (:mod:`rrcache.bench.paper_plots`).
    """

    quick: bool = False
    resolution: Optional[tuple] = None
    frames: Optional[int] = None
    training: dict = field(default_factory=lambda: {"validate": False})
    repeats: int = 3
    candidates: int = 24
    probe_frames: int = 6
    probe_resolution: Optional[tuple] = None
    search_frames: int = 24
    tolerance: float = 0.05
    max_steps: int = 8
    min_scale: float = 0.1
    plots: bool = True
    figures: bool = True
    scene_overrides: dict = field(default_factory=dict)

    def for_scene(self, name: str) -> "BenchSettings":
        over = self.scene_overrides.get(name)
        return replace(self, scene_overrides={}, **over) if over else self

    def to_json(self) -> dict:
        return _finite(asdict(self))


#: chess is ~1.4 s per frame at 640×480 (2 threads): its bench runs at 320×240 over the first 60
#: frames (the steady state of Δn = 50 and 10 frames more), one side-by-side run per selection,
#: so that the whole bench takes about an hour on a two-core machine; ``rrcache profile`` on the
#: full session gives its precomputation time at 640×480
FULL = BenchSettings(scene_overrides={"chess": {"repeats": 1, "resolution": (320, 240), "frames": 60}})
QUICK = BenchSettings(
    quick=True, resolution=(160, 120), frames=40,
    training={"periods": (2, 8, 16), "timing_frames": 4, "timing_periods": (2, 16), "budget_s": 15.0,
              "validate": False},
    repeats=1, candidates=8, probe_frames=2, probe_resolution=(40, 30), search_frames=8, tolerance=0.1,
    max_steps=4, plots=False,
    # the ambient-occlusion shader is ~50× the cost of the others per pixel
    scene_overrides={"chess": {"resolution": (64, 48), "frames": 20, "probe_resolution": (32, 24),
                               "search_frames": 5},
                     # the temple's 1024² shadow map is a fixed cost per frame: at 160×120 it outweighs
                     # the shading and the ceiling stopped the profile (0.50×) on a loaded machine
                     "temple": {"resolution": (320, 240), "frames": 30}},
)


@dataclass
class MethodRow:
    """One row of a side-by-side table: the cache algorithms, or the equal-time methods."""

    method: str
    setting: str
    speedup: float
    mean_error: float
    psnr: float
    ms: float
    original_ms: float
    matched: Optional[bool] = None
    steps: list = field(default_factory=list)
    #: the median ms of each stage of a frame (the render cache's row)
    stages: Optional[dict] = None


@dataclass
class SceneResult:
    name: str
    shader: str
    session: str
    resolution: tuple
    frames: int
    static_cost: int
    cacheable_nodes: int
    trained_nodes: int = 0
    precompute_s: Optional[float] = None
    training_s: Optional[float] = None
    precompute_resumed: bool = False
    profile_run_s: Optional[float] = None
    profile: Optional[str] = None
    original_ms: Optional[float] = None
    limit_speedup: Optional[float] = None
    limit_ms: Optional[float] = None
    limit_original_ms: Optional[float] = None
    limit_algorithm: Optional[str] = None
    medium: Optional[str] = None
    target_speedup: Optional[float] = None
    selections: list = field(default_factory=list)
    algorithms: list = field(default_factory=list)
    equal_time: list = field(default_factory=list)
    #: amortized sampling at the paper's setting per trained estimator (:func:`_amortized_rows`)
    amortized: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    wall_s: float = 0.0
    figure: Optional[str] = None
    #: the cache filter the profile chose (rrcache.profiler.filters) and what each candidate measured
    filter: Optional[str] = None
    filter_times: Optional[dict] = None
    #: the medium selection's misses by cause (rrcache.bench.cache.MissRow as JSON)
    misses: list = field(default_factory=list)

    def to_json(self) -> dict:
        out = asdict(self)
        out["selections"] = [s.to_json() for s in self.selections]
        return _finite(out)


def _cap(psnr: float) -> float:
    return min(float(psnr), PSNR_CAP)


def _say(progress: Optional[ProgressFn], stage: str, done=None, total=None) -> None:
    if progress is not None:
        progress(stage, done, total)


def _effective_session(scene: Scene, settings: BenchSettings, out: Path) -> str:
    """The session the bench runs: the scene's own, or a scaled copy in ``out/sessions``."""
    from rrcache.session import load_session

    session = load_session(scene.session)
    w, h = session.resolution
    size = (w, h)
    if settings.resolution is not None:
        # fit inside the requested size, keeping the session's aspect ratio
        scale = min(settings.resolution[0] / w, settings.resolution[1] / h)
        if scale < 1:
            size = (max(8, int(round(w * scale))), max(8, int(round(h * scale))))
    frames = session.frames if settings.frames is None else min(int(settings.frames), session.frames)
    if size == (w, h) and frames == session.frames:
        return scene.session
    return str(scaled_session(scene.session, out / "sessions" / f"{scene.name}.json", size, frames))


def _choose_medium(selections: list) -> Optional[Selection]:
    by_label = {s.label: s for s in selections}
    for label in (MEDIUM, "e4", "e2", "e1"):
        row = by_label.get(label)
        if row is not None and row.parts:
            return row
    return None


def _measure_selections(prof, work, session, frames, settings: BenchSettings, progress) -> list[Selection]:
    """The profile's selections, each measured again beside the original (``repeats`` times;
    the speed-up is the median): the same records, their measured figures replaced. The
    original shader is not rendered (error 0, speed-up 1)."""
    from rrcache.harness.cached import compare
    from rrcache.pipeline import variant_for_selection

    options = prof.settings.cache_options()

    def measure(sel: Selection) -> Selection:
        _say(progress, f"selection {sel.label}", None, None)
        if not sel.parts:
            return sel.replace(measured_error=0.0, measured_psnr=PSNR_CAP, measured_speedup=1.0,
                               measured_ms=None, measured_original_ms=None, hit_rate=None, frames=0, speedups=())
        variant, period = variant_for_selection(work, sel)
        runs = [compare(variant, session, work.prepared, frames, period=period, **options)
                for _ in range(settings.repeats)]
        first = runs[0]
        speedups = [r.speedup for r in runs]
        return sel.with_measurement(
            first.mean_error, _cap(first.psnr), float(statistics.median(r.ms_per_frame for r in runs)),
            float(statistics.median(r.original_ms_per_frame for r in runs)), float(statistics.median(speedups)),
            first.hit_rate, len(first.frames), speedups)

    # the profiler's rule for sets of nodes (rrcache.profiler.sets.keep_faster), on the bench's
    # own measurements: the bench profiles without validation, where that rule runs
    from rrcache.profiler.sets import prefer_singles

    return prefer_singles(prof, [measure(sel) for sel in prof.selections], measure)


#: the paper's amortized setting (Nehab et al. 2007 §7.3: 4 of 16 PCF samples per frame, λ = 3/5)
PAPER_SHARE, PAPER_BLEND = 4, 0.6


#: the amortized settings the bench measures at the paper's m and λ: (history, filter, payload)
AMORTIZED_SETTINGS = (("blend", "bilinear", "f4"), ("slots", "bilinear", "f4"), ("slots", "catmull-rom-y", "u8"))


def _amortized_label(history: str, filter_: str, payload: str) -> str:
    if history == "blend":
        return "amortized sampling (Nehab 2007 §6)"
    extra = "" if (filter_, payload) == ("bilinear", "f4") else f", {'8-bit' if payload == 'u8' else payload}, {filter_}"
    return f"amortized sampling (per-subset slots{extra})"


def _amortized_rows(prof, work, session, frames, settings: BenchSettings, progress) -> list[MethodRow]:
    """Each trained estimator of the profile at the paper's setting (N/4 of its N terms per frame,
    at least 1, blend λ = 3/5), measured beside the original as the selections are (error against
    the original; ``rrcache bench-amortize`` measures against a many-sample reference): the
    paper's single running estimate (``blend`` history) and, where the N/m subset sums fit in the
    payload, the same m and λ with one reprojected sum per subset (``slots``, exact on a still
    image; :mod:`rrcache.compiler.amortize`), and where the terms' range is known, the slots in
    8 bits resampled with Catmull-Rom down the screen (:data:`AMORTIZED_SETTINGS`)."""
    from rrcache.harness.cached import compare
    from rrcache.pipeline import variant_for_selection
    from rrcache.selection import AmortizedLoop, slots_fit

    rows = []
    for est in getattr(prof, "estimators", []):
        if not est.trained:
            continue
        m = max(1, est.samples // PAPER_SHARE)
        for history, filter_, payload in AMORTIZED_SETTINGS:
            sel = Selection((AmortizedLoop(est.id, m, PAPER_BLEND, history=history, filter=filter_, payload=payload),),
                            0.0, float("nan"), 1.0, algorithm=prof.algorithm)
            if history == "slots":
                why = (slots_fit(est.samples, m, est.components) if est.components
                       else "the profile does not record its accumulators' components (written before them)")
                if why:
                    _say(progress, f"amortized {sel.describe()}: not measured ({why})", None, None)
                    continue
            try:
                variant, period = variant_for_selection(work, sel)
            except RRCacheError as err:  # an 8-bit payload needs the terms' range
                _say(progress, f"amortized {sel.describe()}: not measured ({err.message})", None, None)
                continue
            _say(progress, f"amortized {sel.describe()}", None, None)
            runs = [compare(variant, session, work.prepared, frames, period=period, **prof.settings.cache_options())
                    for _ in range(settings.repeats)]
            first = runs[0]
            used = first.payload_dtype  # f4 where an 8-bit payload's range did not hold
            setting = f"{est.id}: {m} of {est.samples} per frame, λ={PAPER_BLEND:g}" + (
                "" if history == "blend" else ", slots") + (
                "" if (filter_, used) == ("bilinear", "f4") else f", {used}, {filter_}")
            rows.append(MethodRow(_amortized_label(history, filter_, used), setting,
                                  float(statistics.median(r.speedup for r in runs)),
                                  first.mean_error, _cap(first.psnr), float(statistics.median(r.ms_per_frame for r in runs)),
                                  float(statistics.median(r.original_ms_per_frame for r in runs)),
                                  steps=[r.speedup for r in runs]))
    return rows


def _within(speedup: float, target: float, tolerance: float) -> bool:
    return bool(math.isfinite(speedup) and abs(speedup / target - 1.0) <= tolerance)


def _equal_time(work, session, frames, medium: Selection,
                settings: BenchSettings, result: SceneResult, progress) -> list[MethodRow]:
    target = medium.measured_speedup
    rows = [MethodRow("reprojection cache (ours)", f"{medium.label}: {medium.describe()}",
                      medium.measured_speedup, medium.measured_error, medium.measured_psnr, medium.measured_ms,
                      medium.measured_original_ms, True)]
    search = list(frames)[:max(1, settings.search_frames)]

    try:
        rows.append(dynres_row(work, session, frames, search, target, settings, progress))
    except RRCacheError as err:
        result.notes.append(f"dynamic resolution failed: {err}")
    try:
        rows.append(render_cache_row(work, session, frames, search, target, settings, progress))
    except RRCacheError as err:
        result.notes.append(f"render cache failed: {err}")
    try:
        row = _simplification_row(work, session, frames, search, target, settings, result, progress)
    except RRCacheError as err:
        result.notes.append(f"simplification failed: {err}")
    else:
        if row is not None:
            rows.append(row)
    return rows


def dynres_row(work, session, frames, search, target, settings, progress, on_frame=None) -> MethodRow:
    """Dynamic resolution tuned to the ``target`` speed-up over the ``search`` frames, then measured
    over ``frames`` beside the original (``on_frame(row, frame, original)`` per frame)."""
    from rrcache.alternatives import dynres

    def dyn_step(scale, speedup):
        _say(progress, f"dynres s={scale:.3f}: {speedup:.2f}× (target {target:.2f}×)")

    found = dynres.tune_scale(work.prepared, session, None, search, target, lo=settings.min_scale,
                              rel_tol=settings.tolerance, max_steps=settings.max_steps, progress=dyn_step)
    final = dynres.measure_scale(work.prepared, session, None, frames, on_frame=on_frame)(found.value)
    low = dynres.low_size(tuple(session.resolution), found.value)
    return MethodRow("dynamic resolution", f"scale {found.value:.3f} ({low[0]}×{low[1]}, bilinear)",
                     final.speedup, final.mean_error, _cap(final.psnr), final.ms_per_frame,
                     final.original_ms_per_frame, _within(final.speedup, target, settings.tolerance),
                     [list(s) for s in found.steps])


#: the equal-time row of the render cache (Walter, Drettakis, Greenberg 2002)
RENDER_CACHE = "render cache (Walter 2002)"


def render_cache_row(work, session, frames, search, target, settings, progress, on_frame=None,
                     render_cache=None) -> MethodRow:
    """The render cache with its sample share tuned to the ``target`` speed-up over the ``search``
    frames (:func:`rrcache.alternatives.render_cache.tune.tune_samples`), then measured over
    ``frames`` beside the original; ``render_cache``: its other settings (the defaults when None).
    The row's ``stages`` are the median ms of each stage of its frames."""
    from rrcache.alternatives.render_cache import RenderCacheSettings
    from rrcache.alternatives.render_cache.tune import compare, tune_samples

    base = render_cache or RenderCacheSettings()

    def step(share, speedup):
        _say(progress, f"render cache {share:.2%} of the pixels: {speedup:.2f}× (target {target:.2f}×)")

    found = tune_samples(work.prepared, session, search, target, base, rel_tol=settings.tolerance,
                         max_steps=settings.max_steps, progress=step)
    final = compare(work.prepared, session, frames, replace(base, samples=found.value), on_frame=on_frame)
    chosen = replace(base, samples=found.value)
    row = MethodRow(RENDER_CACHE, f"{chosen.describe().split(': ', 1)[1]} ({final.budget} pixels), a cache of "
                                  f"{base.points_per_pixel:g}× the pixels",
                    final.speedup, final.mean_error, _cap(final.psnr), final.ms_per_frame,
                    final.original_ms_per_frame, _within(final.speedup, target, settings.tolerance),
                    [list(s) for s in found.steps])
    row.stages = dict(final.stages)
    return row


def _simplification_row(work, session, frames, search, target, settings, result, progress) -> Optional[MethodRow]:
    from rrcache.alternatives import simplify
    from rrcache.alternatives.measure import compare_renderers
    from rrcache.harness.renderer import Renderer

    w, h = session.resolution
    probe_size = settings.probe_resolution or (max(8, w // 4), max(8, h // 4))
    probe_size = (min(probe_size[0], w), min(probe_size[1], h))
    n = len(frames)
    probe = sorted({int(round(x)) for x in np.linspace(frames[0], frames[-1], max(1, settings.probe_frames))}) \
        if n > 1 else list(frames)
    # static cost taken as proportional to time: the simplified shader should keep at least half the
    # cost the target suggests, so the candidates are the costliest nodes saving no more than the rest
    floor = 0.5 * result.static_cost / max(target, 1.0)
    pool = [x for x in work.table.nodes if not x.final and x.cost <= result.static_cost - floor]
    costliest = sorted(pool, key=lambda x: (-x.cost, x.id))[:settings.candidates]
    ids = [x.id for x in costliest]
    done = {"k": 0}

    def probe_step(_node_id):
        done["k"] += 1
        _say(progress, "simplification: node means and errors", done["k"], 2 * len(ids))

    if not ids:
        result.notes.append("simplification: no cacheable node (besides the final colour) saves less than the "
                            "target allows; left out")
        return None
    ranking = simplify.rank_candidates(work, session, ids, probe, probe_size, probe_step)
    if not ranking:
        result.notes.append("simplification: no candidate saves static cost; left out")
        return None

    def simp_step(k, speedup):
        _say(progress, f"simplification k={k}: {speedup:.2f}× (target {target:.2f}×)")

    tuned = simplify.tune_simplification(work, session, ranking, None, search, target, settings.tolerance, simp_step,
                                         cost_floor=floor)
    k = int(tuned.search.value)
    with Renderer(work.prepared, session) as original, Renderer(tuned.shader.prepared, session) as simple:
        final = compare_renderers(original, simple, frames)
    return MethodRow("simplification (Pellacini 2005)",
                     f"{k} of {len(tuned.ranking)} nodes in the greedy order replaced by their means "
                     f"(static cost {tuned.shader.cost} of {result.static_cost}): "
                     + ", ".join(_short(c.text) for c in tuned.ranking[:min(k, 3)]) + (", …" if k > 3 else ""),
                     final.speedup, final.mean_error, _cap(final.psnr), final.ms_per_frame,
                     final.original_ms_per_frame, _within(final.speedup, target, settings.tolerance),
                     [list(s) for s in tuned.search.steps])


def _short(text: str, limit: int = 40) -> str:
    text = " ".join(text.split())
    return "`" + (text if len(text) <= limit else text[:limit - 1] + "…") + "`"


def run_scene(scene: Scene, settings: BenchSettings, out, progress: Optional[ProgressFn] = None) -> SceneResult:
    """Bench one scene (see the module docstring); the profile goes to ``out/<name>.rrprofile``."""
    from rrcache.alternatives.simplify import simplified_shader
    from rrcache.bench import cache as cache_bench
    from rrcache.pipeline import load_for_session
    from rrcache.profiler import profile
    from rrcache.profiles import TrainingSettings
    from rrcache.session import load_session

    started = time.time()
    out = Path(out)
    settings = settings.for_scene(scene.name)
    session_path = _effective_session(scene, settings, out)
    session = load_session(session_path)
    work = load_for_session(scene.shader, session)
    frames = list(range(session.frames))
    result = SceneResult(scene.name, scene.shader, session_path, tuple(session.resolution), len(frames),
                         simplified_shader(work, {}).cost, len(work.table.nodes))

    folder = out / f"{scene.name}.rrprofile"
    training = TrainingSettings(**settings.training)

    def on_event(event):
        _say(progress, f"profile: {event.stage} {event.detail}".strip(), event.done, event.total)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        prof = profile(scene.shader, session_path, folder, training, progress=on_event, plots=settings.plots)
    result.notes += [f"profile: {w.message}" for w in caught]
    if prof.term_scores:  # the profile measured the order of its sums: its node ids refer to it
        work = load_for_session(scene.shader, session, term_scores=prof.term_scores)
    work.filter = prof.filter  # the selections compile with the profile's filter
    result.filter = prof.filter
    result.filter_times = (prof.plan or {}).get("filter_times")
    counts = prof.counts or {}
    result.profile = str(folder)
    # the profiler's precomputation time: every invocation on its store added up (older
    # profiles only have the training time)
    result.precompute_s = prof.precompute_s if prof.precompute_s is not None else prof.training_wall_s
    result.training_s = prof.training_wall_s
    result.precompute_resumed = bool(counts.get("error_runs_skipped", 0) or counts.get("timing_runs_skipped", 0))
    result.profile_run_s = prof.run_wall_s
    result.trained_nodes = len(prof.trained_nodes)
    if not prof.selections:
        result.notes.append("no node was trained (budget too small): nothing selected")
        result.wall_s = time.time() - started
        return result

    result.selections = _measure_selections(prof, work, session, frames, settings, progress)
    result.notes += [f"{s.label}: {s.fallback}" for s in result.selections if s.fallback]
    try:
        result.amortized = _amortized_rows(prof, work, session, frames, settings, progress)
    except RRCacheError as err:
        result.notes.append(f"amortized sampling failed: {err}")
    originals = [s.measured_original_ms for s in result.selections if s.measured_original_ms is not None]
    medium = _choose_medium(result.selections)
    if medium is None:
        result.notes.append("every selection is the original shader: no algorithm, limit or equal-time comparison")
        result.original_ms = _original_ms(work, session, frames)
        result.wall_s = time.time() - started
        return result
    result.medium, result.target_speedup = medium.label, medium.measured_speedup
    if medium.label != MEDIUM:
        result.notes.append(f"{MEDIUM} caches nothing; the medium selection is {medium.label}")

    if not medium.choice.one_node:  # an amortized estimator, several nodes: the algorithms and limit are one node's
        if medium.multi:  # the all-hit limit of the set (the algorithms and the misses are one node's)
            _set_limit(prof, work, session, frames, medium, result, progress)
        result.notes.append(f"the {medium.label} selection is {medium.describe()} ({medium.choice.title}): the "
                            "algorithms and the miss breakdown are measured for a single cached node only")
        if medium.measured_speedup > 1.0 + settings.tolerance:
            result.equal_time = _equal_time(work, session, frames, medium, settings, result, progress)
            originals += [r.original_ms for r in result.equal_time[1:]]
        result.original_ms = float(statistics.median(originals)) if originals else _original_ms(work, session, frames)
        result.wall_s = time.time() - started
        return result
    _say(progress, f"algorithms and limit on {medium.node}")
    bench = cache_bench.run(scene.shader, session_path, medium.node, periods=(), compare_period=int(medium.period),
                            frames=len(frames), blocks=(), repeats=1, limit_algorithm=prof.algorithm,
                            base_filter=prof.filter, limit_filter=prof.filter, misses=True,
                            term_scores=prof.term_scores,
                            progress=lambda msg, done, total: _say(progress, f"algorithms: {msg}", done, total))
    result.misses = [asdict(m) for m in bench.misses]
    result.algorithms = [MethodRow(r.algorithm, f"Δn={r.period}, k={r.block}", r.speedup, r.mean_error, _cap(r.psnr),
                                   r.ms_per_frame, r.original_ms_per_frame) for r in bench.algorithms]
    originals += [r.original_ms for r in result.algorithms]
    result.limit_ms, result.limit_original_ms = bench.limit_ms, bench.limit_original_ms
    result.limit_speedup = bench.limit_speedup
    result.limit_algorithm = prof.algorithm

    if medium.measured_speedup > 1.0 + settings.tolerance:
        result.equal_time = _equal_time(work, session, frames, medium, settings, result, progress)
        originals += [r.original_ms for r in result.equal_time[1:]]
    else:
        result.notes.append(f"the {medium.label} selection measured {medium.measured_speedup:.2f}×, no faster than "
                            "the original: no equal-time comparison")
    result.original_ms = float(statistics.median(originals)) if originals else _original_ms(work, session, frames)
    result.wall_s = time.time() - started
    return result


def _set_limit(prof, work, session, frames, medium: Selection, result: "SceneResult", progress) -> None:
    """The all-hit limit of a selection of several nodes: its variant with every node hitting."""
    from rrcache.harness.limit import all_hit_limit, probe_frames
    from rrcache.pipeline import variant_for_selection

    _say(progress, f"limit of {medium.describe()}")
    variant, periods = variant_for_selection(work, medium)
    options = prof.settings.cache_options()
    limit = all_hit_limit(variant, session, work.prepared, probe_frames(frames), None, period=periods,
                          color_format=prof.settings.timing_format, **options)
    result.limit_ms, result.limit_original_ms = limit.limit_ms, limit.original_median_ms
    result.limit_speedup = limit.original_median_ms / limit.limit_ms
    result.limit_algorithm = prof.algorithm


def _original_ms(work, session, frames) -> float:
    from rrcache.harness.renderer import render

    return float(render(work.prepared, session, frames=list(frames)[:10]).ms_per_frame)


@dataclass
class BenchResult:
    settings: BenchSettings
    scenes: list = field(default_factory=list)
    started: str = ""
    wall_s: float = 0.0

    def to_json(self) -> dict:
        return {"rrcache_bench": 1, "quick": self.settings.quick, "started": self.started,
                "wall_s": self.wall_s, "threads": os.environ.get("LP_NUM_THREADS"),
                "settings": self.settings.to_json(), "scenes": [s.to_json() for s in self.scenes]}


def run(scenes: list, settings: BenchSettings = FULL, out="rrcache-bench", progress: Optional[ProgressFn] = None,
        on_scene: Optional[Callable[[SceneResult], None]] = None) -> BenchResult:
    """Bench every scene in turn; ``bench.json`` and ``bench.md`` in ``out`` are rewritten after
    each scene (``on_scene`` is called then too)."""
    from rrcache.bench.paper_report import markdown

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    result = BenchResult(settings, started=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()))
    t0 = time.time()
    for scene in scenes:
        _say(progress, f"{scene.name}: starting")
        result.scenes.append(run_scene(scene, settings, out, lambda s, d=None, t=None, n=scene.name:
                                       _say(progress, f"{n}: {s}", d, t)))
        result.wall_s = time.time() - t0
        if settings.figures:
            from rrcache.bench.paper_plots import write_scene_plot

            result.scenes[-1].figure = Path(write_scene_plot(result.scenes[-1], out)).name
        _write(out / "bench.json", json.dumps(result.to_json(), indent=2, ensure_ascii=False) + "\n")
        _write(out / "bench.md", markdown(result))
        if on_scene is not None:
            on_scene(result.scenes[-1])
    return result


def _write(path: Path, text: str) -> None:
    atomic.write_text(path, text)
