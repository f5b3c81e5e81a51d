"""`CacheRuntime`: runs a cached shader variant inside any moderngl render loop.

The runtime owns everything the cache needs on the GL side: the double-buffered payload and
inverse-depth textures, the depth buffer the passes share, the refresh pattern (block size, mode,
seed: uniforms of the rule in :mod:`rrcache.runtime.refresh`; no texture), the clock
and the occlusion queries that count shaded fragments. The application owns its geometry: each
frame it hands the runtime a ``draw(program, pass_name)`` callback that sets its own uniforms on
``program`` (including ``u_prevModelViewProjectionMatrix`` per object, for reprojection, or
``u_reprojectionMatrix`` = previous MVP × inverse(this MVP) when the variant was compiled with the
user's own vertex shader; the manifest lists the uniforms of each pass) and renders its vertex
arrays with it.

Passes (docs/design.md §3; Sitthi-amorn 2008a §3):

three-pass (default; programs ``reproject``, ``payload``, ``shade``)
    1. ``reproject`` — depth test ``<`` with depth writes. At a hit it writes the reconstructed
       payload and this pixel's inverse depth to this frame's cache; at a miss or a refresh it
       *discards*, so neither depth nor cache is written there. ``discard`` keeps early depth
       testing on llvmpipe, and no nudged depth is needed.
    2. ``payload`` — depth test ``<`` with depth writes: it runs only where pass 1 left no depth
       for this surface (misses and refreshes; at hits the stored depth equals the fragment's, so
       ``<`` fails and early-z culls the fragment). It computes the payload from scratch.
    3. ``shade`` — depth test ``==`` without writes against the now complete depth buffer: the
       original shader with the cached value replaced by ``rr_current()``, into the colour target.
       Equality (not ``<=``) matters when a pass discards a fragment after the cached value (an
       alpha test on it): no depth was written for that fragment, so the final pass must not
       shade it either, and the surface behind it, whose depth is there, is shaded instead.
two-pass (programs ``hit``, ``miss``; Nehab 2007 §3.4)
    1. ``hit`` shades hit pixels completely (colour, payload, depth); misses discard.
    2. ``miss`` computes payload and colour at the remaining pixels (three render targets).
one-pass (program ``single``): a dynamic branch in one shader.

All passes rely on identical vertex processing to reproduce identical depths; the compiler emits
one vertex shader for all of them.

Adaptive refresh (a variant compiled with ``adaptive=True``; :mod:`rrcache.runtime.adaptive`):
``threshold``, ``fast_period`` and ``spread`` make the runtime keep each entry's volatility in
two more ``R32F`` targets (read: the previous frame's, unit 14; written after the inverse depth)
and set the adaptive rule's uniforms each frame.

Window: :meth:`CacheRuntime.set_window` restricts every pass (clears included) to a rectangle
of the targets with the scissor test, at the targets' full pixel density; read-backs return
only that rectangle. The profiler measures the error of a cache this way on part of the frame
at full resolution (the resampling blur of a cache depends on the pixel size, so a smaller
render would overstate it). Pixels reprojecting from outside the window miss, as at the edge of
the screen.

Counting: ``FrameStats.misses`` is the number of fragments the miss pass shaded (an occlusion
query; it includes overdraw among missed fragments), ``covered`` the number of visible pixels
(the query of the final three-pass pass). Exact per-pixel hit maps come from
:meth:`CacheRuntime.hit_map`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional, Sequence

import moderngl
import numpy as np

from rrcache.budgets import MAX_RUNTIME_PERIOD, check_period
from rrcache.errors import RRCacheError
from rrcache.gl.context import bind_default_framebuffer
from rrcache.gl.formats import bytes_per_texel, color_dtype, texture_floats
from rrcache.gl.limits import check_target_size, target_guard
from rrcache.gl.window import check_window, crop_rows
from rrcache.runtime import glsl as G
from rrcache.runtime.adaptive import DEFAULT_FAST_PERIOD, DEFAULT_SPREAD, adaptive_uniforms
from rrcache.runtime.refresh import BLOCK_SIZES, REFRESH_MODES, refresh_uniforms

ALGORITHMS = {
    "three-pass": ("reproject", "payload", "shade"),
    "two-pass": ("hit", "miss"),
    "one-pass": ("single",),
}

PAYLOAD_DTYPES = ("f2", "f4")
#: the payload formats the runtime can hold: the compiler's (above) and ``u8``, 8-bit unsigned
#: normalised (RGBA8), which only an amortized variant with a known range of its values writes
#: (it encodes into [0, 1]: rrcache.compiler.amortize); ``payload_decode`` turns it back
RUNTIME_PAYLOAD_DTYPES = PAYLOAD_DTYPES + ("u8",)
_TEXTURE_DTYPE = {"f2": "f2", "f4": "f4", "u8": "f1"}
_PAYLOAD_BYTES = {"f2": 2, "f4": 4, "u8": 1}

# The cache's run-time parameters, given here once: every caller that does not choose one
# (the harness, the profiler's settings, the command line, a variant's manifest) takes these.
#: the refresh period Δn: every pixel is recomputed at least once in this many frames
DEFAULT_PERIOD = 8
#: the side of the square pixel blocks refreshed together (one of BLOCK_SIZES)
DEFAULT_BLOCK = 4
#: the refresh pattern (one of REFRESH_MODES)
DEFAULT_REFRESH = "random"
#: the relative depth difference beyond which a reprojected sample is a miss
DEFAULT_DEPTH_EPSILON = 1e-3
#: the hit test and payload reconstruction of a cached node when nothing chooses one (one of
#: rrcache.runtime.glsl.FILTERS). ``plane`` serves the band along depth edges from the texels of
#: the pixel's own surface, which ``bilinear`` misses: on chess (320x240, the static occlusion
#: at Δn = 50) it cut the 4x4 blocks holding a miss from a fifth to a twentieth at nearly the
#: same error, but on Marble (the whole noise at Δn = 16) it cost more than it saved and lost
#: 1.7 dB, so it is not the default everywhere
DEFAULT_FILTER = "bilinear"

DrawCallback = Callable[[moderngl.Program, str], None]

_UNIT_PREV_PAYLOAD, _UNIT_PREV_INVDEPTH, _UNIT_PREV_STATE, _UNIT_CUR_PAYLOAD = 12, 13, 14, 15


@dataclass
class FrameStats:
    """What one cached frame did. ``None`` where the algorithm cannot count it with queries."""

    frame: int
    covered: Optional[int]
    misses: Optional[int]

    @property
    def hits(self) -> Optional[int]:
        if self.covered is None or self.misses is None:
            return None
        return max(self.covered - self.misses, 0)


class CacheRuntime:
    """Run a compiled cache variant frame by frame.

    ``programs`` maps the pass names of ``algorithm`` (see :data:`ALGORITHMS`) to linked
    programs. ``size`` is (width, height). ``period`` (Δn), ``block`` (k), ``refresh`` and
    ``depth_epsilon`` can be changed between frames (they are uniforms or small textures).
    ``color_format`` (``rgba8``, ``rgba16f``, ``rgba32f``; :mod:`rrcache.gl.formats`) is the
    format of the colour target the variant draws into. ``depth_channel`` is the variant's
    (:attr:`rrcache.compiler.variant.Variant.depth_channel`): the payload channel its passes keep
    the inverse depth in (one texture and render target fewer), None for its own texture. ``cull_back_faces``: True/False sets face culling for every pass; None (the default) leaves
    the application's culling state alone (the draw callback may set it per object).
    A variant of several nodes runs in a :class:`rrcache.runtime.multi.MultiCacheRuntime` (one
    period and one payload per node); :meth:`from_spec` makes either from a variant's spec.

    Example, inside a render loop (``draw`` renders the scene with the given program)::

        rt = CacheRuntime(ctx, programs, "three-pass", (640, 480), period=16)
        for frame in range(100):
            stats = rt.frame(draw)
            image = rt.read_color()
    """

    @classmethod
    def from_spec(cls, ctx: moderngl.Context, programs: dict, spec, size: tuple[int, int], *,
                  payload_components, payload_dtype: Optional[str] = None, depth_channel: Optional[int] = None,
                  payload_decode=None, phase_cycle: int = 1, **target) -> "CacheRuntime":
        """The runtime of a variant described by ``spec`` (a :class:`rrcache.runtime.spec.VariantSpec`,
        taken whole: algorithm, periods, refresh, adaptive refresh, blend), with what its
        compilation fixed (``payload_components``, ``depth_channel``, ``payload_decode``,
        ``phase_cycle``: a compiled variant's :meth:`~rrcache.compiler.variant.Variant.runtime`
        passes them) and the application's ``target`` options (``color_format``, ``clear_color``,
        ``seed``, ``cull_back_faces``). ``payload_dtype`` overrides the spec's (a 16- or 8-bit
        cache starts in 32 bits until its values are known to fit)."""
        return cls(ctx, programs, spec.algorithm, size, payload_dtype=payload_dtype or spec.payload,
                   payload_components=payload_components, depth_channel=depth_channel,
                   payload_decode=payload_decode, phase_cycle=phase_cycle, **spec.runtime_options(), **target)

    def __init__(
        self,
        ctx: moderngl.Context,
        programs: dict[str, moderngl.Program],
        algorithm: str = "three-pass",
        size: tuple[int, int] = (640, 480),
        *,
        period: int = DEFAULT_PERIOD,
        block: int = DEFAULT_BLOCK,
        refresh: str = DEFAULT_REFRESH,
        seed: int = 0,
        payload_dtype: str = "f4",
        payload_components: int = 4,
        depth_epsilon: float = DEFAULT_DEPTH_EPSILON,
        clear_color: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0),
        cull_back_faces: Optional[bool] = None,
        blend: float = 0.0,
        phase_cycle: int = 1,
        color_format: str = "rgba32f",
        depth_channel: Optional[int] = None,
        threshold: Optional[float] = None,
        fast_period: int = DEFAULT_FAST_PERIOD,
        spread: float = DEFAULT_SPREAD,
        payload_decode: Optional[tuple[Sequence[float], Sequence[float]]] = None,
    ):
        if algorithm not in ALGORITHMS:
            raise ValueError(f"algorithm must be one of {tuple(ALGORITHMS)}, not {algorithm!r}")
        missing = [p for p in self.required_passes(algorithm, programs) if p not in programs]
        if missing:
            raise ValueError(f"{algorithm} needs programs for passes {missing}")
        if payload_dtype not in RUNTIME_PAYLOAD_DTYPES:
            raise ValueError(f"payload_dtype must be one of {RUNTIME_PAYLOAD_DTYPES}, not {payload_dtype!r}")
        # (offset, span) per channel: what the passes wrote is (value - offset) / span, which
        # read_payload undoes (None: the values themselves)
        self.payload_decode = None if payload_decode is None else tuple(
            np.asarray(v, np.float32).reshape(4) for v in payload_decode)
        if refresh not in REFRESH_MODES:
            raise ValueError(f"refresh must be one of {REFRESH_MODES}, not {refresh!r}")
        if block not in BLOCK_SIZES:
            raise ValueError(f"block must be one of {BLOCK_SIZES}, not {block}")
        # adaptive refresh (rrcache.runtime.adaptive): a variant compiled for it declares
        # rr_threshold and needs one (and the volatility targets); any other variant takes none
        compiled_adaptive = any(programs[p] is not None and "rr_threshold" in programs[p]
                                for p in self.required_passes(algorithm, programs))
        if compiled_adaptive and threshold is None:
            raise ValueError("this variant was compiled for adaptive refresh: give a threshold")
        if threshold is not None and not compiled_adaptive:
            raise ValueError("a threshold needs a variant compiled with adaptive=True")
        self.adaptive = threshold is not None
        self.threshold = float(threshold) if threshold is not None else None
        self.fast_period = check_period(fast_period, "fast_period", MAX_RUNTIME_PERIOD) if self.adaptive else 1
        self.spread = float(spread)
        self.ctx = ctx
        self.color_format = color_format
        self._color_dtype = color_dtype(color_format)
        self.programs = programs
        self.algorithm = algorithm
        self.payload_dtype = payload_dtype
        if payload_components not in (1, 2, 3, 4):
            raise ValueError(f"payload_components must be 1 to 4, not {payload_components}")
        self.payload_components = int(payload_components)
        #: each cached node's payload components (one node here; MultiCacheRuntime sets its own)
        self.node_components = getattr(self, "node_components", None) or (self.payload_components,)
        if depth_channel is not None and (int(depth_channel) != self.payload_components or payload_dtype != "f4"):
            raise ValueError(f"the inverse depth packs into channel {self.payload_components} of a 32-bit payload "
                             f"(rrcache.runtime.glsl.depth_channel_for), not channel {depth_channel} of {payload_dtype}")
        self.depth_channel = None if depth_channel is None else int(depth_channel)
        self._check_depth_layout(programs)
        self.clear_color = clear_color
        self.cull_back_faces = cull_back_faces
        self.depth_epsilon = float(depth_epsilon)
        self.blend = float(blend)  # λ of an amortized variant: c = λ·c_prev + (1-λ)·x at hits
        # an amortized variant's per-phase programs: at clock % phase_cycle == k > 0 the pass
        # "<name>@<k>" runs in the place of "<name>" (rrcache.compiler.amortize, "frame" mode)
        self.phase_cycle = int(phase_cycle)
        self.seed = seed
        self._period = 1
        self.period = period
        self._block = block
        self._refresh_mode = refresh
        self.clock = 0
        self._index = 0
        self._valid = False
        self._resources: list = []
        # one query per counted pass, read after the whole frame is submitted: reading a
        # result right after its pass waits for that pass and stalls the next one's set-up
        # (about 0.2 ms of Marble's ~17 ms cached frame at 640x480, measured side by side)
        self._queries = [ctx.query(samples=True), ctx.query(samples=True)]
        self.size = (0, 0)
        self.window: Optional[tuple[int, int, int, int]] = None
        self.resize(size)

    def _check_depth_layout(self, programs) -> None:
        """The pass that reads the previous frame's cache must read the inverse depth where this
        runtime keeps it: a variant compiled with the inverse depth packed into the payload has
        no ``rr_prevInvDepth`` (and a runtime made without its ``depth_channel`` would never
        clear that channel: stale entries would hit)."""
        first = programs.get(ALGORITHMS[self.algorithm][0])
        if first is None or not hasattr(first, "__contains__"):
            return
        separate = G.PREV_INVDEPTH in first
        if separate and self.depth_channel is not None:
            raise ValueError("these programs read the inverse depth from its own texture: make the runtime "
                             "without depth_channel (it must be the variant's depth_channel)")
        if not separate and self.depth_channel is None and G.PREV_PAYLOAD in first:
            raise ValueError("these programs keep the inverse depth in the payload: pass "
                             "depth_channel=variant.depth_channel and payload_components=variant.components")

    def required_passes(self, algorithm: str, programs) -> tuple:
        """The programs ``algorithm`` needs (a multi-node runtime may run another layout)."""
        return ALGORITHMS[algorithm]

    # ------------------------------------------------------------------ configuration

    @property
    def period(self) -> int:
        return self._period

    @period.setter
    def period(self, value: int) -> None:
        try:
            self._period = check_period(value, "period", MAX_RUNTIME_PERIOD)
        except RRCacheError as err:  # the runtime's API has always raised ValueError here
            raise ValueError(str(err)) from None

    def set_refresh(self, mode: Optional[str] = None, block: Optional[int] = None, seed: Optional[int] = None) -> None:
        """Change the refresh pattern (mode ``random``/``tiled``, block size k, seed)."""
        if mode is not None:
            if mode not in REFRESH_MODES:
                raise ValueError(f"refresh must be one of {REFRESH_MODES}, not {mode!r}")
            self._refresh_mode = mode
        if block is not None:
            if block not in BLOCK_SIZES:
                raise ValueError(f"block must be one of {BLOCK_SIZES}, not {block}")
            self._block = block
        if seed is not None:
            self.seed = seed

    # ------------------------------------------------------------------ resources

    def resize(self, size: tuple[int, int]) -> None:
        """(Re)allocate every target for a new viewport size; the cache starts empty."""
        w, h = int(size[0]), int(size[1])
        if w < 1 or h < 1:
            raise ValueError(f"viewport size must be positive, not {w}x{h}")
        check_target_size(self.ctx, (w, h), self.bytes_per_pixel(), "cache size")
        self._release_targets()
        ctx = self.ctx
        self.size = (w, h)
        with target_guard((w, h), "cache size"):
            self.depth = ctx.depth_texture((w, h))
            self.color = ctx.texture((w, h), 4, dtype=self._color_dtype)
            packed = self.depth_channel is not None
            channels = self.payload_components + (1 if packed else 0)
            self._payload = [ctx.texture((w, h), channels, dtype=_TEXTURE_DTYPE[self.payload_dtype]) for _ in range(2)]
            # packed: the inverse depth is the payload's channel depth_channel, no texture of its own
            self._invdepth = [] if packed else [ctx.texture((w, h), 1, dtype="f4") for _ in range(2)]
            # adaptive refresh: each entry's volatility, written after the inverse depth
            self._state = [ctx.texture((w, h), 1, dtype="f4") for _ in range(2)] if self.adaptive else []
            state = [[t] for t in self._state] if self.adaptive else [[], []]
            for tex in self._payload + self._invdepth + self._state:
                tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
                tex.repeat_x = tex.repeat_y = False
            depth_of = self._payload if packed else self._invdepth
            cache = [[self._payload[i]] + ([] if packed else [self._invdepth[i]]) for i in range(2)]
            if self.algorithm == "three-pass":
                self._cache_fbos = [ctx.framebuffer(cache[i] + state[i], self.depth) for i in range(2)]
            else:
                self._cache_fbos = [ctx.framebuffer([self.color] + cache[i] + state[i], self.depth)
                                    for i in range(2)]
            # cleared each frame: inverse depth to 0 ("nothing cached here") with the depth buffer, and
            # the colour to the background; the payload needs no clear (it is read only where the
            # inverse depth says a surface was cached; packed, it is cleared with it)
            self._clear_fbos = [ctx.framebuffer([depth_of[i]], self.depth) for i in range(2)]
            self._out_fbo = ctx.framebuffer([self.color], self.depth)
            self._color_only_fbo = ctx.framebuffer([self.color])
        self._resources = [self.depth, self.color, *self._payload, *self._invdepth, *self._state, *self._cache_fbos,
                           *self._clear_fbos, self._out_fbo, self._color_only_fbo]
        self._make_zero_fbos()
        if self.window is not None:
            try:
                check_window(self.window, self.size)
            except ValueError:
                self.window = None
        self._apply_window()
        self.reset()

    def set_window(self, window: Optional[tuple[int, int, int, int]]) -> None:
        """Restrict rendering to ``window`` = (x, y, width, height) in pixels of the targets,
        origin at the bottom left as in GL (None: the whole target). The cache starts empty."""
        self.window = check_window(window, self.size)
        self._apply_window()
        self.reset()

    def _apply_window(self) -> None:
        # the inverse depth outside the window is never written again: clear it to "nothing
        # cached" once, over the whole target, so that reprojecting from there misses
        for fbo in self._clear_fbos:
            fbo.scissor = None
            fbo.use()
            fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        bind_default_framebuffer(self.ctx)
        for fbo in (*self._cache_fbos, *self._clear_fbos, self._out_fbo, self._color_only_fbo):
            fbo.scissor = self.window

    def bytes_per_pixel(self) -> int:
        """Memory per pixel of the cache's targets (depth, colour, two payloads, two inverse
        depths) plus the colour and depth read back (41): what :meth:`resize` checks first."""
        packed = getattr(self, "depth_channel", None) is not None
        payload = (self.payload_components + (1 if packed else 0)) * _PAYLOAD_BYTES[self.payload_dtype]
        state = 2 * 4 if getattr(self, "adaptive", False) else 0
        return 4 + bytes_per_texel(self.color_format) + 2 * payload + (0 if packed else 2 * 4) + state + 41

    def reset(self) -> None:
        """Forget the cache: the next frame misses everywhere (as after a camera cut), the clock
        starts again at 0 and the cache's targets (payloads, inverse depths, volatility) are
        cleared, so a run after a reset renders exactly what a new runtime does whatever ran
        before it (a profile resumed after a kill measures what an uninterrupted one does; a
        renderer serving many runs measures what one per run would: the bilinear lookups of the
        second frame near silhouettes read texels the first frame did not write). Binds the
        default framebuffer."""
        self._valid = False
        self.clock = 0
        for fbo in getattr(self, "_zero_fbos", ()):
            fbo.scissor = None
            fbo.use()
            fbo.clear(0.0, 0.0, 0.0, 0.0)
        bind_default_framebuffer(self.ctx)

    def _cache_textures(self) -> list:
        """Every texture the cache keeps from frame to frame (what :meth:`reset` clears)."""
        return [*self._payload, *self._invdepth, *self._state]

    def _make_zero_fbos(self) -> None:
        """One framebuffer per cache texture, to clear it whole (:meth:`reset`)."""
        self._zero_fbos = [self.ctx.framebuffer([tex]) for tex in self._cache_textures()]
        self._resources += self._zero_fbos

    def _release_targets(self) -> None:
        # moderngl re-binds the current framebuffer whenever it creates a new one: if the bound
        # framebuffer was released (ours, or one of the application's) that raises
        # GL_INVALID_OPERATION, so bind the default framebuffer before releasing or creating any
        bind_default_framebuffer(self.ctx)
        for res in self._resources:
            res.release()
        self._resources = []
        self._zero_fbos = []

    def release(self) -> None:
        """Release every GL object the runtime made (not the programs, which the caller owns)."""
        self._release_targets()
        self._queries = []

    # ------------------------------------------------------------------ the frame

    def _begin_frame(self) -> None:
        """The state every frame starts from: depth test on, faces culled as asked, this frame's
        colour cleared and its depth cleared to the far plane."""
        ctx = self.ctx
        ctx.enable(moderngl.DEPTH_TEST)
        if self.cull_back_faces is True:
            ctx.enable(moderngl.CULL_FACE)
        elif self.cull_back_faces is False:
            ctx.disable(moderngl.CULL_FACE)
        self._color_only_fbo.use()
        self._color_only_fbo.clear(*self.clear_color)
        clear_fbo = self._clear_fbos[self._index]
        clear_fbo.depth_mask = True
        clear_fbo.use()
        clear_fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)

    def _set(self, program: moderngl.Program, name: str, value) -> None:
        if name in program:
            program[name].value = value

    def _bind_cache_uniforms(self, program: moderngl.Program) -> None:
        prev = 1 - self._index
        self._payload[prev].use(_UNIT_PREV_PAYLOAD)
        if self._invdepth:
            self._invdepth[prev].use(_UNIT_PREV_INVDEPTH)
        if self.algorithm == "three-pass":
            self._payload[self._index].use(_UNIT_CUR_PAYLOAD)
        self._set(program, G.PREV_PAYLOAD, _UNIT_PREV_PAYLOAD)
        self._set(program, G.PREV_INVDEPTH, _UNIT_PREV_INVDEPTH)
        self._set(program, G.CUR_PAYLOAD, _UNIT_CUR_PAYLOAD)
        for name, value in self._refresh_values.items():
            self._set(program, name, value)
        if self.adaptive:
            self._state[prev].use(_UNIT_PREV_STATE)
            self._set(program, "rr_prevState", _UNIT_PREV_STATE)
            for name, value in self._adaptive_values.items():
                self._set(program, name, value)
        self._set(program, "rr_valid", self._valid)
        self._set(program, "rr_depthEpsilon", self.depth_epsilon)
        # amortized sampling (rrcache.compiler.amortize): the frame picks the subset, λ the blend
        self._set(program, "rr_amortFrame", self.clock)
        self._set(program, "rr_lambda", self.blend)

    def _run(self, pass_name: str, draw: DrawCallback, query: Optional[moderngl.Query] = None) -> None:
        program = self.programs[pass_name]
        if self.phase_cycle > 1 and self.clock % self.phase_cycle:
            program = self.programs.get(f"{pass_name}@{self.clock % self.phase_cycle}", program)
        self._bind_cache_uniforms(program)
        if query is None:
            draw(program, pass_name)
            return
        with query:
            draw(program, pass_name)

    def frame(self, draw: DrawCallback, count: bool = True, after_first_pass: Optional[Callable[[], None]] = None,
              mark: Optional[Callable[[str], None]] = None) -> FrameStats:
        """Render one frame with the cache and advance the clock.

        ``after_first_pass`` (diagnostics only; it breaks timing) runs after the reprojection
        pass, e.g. to read the hit map. ``mark(stage)`` (diagnostics: the per-pass breakdown of
        ``rrcache bench-cache``) is called after the clears (``"clear"``), after each pass (its
        name) and after the query results are read (``"queries"``); it may wait for the GPU.
        """
        ctx = self.ctx
        mark = mark or (lambda _stage: None)
        self._begin_frame()
        cache_fbo = self._cache_fbos[self._index]
        cache_fbo.depth_mask = True
        cache_fbo.use()
        ctx.depth_func = "<"
        first, second = self._queries if count else (None, None)
        # the refresh rule's uniforms, once per frame for every pass
        self._refresh_values = refresh_uniforms(self.size, self._block, self._refresh_mode, self.seed,
                                                self._period, self.clock)
        if self.adaptive:
            self._adaptive_values = adaptive_uniforms(self.size, self._block, self._refresh_mode, self.seed,
                                                      self.fast_period, self.clock, self.threshold, self.spread,
                                                      self.payload_components)
        mark("clear")
        covered = misses = None
        if self.algorithm == "three-pass":
            self._run("reproject", draw)
            mark("reproject")
            if after_first_pass:
                after_first_pass()
                cache_fbo.use()
            self._run("payload", draw, first)
            mark("payload")
            self._out_fbo.depth_mask = False
            self._out_fbo.use()
            ctx.depth_func = "=="
            self._run("shade", draw, second)
            mark("shade")
            self._out_fbo.depth_mask = True
            if count:
                misses, covered = int(first.samples), int(second.samples)
        elif self.algorithm == "two-pass":
            self._run("hit", draw, first)
            mark("hit")
            if after_first_pass:
                after_first_pass()
                cache_fbo.use()
            self._run("miss", draw, second)
            mark("miss")
            if count:
                misses = int(second.samples)
                covered = int(first.samples) + misses
        else:
            self._run("single", draw)
            mark("single")
        if count:
            mark("queries")
        return self._end_frame(covered, misses)

    def _end_frame(self, covered, misses) -> FrameStats:
        """The frame's statistics; the depth test back to ``<``, the targets swapped (this
        frame's cache becomes the previous one) and the clock advanced."""
        self.ctx.depth_func = "<"
        stats = FrameStats(self.clock, covered, misses)
        self._index = 1 - self._index
        self._valid = True
        self.clock += 1
        return stats

    # ------------------------------------------------------------------ read-back

    def _read(self, tex: moderngl.Texture, components: int) -> np.ndarray:
        w, h = self.size
        return crop_rows(texture_floats(tex.read(), tex.dtype, (h, w, components)), self.window).astype(np.float32)

    def read_color(self) -> np.ndarray:
        """The last frame's colour, float32 (height, width, 4), row 0 = top of the image (only
        the window when one is set, as every read)."""
        return self._read(self.color, 4)

    def read_depth(self) -> np.ndarray:
        """The last frame's window depth (1.0 where nothing was drawn), row 0 = top."""
        w, h = self.size
        return crop_rows(np.frombuffer(self.depth.read(), dtype=np.float32).reshape(h, w), self.window).copy()

    def read_payload(self) -> np.ndarray:
        """The last frame's cache payload, float32 (height, width, 4; unused channels 0), row 0
        = top. Pixels where nothing was cached hold stale values: mask them with
        :meth:`read_inverse_depth` > 0."""
        payload = self._read(self._payload[1 - self._index], self.payload_components + (self.depth_channel is not None))
        payload = payload[..., :self.payload_components]
        if self.payload_decode is not None:
            offset, span = self.payload_decode
            payload = payload * span[:self.payload_components] + offset[:self.payload_components]
        if self.payload_components < 4:
            payload = np.concatenate([payload, np.zeros(payload.shape[:2] + (4 - self.payload_components,), np.float32)], axis=-1)
        return payload

    def read_payloads(self) -> list:
        """Every cached node's payload (:meth:`read_payload`), in node order: one here."""
        return [self.read_payload()]

    def read_inverse_depth(self, current: bool = False) -> np.ndarray:
        """1/w of the visible surface per pixel (0 where nothing is cached), row 0 = top.
        ``current=True`` reads the target being written in the frame in progress (for
        ``after_first_pass`` diagnostics: after pass 1 it is non-zero exactly at the hits)."""
        index = self._index if current else 1 - self._index
        if self.depth_channel is not None:
            return self._read(self._payload[index], self.payload_components + 1)[..., self.depth_channel]
        return self._read(self._invdepth[index], 1)[..., 0]

