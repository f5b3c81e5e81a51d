"""Δn = 1 exactness of variants caching two or three nodes, over ``tests/corpus``.

For every corpus shader (the session as in :mod:`tests.test_corpus`), the nodes are the ones
that test picks (``COSTLIEST`` = 4 costliest and ``SAMPLED`` = 2 seeded others). The pairs
tested are every pair among the ``PAIR_COSTLIEST`` = 3 costliest of them (3 pairs) and
``PAIR_SAMPLED`` = 2 more drawn with a fixed seed from the remaining pairs of the six (so 5 pairs
per shader), plus the triple of the 3 costliest (three-pass in the per-node layout, or the union
layout where the shader can discard or a node needs derivatives); each is compiled in each algorithm that every
node of it allows, rendered at Δn = 1 for every node on a 64×64 frame for ``FRAMES`` = 3
frames, and each frame must equal the original's within the corpus tolerance. Pairs in which one
node lies inside the other (nested) are tested like the others; how many there were is printed.

The cap keeps the test to a few minutes on a loaded two-core machine with llvmpipe.
"""
from __future__ import annotations

import itertools
import random

import numpy as np
import pytest

from rrcache.compiler import ALGORITHMS
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.renderer import Renderer
from rrcache.pipeline import load_for_session, variant_for_nodes
from tests.test_corpus import SHADERS, SIZE, TOLERANCE, expects_nodes, picked_nodes, session_of, untidy_blocks

FRAMES = 3
PAIR_COSTLIEST, PAIR_SAMPLED = 3, 2


def picked_sets(table) -> list:
    nodes = picked_nodes(table)
    first = list(itertools.combinations(nodes[:PAIR_COSTLIEST], 2))
    rest = [p for p in itertools.combinations(nodes, 2) if p not in first]
    sets = first + random.Random(18).sample(rest, min(PAIR_SAMPLED, len(rest)))
    if len(nodes) >= 3:
        sets.append(tuple(nodes[:3]))
    return sets


def nested(work, a, b) -> bool:
    from rrcache.glsl.ast import walk
    return any(n is b.node for n in walk(a.node)) or any(n is a.node for n in walk(b.node))


@pytest.mark.parametrize("shader", [s for s in SHADERS if expects_nodes(s)], ids=lambda p: p.stem)
def test_node_sets_reproduce_the_original_at_period_one(gl_ctx, shader):
    session = session_of(shader)
    work = load_for_session(shader, session)
    frames = range(min(FRAMES, session.frames))
    with Renderer(work.prepared, session, SIZE) as original:
        reference = [original.render_frame(i) for i in frames]
    sets = picked_sets(work.table)
    if not sets:
        pytest.skip(f"{shader.name} lists fewer than two nodes")
    done, per_node = 0, 0
    nests = sum(nested(work, a, b) for s in sets for a, b in itertools.combinations(s, 2))
    for nodes in sets:
        ids = [n.id for n in nodes]
        for algorithm in ALGORITHMS:
            if any(algorithm not in n.algorithms for n in nodes):
                continue
            variant = variant_for_nodes(work, ids, algorithm)
            per_node += "node_0" in variant.passes
            for name, source in variant.passes.items():
                assert not untidy_blocks(source.fragment), (shader.name, ids, algorithm, name)
            with CachedRenderer(variant, session, work.prepared, SIZE, period=[1] * len(ids)) as cached:
                for ref in reference:
                    got = cached.render_frame(ref.index)
                    err = float(np.abs(got.image - ref.image)[ref.mask].max())
                    assert err <= TOLERANCE, (shader.name, ids, algorithm, ref.index, err)
            done += 1
    print(f"{shader.name}: {done} variants of {len(sets)} node sets ({nests} nested pairs, {per_node} "
          "three-pass variants in the per-node layout) exact at Δn=1")
    assert done >= len(sets)
