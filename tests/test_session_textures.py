"""Images through OpenImageIO: formats, exactness, orientation, cube maps, failures."""
import numpy as np
import OpenImageIO as oiio
import pytest

from rrcache.session.textures import ImageLoadError, read_image, split_cube_cross, split_cube_strip, stack_cube_faces


def write_image(path, data, fmt):
    """Write ``data`` (H×W×C) with OpenImageIO in pixel format ``fmt``."""
    h, w, c = data.shape
    out = oiio.ImageOutput.create(str(path))
    assert out is not None, oiio.geterror()
    assert out.open(str(path), oiio.ImageSpec(w, h, c, fmt)), out.geterror()
    assert out.write_image(data), out.geterror()
    out.close()
    return str(path)


def test_png_8bit_scaled_and_top_row_first(tmp_path):
    img = np.zeros((3, 4, 3), np.uint8)
    img[0] = 255  # top row white
    img[2, :, 0] = 51
    m = read_image(write_image(tmp_path / "a.png", img, oiio.UINT8))
    assert m.shape == (3, 4, 3) and m.dtype == np.float32
    assert np.all(m[0] == 1.0) and np.allclose(m[2, :, 0], 0.2) and np.all(m[1] == 0.0)


def test_tiff_16bit_and_grey_channel(tmp_path):
    img = np.array([[[0], [65535]], [[32768], [1]]], np.uint16)
    m = read_image(write_image(tmp_path / "a.tif", img, oiio.UINT16))
    assert m.shape == (2, 2, 1)
    assert np.allclose(m[..., 0], img[..., 0] / 65535.0, atol=1e-7)


def test_float_exr_is_exact(tmp_path):
    rng = np.random.default_rng(1)
    data = (rng.standard_normal((5, 7, 4)) * 1e3).astype(np.float32)
    data[0, 0, 0] = 1e-30
    data[1, 1, 1] = -123456.789
    m = read_image(write_image(tmp_path / "records.exr", data, oiio.FLOAT))
    assert m.dtype == np.float32 and np.array_equal(m, data)


def test_half_exr_hdr_and_jpeg(tmp_path):
    half = np.array([[[0.5, 2.0, 1024.0]]], np.float32)
    assert np.array_equal(read_image(write_image(tmp_path / "h.exr", half, oiio.HALF)), half)
    hdr = np.full((2, 2, 3), 4.0, np.float32)
    assert np.allclose(read_image(write_image(tmp_path / "e.hdr", hdr, oiio.FLOAT)), 4.0, rtol=0.02)
    grey = np.full((8, 8, 3), 128, np.uint8)
    assert np.allclose(read_image(write_image(tmp_path / "g.jpg", grey, oiio.UINT8)), 128 / 255, atol=0.02)


def test_cube_faces_and_strips():
    faces = [np.full((2, 2, 3), k, np.float32) for k in range(6)]
    cube = stack_cube_faces(faces)
    assert cube.shape == (6, 2, 2, 3) and [cube[k, 0, 0, 0] for k in range(6)] == list(range(6))
    strip = np.concatenate(faces, axis=1)
    assert np.array_equal(split_cube_strip(strip), cube)
    assert np.array_equal(split_cube_strip(np.concatenate(faces, axis=0)), cube)
    with pytest.raises(ImageLoadError, match="6:1"):
        split_cube_strip(np.zeros((2, 5, 3), np.float32))
    with pytest.raises(ImageLoadError, match="face 3"):
        stack_cube_faces(faces[:3] + [np.zeros((4, 4, 3), np.float32)] + faces[4:])


def test_missing_and_garbage(tmp_path):
    with pytest.raises(ImageLoadError, match="not found"):
        read_image(str(tmp_path / "nope.png"))
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"this is not a png" * 10)
    with pytest.raises(ImageLoadError, match="cannot"):
        read_image(str(bad))


# --- cube maps in the cross layouts glslViewer reads (issue 14) -----------------------------------

FACE_COLOURS = [(1, 0, 0), (0, 1, 1), (0, 1, 0), (1, 0, 1), (0, 0, 1), (1, 1, 0)]  # +X -X +Y -Y +Z -Z
_S = 4


def _faces():
    """Six 4×4 RGBA faces, each its own colour; alpha 1 except on the edge the face shares with +Z
    (alpha 0.5 there), so that orientation can be checked on the GL side too."""
    faces = np.ones((6, _S, _S, 4), np.float32)
    for k, c in enumerate(FACE_COLOURS):
        faces[k, ..., :3] = c
    faces[2, -1, :, 3] = 0.5   # +Y: bottom row touches +Z
    faces[3, 0, :, 3] = 0.5    # -Y: top row
    faces[1, :, -1, 3] = 0.5   # -X: right column
    faces[0, :, 0, 3] = 0.5    # +X: left column
    faces[5, 0, 0, 3] = 0.25   # -Z: its top-left texel (GL: toward +X +Y), upside down in a vertical cross
    return faces


def _cross(faces, vertical):
    s = _S
    img = np.zeros((4 * s, 3 * s, 4) if vertical else (3 * s, 4 * s, 4), np.float32)
    cells = {0: (1, 2), 1: (1, 0), 2: (0, 1), 3: (2, 1), 4: (1, 1), 5: (3, 1) if vertical else (1, 3)}
    for k, (r, c) in cells.items():
        face = faces[k][::-1, ::-1] if (vertical and k == 5) else faces[k]
        img[r * s:(r + 1) * s, c * s:(c + 1) * s] = face
    return img


@pytest.mark.parametrize("vertical", [False, True])
def test_cross_layouts_split_like_strips(tmp_path, vertical):
    faces = _faces()
    strip = np.concatenate(list(faces), axis=1)
    cross = _cross(faces, vertical)
    assert cross.shape[:2] == ((16, 12) if vertical else (12, 16))
    assert np.array_equal(split_cube_strip(strip), faces)
    assert np.array_equal(split_cube_strip(cross), faces)
    # through a file (a session's single-image cube map), each face keeps its own colour
    path = write_image(tmp_path / "cross.exr", cross, oiio.FLOAT)
    split = split_cube_strip(read_image(path))
    assert [tuple(split[k, 1, 1, :3]) for k in range(6)] == FACE_COLOURS
    assert np.array_equal(split, faces)


def test_bad_cross_sizes():
    with pytest.raises(ImageLoadError, match="4:3 or 3:4 cross"):
        split_cube_strip(np.zeros((9, 10, 3), np.float32))
    with pytest.raises(ImageLoadError, match="4:3"):
        split_cube_cross(np.zeros((6, 9, 3), np.float32))


@pytest.mark.parametrize("vertical", [False, True])
def test_cross_cube_map_samples_right_in_gl(gl_ctx, tmp_path, vertical):
    """A session cube map from a cross: each axis direction samples its face's colour, and a
    direction next to +Z samples the edge that borders +Z in the cross (GL's face orientation)."""
    import json

    from rrcache.gl.resources import GLScope
    from rrcache.gl.program import build_program
    from rrcache.gl.textures import texture_from_asset
    from rrcache.session import load_session

    write_image(tmp_path / "env.exr", _cross(_faces(), vertical), oiio.FLOAT)
    session = {"rrcache_session": 1, "resolution": [8, 8], "frames": 1,
               "camera": {"keyframes": [{"frame": 0, "eye": [0, 0, 3], "target": [0, 0, 0]}]},
               "objects": [{"procedural": {"type": "icosphere"}}],
               "textures": {"u_env": {"path": "env.exr", "kind": "cube", "filter": "nearest"}}}
    (tmp_path / "s.json").write_text(json.dumps(session))
    asset = load_session(tmp_path / "s.json").textures["u_env"]
    dirs = ["vec3(1,0,0)", "vec3(-1,0,0)", "vec3(0,1,0)", "vec3(0,-1,0)", "vec3(0,0,1)", "vec3(0,0,-1)",
            # next to +Z on each side face, then the far side of +Y (no edge mark)
            "vec3(0,1,0.9)", "vec3(0,-1,0.9)", "vec3(-1,0,0.9)", "vec3(1,0,0.9)", "vec3(0,1,-0.9)",
            "vec3(0.9,0.9,-1)", "vec3(-0.9,-0.9,-1)"]
    fs = ("#version 330\nuniform samplerCube t;\nout vec4 c;\nvoid main() {\n"
          f"    vec3 d[{len(dirs)}] = vec3[{len(dirs)}](" + ", ".join(dirs) + ");\n"
          "    c = texture(t, d[int(gl_FragCoord.x)]);\n}\n")
    vs = "#version 330\nin vec2 p;\nvoid main() { gl_Position = vec4(p, 0.0, 1.0); }\n"
    with GLScope() as scope:
        prog = scope.own(build_program(gl_ctx, vs, fs))
        tex = scope.own(texture_from_asset(gl_ctx, asset))
        tex.use(0)
        prog["t"].value = 0
        color = scope.own(gl_ctx.texture((len(dirs), 1), 4, dtype="f4"))
        fbo = scope.own(gl_ctx.framebuffer([color]))
        vbo = scope.own(gl_ctx.buffer(np.array([-1, -1, 3, -1, -1, 3], "f4").tobytes()))
        vao = scope.own(gl_ctx.vertex_array(prog, [(vbo, "2f", "p")]))
        fbo.use()
        fbo.clear()
        vao.render()
        img = np.frombuffer(color.read(), np.float32).reshape(len(dirs), 4)
    assert [tuple(img[k, :3]) for k in range(6)] == FACE_COLOURS
    assert img[6:10, 3].tolist() == [0.5] * 4 and img[10, 3] == 1.0
    assert img[11, 3] == 0.25 and img[12, 3] == 1.0
