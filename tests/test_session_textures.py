"""Images through OpenImageIO: formats, exactness, orientation, cube maps, failures."""
import numpy as np
import OpenImageIO as oiio
import pytest

from rrcache.session.textures import ImageLoadError, read_image, split_cube_strip, stack_cube_faces


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
