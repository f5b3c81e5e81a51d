"""Drawing a session's objects with any program: the part of the harness shared by the plain
renderer and the cached one (one program per pass).

:class:`SceneDrawer` uploads meshes and textures once, checks each program it is given against
the session (:func:`rrcache.harness.bindings.plan_bindings`), and per frame sets the built-in
uniforms of docs/design.md §4 (camera, light, time, matrices, the previous frame's
model-view-projection for reprojection), the session's uniforms and samplers, and renders every
object, culling back faces unless the object is ``double_sided``.

>>> from rrcache.gl import GLScope, build_program, get_context
>>> from rrcache.compiler.prepared import prepare_file
>>> from rrcache.compiler.vertex import vertex_source
>>> from rrcache.session import load_session
>>> ctx, scope = get_context(), GLScope()
>>> session = load_session("sessions/marble.json")
>>> prepared = prepare_file("shaders/glslviewer_basic.glsl", session)
>>> program = scope.own(build_program(ctx, vertex_source({n: d.type for n, d in prepared.inputs.items()}),
...                                   prepared.source))
>>> drawer = SceneDrawer(ctx, session, prepared, (32, 24), scope)
>>> _ = drawer.add_program(program)
>>> scope.own(ctx.simple_framebuffer((32, 24))).use()   # a target to draw into
>>> drawer.set_frame(10); drawer.draw(program)
>>> scope.release()
"""
from __future__ import annotations

from typing import Optional

import moderngl
import numpy as np

from rrcache.errors import UnsupportedShaderError
from rrcache.gl.program import build_program
from rrcache.gl.resources import GLScope
from rrcache.gl.textures import texture_from_asset
from rrcache.gl.uniforms import write_uniform
from rrcache.harness.bindings import BUILTINS, BindingPlan, lookup, plan_bindings
from rrcache.compiler.prepared import PreparedShader
from rrcache.compiler.vertex import ATTRIBUTES
from rrcache.session.shadow import BIAS, light_view_projection

#: the texture unit of the shadow map (session textures count up from 0; the cache uses 12-15)
SHADOW_UNIT = 11

_SHADOW_VERTEX = """#version 330 core
in vec3 a_position;
uniform mat4 rr_lightModelViewProjection;
void main() { gl_Position = rr_lightModelViewProjection * vec4(a_position, 1.0); }
"""
_SHADOW_FRAGMENT = "#version 330 core\nvoid main() {}\n"

# value for a vertex attribute the mesh does not have
_DEFAULTS = {"normal": (0.0, 0.0, 1.0), "texcoord": (0.0, 0.0), "color": (1.0, 1.0, 1.0, 1.0),
             "tangent": (1.0, 0.0, 0.0, 1.0)}
_FIELDS = {"position": "positions", "normal": "normals", "texcoord": "texcoords", "color": "colors",
           "tangent": "tangents"}


def attribute_data(mesh, attr: str, size: int) -> np.ndarray:
    """The vertex attribute ``attr`` (``position normal texcoord color tangent``) of ``mesh`` as a
    contiguous float32 N×``size`` array; a mesh without it gets the default value at every vertex
    (a normal (0, 0, 1), texcoord 0, opaque white, tangent (1, 0, 0, 1))."""
    n = int(np.asarray(mesh.positions).shape[0])
    data = getattr(mesh, _FIELDS[attr], None)
    if data is None:
        data = np.tile(np.asarray(_DEFAULTS[attr], np.float32), (n, 1))
    return np.ascontiguousarray(np.asarray(data, np.float32).reshape(n, size))


def normal_matrix(model: np.ndarray) -> np.ndarray:
    """The world-space normal matrix (inverse transpose of the model matrix's 3×3 part)."""
    m3 = np.asarray(model, dtype=np.float64)[:3, :3]
    try:
        return np.linalg.inv(m3).T
    except np.linalg.LinAlgError:  # a zero scale: no meaningful normals, keep the rotation part
        return m3


def reprojection_matrix(mvp: np.ndarray, prev_mvp: np.ndarray) -> np.ndarray:
    """This frame's clip position → the previous frame's, for one object:
    ``prev_mvp @ inverse(mvp)`` in double precision (what a user's vertex shader multiplies
    ``gl_Position`` by to find ``rr_prevClip``; see :mod:`rrcache.compiler.user_vertex`).

    >>> m = np.diag([2.0, 2.0, 2.0, 1.0])
    >>> bool(np.allclose(reprojection_matrix(m, m), np.eye(4)))
    True
    """
    mvp = np.asarray(mvp, dtype=np.float64)
    try:
        inv = np.linalg.inv(mvp)
    except np.linalg.LinAlgError:
        inv = np.linalg.pinv(mvp)
    return np.asarray(prev_mvp, dtype=np.float64) @ inv


def frame_builtins(session, index: int, size: tuple[int, int], static: bool = False) -> tuple[dict, list[dict]]:
    """The built-in uniforms of frame ``index`` at ``size`` (docs/design.md §4) as plain values:
    the frame's (``u_camera``, ``u_light``, ``u_lightColor``, ``u_resolution``, ``u_time``,
    ``u_frame``, ``u_viewMatrix``, ``u_projectionMatrix``) and, per object, ``u_modelMatrix``,
    ``u_modelViewProjectionMatrix``, ``u_normalMatrix``, ``u_prevModelViewProjectionMatrix``
    (frame ``index - 1``'s; frame 0 and ``static`` use this frame's) and ``u_reprojectionMatrix``,
    with ``"cull"`` (back faces culled). Matrices are numpy arrays in math convention (row-major;
    GL takes them transposed). One computation for every renderer: the harness's and the WebGL2
    page's (:mod:`rrcache.webgl`).

    >>> from rrcache.session import load_session
    >>> frame, objects = frame_builtins(load_session("sessions/marble.json"), 3, (64, 48))
    >>> frame["u_frame"], frame["u_resolution"], sorted(objects[0])[:3]
    (3, (64.0, 48.0), ['cull', 'u_modelMatrix', 'u_modelViewProjectionMatrix'])
    """
    w, h = size
    prev = index if static else max(index - 1, 0)
    cam, cam_prev = session.camera_at(index), session.camera_at(prev)
    view, proj = cam.view, cam.projection(w / h)
    view_proj = proj @ view
    prev_view_proj = cam_prev.projection(w / h) @ cam_prev.view
    light = session.light_at(index)
    frame = {"u_camera": cam.eye, "u_light": light.position, "u_lightColor": light.color,
             "u_resolution": (float(w), float(h)), "u_time": index / session.fps, "u_frame": index,
             "u_viewMatrix": view, "u_projectionMatrix": proj}
    objects = []
    for obj in session.objects:
        model = obj.model_matrix(index)
        mvp, prev_mvp = view_proj @ model, prev_view_proj @ obj.model_matrix(prev)
        objects.append({"u_modelMatrix": model, "u_modelViewProjectionMatrix": mvp, "u_normalMatrix": normal_matrix(model),
                        "u_prevModelViewProjectionMatrix": prev_mvp,
                        "u_reprojectionMatrix": reprojection_matrix(mvp, prev_mvp),
                        "cull": not getattr(obj, "double_sided", False)})
    return frame, objects


class SceneDrawer:
    """Draws the objects of ``session`` at ``size`` with programs registered by
    :meth:`add_program`. GL objects are owned by ``scope``."""

    def __init__(self, ctx: moderngl.Context, session, prepared: PreparedShader, size: tuple[int, int],
                 scope: GLScope, cull_back_faces: Optional[bool] = None):
        self.ctx = ctx
        self.session = session
        self.prepared = prepared
        self.size = size
        self.scope = scope
        self.cull_back_faces = cull_back_faces
        self.notes: list[str] = list(getattr(session, "notes", None) or [])
        self._plans: dict[int, BindingPlan] = {}
        self._vaos: dict[int, list] = {}
        self._buffers: dict[tuple[int, str], moderngl.Buffer] = {}
        self._indices: dict[int, moderngl.Buffer] = {}
        self._textures: dict[str, tuple[int, moderngl.Texture]] = {}
        self._frame: Optional[int] = None
        self._builtins: dict = {}
        self._objects: list[dict] = []
        self.shadow_map = getattr(session, "shadow_map", None)
        self._shadow = None  # (program, depth texture, framebuffer, vertex arrays), made on first use
        self._light_matrix = np.eye(4)
        self._light_mvps: list = []

    # ------------------------------------------------------------------ programs
    def add_program(self, program: moderngl.Program) -> BindingPlan:
        """Check ``program`` against the session, upload what it needs, and remember it."""
        plan = plan_bindings(program, self.prepared, self.session)
        for name, uniform, _kind in plan.samplers:
            unit, _tex = self._texture(name)
            uniform.value = unit
        if plan.shadow is not None:
            plan.shadow.value = SHADOW_UNIT
        self._plans[id(program)] = plan
        self._vaos[id(program)] = [self._object_vao(program, i, obj) for i, obj in enumerate(self.session.objects)]
        for note in plan.notes:
            if note not in self.notes:
                self.notes.append(note)
        return plan

    def _texture(self, name: str):
        if name not in self._textures:
            tex = self.scope.own(texture_from_asset(self.ctx, self.session.textures[name]))
            self._textures[name] = (len(self._textures), tex)
        return self._textures[name]

    def _buffer(self, index: int, obj, attr: str, size: int) -> moderngl.Buffer:
        key = (index, attr)
        if key not in self._buffers:
            data = attribute_data(obj.mesh, attr, size)
            self._buffers[key] = self.scope.own(self.ctx.buffer(data.tobytes()))
        return self._buffers[key]

    def _object_vao(self, program: moderngl.Program, index: int, obj):
        content = []
        for attr, (glsl_type, _define) in ATTRIBUTES.items():
            name = f"a_{attr}"
            if name not in program or not isinstance(program[name], moderngl.Attribute):
                continue
            size = int(glsl_type[-1])
            content.append((self._buffer(index, obj, attr, size), f"{size}f", name))
        if index not in self._indices:
            indices = np.ascontiguousarray(np.asarray(obj.mesh.indices, np.uint32).reshape(-1))
            self._indices[index] = self.scope.own(self.ctx.buffer(indices.tobytes()))
        return self.scope.own(self.ctx.vertex_array(program, content, self._indices[index], index_element_size=4))

    # ------------------------------------------------------------------ frames
    def set_frame(self, index: int, static: bool = False) -> None:
        """Compute the camera, light and per-object matrices of frame ``index`` (and ``index - 1``
        for reprojection; frame 0 uses itself) with :func:`frame_builtins`. ``static``: the
        previous frame is this frame too (a frame shown again, as when measuring the cache with
        every pixel hitting)."""
        session = self.session
        self._builtins, self._objects = frame_builtins(session, index, self.size, static)
        if self.cull_back_faces is not None:
            for per_object in self._objects:
                per_object["cull"] = self.cull_back_faces
        self._light = session.light_at(index)
        self._values = session.uniform_values(index)
        self._frame = index
        if self.shadow_map is not None:
            light_vp = light_view_projection(self._light.position, self.shadow_map, session, index)
            self._light_matrix = BIAS @ light_vp
            self._light_mvps = [light_vp @ obj.model_matrix(index) for obj in session.objects]

    # ------------------------------------------------------------------ shadow map
    def _shadow_resources(self):
        if self._shadow is None:
            ctx, size = self.ctx, int(self.shadow_map.size)
            program = self.scope.own(build_program(ctx, _SHADOW_VERTEX, _SHADOW_FRAGMENT,
                                                   fragment_name="<rrcache shadow-map pass>"))
            depth = self.scope.own(ctx.depth_texture((size, size)))
            depth.compare_func = ""  # sampled as a plain texture: texture(u_lightShadowMap, uv).r
            depth.filter = (moderngl.NEAREST, moderngl.NEAREST)
            depth.repeat_x = depth.repeat_y = False
            fbo = self.scope.own(ctx.framebuffer(depth_attachment=depth))
            vaos = []
            for i, obj in enumerate(self.session.objects):
                if i not in self._indices:
                    indices = np.ascontiguousarray(np.asarray(obj.mesh.indices, np.uint32).reshape(-1))
                    self._indices[i] = self.scope.own(self.ctx.buffer(indices.tobytes()))
                vaos.append(self.scope.own(ctx.vertex_array(
                    program, [(self._buffer(i, obj, "position", 3), "3f", "a_position")], self._indices[i],
                    index_element_size=4)))
            self._shadow = (program, depth, fbo, vaos)
        return self._shadow

    def render_shadow_map(self) -> None:
        """Render the light's depth map of the current frame (nothing when the session's light has
        no shadow map). Every renderer calls it inside its timed frame, before its own passes,
        and binds its own framebuffer afterwards."""
        if self.shadow_map is None:
            return
        if self._frame is None:
            raise RuntimeError("SceneDrawer.render_shadow_map before set_frame")
        program, depth, fbo, vaos = self._shadow_resources()
        ctx = self.ctx
        fbo.use()
        fbo.viewport = (0, 0, depth.width, depth.height)
        fbo.clear(depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.depth_func = "<"
        ctx.cull_face = "back"
        mvp_uniform = program["rr_lightModelViewProjection"]
        for vao, mvp, per_object in zip(vaos, self._light_mvps, self._objects):
            if per_object["cull"]:
                ctx.enable(moderngl.CULL_FACE)
            else:
                ctx.disable(moderngl.CULL_FACE)
            write_uniform(mvp_uniform, mvp)
            vao.render(moderngl.TRIANGLES)

    def _set_builtin(self, plan: BindingPlan, name: str, value) -> None:
        uniform = plan.builtins.get(name)
        if uniform is None:
            return
        try:
            write_uniform(uniform, value)
        except ValueError:
            decl = self.prepared.declaration(name)
            raise UnsupportedShaderError(
                f"built-in uniform `{name}` must be declared {BUILTINS[name]}",
                decl.loc if decl is not None else None,
                hint=f"declare `uniform {BUILTINS[name]} {name};` (docs/design.md §4)") from None

    def draw(self, program: moderngl.Program, _pass_name: str = "") -> None:
        """Draw every object of the current frame with ``program`` into the bound framebuffer
        (depth testing is the caller's; back-face culling is set per object)."""
        if self._frame is None:
            raise RuntimeError("SceneDrawer.draw before set_frame")
        ctx = self.ctx
        plan = self._plans[id(program)]
        for name, value in self._builtins.items():
            self._set_builtin(plan, name, value)
        for name, uniform in plan.session:
            write_uniform(uniform, lookup(self._values, name))
        for name, _uniform, _kind in plan.samplers:
            unit, tex = self._textures[name]
            tex.use(location=unit)
        if plan.shadow is not None:
            self._shadow_resources()[1].use(location=SHADOW_UNIT)
        self._set_builtin(plan, "u_lightMatrix", self._light_matrix)
        ctx.cull_face = "back"
        for vao, per_object in zip(self._vaos[id(program)], self._objects):
            if per_object["cull"]:
                ctx.enable(moderngl.CULL_FACE)
            else:
                ctx.disable(moderngl.CULL_FACE)
            for name, value in per_object.items():
                if name != "cull":
                    self._set_builtin(plan, name, value)
            vao.render(moderngl.TRIANGLES)
