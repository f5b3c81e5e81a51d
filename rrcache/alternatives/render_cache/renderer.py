"""The render cache over the harness: one frame, every stage, timed.

:class:`RenderCacheRenderer` replays a session with the render cache (Walter et al. 1999, 2002)
in front of the user's shader. Frame ``n`` (consecutive frames; a jump is a cold start):

1. **shade** (the renderer): the pixels requested during frame ``n-1`` are shaded with the
   user's shader at frame ``n`` (:class:`~rrcache.alternatives.render_cache.shading.SampleShader`;
   the light's shadow map included). The paper's renderer answers a frame late, asynchronously;
   here it answers at the start of the next frame, with that frame's camera, so a sample lands on
   a pixel centre of the frame that shows it. A cold start (the first frame, or after a jump)
   shades every pixel, as the reprojection cache's first frame misses everywhere;
2. **update points**: the points age (:meth:`~rrcache.alternatives.render_cache.points.PointCache.age_points`:
   the paper's increment for the per-frame budget, faster when not visible or near a colour
   change) and the new samples are unprojected (window depth → world; a moving object's points
   into its object space; a sample with no surface becomes a background point far along its ray)
   and written into the ring. A sample whose colour differs from what the last frame showed at
   its pixel by more than ``change_threshold`` marks a colour change;
3. **predicted projection** / **predicted sampling** (the session knows frame ``n+1``'s camera):
   the points projected on the quarter-resolution occupancy image of frame ``n+1``; its empty
   pixels are requested, at most ``predict_share`` of the budget;
4. **project** and **z-buffer**: every live point into frame ``n``, the nearest per pixel; the
   samples shaded this frame keep their own pixel (the renderer resolved visibility there);
5. **depth cull**, **interpolate** (the 3×3 filter and the priority image) and **prefilter**
   (the 7×7 filter where the 3×3 one finds too few points): :mod:`~rrcache.alternatives.render_cache.filters`;
6. **sampling**: the priority image dithered on the block grid under what is left of the budget
   (:func:`~rrcache.alternatives.render_cache.sampling.dither`): the requests for frame ``n+1``;
7. **display**: the image is uploaded to a texture (an application shows it from there).

The frame time is the wall time of all of it, from the shadow map to the upload and
``ctx.finish()``; ``stages`` has each stage's share (the paper's Table 1). The image and coverage
are read afterwards, untimed, as every renderer of the harness does.

>>> from rrcache.compiler.prepared import prepare_file
>>> from rrcache.session import load_session
>>> session = load_session("sessions/marble.json")
>>> prepared = prepare_file("shaders/glslviewer_basic.glsl", session)
>>> with RenderCacheRenderer(prepared, session, (32, 24), RenderCacheSettings(samples=0.1)) as rc:
...     frames = [rc.render_frame(i) for i in range(3)]
>>> frames[0].shaded, frames[1].shaded <= frames[1].budget, frames[2].image.shape
(768, True, (24, 32, 4))
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Optional

import moderngl
import numpy as np

from rrcache import watchdog
from rrcache.alternatives.render_cache.filters import box3, depth_cull, reconstruct
from rrcache.alternatives.render_cache.points import BACKGROUND, STATIC, PointCache
from rrcache.alternatives.render_cache.projection import Projector, screen_matrix, zbuffer
from rrcache.alternatives.render_cache.sampling import (block_priority, blocks_to_pixels, dither, grid_size,
                                                        hilbert_order, predicted_requests)
from rrcache.kinds.render_cache import RenderCacheSettings
from rrcache.alternatives.render_cache.shading import SampleShader
from rrcache.gl.formats import ERROR_FORMAT
from rrcache.gl.resources import GLScope
from rrcache.harness.renderer import FrameResult, check_frame_index, session_background
from rrcache.harness.timing import DEFAULT_CLOCK, make_clock

#: a background sample becomes a point this many times the far plane away along its view ray
BACKGROUND_DISTANCE = 1000.0

#: the stages of a frame, in order (the paper's Table 1 plus the renderer and the display)
STAGES = ("shade", "update points", "predicted projection", "predicted sampling", "project", "z-buffer",
          "depth cull", "interpolate", "prefilter", "sampling", "display")


@dataclass
class RenderCacheFrame(FrameResult):
    """A :class:`~rrcache.harness.renderer.FrameResult` with the render cache's own figures:
    ``shaded`` pixels this frame (every pixel on a cold start), the per-frame pixel ``budget``,
    the pixels ``requested`` for the next frame (``predicted`` of them by prediction), the live
    ``points``, how the image's pixels were filled (``filled``: point, interpolated,
    prefiltered, empty) and the ms of each stage (``stages``)."""

    shaded: int = 0
    budget: int = 0
    requested: int = 0
    predicted: int = 0
    points: int = 0
    cold: bool = False
    filled: dict = field(default_factory=dict)
    stages: dict = field(default_factory=dict)


class RenderCacheRenderer:
    """Renders frames of ``session`` through the render cache in front of ``prepared`` at ``size``
    (default: the session's) with ``settings`` (see the module docstring); the renderer shades into
    ``color_format`` (:mod:`rrcache.gl.formats`), the points and the image are float32."""

    def __init__(self, prepared, session, size: Optional[tuple[int, int]] = None,
                 settings: RenderCacheSettings = RenderCacheSettings(), ctx: Optional[moderngl.Context] = None,
                 color_format: str = ERROR_FORMAT):
        self.settings = settings.checked()
        self.session = session
        self.size = tuple(int(v) for v in (size or session.resolution))
        w, h = self.size
        self.pixels = w * h
        self.budget = settings.pixel_budget(self.pixels)
        self.cache = PointCache(settings.capacity(self.pixels))
        self.projector = Projector(self.cache.capacity)
        self.quarter = (-(-w // 4), -(-h // 4))
        self.grid = grid_size(self.size, settings.block)
        self._order = hilbert_order(*self.grid)
        self._rng = np.random.default_rng(settings.seed)
        self._scope = GLScope()
        try:
            self.shader = SampleShader(prepared, session, self.size, ctx, color_format)
            self.ctx = self.shader.ctx
            self.frame_clock = make_clock(DEFAULT_CLOCK, self.ctx)  # (rrcache.harness.timing)
            self.notes = self.shader.notes
            self._display = self._scope.own(self.ctx.texture(self.size, 3, dtype="f4"))
        except BaseException:
            self._scope.release()
            raise
        self._warm = False
        self._reset()

    def _reset(self) -> None:
        self.cache.clear()
        self._last: Optional[int] = None
        self._requests = np.zeros(0, np.int64)
        background = np.asarray(session_background(self.session)[:3], np.float32)
        self._previous = np.broadcast_to(background[:, None, None], (3, self.size[1], self.size[0])).copy()
        self._visible = None
        self._changed = np.zeros(0, np.int64)

    # ------------------------------------------------------------------ geometry
    def _matrices(self, frame: int, scale: float = 1.0):
        """The screen matrix of ``frame`` (scaled by ``scale`` in x and y) and one per moving object."""
        w, h = self.size
        cam = self.session.camera_at(frame)
        view_projection = cam.projection(w / h) @ cam.view
        screen = np.diag([scale, scale, 1.0]) @ screen_matrix(view_projection, self.size)
        moving = {k: screen @ self.session.objects[k].model_matrix(frame) for k in self.shader.moving}
        return screen, moving

    def _unproject(self, samples) -> tuple[np.ndarray, np.ndarray]:
        """World (or moving objects' object-space) positions and the objects of the samples."""
        w, h = self.size
        cam = self.session.camera_at(samples.frame)
        inverse = np.linalg.inv(cam.projection(w / h) @ cam.view)
        cols, rows = samples.pixels % w, samples.pixels // w
        background = samples.depth >= 1.0
        ndc = np.stack([(cols + 0.5) * (2.0 / w) - 1.0, (rows + 0.5) * (2.0 / h) - 1.0,
                        np.where(background, 1.0, samples.depth.astype(np.float64) * 2.0 - 1.0),
                        np.ones(len(cols))])
        world = inverse @ ndc
        world = (world[:3] / world[3]).T
        objects = samples.object.astype(np.int16).copy()
        if background.any():
            eye = np.asarray(cam.eye, np.float64)
            ray = world[background] - eye
            ray /= np.linalg.norm(ray, axis=1, keepdims=True)
            world[background] = eye + ray * (BACKGROUND_DISTANCE * cam.far)
            objects[background] = BACKGROUND
        for k in np.unique(objects[objects >= 0]):
            on = objects == k
            model = self.session.objects[int(k)].model_matrix(samples.frame)
            p = np.linalg.inv(model) @ np.vstack([world[on].T, np.ones(int(on.sum()))])
            world[on] = (p[:3] / p[3]).T
        return world.astype(np.float32), objects

    # ------------------------------------------------------------------ one frame
    def _frame(self, index: int, stages: dict) -> dict:
        s, cache, (w, h) = self.settings, self.cache, self.size
        ctx = self.ctx
        last = time.perf_counter()

        def clock(stage: str) -> None:
            nonlocal last
            now = time.perf_counter()
            stages[stage] = stages.get(stage, 0.0) + (now - last) * 1000.0
            last = now

        cold = self._last is None or index != self._last + 1
        if cold:
            self._reset()
            pixels = np.arange(self.pixels, dtype=np.int64)
        else:
            pixels = self._requests
        samples = self.shader.shade(index, pixels, every_pixel=cold)
        clock("shade")

        # update points: age, then insert the new samples
        if not cold:
            cache.age_points(self.budget, self._visible, s.invisible_rate, self._changed, s.change_penalty)
        positions, objects = self._unproject(samples)
        changed_pixels = np.zeros(0, np.int64)
        if not cold and len(samples.pixels):
            before = self._previous.reshape(3, -1)[:, samples.pixels].T
            diff = np.sqrt(((samples.color - before) ** 2).sum(axis=1))
            changed_pixels = samples.pixels[diff > s.change_threshold]
        fresh = cache.insert(positions, samples.color, objects, index)
        fresh_pixels = samples.pixels[-len(fresh):] if len(fresh) else samples.pixels[:0]
        clock("update points")

        # predictive sampling on the next frame's camera
        predicted = np.zeros(0, np.int64)
        if s.predict and index + 1 < self.session.frames:
            screen_q, moving_q = self._matrices(index + 1, 0.25)
            occupied = self.projector.occupancy(cache, screen_q, self.quarter, moving_q)
            clock("predicted projection")
            allowed = int(s.predict_share * self.budget) // (s.block * s.block)
            predicted = predicted_requests(occupied, self.quarter, self.size, s.block, allowed)
            clock("predicted sampling")

        # projection and z-buffer of this frame
        screen, moving = self._matrices(index)
        pix, depth, slots = self.projector.project(cache, screen, self.size, moving)
        clock("project")
        owner, nearest = zbuffer(pix, depth, slots, self.pixels, s.tiled, w, s.tile)
        if len(fresh):  # the samples shaded for this frame keep their pixel
            owner[fresh_pixels] = fresh
            nearest[fresh_pixels] = self.projector.depth_of(cache, fresh, screen, moving)
        clock("z-buffer")

        has_point = (owner >= 0).reshape(h, w)
        exempt = np.zeros(self.pixels, bool)
        exempt[fresh_pixels] = True
        keep = depth_cull(nearest.reshape(h, w), has_point, s.cull, exempt.reshape(h, w))
        clock("depth cull")

        kept = np.flatnonzero(keep)
        kept_slots = owner[kept]
        colors = np.zeros((3, self.pixels), np.float32)
        colors[:, kept] = cache.color[:, kept_slots]
        ages = np.zeros(self.pixels, np.float32)
        ages[kept] = cache.age[kept_slots]
        image, priority, filled = reconstruct(colors.reshape(3, h, w), keep, ages.reshape(h, w), self._previous,
                                              s.min_points, s.smooth, clock)

        # what the next frame's ageing needs: the visible points and those near a colour change
        self._visible = kept_slots
        if len(changed_pixels):
            near = np.zeros(self.pixels, np.float32)
            near[changed_pixels] = 1.0
            around = (box3(near.reshape(h, w)) > 0).reshape(-1) & keep.reshape(-1) & ~exempt
            self._changed = owner[np.flatnonzero(around)]
        else:
            self._changed = np.zeros(0, np.int64)

        # sampling: the priority image dithered under what prediction left of the budget
        block_budget = (self.budget - len(predicted) * s.block * s.block) // (s.block * s.block)
        reactive = dither(block_priority(priority, s.block), self._order, block_budget, float(self._rng.random()),
                          excluded=predicted)
        chosen = np.union1d(predicted, reactive)
        self._requests = blocks_to_pixels(chosen, self.size, s.block)
        clock("sampling")

        self._display.write(np.ascontiguousarray(np.moveaxis(image, 0, -1)))
        self.frame_clock.mark()  # the upload done
        clock("display")
        self._previous = image
        self._last = index
        return dict(shaded=len(samples.pixels), requested=len(self._requests),
                    predicted=int(len(blocks_to_pixels(predicted, self.size, s.block))), cold=cold,
                    filled=filled, keep=keep, owner=owner)

    def render_frame(self, index: int) -> RenderCacheFrame:
        """Render frame ``index`` (frames in order; a jump is a cold start). The first call renders
        once untimed (llvmpipe compiles the shader then) and starts over."""
        index = check_frame_index(self.session, index)
        if not self._warm:  # compiles the user's shader, and the mask pass on a masked frame
            self._frame(index, {})
            self.shader.shade(index, np.zeros(1, np.int64))
            self._reset()
            self._warm = True
        stages: dict = {}
        with watchdog.frame(f"frame {index} of the render cache"):
            self.frame_clock.start()
            info = self._frame(index, stages)
            ms = self.frame_clock.stop()
            cpu_ms = self.frame_clock.cpu_ms
        w, h = self.size
        image = np.ones((h, w, 4), np.float32)
        image[..., :3] = np.moveaxis(self._previous, 0, -1)
        keep, owner = info["keep"].reshape(-1), info["owner"]
        surface = np.zeros(self.pixels, bool)
        surface[keep] = self.cache.object[owner[keep]] != BACKGROUND
        mask = surface.reshape(h, w)[::-1].copy()
        return RenderCacheFrame(index, image[::-1].copy(), int(mask.sum()), ms, mask, cpu_ms=cpu_ms,
                                shaded=info["shaded"], budget=self.budget, requested=info["requested"],
                                predicted=info["predicted"], points=self.cache.count(), cold=info["cold"],
                                filled=info["filled"], stages=stages)

    def frames(self, indices):
        for index in indices:
            yield self.render_frame(index)

    def release(self) -> None:
        shader = getattr(self, "shader", None)
        if shader is not None:
            shader.release()
        self._scope.release()

    def __enter__(self) -> "RenderCacheRenderer":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


__all__ = ["RenderCacheRenderer", "RenderCacheFrame", "STAGES", "STATIC"]
