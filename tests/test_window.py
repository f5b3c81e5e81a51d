"""Rendering through a window (rrcache.gl.window): the scissor test at full pixel density.

- the plain renderer's window image is exactly the crop of the whole frame;
- a cached variant in a window reproduces the original's crop at Δn = 1 and, over a few frames
  at Δn = 4, hits inside the window like the whole frame does away from its edges;
- a window outside the frame is refused.
"""
from __future__ import annotations

import numpy as np
import pytest

from scene_files import write_scene

from rrcache.harness.cached import CachedRenderer, compare
from rrcache.harness.renderer import Renderer
from rrcache.pipeline import load_for_session, variant_for
from rrcache.session import load_session

WINDOW = (16, 8, 32, 24)  # x, y from the bottom left; 64×48 frame


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    shader, session_path = write_scene(tmp_path_factory.mktemp("window"))
    session = load_session(session_path)
    return load_for_session(shader, session), session


def _crop(image):
    x, y, w, h = WINDOW
    rows = image.shape[0]
    return image[rows - y - h: rows - y, x: x + w]


def test_window_image_is_the_crop_of_the_frame(scene):
    work, session = scene
    with Renderer(work.prepared, session) as whole, Renderer(work.prepared, session, window=WINDOW) as part:
        full, win = whole.render_frame(3), part.render_frame(3)
    assert win.image.shape == (24, 32, 4)
    assert np.array_equal(win.image, _crop(full.image)) and np.array_equal(win.mask, _crop(full.mask))
    assert 0 < win.covered_pixels <= 32 * 24


def test_cached_variant_in_a_window(scene):
    work, session = scene
    node = max(work.table.nodes, key=lambda n: n.cost).id
    variant = variant_for(work, node)
    exact = compare(variant, session, work.prepared, range(4), period=1, window=WINDOW)
    assert exact.resolution == (64, 48) and exact.mean_error <= 1e-6
    with CachedRenderer(variant, session, work.prepared, period=4, window=WINDOW) as cached, \
            Renderer(work.prepared, session, window=WINDOW) as original:
        for index in range(6):
            got, ref = cached.render_frame(index), original.render_frame(index)
            assert got.image.shape == ref.image.shape == (24, 32, 4)
            assert np.array_equal(got.mask, ref.mask)
        # Δn = 4: a quarter of the blocks refresh; a slow camera keeps most of the rest
        assert got.hits / got.covered_pixels > 0.5


def test_window_outside_the_frame_is_refused(scene):
    work, session = scene
    with pytest.raises(ValueError, match="not inside"):
        Renderer(work.prepared, session, window=(40, 0, 32, 24))
