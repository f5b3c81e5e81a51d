"""The analysis and the compiler on the shaders of ``tests/corpus`` (see its README.md).

For every ``tests/corpus/*.glsl`` (with the session of the same name, else
``default_session.json``):

1. every analysis pass runs on it in order (inlining, unrolling, compound-assignment expansion,
   sum reordering)
   and the program each one returns type-checks: a pass that rejects its own rewrite fails here,
   naming the pass;
2. the node table is built, and the variants of at most ``COSTLIEST + SAMPLED`` listed nodes (the
   ``COSTLIEST`` costliest and a seeded sample of ``SAMPLED`` others) are compiled by the GL
   driver in each of the three algorithms and rendered at Δn = 1 (refresh every frame) on a
   64×64 frame for ``FRAMES`` frames; each frame must equal the original's within ``TOLERANCE``,
   and every pass's text must be tidy (no empty block, no block holding only a block).
   An algorithm the node table marks a node invalid for (one-pass for a value that needs
   screen-space derivatives) must be refused by the compiler instead.

The cap keeps the test quick on a small, shared machine: a corpus shader lists tens of nodes,
and each variant costs a few driver compilations (about a second per node and algorithm on a
loaded two-core machine with llvmpipe).
"""
from __future__ import annotations

import random
from pathlib import Path

import numpy as np
import pytest

from rrcache.analysis.compound import expand_unit
from rrcache.analysis.sums import reorder_sums
from rrcache.analysis.inline import inline_unit
from rrcache.analysis.unroll import unroll_unit
from rrcache.compiler import ALGORITHMS
from rrcache.glsl import ast as A
from rrcache.glsl.parser import parse_source
from rrcache.errors import UnsupportedShaderError
from rrcache.glsl.semantic import check
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.renderer import Renderer
from rrcache.pipeline import load_for_session, variant_for
from rrcache.session import load_session
from rrcache.session.changes import per_frame_uniforms

CORPUS = Path(__file__).parent / "corpus"
SHADERS = sorted(CORPUS.glob("*.glsl"))
DEFAULT_SESSION = CORPUS / "default_session.json"
COSTLIEST, SAMPLED = 4, 2
FRAMES = 2
SIZE = (64, 64)
TOLERANCE = 1e-4


def session_of(shader: Path):
    own = shader.with_suffix(".json")
    return load_session(own if own.exists() else DEFAULT_SESSION)


def picked_nodes(table) -> list:
    """The costliest ``COSTLIEST`` listed nodes and a seeded sample of ``SAMPLED`` others."""
    by_cost = sorted(table.nodes, key=lambda n: -n.cost)
    rest = by_cost[COSTLIEST:]
    return by_cost[:COSTLIEST] + random.Random(13).sample(rest, min(SAMPLED, len(rest)))


def untidy_blocks(text: str) -> list:
    """Empty blocks in statement lists and blocks whose only statement is a block."""
    return [n.loc for n in A.walk(parse_source(text)) if isinstance(n, A.Compound) and (
        any(isinstance(x, A.Compound) and not x.stmts for x in n.stmts)
        or (len(n.stmts) == 1 and isinstance(n.stmts[0], A.Compound)))]


def expects_nodes(shader: Path) -> bool:
    return "// corpus: no-nodes" not in shader.read_text()


def test_the_corpus_is_there():
    assert SHADERS and DEFAULT_SESSION.exists()


@pytest.mark.parametrize("shader", SHADERS, ids=lambda p: p.stem)
def test_every_analysis_pass_keeps_the_program_valid(shader):
    work = load_for_session(shader, session_of(shader))
    unit, info = work.shader.unit, work.shader.info
    # inline_unit works on a copy; the later passes work in place on what it returned
    moving = per_frame_uniforms(session_of(shader))
    for name, run in (("inlining", inline_unit),
                      ("unrolling", lambda u: unroll_unit(u, info)),
                      ("compound-assignment expansion", expand_unit),
                      ("sum reordering", lambda u: (reorder_sums(u, moving), u)[1])):
        unit = run(unit)
        try:
            check(unit, str(shader))
        except Exception as err:  # the pass made an invalid program: say which pass
            pytest.fail(f"{name} made an invalid program: {err}")
    if expects_nodes(shader):
        assert work.table.nodes, f"{shader.name}: no node listed"


@pytest.mark.parametrize("shader", SHADERS, ids=lambda p: p.stem)
def test_listed_nodes_reproduce_the_original_at_period_one(gl_ctx, shader):
    session = session_of(shader)
    work = load_for_session(shader, session)
    frames = range(min(FRAMES, session.frames))
    with Renderer(work.prepared, session, SIZE) as original:
        reference = [original.render_frame(i) for i in frames]
    assert reference[0].covered_pixels > 200, "the object must cover part of the frame"
    for node in picked_nodes(work.table):
        for algorithm in ALGORITHMS:
            if algorithm not in node.algorithms:    # the table says why; the compiler refuses it
                with pytest.raises(UnsupportedShaderError, match=f"cannot be cached with {algorithm}"):
                    variant_for(work, node.id, algorithm)
                continue
            variant = variant_for(work, node.id, algorithm)
            for name, source in variant.passes.items():
                assert not untidy_blocks(source.fragment), (shader.name, node.id, algorithm, name)
            with CachedRenderer(variant, session, work.prepared, SIZE, period=1) as cached:
                for ref in reference:
                    got = cached.render_frame(ref.index)
                    err = float(np.abs(got.image - ref.image)[ref.mask].max())
                    assert err <= TOLERANCE, (shader.name, node.id, node.text, algorithm, ref.index, err)
