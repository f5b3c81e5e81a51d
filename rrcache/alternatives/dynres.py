"""Dynamic resolution (main paper §5.4, after Montrym et al. 1997): shade the original shader at
a reduced resolution and upsample bilinearly to the target.

:class:`DynresRenderer` renders frame ``i`` of a session with the unchanged shader into an
off-screen RGBA32F target of ``round(w·s) × round(h·s)`` pixels (the shader sees that size as
``u_resolution``), then draws one full-screen triangle into the ``w × h`` target that samples it
with ``GL_LINEAR`` filtering (texel centres aligned: bilinear upsampling). The time of a frame
covers both: clear, scene draws, upsample draw and ``ctx.finish()``.

:func:`tune_scale` finds the scale whose speed-up over the original matches a target, each step
measured side by side with the original (:func:`rrcache.alternatives.measure.compare_renderers`)
and searched by :func:`rrcache.alternatives.search.match_scale`.

>>> from rrcache.pipeline import load_for_session
>>> from rrcache.session import load_session
>>> session = load_session("sessions/marble.json")
>>> work = load_for_session("shaders/glslviewer_basic.glsl", session)
>>> with DynresRenderer(work.prepared, session, (64, 48), scale=0.5) as r:
...     r.low_size, r.render_frame(0).image.shape
((32, 24), (48, 64, 4))
"""
from __future__ import annotations

from typing import Callable, Optional

import moderngl
import numpy as np

from rrcache.errors import RRCacheError
from rrcache.gl.context import get_context
from rrcache.gl.program import build_program, fullscreen_vertex
from rrcache.gl.resources import GLScope
from rrcache.harness.drawer import SceneDrawer
from rrcache.harness.renderer import FrameResult, Renderer, check_frame_index, session_background
from rrcache.harness.timing import DEFAULT_CLOCK, make_clock
from rrcache.compiler.vertex import vertex_for
from rrcache.alternatives.measure import compare_renderers
from rrcache.alternatives.search import SearchResult, match_scale

_UPSAMPLE_FRAGMENT = """#version 330 core
uniform sampler2D rr_low;
uniform vec2 rr_targetSize;
out vec4 rr_color;
void main() {
    rr_color = texture(rr_low, gl_FragCoord.xy / rr_targetSize);
}
"""


def low_size(size: tuple[int, int], scale: float) -> tuple[int, int]:
    """The shading resolution for ``scale`` (at least 1×1).

    >>> low_size((640, 480), 0.5), low_size((64, 48), 0.01)
    ((320, 240), (1, 1))
    """
    if not (isinstance(scale, (int, float)) and 0 < scale <= 1):
        raise RRCacheError(f"{scale!r} is not a resolution scale", "dynamic resolution",
                           hint="give a scale in (0, 1], the fraction of the width and height shaded")
    w, h = size
    return max(1, int(round(w * scale))), max(1, int(round(h * scale)))


class DynresRenderer:
    """Renders frames of ``session`` through ``prepared`` shaded at ``scale`` of ``size`` and
    upsampled bilinearly to ``size``. :meth:`render_frame` returns a
    :class:`~rrcache.harness.renderer.FrameResult` at ``size`` whose ``mask`` is the low-resolution
    coverage upsampled by nearest neighbour."""

    def __init__(self, prepared, session, size: Optional[tuple[int, int]], scale: float,
                 ctx: Optional[moderngl.Context] = None, clock: str = DEFAULT_CLOCK):
        self.ctx = ctx or get_context()
        self.clock = make_clock(clock, self.ctx)
        self.session = session
        self.size = tuple(int(v) for v in (size or session.resolution))
        self.scale = float(scale)
        self.low_size = low_size(self.size, self.scale)
        self._scope = GLScope()
        self._warm = False
        try:
            self._setup(prepared)
        except BaseException:
            self._scope.release()
            raise

    def _setup(self, prepared) -> None:
        ctx, scope = self.ctx, self._scope
        inputs = {name: d.type for name, d in prepared.inputs.items()}
        locs = {name: d.loc for name, d in prepared.inputs.items()}
        self.program = scope.own(build_program(ctx, vertex_for(inputs, locs, getattr(prepared, "vertex", None)), prepared.source, prepared.line_map,
                                               fragment_name=prepared.path))
        self.drawer = SceneDrawer(ctx, self.session, prepared, self.low_size, scope)
        self.drawer.add_program(self.program)
        self.notes = self.drawer.notes
        self._low = scope.own(ctx.texture(self.low_size, 4, dtype="f4"))
        self._low.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self._low.repeat_x = self._low.repeat_y = False
        self._low_depth = scope.own(ctx.depth_texture(self.low_size))
        self._low_fbo = scope.own(ctx.framebuffer([self._low], self._low_depth))
        self._color = scope.own(ctx.texture(self.size, 4, dtype="f4"))
        self._fbo = scope.own(ctx.framebuffer([self._color]))
        self._upsample = scope.own(build_program(ctx, fullscreen_vertex(0.0), _UPSAMPLE_FRAGMENT,
                                                 fragment_name="<rrcache bilinear upsample>"))
        self._upsample["rr_low"].value = 0
        self._upsample["rr_targetSize"].value = tuple(float(v) for v in self.size)
        self._quad = scope.own(ctx.vertex_array(self._upsample, []))

    def _draw(self, index: int) -> float:
        ctx = self.ctx
        self.drawer.set_frame(index)
        self.clock.start()
        self.drawer.render_shadow_map()  # the light's depth pass is part of the frame
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.depth_func = "<"
        self._low_fbo.use()
        self._low_fbo.viewport = (0, 0, *self.low_size)
        self._low_fbo.clear(*session_background(self.session), depth=1.0)
        self.drawer.draw(self.program)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        self._fbo.use()
        self._fbo.viewport = (0, 0, *self.size)
        self._low.use(location=0)
        self._quad.render(moderngl.TRIANGLES, vertices=3)
        return self.clock.stop()

    def render_frame(self, index: int) -> FrameResult:
        """Render frame ``index`` (the first call draws once untimed: llvmpipe compiles then)."""
        index = check_frame_index(self.session, index)
        if not self._warm:
            self._draw(index)
            self._warm = True
        ms = self._draw(index)
        w, h = self.size
        lw, lh = self.low_size
        image = np.frombuffer(self._color.read(), dtype=np.float32).reshape(h, w, 4)[::-1].copy()
        depth = np.frombuffer(self._low_depth.read(), dtype=np.float32).reshape(lh, lw)[::-1]
        rows = np.minimum((np.arange(h) + 0.5) * lh / h, lh - 1).astype(int)
        cols = np.minimum((np.arange(w) + 0.5) * lw / w, lw - 1).astype(int)
        mask = (depth < 1.0)[np.ix_(rows, cols)]
        return FrameResult(index, image, int(mask.sum()), ms, mask)

    def release(self) -> None:
        self._scope.release()

    def __enter__(self) -> "DynresRenderer":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def measure_scale(prepared, session, size, frames, original: Optional[Renderer] = None,
                  on_frame: Optional[Callable] = None):
    """A function ``scale -> Comparison`` measuring dynamic resolution at ``scale`` over
    ``frames`` side by side with the original (``original`` reused when given;
    ``on_frame(row, frame, original's frame)`` after each frame)."""

    def run(scale: float):
        own = original is None
        ref = Renderer(prepared, session, size) if own else original
        try:
            with DynresRenderer(prepared, session, size, scale) as dyn:
                return compare_renderers(ref, dyn, frames, on_frame=on_frame)
        finally:
            if own:
                ref.release()

    return run


def tune_scale(prepared, session, size, frames, target_speedup: float, lo: float = 0.1, rel_tol: float = 0.05,
               max_steps: int = 8, progress: Optional[Callable[[float, float], None]] = None) -> SearchResult:
    """The scale whose measured speed-up (over ``frames``, side by side) matches
    ``target_speedup``; ``progress(scale, speedup)`` after each step."""
    with Renderer(prepared, session, size) as original:
        run = measure_scale(prepared, session, size, frames, original)

        def measure(scale: float) -> float:
            speedup = run(scale).speedup
            if progress is not None:
                progress(scale, speedup)
            return speedup

        return match_scale(measure, target_speedup, lo=lo, hi=1.0, rel_tol=rel_tol, max_steps=max_steps)
