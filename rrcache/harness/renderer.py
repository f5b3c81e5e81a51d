"""Replaying a session through a fragment shader.

:class:`Renderer` compiles the shader with the generated vertex shader, checks that the session
supplies every uniform and sampler the program uses, uploads meshes and textures once, and then
renders frames into a colour target (RGBA32F by default; ``color_format``) plus a depth texture: depth test on, back faces
drawn, cleared to the session background. Per frame it returns a :class:`FrameResult`: the image
(H×W×4 float32, row 0 = top), the covered pixels (where geometry was drawn: depth written), the
samples that passed the depth test (an occlusion query: shaded fragments, overdraw included) and
the time of the draws (the frame clock of :mod:`rrcache.harness.timing` around clear and draws:
by default wall time between two ``ctx.finish()``), after one untimed warm-up draw of the
program, since llvmpipe compiles on the first draw.

>>> from rrcache.session import load_session
>>> session = load_session("sessions/marble.json")
>>> result = render("shaders/glslviewer_basic.glsl", session, frames=3, resolution=(64, 48))
>>> result.frames[0].image.shape, result.ms_per_frame > 0, result.frames[0].covered_pixels > 0
((48, 64, 4), True, True)
"""
from __future__ import annotations

import statistics
import time
from dataclasses import dataclass, field
from typing import Callable, Iterable, Optional

import moderngl
import numpy as np

from rrcache.errors import SessionError
from rrcache.gl.context import get_context
from rrcache import watchdog
from rrcache.gl.formats import ERROR_FORMAT, color_dtype, texture_floats
from rrcache.gl.limits import check_target_size, target_guard
from rrcache.gl.program import build_program
from rrcache.gl.resources import GLScope
from rrcache.gl.window import check_window, crop_rows
from rrcache.harness.drawer import SceneDrawer
from rrcache.compiler.prepared import PreparedShader, load_user_vertex, prepare, prepare_file
from rrcache.harness.timing import DEFAULT_CLOCK, make_clock
from rrcache.compiler.vertex import vertex_for

#: bytes per pixel a renderer needs: RGBA32F colour and depth targets (20), the colour read back
#: and flipped (32), the depth read back (4) and the coverage mask (1); checked before allocating
TARGET_BYTES_PER_PIXEL = 57


@dataclass
class FrameResult:
    """One rendered frame: ``image`` H×W×4 float32 (row 0 = top), ``mask`` H×W bool (covered
    pixels), ``covered_pixels`` = ``mask.sum()``, ``samples_passed`` (fragments that passed the
    depth test, overdraw counted), ``ms`` wall time of the draws."""

    index: int
    image: np.ndarray
    covered_pixels: int
    ms: float
    mask: np.ndarray
    samples_passed: int = 0
    cpu_ms: float = float("nan")  # process CPU time over the same span as ms (all threads)


@dataclass
class RenderResult:
    """Every rendered frame, the notes on the session (unused uniforms...), the median ms per frame
    and the resolution (w, h)."""

    frames: list[FrameResult]
    notes: list[str] = field(default_factory=list)
    ms_per_frame: float = float("nan")
    resolution: tuple[int, int] = (0, 0)


def parse_resolution(text: str) -> tuple[int, int]:
    """``"640x480"`` → ``(640, 480)``; raises ``ValueError`` on anything else.

    >>> parse_resolution("64x48")
    (64, 48)
    """
    parts = text.lower().replace("×", "x").split("x")
    if len(parts) != 2 or not all(p.strip().isdigit() for p in parts):
        raise ValueError(f"expected WIDTHxHEIGHT such as 640x480, got {text!r}")
    w, h = (int(p) for p in parts)
    if w < 1 or h < 1:
        raise ValueError(f"resolution must be positive, got {text!r}")
    return w, h


class Renderer:
    """Renders frames of ``session`` through ``prepared`` at ``resolution`` (default: the session's).

    Back faces are culled for every object the session does not mark ``double_sided`` (pass
    ``cull_back_faces`` to override). ``color_format`` (:mod:`rrcache.gl.formats`) is the colour
    target's format: ``rgba32f`` (the default, exact) for error runs, ``rgba8`` to time frames as
    an application draws them; images are float32 either way. Holds GL objects until :meth:`release` (or the end of a
    ``with`` block). ``notes`` lists what
    the session supplies that the shader does not use. ``window`` = (x, y, w, h) (pixels, origin
    bottom left) renders only that rectangle of the frame, at full pixel density (scissor test);
    images and masks are then of the window's size.

    >>> from rrcache.compiler.prepared import prepare_file
    >>> from rrcache.session import load_session
    >>> session = load_session("sessions/marble.json")
    >>> prepared = prepare_file("shaders/glslviewer_basic.glsl", session)
    >>> with Renderer(prepared, session, (32, 24)) as r:
    ...     first = r.render_frame(0)
    >>> first.image.shape
    (24, 32, 4)
    """

    def __init__(self, prepared: PreparedShader, session, resolution: Optional[tuple[int, int]] = None,
                 cull_back_faces: Optional[bool] = None, ctx: Optional[moderngl.Context] = None,
                 window: Optional[tuple[int, int, int, int]] = None, color_format: str = ERROR_FORMAT,
                 clock: str = DEFAULT_CLOCK):
        self.ctx = ctx or get_context()
        self.clock = make_clock(clock, self.ctx)
        self.prepared = prepared
        self.color_format = color_format
        self._color_dtype = color_dtype(color_format)
        self.session = session
        self.size = tuple(int(v) for v in (resolution or session.resolution))
        self._asked_size = resolution is not None
        self.window = check_window(window, self.size)
        self.cull_back_faces = cull_back_faces
        self._warm = False
        self._scope = GLScope()
        try:
            self._setup()
        except BaseException:
            self._scope.release()
            raise

    # ------------------------------------------------------------------ setup
    def _setup(self) -> None:
        ctx, prepared = self.ctx, self.prepared
        where = "resolution" if self._asked_size else f"{self.session.path}: resolution"
        check_target_size(ctx, self.size, TARGET_BYTES_PER_PIXEL, where)
        inputs = {name: d.type for name, d in prepared.inputs.items()}
        locs = {name: d.loc for name, d in prepared.inputs.items()}
        user = getattr(prepared, "vertex", None)
        self.vertex_source = vertex_for(inputs, locs, user)
        self.program = self._scope.own(build_program(
            ctx, self.vertex_source, prepared.source, prepared.line_map, fragment_name=prepared.path,
            vertex_name=user.path if user is not None else "<generated vertex shader>"))
        self.drawer = SceneDrawer(ctx, self.session, prepared, self.size, self._scope, self.cull_back_faces)
        self.plan = self.drawer.add_program(self.program)
        self.notes = self.drawer.notes
        w, h = self.size
        with target_guard(self.size, where):
            self._color = self._scope.own(ctx.texture((w, h), 4, dtype=self._color_dtype))
            self._depth = self._scope.own(ctx.depth_texture((w, h)))
            self.fbo = self._scope.own(ctx.framebuffer([self._color], self._depth))
        self.fbo.scissor = self.window
        # moderngl's Query has no release(); it goes with the Python object
        self._query = ctx.query(samples=True)

    # ------------------------------------------------------------------ per frame
    def _check_frame(self, index: int) -> int:
        return check_frame_index(self.session, index)

    def _draw(self, index: int, stages: Optional[dict] = None) -> tuple[float, int]:
        ms, samples, self._cpu_ms = self._draw_timed(index, stages)
        return ms, samples

    def _draw_timed(self, index: int, stages: Optional[dict] = None) -> tuple[float, int, float]:
        ctx = self.ctx
        self.drawer.set_frame(index)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.depth_func = "<"
        self.fbo.use()
        self.fbo.viewport = (0, 0, *self.size)
        background = session_background(self.session)
        clock = self.clock
        clock.start()
        start = clock.started
        if self.drawer.shadow_map is not None:  # the light's depth pass is part of the frame
            self.drawer.render_shadow_map()
            ctx.depth_func = "<"
            self.fbo.use()
            self.fbo.viewport = (0, 0, *self.size)
        self.fbo.clear(*background, depth=1.0)
        if stages is not None:
            cleared = clock.mark()
        with self._query:
            self.drawer.draw(self.program)
        ms = clock.stop()
        samples = int(self._query.samples)
        if stages is not None:
            end = clock.end
            stages.setdefault("clear", []).append((cleared - start) * 1000.0)
            stages.setdefault("draw", []).append((end - cleared) * 1000.0)
            stages.setdefault("queries", []).append((time.perf_counter() - end) * 1000.0)
        return ms, samples, clock.cpu_ms

    def render_frame(self, index: int, stages: Optional[dict] = None) -> FrameResult:
        """Render frame ``index`` (an int in ``0..session.frames-1``) and read it back.

        The first call draws once untimed (llvmpipe compiles the shader on its first draw).
        ``stages`` (a dict; diagnostics) gets the ms of the clear, the draw, the query result
        and the read-back of this frame, the GPU waited for after each.
        """
        index = self._check_frame(index)
        with watchdog.frame(f"frame {index} of the original"):
            if not self._warm:
                self._draw(index)
                self._warm = True
            ms, samples = self._draw(index, stages)
        read = time.perf_counter()
        w, h = self.size
        image = crop_rows(texture_floats(self._color.read(), self._color_dtype, (h, w, 4)), self.window).copy()
        depth = crop_rows(np.frombuffer(self._depth.read(), dtype=np.float32).reshape(h, w), self.window)
        if stages is not None:
            stages.setdefault("read-back", []).append((time.perf_counter() - read) * 1000.0)
        mask = depth < 1.0
        return FrameResult(index, image, int(mask.sum()), ms, mask, samples, self._cpu_ms)

    def frames(self, indices: Iterable[int]):
        """Yield a :class:`FrameResult` per frame index, in order."""
        for index in indices:
            yield self.render_frame(index)

    def release(self) -> None:
        """Release every GL object of this renderer (safe to call twice)."""
        self._scope.release()

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def check_frame_index(session, index: int) -> int:
    """``index`` as an int, or a :class:`SessionError` when it is outside the session."""
    index = int(index)
    if not 0 <= index < session.frames:
        raise SessionError(f"frame {index} is outside the session's {session.frames} frames (0..{session.frames - 1})",
                           str(session.path), "frames")
    return index


def session_background(session) -> tuple[float, float, float, float]:
    """The session's clear colour as RGBA (alpha 1 when only RGB is given; default transparent black)."""
    background = tuple(getattr(session, "background", None) or (0.0, 0.0, 0.0, 0.0))
    return (background + (1.0,))[:4] if len(background) == 3 else background


def frame_indices(session, frames=None) -> list[int]:
    """``None`` → every frame; an int ``n`` → the first ``n`` (at most all); an iterable → as given.

    >>> from types import SimpleNamespace
    >>> frame_indices(SimpleNamespace(frames=5), 3)
    [0, 1, 2]
    """
    if frames is None:
        return list(range(session.frames))
    if isinstance(frames, (int, np.integer)):
        if frames < 1:
            raise SessionError(f"asked for {frames} frames; at least 1 is needed", str(getattr(session, "path", "")), "frames")
        return list(range(min(int(frames), session.frames)))
    return [int(f) for f in frames]


def as_prepared(shader, session, defines=None) -> PreparedShader:
    """A :class:`PreparedShader` from a prepared shader, a front-end ``Shader`` or a shader path
    (loaded with the session's ``MODEL_VERTEX_*`` defines plus ``defines``), with the session's
    ``"vertex"`` shader when it names one."""
    if isinstance(shader, PreparedShader):
        return shader
    if hasattr(shader, "unit"):
        return prepare(shader, defines, load_user_vertex(None, session, shader.defines or defines))
    return prepare_file(shader, session, defines)


def render(shader, session, frames=None, resolution=None, defines=None,
           progress: Optional[Callable[[FrameResult], None]] = None, keep_images: bool = True,
           color_format: str = ERROR_FORMAT) -> RenderResult:
    """Render ``frames`` of ``session`` (None: all, an int: the first n, or a list of indices).

    ``shader`` is a :class:`PreparedShader`, a front-end ``Shader`` or a path; ``progress`` is
    called with each :class:`FrameResult` as it is done. With ``keep_images=False`` frames are
    streamed: ``progress`` sees each image, and the result keeps only the per-frame figures
    (``image`` and ``mask`` are None), so a session of a million frames runs in constant memory.
    ``color_format``: the colour target (:mod:`rrcache.gl.formats`).

    >>> from rrcache.session import load_session
    >>> result = render("shaders/glslviewer_basic.glsl", load_session("sessions/marble.json"),
    ...                 frames=2, resolution=(32, 24))
    >>> [f.index for f in result.frames]
    [0, 1]
    """
    prepared = as_prepared(shader, session, defines)
    indices = frame_indices(session, frames)
    results = []
    with Renderer(prepared, session, resolution, color_format=color_format) as renderer:
        for result in renderer.frames(indices):
            if progress is not None:
                progress(result)
            if not keep_images:
                result.image = result.mask = None
            results.append(result)
        notes = renderer.notes
        size = renderer.size
    ms = statistics.median(r.ms for r in results) if results else float("nan")
    return RenderResult(results, notes, ms, size)
