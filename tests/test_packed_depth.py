"""The inverse depth packed into the payload's free channel (issue 15, Build 6: one render
target and one fetch fewer in the cache's passes) changes nothing in the images.

On Marble at 64×64, for a float node (packed into channel 1), a vec3 node (channel 3) and in
each algorithm, the packed variant (``pack_depth=True``) and the unpacked one (the default) render the same frames at Δn = 4 (hits and refreshes mixed) with the same hit counts,
and images equal within 5e-4 (measured: bit for bit on most frames; at most 2e-6 for the float
node and 1.6e-4 for the vec3 node, at a few pixels: llvmpipe filters an RG32F or RGBA32F
texture with other rounding than an R32F or RGB32F one, and the cached value is resampled
frame after frame; the same unpacked variant rendered twice is bit for bit); a vec4 node and a
16-bit payload keep the separate texture.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("LP_NUM_THREADS", "1")

from rrcache.compiler import ALGORITHMS, instance  # noqa: E402
from rrcache.harness.cached import CachedRenderer  # noqa: E402
from rrcache.pipeline import load_for_session  # noqa: E402
from rrcache.runtime.glsl import depth_channel_for  # noqa: E402
from rrcache.session import load_session  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SIZE = (64, 64)
FRAMES = 5


@pytest.fixture(scope="module")
def marble():
    session = load_session(ROOT / "sessions" / "marble.json")
    return session, load_for_session(ROOT / "shaders" / "marble.glsl", session)


def node_of_type(work, type_name):
    return max((n for n in work.table.nodes if n.type == type_name), key=lambda n: n.cost)


def render(variant, session, work):
    with CachedRenderer(variant, session, work.prepared, SIZE, period=4) as cached:
        frames = [cached.render_frame(i) for i in range(FRAMES)]
    return [f.image for f in frames], [f.hits for f in frames]


@pytest.mark.parametrize("type_name", ["float", "vec3"])
@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_packed_renders_the_same_frames(gl_ctx, marble, algorithm, type_name):
    session, work = marble
    node = node_of_type(work, type_name)
    if algorithm not in node.algorithms:
        pytest.skip(f"{algorithm} cannot cache {node.id}")
    packed = instance(work.table, node.id, algorithm, vertex=work.vertex, pack_depth=True)
    plain = instance(work.table, node.id, algorithm, vertex=work.vertex)
    assert packed.depth_channel == node_components(type_name) and plain.depth_channel is None
    assert all("rr_outInvDepth" not in p.fragment and "rr_prevInvDepth" not in p.fragment
               for p in packed.passes.values())
    images_p, hits_p = render(packed, session, work)
    images_u, hits_u = render(plain, session, work)
    assert hits_p == hits_u, (hits_p, hits_u)
    if algorithm != "one-pass":  # one-pass counts nothing (no query)
        assert sum(hits_p[1:]) > 0, hits_p
    for a, b in zip(images_p, images_u):
        assert float(np.abs(a - b).max()) <= 5e-4


def node_components(type_name):
    return {"float": 1, "vec2": 2, "vec3": 3, "vec4": 4}[type_name]


def test_no_room_no_packing(marble):
    _, work = marble
    assert depth_channel_for(4, "f4") is None and depth_channel_for(1, "f2") is None
    vec4 = [n for n in work.table.nodes if n.type == "vec4"]
    if vec4:
        assert instance(work.table, vec4[0].id, "three-pass", vertex=work.vertex, pack_depth=True).depth_channel is None
    node = node_of_type(work, "float")
    assert instance(work.table, node.id, "two-pass", payload_dtype="f2", vertex=work.vertex,
                    pack_depth=True).depth_channel is None
    assert instance(work.table, node.id, "two-pass", vertex=work.vertex).depth_channel is None  # the default
