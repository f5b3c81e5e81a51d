"""Amortized variants of every estimator of ``tests/corpus`` (and of the paper scenes' shaders
the analysis finds one in), under every algorithm, 64×64, 3 frames:

- ``m = N, λ = 0`` reproduces the original at every frame (Δ-exactness);
- ``m < N``: the first frame (every pixel a miss, all N samples) is the original, later frames
  are finite.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rrcache.analysis.estimators import find_estimators
from rrcache.compiler.amortize import instance_amortized
from rrcache.harness.cached import CachedRenderer, compare
from rrcache.harness.renderer import Renderer
from rrcache.pipeline import load_for_session
from rrcache.session import load_session

ROOT = Path(__file__).resolve().parent.parent
CORPUS = ROOT / "tests" / "corpus"
SIZE = (64, 64)
ALGORITHMS = ["three-pass", "two-pass", "one-pass"]


def _session(shader: Path):
    own = shader.with_suffix(".json")
    return load_session(own if own.exists() else CORPUS / "default_session.json")


def _cases():
    out = []
    for shader in sorted(CORPUS.glob("*.glsl")) + [ROOT / "shaders" / "pcf_shadows.glsl"]:
        session = ROOT / "sessions" / "temple.json" if shader.name == "pcf_shadows.glsl" else None
        work = load_for_session(str(shader), load_session(session) if session else _session(shader))
        for est in find_estimators(work.shader).estimators:
            out += [(shader, session, est.id, est.samples, algorithm) for algorithm in ALGORITHMS]
    return out


CASES = _cases()


def test_the_corpus_has_estimators():
    assert len({(c[0], c[2]) for c in CASES}) >= 6


@pytest.mark.parametrize("shader,session,estimator,total,algorithm", CASES,
                         ids=[f"{c[0].stem}-{c[2]}-{c[4]}" for c in CASES])
def test_all_samples_no_blend_is_the_original(gl_ctx, shader, session, estimator, total, algorithm):
    session = load_session(session) if session else _session(shader)
    work = load_for_session(str(shader), session)
    exact = instance_amortized(work.shader, estimator, algorithm, samples=total, blend=0.0)
    result = compare(exact, session, work.prepared, range(3), period=1000, resolution=SIZE)
    assert all(f.mean_error <= 1e-5 for f in result.frames), [f.mean_error for f in result.frames]
    part = instance_amortized(work.shader, estimator, algorithm, samples=max(1, total // 3), blend=0.6)
    with Renderer(work.prepared, session, SIZE) as original, \
            CachedRenderer(part, session, work.prepared, SIZE, period=1000) as cached:
        first, ref = cached.render_frame(0), original.render_frame(0)
        assert np.abs(first.image - ref.image)[ref.mask].max() <= 1e-5
        later = cached.render_frame(1)
        assert np.isfinite(later.image).all()
