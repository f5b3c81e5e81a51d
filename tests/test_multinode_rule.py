"""The pair-combination rule of :mod:`rrcache.bench.pairs` against one measured pair: Marble's
lighting (n2475, outer, at Δn = 4) over its albedo (n2442, inner, at Δn = 50), 96×72, 6 frames.

The rule predicts the pair's error as the sum of the singles' errors, an upper bound (see the
module); the measured pair must lie under it (5% slack for the resampling's noise) and above half
of it (the rule is a useful prediction, not only a bound). Times are not asserted (a test never
asserts a duration); the time rule's figures are measured by ``python -m rrcache.bench.pairs``
(docs/multinode.md).
"""
from __future__ import annotations

from rrcache.bench.pairs import predict
from rrcache.harness.cached import compare
from rrcache.pipeline import load_for_session, variant_for, variant_for_nodes
from rrcache.session import load_session

OUTER, INNER = "n2475", "n2442"


def test_pair_error_is_predicted_by_the_sum_of_the_singles(gl_ctx):
    session = load_session("sessions/marble.json")
    work = load_for_session("shaders/marble.glsl", session)
    assert [work.node(OUTER).line, work.node(INNER).line] == [131, 117]   # lighting, albedo
    frames, size = range(6), (96, 72)

    def error(variant, period):
        return compare(variant, session, work.prepared, frames, period=period, resolution=size).mean_error

    e_pair = error(variant_for_nodes(work, [OUTER, INNER]), (4, 50))
    e_outer = error(variant_for(work, OUTER), 4)
    e_inner = error(variant_for(work, INNER), 50)
    predicted, _ = predict(e_outer, e_inner, 1.0, 1.0, 0.5)
    assert e_outer > 0 and e_inner > 0
    assert 0.5 * predicted <= e_pair <= 1.05 * predicted, (e_pair, e_outer, e_inner)
