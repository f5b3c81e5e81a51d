"""Replaying a session through a cached variant, and comparing it with the original side by side.

:class:`CachedRenderer` draws the session's objects (:class:`~rrcache.harness.drawer.SceneDrawer`)
with every pass program of a compiled :class:`~rrcache.compiler.Variant` through the public
:class:`~rrcache.runtime.CacheRuntime`, so what is measured is what an application runs.

:func:`compare` renders the original and the variant frame by frame in one run, alternating them
so that machine noise touches both alike, and reports the paper's error (mean per-pixel RGB L2
over covered pixels), PSNR, hit rate and the speed-up as a ratio of median frame times.

Hits and misses come from occlusion queries while timing (misses = fragments the miss pass shaded,
overdraw included; hits = covered − misses); ``hit_maps=True`` also reads the exact per-pixel hit
map after the reprojection pass (that read-back stalls the pipeline: such frames are not timed
fairly and the comparison says so).
"""
from __future__ import annotations

import statistics
import time
import warnings
from dataclasses import dataclass, field
from typing import Callable, Optional

import moderngl
import numpy as np

from rrcache import watchdog
from rrcache.gl.context import get_context
from rrcache.gl.resources import GLScope
from rrcache.harness.drawer import SceneDrawer
from rrcache.harness.metrics import mean_l2, nonfinite_count, psnr
from rrcache.compiler.prepared import PreparedShader
from rrcache.harness.renderer import Renderer, check_frame_index, session_background
from rrcache.harness.timing import DEFAULT_CLOCK, make_clock
from rrcache.runtime import DEFAULT_PERIOD
from rrcache.runtime.spec import VariantSpec

def _unreliable() -> float:
    from rrcache.harness.timing import UNRELIABLE_NOISE

    return UNRELIABLE_NOISE


#: the largest finite 16-bit float: payload values beyond it would be stored as ±inf
HALF_MAX = 65504.0
#: how far beyond [0, 1] an 8-bit payload's encoded value may be (float rounding) and still fit
ENCODED_SLACK = 1e-4


@dataclass
class CachedFrame:
    """One frame of a cached variant: ``image`` H×W×4 (row 0 = top), ``mask`` covered pixels,
    ``hits``/``misses`` (queries), ``ms`` wall time of the passes, ``hit_map`` (exact, only
    with ``hit_maps=True``; row 0 = top)."""

    index: int
    image: np.ndarray
    mask: np.ndarray
    covered_pixels: int
    hits: Optional[int]
    misses: Optional[int]
    ms: float
    hit_map: Optional[np.ndarray] = None
    payload: Optional[np.ndarray] = None
    cpu_ms: float = float("nan")  # process CPU time over the same span as ms (all threads)
    #: why the misses missed (``miss_causes=True``): :func:`rrcache.runtime.misses.summarise`
    miss_causes: Optional[dict] = None
    #: per pixel the index of its cause in ``rrcache.runtime.misses.MISS_CAUSES`` (-1: a hit or
    #: not covered; row 0 = top), with ``miss_causes``
    miss_map: Optional[np.ndarray] = None


def _range_remedy(variant) -> str:
    """What to do when an 8-bit payload's range did not hold, by where the range came from."""
    source = (getattr(variant, "amortized", None) or {}).get("range_source")
    loop = f"the loop at {variant.node_loc}" if getattr(variant, "node_loc", None) else "the loop"
    if source == "pragma":
        return f"check the range declared with '#pragma rrcache estimator range(LO, HI)' before {loop}"
    if source == "analysis":
        return (f"the analysis's bound on the terms of {loop} did not hold in 32-bit floats; declare a wider "
                "range with '#pragma rrcache estimator range(LO, HI)' before it")
    return f"the term range given for {loop} does not hold"


def runtime_spec(variant, spec: Optional[VariantSpec] = None, period=None, **fields) -> VariantSpec:
    """The spec ``variant`` runs with: ``spec`` whole, else the variant's own spec with the runtime
    fields given as keywords (``period``: one int for every node, or one per node; ``block``,
    ``refresh``, ``depth_epsilon``, ``threshold``, ``fast_period``, ``spread``, ``blend``)."""
    if spec is not None:
        if fields or period is not None:
            raise TypeError("give the spec, or its runtime fields as keywords, not both")
        return spec
    if period is not None:
        if isinstance(period, (int, np.integer)):
            fields["periods"] = (int(period),) * variant.node_count
        else:
            fields["periods"] = tuple(int(p) for p in period)
            if len(fields["periods"]) != variant.node_count:
                raise ValueError(f"{variant.node_count} periods expected (one per node), not {len(fields['periods'])}")
    elif not variant.spec.periods and variant.node_count > 1:
        fields["periods"] = (DEFAULT_PERIOD,) * variant.node_count
    return variant.spec.with_runtime(**fields)


class CachedRenderer:
    """Renders frames of ``session`` with ``variant`` (a compiled :class:`Variant`).

    ``prepared`` is the original shader prepared by the harness: its declarations name the places
    in error messages when the session lacks a uniform a pass needs. Frames must be rendered in
    order for the cache to mean anything (frame ``i`` reprojects from the last rendered frame);
    a jump resets the cache (every pixel misses, as after a camera cut). ``window`` (x, y, w, h)
    renders only that rectangle at full pixel density (see :mod:`rrcache.gl.window`).
    ``spec`` is what the runtime runs (the variant's :class:`~rrcache.runtime.spec.VariantSpec`
    with the runtime's fields set: periods, refresh, adaptive threshold, blend); or give those
    fields as keywords (``period=``, ``block=``, ``threshold=`` …; :func:`runtime_spec`). A
    variant of several nodes takes one period per node (a sequence in the variant's node order;
    one int: every node).
    """

    def __init__(self, variant, session, prepared: PreparedShader, resolution: Optional[tuple[int, int]] = None,
                 spec: Optional[VariantSpec] = None, *, seed: int = 0, hit_maps: bool = False,
                 keep_payload: bool = False, window: Optional[tuple[int, int, int, int]] = None,
                 color_format: str = "rgba32f", clock: str = DEFAULT_CLOCK, miss_causes: bool = False, **runtime):
        self.ctx = get_context()
        hit_maps = hit_maps or miss_causes
        self.spec = runtime_spec(variant, spec, **runtime)
        self.clock = make_clock(clock, self.ctx)
        self.color_format = color_format
        self.variant = variant
        self.session = session
        self.size = tuple(int(v) for v in (resolution or session.resolution))
        self.hit_maps = hit_maps
        self.keep_payload = keep_payload
        # a 16-bit or 8-bit payload asked for starts in 32 bits: the untimed first frame checks
        # that its values fit (half floats; the 8-bit encoding's range) before the cache is made
        # narrower (see _settle_payload)
        self.payload_dtype = variant.payload_dtype
        self.payload_note: Optional[str] = None
        self._check_payload = variant.payload_dtype in ("f2", "u8")
        self._scope = GLScope()
        self._last: Optional[int] = None
        self._warm = False
        try:
            self.programs = {name: self._scope.own(p) for name, p in variant.build_programs(self.ctx).items()}
            self.drawer = SceneDrawer(self.ctx, session, prepared, self.size, self._scope)
            for program in self.programs.values():
                self.drawer.add_program(program)
            self.notes = self.drawer.notes
            self.runtime = variant.runtime(
                self.ctx, self.programs, self.size, self.spec, seed=seed, clear_color=session_background(session),
                color_format=color_format, payload_dtype="f4" if self._check_payload else variant.payload_dtype)
            if window is not None:
                self.runtime.set_window(window)
            self._classifier = None
            if miss_causes:  # diagnostics: each miss's cause (rrcache.runtime.misses)
                from rrcache.runtime.misses import MissClassifier

                first = variant.passes[variant.pass_names[0]]
                self._classifier = MissClassifier(self.ctx, self.runtime, first.vertex, variant.filter,
                                                  self.drawer.add_program)
                self._scope.own(self._classifier.program)
        except BaseException:
            self._scope.release()
            raise

    @property
    def period(self) -> int:
        return self.runtime.period

    @period.setter
    def period(self, value: int) -> None:
        self.runtime.period = value

    def respec(self, spec: VariantSpec) -> None:
        """Run the next frames with ``spec``'s runtime fields (periods, refresh, adaptive
        threshold, blend; the passes stay: ValueError for a spec compiled otherwise) and an empty
        cache: one renderer serves every period of a training run."""
        if spec.compiled() != self.spec.compiled():
            raise ValueError(f"{spec} needs other passes than this renderer's {self.spec.compiled()}")
        rt = self.runtime
        rt.period = spec.period
        rt.set_refresh(mode=spec.refresh, block=spec.block)
        rt.depth_epsilon = float(spec.depth_epsilon)
        rt.blend = float(spec.blend)
        if rt.adaptive:
            rt.threshold, rt.fast_period, rt.spread = float(spec.threshold), int(spec.fast_period), float(spec.spread)
        self.spec = spec
        self.reset()

    def _settle_payload(self) -> None:
        """After the untimed first frames of a 16-bit or 8-bit payload request: if any covered
        pixel's payload does not fit (beyond ±65504 or overflowing for 16 bits; outside the
        encoding's range for 8 bits, which a range declared with the pragma can be), keep 32 bits,
        warn and say so in ``payload_note``; else switch the cache to the narrower format. Later
        frames are not checked."""
        self._check_payload = False
        rt = self.runtime
        payloads = [p[..., :c] for p, c in zip(rt.read_payloads(), rt.node_components)]
        covered = rt.read_depth() < 1.0
        if self.payload_dtype == "u8":
            offset, span = rt.payload_decode
            c = rt.payload_components
            stored = np.concatenate([((p[covered] - offset[:c]) / span[:c]).ravel() for p in payloads])
            outside = stored[~((stored >= -ENCODED_SLACK) & (stored <= 1.0 + ENCODED_SLACK))]
            if outside.size == 0:
                rt.payload_dtype = "u8"
                rt.resize(self.size)
                return
            low, high = offset[:c], offset[:c] + span[:c]
            problem = (f"{outside.size} payload value(s) are outside the range the 8-bit payload encodes "
                       f"([{float(low.min()):g}, {float(high.max()):g}]: the terms' range times the samples per slot)")
            remedy = _range_remedy(self.variant)
        else:
            values = np.concatenate([np.abs(p[covered]).ravel() for p in payloads])
            finite = values[np.isfinite(values)]
            largest = float(finite.max()) if finite.size else 0.0
            if largest <= HALF_MAX:
                rt.payload_dtype = "f2"
                rt.resize(self.size)
                return
            problem = f"payload values up to {largest:.6g} are beyond the 16-bit float range (±{HALF_MAX:g})"
            remedy = ""
        self.payload_dtype = "f4"
        self.payload_note = f"{problem}: the cache uses 32-bit floats instead" + (f" ({remedy})" if remedy else "")
        self.notes.append(self.payload_note)
        warnings.warn(self.payload_note, RuntimeWarning, stacklevel=3)

    def reset(self) -> None:
        """Empty the cache: the next frame misses everywhere."""
        self.runtime.reset()
        self._last = None

    def _frame(self, hit_box: Optional[dict]):
        """Run the passes of the frame set on the drawer; with ``hit_box`` the exact hit map is
        read after the first pass into ``hit_box["map"]``."""
        def read_hits():
            hit_box["map"] = self.runtime.read_inverse_depth(current=True) > 0
        self.drawer.render_shadow_map()  # the light's depth pass is part of the frame
        return self.runtime.frame(self.drawer.draw, after_first_pass=read_hits if hit_box is not None else None)

    def render_frame(self, index: int) -> CachedFrame:
        """Render frame ``index`` with the cache. The first call renders it once untimed to warm
        up llvmpipe's shader compilation, then resets the cache."""
        index = check_frame_index(self.session, index)
        ctx = self.ctx
        if self._last is not None and index != self._last + 1:
            self.runtime.reset()
        self.drawer.set_frame(index)
        if not self._warm:
            # an amortized variant has one program per phase (rrcache.compiler.amortize), each
            # compiled by the driver when first drawn: draw every phase once here, untimed; the
            # clock stays where it was set (a run restarted at a later frame keeps its refresh
            # schedule whether this renderer is new or served runs before)
            clock = self.runtime.clock
            for _ in range(max(1, int(self.runtime.phase_cycle))):
                self._frame(None)
            if self._check_payload:
                self._settle_payload()
            self.runtime.reset()
            self.runtime.clock = clock
            self._warm = True
        hit_box = {} if self.hit_maps else None
        codes = self._classifier.classify(self.drawer.draw) if self._classifier is not None else None
        with watchdog.frame(f"frame {index} of the cached variant"):
            self.clock.start()
            stats = self._frame(hit_box)
            ms = self.clock.stop()
            cpu_ms = self.clock.cpu_ms
        self._last = index
        image = self.runtime.read_color()
        mask = self.runtime.read_depth() < 1.0
        covered = int(mask.sum())
        hit_map = hit_box.get("map") if hit_box is not None else None
        if hit_map is not None:
            hits = int((hit_map & mask).sum())
            misses = covered - hits
        elif stats.misses is not None:
            misses = min(int(stats.misses), covered)
            hits = covered - misses
        else:  # one-pass: a dynamic branch, nothing for a query to count
            hits = misses = None
        payload = self.runtime.read_payload() if self.keep_payload else None
        frame = CachedFrame(index, image, mask, covered, hits, misses, ms, hit_map, payload, cpu_ms)
        if codes is not None and hit_map is not None:
            from rrcache.runtime.misses import causes, summarise

            window = self.runtime.window
            origin, height = ((window[0], window[1]), window[3]) if window else ((0, 0), self.size[1])
            frame.miss_map = causes(codes, hit_map, mask)
            frame.miss_causes = summarise(frame.miss_map, mask, origin, height)
        return frame

    def render_static(self, index: int, repeats: int = 5, between: Optional[Callable[[], None]] = None,
                      stages: Optional[dict] = None) -> float:
        """The cached pipeline's best case: frame ``index`` shown again and again with nothing
        moving and no refresh, so every covered pixel hits after the first showing. Returns the
        median ms of the ``repeats`` hitting frames (the speed-up limit's denominator). The cache
        is reset afterwards and the period restored.

        Each frame is read back as :meth:`render_frame` does, and ``between()`` (if given) runs
        before each frame: :func:`compare` renders the original between two cached frames, and
        a limit measured back to back, with the CPU caches warm from the frame before, came out
        ~25% faster than the same all-hit frame measured that way (Marble, 640×480).

        ``stages`` (a dict; diagnostics) gets, per timed frame, the ms of each stage of the frame
        (``clear``, each pass, ``queries``: the runtime waits for the GPU after each) and of the
        read-back (``read-back``); the frame time is then that of the staged frame."""
        index = check_frame_index(self.session, index)
        if self._check_payload:  # decide the payload precision first, on an untimed frame
            self.render_frame(index)
        saved = self.runtime.period
        self.runtime.period = 2 ** 30
        self.runtime.reset()
        self.drawer.set_frame(index, static=True)
        times = []
        try:
            for i in range(repeats + 2):
                if between is not None:
                    between()
                marks: list = []

                def mark(stage):
                    marks.append((stage, self.clock.mark()))

                self.clock.start()
                start = self.clock.started
                self.drawer.render_shadow_map()
                stats = self.runtime.frame(self.drawer.draw, mark=mark if stages is not None else None)
                ms = self.clock.stop()
                end = self.clock.end
                self.runtime.read_color()
                self.runtime.read_depth()
                if i >= 2:
                    times.append(ms)
                    if stages is not None:
                        last = start
                        for stage, at in marks:
                            stages.setdefault(stage, []).append((at - last) * 1000.0)
                            last = at
                        stages.setdefault("read-back", []).append((time.perf_counter() - end) * 1000.0)
            self.last_static_stats = stats
        finally:
            self.runtime.period = saved
            self.runtime.reset()
            self._last = None
        return statistics.median(times)

    def release(self) -> None:
        """Release every GL object (safe to call twice)."""
        classifier = getattr(self, "_classifier", None)
        if classifier is not None:
            classifier._release_targets()
            self._classifier = None
        runtime = getattr(self, "runtime", None)
        if runtime is not None:
            runtime.release()
            self.runtime = None
        self._scope.release()

    def __enter__(self) -> "CachedRenderer":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


@dataclass
class FrameComparison:
    index: int
    mean_error: float
    psnr: float
    hits: Optional[int]
    misses: Optional[int]
    covered: int
    ms: float
    original_ms: float
    nonfinite: int = 0
    left_out: int = 0
    original_nonfinite: int = 0
    #: why the misses missed (``compare(..., miss_causes=True)``; rrcache.runtime.misses.summarise)
    miss_causes: Optional[dict] = None


@dataclass
class Comparison:
    """The variant against the original over the frames of one run (timed side by side)."""

    frames: list[FrameComparison] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    resolution: tuple[int, int] = (0, 0)
    skip_first: int = 1  # frames left out of the summary: the first one has no cache
    payload_dtype: str = "f4"  # the cache precision used (f4 when an f2 request did not fit)
    color_format: str = "rgba32f"  # the colour target both drew into

    def _steady(self) -> list[FrameComparison]:
        steady = self.frames[self.skip_first:]
        return steady or self.frames

    @property
    def mean_error(self) -> float:
        return float(np.mean([f.mean_error for f in self._steady()]))

    @property
    def psnr(self) -> float:
        return float(np.mean([min(f.psnr, 100.0) for f in self._steady()]))

    @property
    def exact(self) -> bool:
        """Every steady frame equal to the original's over its covered pixels (some covered)."""
        steady = self._steady()
        return any(f.covered for f in steady) and all(f.mean_error == 0.0 for f in steady)

    @property
    def hits(self) -> Optional[int]:
        """Hits summed over the steady frames (None when the algorithm cannot count them:
        one-pass without ``hit_maps``)."""
        counted = [f.hits for f in self._steady() if f.hits is not None]
        return sum(counted) if counted else None

    @property
    def misses(self) -> Optional[int]:
        counted = [f.misses for f in self._steady() if f.misses is not None]
        return sum(counted) if counted else None

    @property
    def hit_rate(self) -> float:
        if self.hits is None:
            return float("nan")
        total = self.hits + self.misses
        return self.hits / total if total else 0.0

    @property
    def ms_per_frame(self) -> float:
        return statistics.median(f.ms for f in self._steady())

    @property
    def miss_causes(self) -> Optional[dict]:
        """The steady frames' miss causes added up (None unless measured with ``miss_causes``)."""
        from rrcache.runtime.misses import add_summaries

        total = None
        for f in self._steady():
            if f.miss_causes is not None:
                total = add_summaries(total, f.miss_causes)
        return total

    @property
    def original_ms_per_frame(self) -> float:
        return statistics.median(f.original_ms for f in self._steady())

    @property
    def speedup(self) -> float:
        return self.original_ms_per_frame / self.ms_per_frame if self.ms_per_frame > 0 else float("nan")

    @property
    def _float(self) -> bool:
        return self.color_format != "rgba8"

    @property
    def speedup_interval(self) -> tuple[float, float]:
        """A 95% bootstrap interval of :attr:`speedup` over the steady frame pairs
        (:func:`rrcache.harness.timing.ratio_interval`)."""
        from rrcache.harness.timing import ratio_interval

        steady = self._steady()
        return ratio_interval([f.original_ms for f in steady], [f.ms for f in steady])

    @property
    def noise(self) -> float:
        """The relative noise of the original's frame times in this run
        (:func:`rrcache.harness.timing.frame_noise`)."""
        from rrcache.harness.timing import frame_noise

        return frame_noise([f.original_ms for f in self._steady()])

    def summary(self) -> dict:
        """The figures ``rrcache render --node ... --json`` prints."""
        return {
            # an exact variant has no PSNR (None, null in JSON: infinite) and says so, never "100 dB"
            "mean_error": self.mean_error, "psnr": None if self.exact else self.psnr,
            "exact": self.exact, "hit_rate": self.hit_rate,
            "hits": self.hits, "misses": self.misses, "ms_per_frame": self.ms_per_frame,
            "original_ms_per_frame": self.original_ms_per_frame, "speedup": self.speedup,
            # pixels with NaN/Inf (variant and original), and covered pixels the error left out
            # because either image was not finite there: summed over the summary's frames
            # (None in an 8-bit target, where a NaN or an infinity cannot be told from a colour)
            "nonfinite_pixels": sum(f.nonfinite for f in self._steady()) if self._float else None,
            "original_nonfinite_pixels": sum(f.original_nonfinite for f in self._steady()) if self._float else None,
            "error_left_out_pixels": sum(f.left_out for f in self._steady()),
            "payload_dtype": self.payload_dtype,
            "color_format": self.color_format,
            # how far the speed-up can be trusted: a 95% interval over frame pairs, the noise of
            # the original's frame times, and whether it was too noisy to rely on
            "speedup_ci95": list(self.speedup_interval),
            "noise": self.noise,
            "reliable": self.noise <= _unreliable(),
        }


def compare(variant, session, prepared: PreparedShader, frames, spec: Optional[VariantSpec] = None,
            resolution: Optional[tuple[int, int]] = None, hit_maps: bool = False,
            on_frame: Optional[Callable[[FrameComparison, CachedFrame, object], None]] = None,
            window: Optional[tuple[int, int, int, int]] = None, color_format: str = "rgba32f",
            clock: str = DEFAULT_CLOCK, miss_causes: bool = False, **runtime) -> Comparison:
    """Render ``frames`` (consecutive indices) with the original and with ``variant``, alternating
    frame by frame, and compare them. ``on_frame(comparison_row, cached_frame, original_frame)``
    is called per frame (for progress bars and writing images). ``window``: both render only
    that rectangle of the frame (errors and times are then the window's). ``color_format``: the
    colour target both draw into (:mod:`rrcache.gl.formats`; ``rgba8`` as an application draws,
    the error then being what it displays). ``spec`` (or the runtime keywords ``period=``,
    ``threshold=`` …, :func:`runtime_spec`): what the cache runs with. ``clock``: the frame clock
    both are timed with (:mod:`rrcache.harness.timing`). ``miss_causes``: each frame's misses
    sorted by cause (:mod:`rrcache.runtime.misses`; it reads hit maps, so the times are not fair)."""
    result = Comparison()
    result.color_format = color_format
    with Renderer(prepared, session, resolution, window=window, color_format=color_format, clock=clock) as original, \
            CachedRenderer(variant, session, prepared, resolution, runtime_spec(variant, spec, **runtime),
                           hit_maps=hit_maps, window=window, color_format=color_format, clock=clock,
                           miss_causes=miss_causes) as cached:
        result.resolution = original.size
        result.notes = list(original.notes)
        for index in frames:
            ref = original.render_frame(index)
            got = cached.render_frame(index)
            err, left_out = mean_l2(got.image, ref.image, ref.mask)
            row = FrameComparison(index, float(err), float(psnr(got.image, ref.image)), got.hits, got.misses,
                                  got.covered_pixels, got.ms, ref.ms, nonfinite_count(got.image), int(left_out),
                                  nonfinite_count(ref.image), got.miss_causes)
            result.frames.append(row)
            result.payload_dtype = cached.payload_dtype
            if cached.payload_note and cached.payload_note not in result.notes:
                result.notes.append(cached.payload_note)
            if on_frame is not None:
                on_frame(row, got, ref)
    return result
