"""The GL layer: context, program error mapping, uniform writes of every type, textures."""
from __future__ import annotations

import numpy as np
import pytest

from rrcache.errors import GLError, SourceLoc
from rrcache.gl import context as gl_context
from rrcache.gl.program import build_program, parse_log
from rrcache.gl.resources import GLScope
from rrcache.gl.textures import texture_from_array
from rrcache.gl.uniforms import encode_uniform, write_uniform

VS = "#version 330\nin vec2 p;\nvoid main() { gl_Position = vec4(p, 0.0, 1.0); }\n"


def draw_fullscreen(ctx, fragment_src, setup=None, size=(1, 1)):
    """Render a full-screen triangle with ``fragment_src``; return the RGBA32F image (row 0 = bottom)."""
    with GLScope() as scope:
        prog = scope.own(build_program(ctx, VS, fragment_src))
        if setup is not None:
            setup(prog, scope)
        color = scope.own(ctx.texture(size, 4, dtype="f4"))
        fbo = scope.own(ctx.framebuffer([color]))
        vbo = scope.own(ctx.buffer(np.array([-1, -1, 3, -1, -1, 3], "f4").tobytes()))
        vao = scope.own(ctx.vertex_array(prog, [(vbo, "2f", "p")]))
        fbo.use()
        fbo.clear(0, 0, 0, 0)
        vao.render()
        return np.frombuffer(color.read(), np.float32).reshape(size[1], size[0], 4).copy()


# --------------------------------------------------------------------------- context

def test_context_is_cached_and_core_330(gl_ctx):
    assert gl_context.get_context() is gl_ctx
    assert gl_ctx.version_code >= 330


def test_other_thread_count_warns(gl_ctx):
    current = gl_context.context_threads()
    other = 3 if current != "3" else 2
    with pytest.warns(RuntimeWarning, match="LP_NUM_THREADS"):
        assert gl_context.get_context(threads=other) is gl_ctx


def test_threads_are_set_before_creation(monkeypatch):
    seen = {}

    class FakeContext:
        version_code = 450

    def create(**kwargs):
        import os
        seen["threads"] = os.environ.get("LP_NUM_THREADS")
        seen["kwargs"] = kwargs
        return FakeContext()

    monkeypatch.setattr(gl_context, "_ctx", None)
    monkeypatch.setattr(gl_context, "_threads", None)
    monkeypatch.setenv("LP_NUM_THREADS", "1")
    monkeypatch.setattr(gl_context.moderngl, "create_standalone_context", create)
    ctx = gl_context.get_context(threads=2)
    assert isinstance(ctx, FakeContext) and seen["threads"] == "2"
    assert seen["kwargs"] == {"backend": "egl", "require": 330}
    assert gl_context.context_threads() == "2"


def test_old_gl_version_is_refused(monkeypatch):
    class OldContext:
        version_code = 310
        released = False

        def release(self):
            OldContext.released = True

    monkeypatch.setattr(gl_context, "_ctx", None)
    monkeypatch.setattr(gl_context, "_threads", None)
    monkeypatch.setattr(gl_context.moderngl, "create_standalone_context", lambda **kw: OldContext())
    with pytest.raises(GLError, match="3.1"):
        gl_context.get_context()
    assert OldContext.released


def test_missing_egl_becomes_gl_error(monkeypatch):
    def fail(**kwargs):
        raise Exception("libEGL.so.1: cannot open shared object file")

    monkeypatch.setattr(gl_context, "_ctx", None)
    monkeypatch.setattr(gl_context.moderngl, "create_standalone_context", fail)
    with pytest.raises(GLError) as info:
        gl_context.get_context()
    assert "libegl1" in str(info.value) and "libgl1-mesa-dri" in str(info.value)


# --------------------------------------------------------------------------- programs

def test_parse_log_mesa_and_nvidia():
    log = "0:12(5): error: `foo' undeclared\n0:13(1): warning: unused\n0(7) : error C1008: undefined variable"
    diags = parse_log(log)
    assert [(d.severity, d.line, d.col) for d in diags] == [("error", 12, 5), ("warning", 13, 1), ("error", 7, 0)]
    assert diags[0].message == "`foo' undeclared"


def test_compile_error_names_original_line(gl_ctx):
    fragment = "#version 330 core\nout vec4 c;\nvoid main() {\n    c = vec3(1.0);\n}\n"
    # printed line 4 came from line 27 of the user's file
    line_map = [SourceLoc("marble.frag", 1, 1), None, SourceLoc("marble.frag", 20, 1), SourceLoc("marble.frag", 27, 5), None]
    with pytest.raises(GLError) as info:
        build_program(gl_ctx, VS, fragment, line_map, fragment_name="printed.frag")
    err = info.value
    assert err.where.startswith("marble.frag:27:")
    assert err.loc.file == "marble.frag" and err.loc.line == 27
    assert "vec3" in str(err)  # the driver's own message is kept


def test_compile_error_without_map_names_printed_line(gl_ctx):
    fragment = "#version 330 core\nout vec4 c;\nvoid main() {\n    c = undefined_thing;\n}\n"
    with pytest.raises(GLError, match=r"^shader\.frag:4:\d+: .*undefined_thing"):
        build_program(gl_ctx, VS, fragment, fragment_name="shader.frag")


def test_link_error_is_gl_error(gl_ctx):
    vs = "#version 330\nout vec3 v_x;\nvoid main() { v_x = vec3(0); gl_Position = vec4(0); }\n"
    fs = "#version 330\nin vec4 v_x;\nout vec4 c;\nvoid main() { c = v_x; }\n"
    with pytest.raises(GLError, match="link"):
        build_program(gl_ctx, vs, fs, fragment_name="f.frag")


def test_glscope_releases_in_reverse_once(gl_ctx):
    released = []

    class Thing:
        def __init__(self, name):
            self.name = name

        def release(self):
            released.append(self.name)

    scope = GLScope()
    scope.own(Thing("a"))
    scope.own(Thing("b"))
    scope.release()
    scope.release()
    assert released == ["b", "a"] and len(scope) == 0


# --------------------------------------------------------------------------- uniforms

UNIFORM_CASES = [
    # declaration, expression giving a vec4, value, expected rgba
    ("float u", "vec4(u, 0, 0, 0)", 0.25, [0.25, 0, 0, 0]),
    ("int u", "vec4(float(u), 0, 0, 0)", -7, [-7, 0, 0, 0]),
    ("uint u", "vec4(float(u), 0, 0, 0)", 9, [9, 0, 0, 0]),
    ("bool u", "vec4(u ? 1.0 : 2.0, 0, 0, 0)", True, [1, 0, 0, 0]),
    ("vec2 u", "vec4(u, 0, 0)", [1.5, -2.0], [1.5, -2, 0, 0]),
    ("vec3 u", "vec4(u, 0)", np.array([1.0, 2.0, 3.0]), [1, 2, 3, 0]),
    ("vec4 u", "u", (1, 2, 3, 4), [1, 2, 3, 4]),
    ("ivec3 u", "vec4(vec3(u), 0)", [1, -2, 3], [1, -2, 3, 0]),
    ("bvec2 u", "vec4(vec2(u), 0, 0)", [False, True], [0, 1, 0, 0]),
    ("float u[3]", "vec4(u[0], u[1], u[2], 0)", [0.5, 1.5, 2.5], [0.5, 1.5, 2.5, 0]),
    ("vec2 u[2]", "vec4(u[0], u[1])", [[1, 2], [3, 4]], [1, 2, 3, 4]),
    ("int u[2]", "vec4(float(u[0]), float(u[1]), 0, 0)", np.array([5, 6]), [5, 6, 0, 0]),
    # matrices: nested values are (rows × columns) and m[c][r] reads column c, row r
    ("mat2 u", "vec4(u[0][0], u[0][1], u[1][0], u[1][1])", [[1, 2], [3, 4]], [1, 3, 2, 4]),
    ("mat3 u", "vec4(u[0][1], u[1][0], u[2][2], u[2][0])", np.arange(9.0).reshape(3, 3), [3, 1, 8, 2]),
    ("mat4 u", "vec4(u[3][0], u[3][1], u[3][2], u[0][3])",
     np.array([[1, 0, 0, 5], [0, 1, 0, 6], [0, 0, 1, 7], [8, 0, 0, 1]], float), [5, 6, 7, 8]),
    ("mat2x3 u", "vec4(u[0][2], u[1][0], u[1][2], 0)", [[1, 2], [3, 4], [5, 6]], [5, 2, 6, 0]),
    ("mat2 u", "vec4(u[0][0], u[0][1], u[1][0], u[1][1])", [1, 2, 3, 4], [1, 2, 3, 4]),  # flat: column-major
]


@pytest.mark.parametrize("decl, expr, value, expected", UNIFORM_CASES,
                         ids=[f"{c[0]}-{i}" for i, c in enumerate(UNIFORM_CASES)])
def test_uniform_of_every_type_reaches_the_shader(gl_ctx, decl, expr, value, expected):
    fs = f"#version 330\nuniform {decl};\nout vec4 c;\nvoid main() {{ c = {expr}; }}\n"
    img = draw_fullscreen(gl_ctx, fs, lambda prog, scope: write_uniform(prog["u"], value))
    np.testing.assert_array_equal(img[0, 0], np.array(expected, np.float32))


def test_uniform_value_of_wrong_size_is_refused(gl_ctx):
    fs = "#version 330\nuniform vec3 u;\nout vec4 c;\nvoid main() { c = vec4(u, 1); }\n"
    prog = build_program(gl_ctx, VS, fs)
    try:
        with pytest.raises(ValueError, match="expected 3 components"):
            encode_uniform(prog["u"], [1.0, 2.0])
        with pytest.raises(ValueError):
            encode_uniform(prog["u"], "abc")
    finally:
        prog.release()


def test_int_uniform_refuses_fractions(gl_ctx):
    fs = "#version 330\nuniform int u;\nout vec4 c;\nvoid main() { c = vec4(u); }\n"
    prog = build_program(gl_ctx, VS, fs)
    try:
        with pytest.raises(ValueError, match="integer"):
            encode_uniform(prog["u"], 1.5)
    finally:
        prog.release()


# --------------------------------------------------------------------------- textures

def test_float_texture_exact_and_row_zero_is_top(gl_ctx):
    rng = np.random.default_rng(1)
    data = rng.normal(size=(3, 5, 4)).astype(np.float32) * 1000.0  # beyond [0,1]: must stay exact
    size = (5, 3)
    fs = ("#version 330\nuniform sampler2D t;\nout vec4 c;\n"
          "void main() { c = texelFetch(t, ivec2(gl_FragCoord.xy), 0); }\n")

    def setup(prog, scope):
        tex = scope.own(texture_from_array(gl_ctx, data, filter="nearest"))
        assert tex.dtype == "f4" and tex.components == 4
        prog["t"].value = 0
        tex.use(0)

    img = draw_fullscreen(gl_ctx, fs, setup, size)
    # GL row 0 is the bottom; the array's row 0 is the top
    np.testing.assert_array_equal(img[::-1], data)


@pytest.mark.parametrize("channels", [1, 2, 3])
def test_float_texture_fewer_channels(gl_ctx, channels):
    data = np.arange(2 * 2 * channels, dtype=np.float32).reshape(2, 2, channels) + 0.5
    fs = ("#version 330\nuniform sampler2D t;\nout vec4 c;\n"
          "void main() { c = texelFetch(t, ivec2(gl_FragCoord.xy), 0); }\n")

    def setup(prog, scope):
        tex = scope.own(texture_from_array(gl_ctx, data, filter="nearest"))
        assert tex.components == channels
        prog["t"].value = 0
        tex.use(0)

    img = draw_fullscreen(gl_ctx, fs, setup, (2, 2))[::-1]
    np.testing.assert_array_equal(img[..., :channels], data)


def test_cube_map_faces(gl_ctx):
    faces = np.zeros((6, 2, 2, 4), np.float32)
    for i in range(6):
        faces[i, ..., 0] = i + 1
    faces[2, 0, :, 1] = 7.0   # +Y face, top row (toward -Z in GL's cube convention)
    directions = ["vec3(1,0,0)", "vec3(-1,0,0)", "vec3(0,1,0)", "vec3(0,-1,0)", "vec3(0,0,1)", "vec3(0,0,-1)",
                  "vec3(0.1,1,-0.5)", "vec3(0.1,1,0.5)"]
    fs = ("#version 330\nuniform samplerCube t;\nout vec4 c;\nvoid main() {\n"
          "    vec3 d[8] = vec3[8](" + ", ".join(directions) + ");\n"
          "    c = texture(t, d[int(gl_FragCoord.x)]);\n}\n")

    def setup(prog, scope):
        tex = scope.own(texture_from_array(gl_ctx, faces, kind="cube", filter="nearest"))
        prog["t"].value = 0
        tex.use(0)

    img = draw_fullscreen(gl_ctx, fs, setup, (8, 1))[0]
    assert img[:6, 0].tolist() == [1, 2, 3, 4, 5, 6]
    assert img[6, 1] == 7.0 and img[7, 1] == 0.0


def test_wrap_modes(gl_ctx):
    data = np.array([[[0.0], [1.0]]], np.float32)  # 1 row, 2 texels
    fs = ("#version 330\nuniform sampler2D t;\nout vec4 c;\n"
          "void main() { c = vec4(texture(t, vec2(1.25, 0.5)).x, texture(t, vec2(-0.25, 0.5)).x, 0, 0); }\n")
    results = {}
    for wrap in ("repeat", "clamp", "mirror"):
        def setup(prog, scope, wrap=wrap):
            tex = scope.own(texture_from_array(gl_ctx, data, filter="nearest", wrap=wrap))
            prog["t"].value = 0
            tex.use(0)
        results[wrap] = draw_fullscreen(gl_ctx, fs, setup)[0, 0, :2].tolist()
    assert results["repeat"] == [0.0, 1.0]
    assert results["clamp"] == [1.0, 0.0]
    assert results["mirror"] == [1.0, 0.0]


def test_mipmap_filter_builds_levels(gl_ctx):
    data = np.ones((8, 8, 4), np.float32)
    tex = texture_from_array(gl_ctx, data, filter="mipmap")
    try:
        import moderngl
        assert tex.filter == (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
    finally:
        tex.release()


def test_bad_texture_shapes_raise_gl_error(gl_ctx):
    with pytest.raises(GLError, match="H×W×C"):
        texture_from_array(gl_ctx, np.zeros((2, 2, 5), np.float32))
    with pytest.raises(GLError, match="cube map"):
        texture_from_array(gl_ctx, np.zeros((5, 2, 2, 3), np.float32), kind="cube")
    with pytest.raises(GLError, match="element type"):
        texture_from_array(gl_ctx, np.zeros((2, 2, 3), np.int64))
    with pytest.raises(GLError, match="wrap"):
        texture_from_array(gl_ctx, np.zeros((2, 2, 3), np.float32), wrap="wobble")
