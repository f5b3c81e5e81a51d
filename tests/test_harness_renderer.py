"""The rendering harness on tiny hand-made sessions (64×64, orthographic camera, a few frames).

The session here is a small stand-in with the interface of ``rrcache.session.Session`` (camera,
light, objects, uniforms, textures), so that pixel positions are known exactly: the camera looks
down -Z with an orthographic projection of [-1, 1]², so pixel (row i, column j) of a 64×64 frame
has its centre at x = (j + 0.5)/32 - 1, y = 1 - (i + 0.5)/32.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np
import pytest

from rrcache.errors import GLError, SessionError, UnsupportedShaderError
from rrcache.glsl.frontend import parse_shader
from rrcache.compiler.prepared import Decl, PreparedShader, prepare, prepare_file
from rrcache.harness.reference import ReferenceCache
from rrcache.harness.renderer import Renderer, frame_indices, parse_resolution, render

N = 64


def ortho(left, right, bottom, top, near, far):
    m = np.eye(4)
    m[0, 0], m[1, 1], m[2, 2] = 2 / (right - left), 2 / (top - bottom), -2 / (far - near)
    m[0, 3], m[1, 3], m[2, 3] = -(right + left) / (right - left), -(top + bottom) / (top - bottom), -(far + near) / (far - near)
    return m


def translate(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def quad(x0, y0, x1, y1, z=0.0, colors=None):
    pos = np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]], np.float32)
    return SimpleNamespace(
        positions=pos, normals=np.tile(np.float32([0, 0, 1]), (4, 1)),
        texcoords=((pos[:, :2] - [x0, y0]) / [x1 - x0, y1 - y0]).astype(np.float32),
        colors=colors, tangents=None, indices=np.array([[0, 1, 2], [0, 2, 3]], np.uint32))


def scene_object(mesh, model=None, name="quad"):
    if model is None:
        model = np.eye(4)
    fn = model if callable(model) else (lambda frame: model)
    return SimpleNamespace(name=name, mesh=mesh, model_matrix=fn)


@dataclass
class FakeSession:
    """The parts of ``rrcache.session.Session`` the harness reads."""

    objects: list
    resolution: tuple = (N, N)
    frames: int = 3
    fps: float = 30.0
    uniforms: dict = field(default_factory=dict)
    textures: dict = field(default_factory=dict)
    background: tuple = (0.0, 0.0, 0.0, 0.0)
    path: str = "fake_session.json"
    hash: str = "fake-session-hash"

    def camera_at(self, frame):
        eye = np.array([0.0, 0.0, 5.0 + frame])
        return SimpleNamespace(eye=eye, view=translate(*-eye), projection=lambda aspect: ortho(-1, 1, -1, 1, 0.1, 100))

    def light_at(self, frame):
        return SimpleNamespace(position=np.array([1.0, 2.0, 3.0 + frame]), color=np.array([0.5, 0.25, 1.0]))

    def uniform_values(self, frame):
        return {k: (v(frame) if callable(v) else v) for k, v in self.uniforms.items()}


def shader(source, name="test.frag"):
    return prepare(parse_shader(source, name))


def pixel_centres():
    j = (np.arange(N) + 0.5) / (N / 2) - 1.0
    x = np.tile(j, (N, 1))
    y = -x.T
    return x, y


CENTRE_QUAD = FakeSession([scene_object(quad(-0.5, -0.5, 0.5, 0.5))])


# --------------------------------------------------------------------------- basics

def test_covered_pixels_match_projected_area(gl_ctx):
    result = render(shader("#version 330\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"), CENTRE_QUAD)
    assert len(result.frames) == 3
    for frame in result.frames:
        assert frame.image.shape == (N, N, 4) and frame.image.dtype == np.float32
        assert frame.covered_pixels == 32 * 32
        assert frame.mask[16:48, 16:48].all() and frame.mask.sum() == 32 * 32
        assert frame.samples_passed == 32 * 32
        assert (frame.image[frame.mask] == 1.0).all() and (frame.image[~frame.mask] == 0.0).all()
        assert np.isfinite(frame.ms) and frame.ms > 0


def test_overlapping_objects_cover_their_union_and_overdraw_counts(gl_ctx):
    back = scene_object(quad(-0.5, -0.5, 0.5, 0.5, z=0.0), name="back")
    front = scene_object(quad(0.0, 0.0, 1.0, 1.0, z=0.5), name="front")
    session = FakeSession([back, front], frames=1)
    src = "#version 330\nin vec4 v_position;\nout vec4 c;\nvoid main() { c = vec4(v_position.z); }\n"
    frame = render(shader(src), session).frames[0]
    assert frame.covered_pixels == 32 * 32 + 32 * 32 - 16 * 16
    assert frame.samples_passed == 2 * 32 * 32   # the front quad is drawn second and passes everywhere
    assert frame.image[20, 40, 0] == pytest.approx(0.5)   # the front quad wins the overlap (top right)
    assert frame.image[40, 20, 0] == pytest.approx(0.0)


def test_same_frame_twice_gives_identical_pixels(gl_ctx):
    src = ("#version 330\nin vec4 v_position;\nin vec2 v_texcoord;\nuniform float u_time;\nout vec4 c;\n"
           "void main() { c = vec4(sin(v_position.xy * 40.0 + u_time), fract(v_texcoord * 7.3)); }\n")
    prepared = shader(src)
    with Renderer(prepared, CENTRE_QUAD) as renderer:
        a = renderer.render_frame(1)
        renderer.render_frame(2)
        b = renderer.render_frame(1)
    c = render(prepared, CENTRE_QUAD, frames=[1]).frames[0]
    np.testing.assert_array_equal(a.image, b.image)
    np.testing.assert_array_equal(a.image, c.image)
    assert a.covered_pixels == b.covered_pixels == c.covered_pixels


def test_background_and_resolution_override(gl_ctx):
    session = FakeSession([scene_object(quad(-0.5, -0.5, 0.5, 0.5))], background=(0.1, 0.2, 0.3, 1.0), frames=1)
    result = render(shader("#version 330\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"), session, resolution=(32, 16))
    frame = result.frames[0]
    assert result.resolution == (32, 16) and frame.image.shape == (16, 32, 4)
    assert frame.covered_pixels == 16 * 8
    np.testing.assert_allclose(frame.image[0, 0], [0.1, 0.2, 0.3, 1.0], rtol=1e-6)


def test_frame_selection():
    session = SimpleNamespace(frames=5, path="s.json")
    assert frame_indices(session) == [0, 1, 2, 3, 4]
    assert frame_indices(session, 9) == [0, 1, 2, 3, 4]
    assert frame_indices(session, [4, 2]) == [4, 2]
    with pytest.raises(SessionError):
        frame_indices(session, 0)
    assert parse_resolution("64x48") == (64, 48)
    with pytest.raises(ValueError):
        parse_resolution("64by48")


def test_frame_outside_session_is_an_error(gl_ctx):
    with Renderer(shader("#version 330\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"), CENTRE_QUAD) as r:
        with pytest.raises(SessionError, match="frame 3 is outside"):
            r.render_frame(3)


# --------------------------------------------------------------------------- glslViewer uniforms and varyings

def test_builtin_uniforms(gl_ctx):
    src = ("#version 330\nuniform vec2 u_resolution;\nuniform float u_time;\nuniform int u_frame;\n"
           "uniform vec3 u_camera;\nuniform vec3 u_light;\nuniform vec3 u_lightColor;\nout vec4 c;\n"
           "void main() {\n"
           "    if (gl_FragCoord.x < 32.0) c = vec4(u_resolution, u_time, float(u_frame));\n"
           "    else if (gl_FragCoord.y < 32.0) c = vec4(u_camera, 0.0);\n"
           "    else c = vec4(u_light + 10.0 * u_lightColor, 0.0);\n}\n")
    session = FakeSession([scene_object(quad(-1, -1, 1, 1))])
    frame = render(shader(src), session, frames=[2]).frames[0]
    np.testing.assert_allclose(frame.image[0, 0], [64, 64, 2 / 30, 2], rtol=1e-6)
    np.testing.assert_allclose(frame.image[63, 63], [0, 0, 7, 0], rtol=1e-6)          # bottom right
    np.testing.assert_allclose(frame.image[0, 63], [1 + 5, 2 + 2.5, 5 + 10, 0], rtol=1e-6)  # top right


def test_varyings_and_matrices(gl_ctx):
    model = translate(0.25, -0.25, 0.5)
    src = ("#version 330\nin vec4 v_position;\nin vec3 v_objectPosition;\nin vec2 v_texcoord;\nin vec4 v_color;\n"
           "uniform mat4 u_viewMatrix;\nuniform mat4 u_projectionMatrix;\nuniform mat4 u_modelViewProjectionMatrix;\n"
           "uniform mat4 u_modelMatrix;\nout vec4 c;\n"
           "void main() {\n"
           "    vec4 a = u_projectionMatrix * u_viewMatrix * v_position;\n"
           "    vec4 b = u_modelViewProjectionMatrix * vec4(v_objectPosition, 1.0);\n"
           "    vec4 w = u_modelMatrix * vec4(v_objectPosition, 1.0);\n"
           "    if (gl_FragCoord.x < 32.0) c = vec4(a.xy / a.w, b.xy / b.w);\n"
           "    else if (gl_FragCoord.y < 32.0) c = vec4(w.xyz - v_position.xyz, v_position.z);\n"
           "    else c = vec4(v_texcoord, v_color.ra);\n}\n")
    session = FakeSession([scene_object(quad(-1.25, -0.75, 0.75, 1.25), model)], frames=1)
    image = render(shader(src), session).frames[0].image
    x, y = pixel_centres()
    left = np.s_[:, :32]
    np.testing.assert_allclose(image[left][..., 0], x[left], atol=1e-5)
    np.testing.assert_allclose(image[left][..., 1], y[left], atol=1e-5)
    np.testing.assert_allclose(image[left][..., 2], x[left], atol=1e-5)
    np.testing.assert_allclose(image[left][..., 3], y[left], atol=1e-5)
    np.testing.assert_allclose(image[32:, 32:, :3], 0.0, atol=1e-6)
    np.testing.assert_allclose(image[32:, 32:, 3], 0.5, atol=1e-6)
    top_right = np.s_[:32, 32:]
    np.testing.assert_allclose(image[top_right][..., 0], (x[top_right] + 1) / 2, atol=1e-5)  # texcoord u
    np.testing.assert_allclose(image[top_right][..., 1], (y[top_right] + 1) / 2, atol=1e-5)  # v = 1 at the top
    np.testing.assert_allclose(image[top_right][..., 2:], 1.0)  # no vertex colours: opaque white


def test_world_normals_through_the_normal_matrix(gl_ctx):
    # tilt the quad about X, then stretch Z by 4: normals follow the inverse transpose and stay unit length
    tilt = np.array([[1, 0, 0, 0], [0, np.cos(0.3), -np.sin(0.3), 0], [0, np.sin(0.3), np.cos(0.3), 0], [0, 0, 0, 1]])
    model = np.diag([1.0, 1.0, 4.0, 1.0]) @ tilt
    src = ("#version 330\nin vec3 v_normal;\nuniform mat3 u_normalMatrix;\nout vec4 c;\n"
           "void main() { c = vec4(v_normal, length(u_normalMatrix * vec3(0.0, 0.0, 1.0))); }\n")
    session = FakeSession([scene_object(quad(-1, -1, 1, 1), model)], frames=1)
    frame = render(shader(src), session).frames[0]
    expected = np.linalg.inv(model[:3, :3]).T @ [0, 0, 1]
    norm = np.linalg.norm(expected)
    assert frame.covered_pixels > 0
    got = frame.image[frame.mask]
    np.testing.assert_allclose(got[:, :3], np.tile(expected / norm, (len(got), 1)), atol=1e-5)
    np.testing.assert_allclose(got[:, 3], norm, rtol=1e-5)


def test_previous_clip_position_for_reprojection(gl_ctx):
    moving = scene_object(quad(-0.5, -0.5, 0.5, 0.5), lambda frame: translate(0.125 * frame, 0, 0))
    src = ("#version 330\nin vec4 rr_prevClip;\nin vec4 v_position;\nout vec4 c;\n"
           "void main() { c = vec4(rr_prevClip.xy / rr_prevClip.w, v_position.xy); }\n")
    frames = render(shader(src), FakeSession([moving])).frames
    for frame in frames:
        got = frame.image[frame.mask]
        shift = 0.125 if frame.index > 0 else 0.0   # frame 0 has no previous frame: itself
        np.testing.assert_allclose(got[:, 0], got[:, 2] - shift, atol=1e-5)
        np.testing.assert_allclose(got[:, 1], got[:, 3], atol=1e-5)


def test_varying_declared_smaller_gets_converted(gl_ctx):
    src = "#version 330\nin vec3 v_position;\nin vec3 v_color;\nout vec4 c;\nvoid main() { c = vec4(v_position.xy, v_color.g, 1.0); }\n"
    frame = render(shader(src), CENTRE_QUAD, frames=1).frames[0]
    assert frame.image[16, 16, 0] == pytest.approx(-0.484375) and frame.image[16, 16, 2] == 1.0


def test_vertex_colors_and_legacy_glslviewer_shader(gl_ctx, tmp_path):
    colors = np.tile(np.float32([0.2, 0.4, 0.6, 1.0]), (4, 1))
    session = FakeSession([scene_object(quad(-1, -1, 1, 1, colors=colors))], frames=1)
    path = tmp_path / "legacy.frag"
    path.write_text("#ifdef GL_ES\nprecision mediump float;\n#endif\n"
                    "varying vec4 v_color;\n"
                    "void main() {\n"
                    "#ifdef MODEL_VERTEX_COLOR\n    gl_FragColor = v_color;\n"
                    "#else\n    gl_FragColor = vec4(1.0, 0.0, 1.0, 1.0);\n#endif\n}\n")
    prepared = prepare_file(path, session)
    assert prepared.defines == {"MODEL_VERTEX_COLOR": "1", "MODEL_VERTEX_NORMAL": "1", "MODEL_VERTEX_TEXCOORD": "1"}
    image = render(prepared, session).frames[0].image
    np.testing.assert_allclose(image[10, 10], [0.2, 0.4, 0.6, 1.0], rtol=1e-6)
    # the same file and session through a path
    image2 = render(str(path), session).frames[0].image
    np.testing.assert_array_equal(image, image2)


def test_unknown_varying_is_refused_at_its_declaration(gl_ctx):
    with pytest.raises(UnsupportedShaderError, match=r"odd\.frag:2:\d+: .*v_weird"):
        render(shader("#version 330\nin vec3 v_weird;\nout vec4 c;\nvoid main() { c = vec4(v_weird, 1); }\n",
                      "odd.frag"), CENTRE_QUAD)


def test_unused_unknown_varying_is_tolerated(gl_ctx):
    src = "#version 330\nin vec3 v_weird;\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"
    prepared = shader(src, "odd.frag")
    assert "v_weird" not in prepared.inputs
    assert render(prepared, CENTRE_QUAD, frames=1).frames[0].covered_pixels == 1024


def test_driver_error_names_the_original_line(gl_ctx):
    # the front-end accepts what it checks; here the printed text is altered after the fact so that
    # only the driver can object, and the error must still name the user's line 6
    src = "#version 330\nout vec4 c;\nuniform float u_a[2];\n\n\nvoid main() { c = vec4(u_a[1]); }\n"
    prepared = shader(src, "bad.frag")
    assert "u_a[1]" in prepared.source
    prepared.source = prepared.source.replace("u_a[1]", "u_a[5]")
    with pytest.raises(GLError) as info:
        render(prepared, FakeSession([scene_object(quad(-1, -1, 1, 1))], uniforms={"u_a": [1.0, 2.0]}))
    assert str(info.value).startswith("bad.frag:6:")


# --------------------------------------------------------------------------- session uniforms and textures

def test_session_uniforms_of_several_types_and_keyframes(gl_ctx):
    src = ("#version 330\nuniform float u_f;\nuniform int u_i;\nuniform bool u_b;\nuniform vec3 u_v;\n"
           "uniform float u_arr[3];\nuniform mat2 u_m;\nout vec4 c;\n"
           "void main() {\n"
           "    if (gl_FragCoord.x < 32.0) c = vec4(u_f, float(u_i), u_b ? 1.0 : -1.0, u_arr[2]);\n"
           "    else c = vec4(u_v.z, u_m[0][1], u_m[1][0], 0.0);\n}\n")
    session = FakeSession([scene_object(quad(-1, -1, 1, 1))], uniforms={
        "u_f": lambda frame: 0.5 * frame, "u_i": 7, "u_b": True, "u_v": np.array([1.0, 2.0, 3.0]),
        "u_arr": np.array([1.0, 2.0, 4.0]), "u_m": np.array([[1.0, 2.0], [3.0, 4.0]])})
    frames = render(shader(src), session).frames
    for frame in frames:
        np.testing.assert_allclose(frame.image[5, 5], [0.5 * frame.index, 7, 1, 4])
        np.testing.assert_allclose(frame.image[5, 60], [3, 3, 2, 0])


def test_missing_uniform_names_declaration_and_session(gl_ctx, tmp_path):
    path = tmp_path / "needs.frag"
    path.write_text("#version 330\nout vec4 c;\n\nuniform float u_shininess;\nvoid main() { c = vec4(u_shininess); }\n")
    prepared = prepare_file(path, ())
    with pytest.raises(SessionError) as info:
        render(prepared, CENTRE_QUAD)
    message = str(info.value)
    assert message.startswith("fake_session.json: uniforms:")
    assert f"{path}:4:" in message and "u_shininess" in message
    assert 'add "u_shininess": 0.0 to "uniforms"' in message


def test_unused_declared_uniform_is_not_required(gl_ctx):
    src = "#version 330\nuniform float u_unused;\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"
    assert render(shader(src), CENTRE_QUAD, frames=1).frames[0].covered_pixels == 1024


def test_undeclared_session_uniform_is_a_note(gl_ctx):
    session = FakeSession([scene_object(quad(-1, -1, 1, 1))], frames=1, uniforms={"u_extra": 1.0, "u_time": 3.0},
                          textures={"u_tex": SimpleNamespace(name="u_tex", kind="2d", data=np.zeros((2, 2, 3), np.float32))})
    result = render(shader("#version 330\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"), session)
    joined = "\n".join(result.notes)
    assert "`u_extra` is not declared" in joined
    assert "`u_time` is a built-in" in joined
    assert "texture `u_tex` is not declared" in joined


def test_wrong_session_value_shape_is_an_error(gl_ctx):
    session = FakeSession([scene_object(quad(-1, -1, 1, 1))], frames=1, uniforms={"u_v": [1.0, 2.0]})
    src = "#version 330\nuniform vec3 u_v;\nout vec4 c;\nvoid main() { c = vec4(u_v, 1.0); }\n"
    with pytest.raises(SessionError, match=r"uniforms\.u_v: .*expected 3 components"):
        render(shader(src), session)


def test_struct_uniform_from_a_dict(gl_ctx):
    src = ("#version 330\nstruct L { vec3 color; float power; };\nuniform L u_l;\nout vec4 c;\n"
           "void main() { c = vec4(u_l.color, u_l.power); }\n")
    session = FakeSession([scene_object(quad(-1, -1, 1, 1))], frames=1,
                          uniforms={"u_l": {"color": [0.1, 0.2, 0.3], "power": 2.0}})
    np.testing.assert_allclose(render(shader(src), session).frames[0].image[1, 1], [0.1, 0.2, 0.3, 2.0], rtol=1e-6)


def test_session_texture_2d_row_zero_is_top(gl_ctx):
    data = np.array([[[1, 0, 0, 1], [0, 1, 0, 1]],
                     [[0, 0, 1, 1], [1, 1, 1, 1]]], np.float32)   # row 0 = top of the image
    texture = SimpleNamespace(name="u_tex", kind="2d", data=data, filter="nearest", wrap="clamp")
    session = FakeSession([scene_object(quad(-1, -1, 1, 1))], frames=1, textures={"u_tex": texture})
    src = ("#version 330\nin vec2 v_texcoord;\nuniform sampler2D u_tex;\nout vec4 c;\n"
           "void main() { c = texture(u_tex, v_texcoord); }\n")
    image = render(shader(src), session).frames[0].image
    np.testing.assert_array_equal(image[10, 10], data[0, 0])   # top left
    np.testing.assert_array_equal(image[10, 50], data[0, 1])   # top right
    np.testing.assert_array_equal(image[50, 10], data[1, 0])   # bottom left


def test_session_cube_map(gl_ctx):
    faces = np.zeros((6, 2, 2, 3), np.float32)
    faces[4] = (0.25, 0.5, 0.75)   # +Z
    texture = SimpleNamespace(name="u_env", kind="cube", data=faces, filter="linear", wrap="repeat")
    session = FakeSession([scene_object(quad(-1, -1, 1, 1))], frames=1, textures={"u_env": texture})
    src = ("#version 330\nin vec3 v_normal;\nuniform samplerCube u_env;\nout vec4 c;\n"
           "void main() { c = texture(u_env, v_normal); }\n")
    image = render(shader(src), session).frames[0].image
    np.testing.assert_allclose(image[30, 30, :3], [0.25, 0.5, 0.75])


def test_missing_or_mismatched_texture(gl_ctx):
    src = ("#version 330\nin vec2 v_texcoord;\nuniform sampler2D u_tex;\nout vec4 c;\n"
           "void main() { c = texture(u_tex, v_texcoord); }\n")
    with pytest.raises(SessionError, match=r"fake_session\.json: textures: .*u_tex.*tex\.frag:3"):
        render(shader(src, "tex.frag"), CENTRE_QUAD)
    cube = SimpleNamespace(name="u_tex", kind="cube", data=np.zeros((6, 2, 2, 3), np.float32))
    with pytest.raises(SessionError, match="cube"):
        render(shader(src, "tex.frag"), FakeSession(CENTRE_QUAD.objects, textures={"u_tex": cube}))


def test_prepared_shader_without_front_end(gl_ctx):
    prepared = PreparedShader(
        source="#version 330 core\nin vec2 v_texcoord;\nuniform float u_k;\nout vec4 c;\n"
               "void main() { c = vec4(v_texcoord * u_k, 0.0, 1.0); }\n",
        path="hand.frag", hash="hand", inputs={"v_texcoord": Decl("vec2")}, uniforms={"u_k": Decl("float")})
    session = FakeSession(CENTRE_QUAD.objects, frames=1, uniforms={"u_k": 2.0})
    frame = render(prepared, session).frames[0]
    assert frame.image[47, 47, 0] == pytest.approx(2 * 31.5 / 32)


# --------------------------------------------------------------------------- reference cache

def test_reference_cache_renders_once(gl_ctx, tmp_path):
    src = "#version 330\nin vec4 v_position;\nout vec4 c;\nvoid main() { c = vec4(v_position.xy, 0.0, 1.0); }\n"
    prepared = shader(src)
    cache = ReferenceCache(tmp_path / "refs")
    first = cache.frames(prepared, CENTRE_QUAD, [0, 1])
    assert cache.rendered == 2
    again = cache.frames(prepared, CENTRE_QUAD, [1, 0, 2])
    assert cache.rendered == 3
    np.testing.assert_array_equal(first[1].image, again[0].image)
    assert again[0].covered_pixels == 1024
    # a new cache on the same directory reuses the files
    other = ReferenceCache(tmp_path / "refs")
    from_disk = other.frame(prepared, CENTRE_QUAD, 1)
    assert other.rendered == 0
    np.testing.assert_array_equal(from_disk.image, first[1].image)
    np.testing.assert_array_equal(from_disk.mask, first[1].mask)
    # another resolution is another key
    small = other.frame(prepared, CENTRE_QUAD, 1, resolution=(32, 32))
    assert other.rendered == 1 and small.image.shape == (32, 32, 4)
