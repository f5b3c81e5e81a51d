"""Adaptive refresh and the edge filter on ``tests/corpus`` (the pattern of tests/test_corpus.py):
for the two first picked nodes of every corpus shader, the adaptive variant (edge filter) with
threshold 0 at fast period 1 (every entry volatile, recomputed every frame) must reproduce the
original in the three-pass and two-pass algorithms, at a max age Δn = 50 that alone would leave
most pixels cached."""
from __future__ import annotations

import numpy as np
import pytest

from test_corpus import FRAMES, SHADERS, SIZE, TOLERANCE, picked_nodes, session_of
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.renderer import Renderer
from rrcache.pipeline import load_for_session, variant_for


@pytest.mark.parametrize("shader", SHADERS, ids=lambda p: p.stem)
def test_adaptive_threshold_zero_reproduces_the_original(gl_ctx, shader):
    session = session_of(shader)
    work = load_for_session(shader, session)
    frames = range(min(FRAMES, session.frames))
    with Renderer(work.prepared, session, SIZE) as original:
        reference = [original.render_frame(i) for i in frames]
    checked = 0
    for node in picked_nodes(work.table)[:2]:
        for algorithm in ("three-pass", "two-pass"):
            if algorithm not in node.algorithms:
                continue
            variant = variant_for(work, node.id, algorithm, filter="edge", adaptive=True)
            with CachedRenderer(variant, session, work.prepared, SIZE, period=50, threshold=0.0,
                                fast_period=1) as cached:
                for ref in reference:
                    got = cached.render_frame(ref.index)
                    err = float(np.abs(got.image - ref.image)[ref.mask].max())
                    assert err <= TOLERANCE, (shader.name, node.id, node.text, algorithm, ref.index, err)
                    if ref.index > 0:
                        assert got.hits == 0, (shader.name, node.id, algorithm)
            checked += 1
    assert checked, f"{shader.name}: no node checked"
