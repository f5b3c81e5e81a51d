"""A tiny scene for the compiler's rendering tests: an icosphere seen by a slowly orbiting camera,
drawn with the original shader (the reference) or with a compiled variant through
``CacheRuntime``. Not a test module itself (no ``test_`` prefix)."""
from __future__ import annotations

import numpy as np
import moderngl

from rrcache.compiler import Variant
from rrcache.compiler.emit import interface, vertex_shader
from rrcache.gl.program import build_program
from rrcache.glsl.legacy import to_core
from rrcache.glsl.printer import print_with_map
from rrcache.runtime import CacheRuntime
from rrcache.session.procedural import icosphere


def look_at(eye, target, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    eye = np.asarray(eye, float)
    f = np.asarray(target, float) - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov, aspect, near, far) -> np.ndarray:
    t = 1.0 / np.tan(np.radians(fov) / 2)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = t / aspect, t
    m[2, 2], m[2, 3], m[3, 2] = (far + near) / (near - far), 2 * far * near / (near - far), -1.0
    return m


class Scene:
    """The icosphere, the camera path and the uniform values; ``draw(program, frame)``."""

    def __init__(self, ctx: moderngl.Context, size=(48, 48), uniforms=None, degrees_per_frame=1.5):
        self.ctx = ctx
        self.size = size
        mesh = icosphere(1.0, 3)
        tex = mesh.texcoords if mesh.texcoords is not None else np.zeros((len(mesh.positions), 2))
        data = np.hstack([mesh.positions, mesh.normals, tex]).astype("f4")
        self.vbo = ctx.buffer(data.tobytes())
        self.ibo = ctx.buffer(np.asarray(mesh.indices, dtype="u4").tobytes())
        self.uniforms = dict(uniforms or {})
        self.degrees = degrees_per_frame
        self.proj = perspective(45.0, size[0] / size[1], 0.1, 50.0)
        self.vaos: dict[int, moderngl.VertexArray] = {}

    def view_projection(self, frame: int) -> np.ndarray:
        a = np.radians(frame * self.degrees)
        eye = (2.7 * np.sin(a), 0.6, 2.7 * np.cos(a))
        return self.proj @ look_at(eye, (0.0, 0.0, 0.0))

    def vao(self, program: moderngl.Program) -> moderngl.VertexArray:
        if id(program) not in self.vaos:
            names = ["a_position", "a_normal", "a_texcoord"]
            fmt = " ".join(f if n in program else f.replace("f", "x4") for n, f in
                           zip(names, ["3f", "3f", "2f"]))
            attrs = [n for n in names if n in program]
            self.vaos[id(program)] = self.ctx.vertex_array(program, [(self.vbo, fmt, *attrs)], self.ibo)
        return self.vaos[id(program)]

    def draw(self, program: moderngl.Program, frame: int) -> None:
        mats = {
            "u_modelMatrix": np.eye(4), "u_modelViewProjectionMatrix": self.view_projection(frame),
            "u_prevModelViewProjectionMatrix": self.view_projection(frame - 1),
        }
        for name, m in mats.items():
            if name in program:
                program[name].write(m.T.astype("f4").tobytes())
        if "u_normalMatrix" in program:
            program["u_normalMatrix"].write(np.eye(3, dtype="f4").tobytes())
        for name, value in self.uniforms.items():
            if name in program:
                program[name].value = value
        self.vao(program).render()

    def forget(self, program: moderngl.Program) -> None:
        """Release the vertex array made for ``program`` (call before releasing it)."""
        vao = self.vaos.pop(id(program), None)
        if vao is not None:
            vao.release()

    def release(self) -> None:
        for vao in self.vaos.values():
            vao.release()
        self.vbo.release()
        self.ibo.release()


def original_program(ctx, analysed) -> moderngl.Program:
    """The uncached shader (legacy converted) with the generated vertex shader."""
    unit = to_core(analysed.unit)
    text, line_map = print_with_map(unit)
    vs = vertex_shader(interface(unit)["in"], prev_clip=False)
    return build_program(ctx, vs, text, line_map)


def render_original(scene: Scene, program, frames: int) -> list[np.ndarray]:
    ctx = scene.ctx
    w, h = scene.size
    color = ctx.texture((w, h), 4, dtype="f4")
    depth = ctx.depth_texture((w, h))
    fbo = ctx.framebuffer([color], depth)
    images = []
    try:
        for frame in range(frames):
            fbo.use()
            fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
            ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
            ctx.depth_func = "<"
            scene.draw(program, frame)
            images.append(np.frombuffer(color.read(), "f4").reshape(h, w, 4)[::-1].copy())
    finally:
        fbo.release()
        color.release()
        depth.release()
    return images


def render_variant(scene: Scene, variant: Variant, frames: int, period: int):
    """Images and FrameStats of ``frames`` frames of a variant at refresh period ``period``."""
    programs = variant.build_programs(scene.ctx)
    rt = CacheRuntime(scene.ctx, programs, variant.algorithm, scene.size, period=period,
                      payload_dtype=variant.payload_dtype, payload_components=variant.components,
                      depth_channel=variant.depth_channel)
    images, stats = [], []
    try:
        for frame in range(frames):
            stats.append(rt.frame(lambda prog, _name: scene.draw(prog, frame)))
            images.append(rt.read_color())
    finally:
        rt.release()
        for prog in programs.values():
            scene.forget(prog)
            prog.release()
    return images, stats
