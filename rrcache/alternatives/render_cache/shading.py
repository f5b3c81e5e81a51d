"""The render cache's "renderer": the user's original shader, evaluated only at the requested pixels.

:class:`SampleShader` draws the session's objects with the unchanged shader (the harness's
program, drawer and generated vertex shader, as :class:`~rrcache.harness.renderer.Renderer` does)
into a colour target (``color_format``, RGBA32F by default, as the harness's renderers) and a
depth texture, after a *mask pass*: a full-screen triangle at depth
0 that discards at the requested pixels, so everywhere else the depth test fails before the
fragment shader runs (llvmpipe tests depth early, in blocks: docs/render_cache.md measures what a
scattered mask costs against a full frame). The colour and depth at the requested pixels are read
back: a pixel the geometry did not reach keeps depth 1 and the session's background colour (a
background sample).

When objects of the session move (their model matrix changes over the frames), an *id pass*
draws the moving objects again with a trivial program, depth test ``<=`` against the shaded
depth (nudged toward the camera, depth writes off), writing the object's index + 1: a sample
whose id is 0 lies on a static object.

>>> from rrcache.compiler.prepared import prepare_file
>>> from rrcache.session import load_session
>>> session = load_session("sessions/marble.json")
>>> prepared = prepare_file("shaders/glslviewer_basic.glsl", session)
>>> with SampleShader(prepared, session, (32, 24)) as shader:
...     samples = shader.shade(0, np.array([0, 12 * 32 + 16]))
>>> samples.color.shape, bool(samples.depth[1] < 1.0)
((2, 3), True)
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import moderngl
import numpy as np

from rrcache.gl.context import get_context
from rrcache.gl.formats import ERROR_FORMAT, color_dtype, texture_floats
from rrcache.gl.limits import check_target_size, target_guard
from rrcache.gl.program import build_program, fullscreen_vertex
from rrcache.gl.resources import GLScope
from rrcache.gl.uniforms import write_uniform
from rrcache.harness.drawer import SceneDrawer
from rrcache.harness.renderer import session_background
from rrcache.compiler.vertex import vertex_for

_MASK_FRAGMENT = """#version 330 core
uniform usampler2D rr_mask;
void main() {
    if (texelFetch(rr_mask, ivec2(gl_FragCoord.xy), 0).r != 0u) discard;
}
"""

_ID_VERTEX = """#version 330 core
in vec3 a_position;
uniform mat4 rr_mvp;
void main() {
    gl_Position = rr_mvp * vec4(a_position, 1.0);
    gl_Position.z -= 2e-4 * gl_Position.w;
}
"""

_ID_FRAGMENT = """#version 330 core
uniform float rr_id;
out vec4 rr_out;
void main() { rr_out = vec4(rr_id); }
"""

#: bytes per pixel the shader's targets and read-backs take (checked before allocating)
BYTES_PER_PIXEL = 16 + 4 + 1 + 4 + 16 + 4 + 4


@dataclass
class Samples:
    """What the renderer returned: per requested pixel (flat GL index) its ``color`` (n×3), window
    ``depth`` (1.0: no surface) and ``object`` (the moving object's index, or -1)."""

    frame: int
    pixels: np.ndarray
    color: np.ndarray
    depth: np.ndarray
    object: np.ndarray


def moving_objects(session) -> list[int]:
    """The indices of the session's objects whose model matrix changes over its frames."""
    moving = []
    for k, obj in enumerate(session.objects):
        first = obj.model_matrix(0)
        if any(not np.allclose(obj.model_matrix(f), first) for f in range(1, session.frames)):
            moving.append(k)
    return moving


class SampleShader:
    """Shades requested pixels of ``session`` frames with ``prepared`` at ``size`` (see the module
    docstring). GL objects are released by :meth:`release` (or a ``with`` block)."""

    def __init__(self, prepared, session, size: tuple[int, int], ctx: Optional[moderngl.Context] = None,
                 color_format: str = ERROR_FORMAT):
        self.ctx = ctx or get_context()
        self.color_format = color_format
        self._dtype = color_dtype(color_format)
        self.session = session
        self.size = tuple(int(v) for v in size)
        self.moving = moving_objects(session)
        self._scope = GLScope()
        try:
            self._setup(prepared)
        except BaseException:
            self._scope.release()
            raise

    def _setup(self, prepared) -> None:
        ctx, scope, size = self.ctx, self._scope, self.size
        check_target_size(ctx, size, BYTES_PER_PIXEL, "resolution")
        inputs = {name: d.type for name, d in prepared.inputs.items()}
        locs = {name: d.loc for name, d in prepared.inputs.items()}
        user = getattr(prepared, "vertex", None)
        self.program = scope.own(build_program(
            ctx, vertex_for(inputs, locs, user), prepared.source, prepared.line_map, fragment_name=prepared.path,
            vertex_name=user.path if user is not None else "<generated vertex shader>"))
        self.drawer = SceneDrawer(ctx, self.session, prepared, size, scope)
        self.drawer.add_program(self.program)
        self.notes = self.drawer.notes
        with target_guard(size, "resolution"):
            self._color = scope.own(ctx.texture(size, 4, dtype=self._dtype))
            self._depth = scope.own(ctx.depth_texture(size))
            self.fbo = scope.own(ctx.framebuffer([self._color], self._depth))
            self._mask = scope.own(ctx.texture(size, 1, dtype="u1"))
        self._mask_program = scope.own(build_program(ctx, fullscreen_vertex(-1.0), _MASK_FRAGMENT,
                                                     fragment_name="<render cache sample mask>"))
        self._mask_program["rr_mask"].value = 0
        self._mask_vao = scope.own(ctx.vertex_array(self._mask_program, []))
        self._mask_image = np.zeros(size[0] * size[1], np.uint8)
        self._id_vaos = []
        if self.moving:
            self._id_program = scope.own(build_program(ctx, _ID_VERTEX, _ID_FRAGMENT,
                                                       fragment_name="<render cache object id>"))
            with target_guard(size, "resolution"):
                self._ids = scope.own(ctx.texture(size, 1, dtype="f4"))
                self._id_fbo = scope.own(ctx.framebuffer([self._ids], self._depth))
            for k in self.moving:
                mesh = self.session.objects[k].mesh
                vbo = scope.own(ctx.buffer(np.ascontiguousarray(mesh.positions, np.float32).tobytes()))
                ibo = scope.own(ctx.buffer(np.ascontiguousarray(mesh.indices, np.uint32).tobytes()))
                self._id_vaos.append((k, scope.own(ctx.vertex_array(self._id_program, [(vbo, "3f", "a_position")],
                                                                     ibo, index_element_size=4))))

    def shade(self, frame: int, pixels: np.ndarray, every_pixel: bool = False) -> Samples:
        """Shade ``pixels`` (flat GL indices) of ``frame`` and read them back; ``every_pixel``
        shades the whole frame without a mask (a cold start). Waits for the GPU."""
        ctx, (w, h) = self.ctx, self.size
        self.drawer.set_frame(frame)
        self.drawer.render_shadow_map()  # the light's depth pass, as every renderer draws it
        self.fbo.use()
        self.fbo.viewport = (0, 0, w, h)
        self.fbo.clear(*session_background(self.session), depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        if not every_pixel:
            mask = self._mask_image
            mask[:] = 0
            mask[pixels] = 1
            self._mask.write(mask)
            ctx.disable(moderngl.CULL_FACE)
            ctx.depth_func = "1"  # always: depth 0 wherever the mask does not discard
            self.fbo.color_mask = (False, False, False, False)
            self._mask.use(location=0)
            self._mask_vao.render(moderngl.TRIANGLES, vertices=3)
            self.fbo.color_mask = (True, True, True, True)
        ctx.depth_func = "<"
        self.drawer.draw(self.program)
        objects = np.full(len(pixels), -1, np.int16)
        if self.moving:
            objects = self._object_ids(frame, pixels)
        color = texture_floats(self._color.read(), self._dtype, (h * w, 4))[pixels, :3]
        depth = np.frombuffer(self._depth.read(), np.float32)[pixels]
        return Samples(frame, pixels, color, depth, objects)

    def _object_ids(self, frame: int, pixels: np.ndarray) -> np.ndarray:
        ctx, (w, h) = self.ctx, self.size
        cam = self.session.camera_at(frame)
        view_projection = cam.projection(w / h) @ cam.view
        self._id_fbo.use()
        self._id_fbo.viewport = (0, 0, w, h)
        self._id_fbo.depth_mask = False  # before the clear: keep the shaded depth
        self._id_fbo.clear(0.0, 0.0, 0.0, 0.0)
        ctx.disable(moderngl.CULL_FACE)
        ctx.depth_func = "<="
        for k, vao in self._id_vaos:
            write_uniform(self._id_program["rr_mvp"], view_projection @ self.session.objects[k].model_matrix(frame))
            self._id_program["rr_id"].value = float(k + 1)
            vao.render(moderngl.TRIANGLES)
        self._id_fbo.depth_mask = True
        ids = np.frombuffer(self._ids.read(), np.float32)[pixels]
        return (np.rint(ids).astype(np.int16) - 1)

    def release(self) -> None:
        self._scope.release()

    def __enter__(self) -> "SampleShader":
        return self

    def __exit__(self, *exc) -> None:
        self.release()
