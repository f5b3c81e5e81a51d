"""A shader that blurs through a library function taking its sampler as a parameter (issue 30's
"Must show": the blur library's shader profiles end to end, and its variants render at Δn = 1
identical to the original in every valid algorithm).

``tests/blur_library/blur.frag`` is a glslViewer / WebGL 1 sketch (no ``#version``, ``varying``,
``gl_FragColor``) that ``#include``s ``lib/fast-gaussian-blur.glsl``, a 13-tap Gaussian in seven
bilinear fetches written the way glsl-fast-gaussian-blur's ``blur13(sampler2D image, ...)`` is
(``texture2D``, the library's ``#pragma glslify: export``). Before the inliner substituted sampler
arguments it copied ``image`` into a local (``sampler2D _rr_image_1 = u_image;``), which GLSL
forbids: every cached variant failed to compile.
"""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from safety_cli import QUICK_PROFILE, rrcache

FOLDER = Path(__file__).parent / "blur_library"
SIZE = (64, 64)
TOLERANCE = 1e-4


def test_every_node_in_every_valid_algorithm_reproduces_the_original_at_period_one(gl_ctx):
    from rrcache.compiler import ALGORITHMS
    from rrcache.errors import UnsupportedShaderError
    from rrcache.harness.cached import CachedRenderer
    from rrcache.harness.renderer import Renderer
    from rrcache.pipeline import load_for_session, variant_for
    from rrcache.session import load_session

    session = load_session(FOLDER / "blur.json")
    work = load_for_session(FOLDER / "blur.frag", session)
    in_blur = [n for n in work.table.nodes if any(c.startswith("blur13 ") for c in n.call_chain)]
    assert len(in_blur) >= 10, [n.call_chain for n in work.table.nodes]
    with Renderer(work.prepared, session, SIZE) as original:
        reference = [original.render_frame(i) for i in range(2)]
    assert reference[0].covered_pixels > 200
    compared, expected = 0, sum(len(set(ALGORITHMS) & set(n.algorithms)) for n in work.table.nodes)
    for node in work.table.nodes:
        for algorithm in ALGORITHMS:
            if algorithm not in node.algorithms:  # one-pass: the blur's implicit-LOD fetches need derivatives
                with pytest.raises(UnsupportedShaderError, match=f"cannot be cached with {algorithm}"):
                    variant_for(work, node.id, algorithm)
                continue
            variant = variant_for(work, node.id, algorithm)
            assert not any("sampler2D _rr" in p.fragment for p in variant.passes.values())
            with CachedRenderer(variant, session, work.prepared, SIZE, period=1) as cached:
                for ref in reference:
                    got = cached.render_frame(ref.index)
                    err = float(np.abs(got.image - ref.image)[ref.mask].max())
                    assert err <= TOLERANCE, (node.id, node.text, algorithm, ref.index, err)
            compared += 1
    assert compared == expected >= 2 * len(in_blur), (compared, expected)


def test_the_blur_shader_profiles_end_to_end(tmp_path):
    """``rrcache profile`` on the real files trains the blur's nodes (none dropped by the driver)
    and writes each level; ``rrcache instance`` writes a level again and a blur node's variant in
    each valid algorithm (it compiles what it writes before saying so); ``rrcache render --node``
    renders a blur node's variant."""
    shutil.copytree(FOLDER, tmp_path / "blur")
    case = tmp_path / "blur"
    # a 10 s budget (QUICK_PROFILE has 3): the blur nodes are reached on a loaded machine too
    code, out, lines = rrcache(case, "profile", "blur.frag", "blur.json", "--out", "p", *QUICK_PROFILE,
                               "--budget", "10")
    assert code == 0, lines
    doc = json.loads((case / "p" / "profile.json").read_text())
    trained = [n for n in doc["nodes"] if n["trained"]]
    assert len(trained) >= 2, [n.get("note") for n in doc["nodes"]]
    assert not [n for n in doc["nodes"] if (n.get("note") or "").startswith("dropped")]
    assert any(c.startswith("blur13 ") for n in trained for c in n["call_chain"])
    levels = sorted(p.name for p in (case / "p" / "optimized").iterdir())
    assert levels, "no level written"
    for level in levels:  # a level whose choice is the original holds only its manifest
        assert (case / "p" / "optimized" / level / "manifest.json").exists(), level
        assert not any("sampler2D _rr" in p.read_text() for p in (case / "p" / "optimized" / level).glob("*.frag"))
    code, _, lines = rrcache(case, "instance", "p", "--level", levels[-1], "--out", "again")
    assert code == 0, lines
    assert (case / "again" / "manifest.json").exists()
    blur_node = next(n["id"] for n in trained if any(c.startswith("blur13 ") for c in n["call_chain"]))
    for algorithm in ("three-pass", "two-pass"):
        code, _, lines = rrcache(case, "instance", "blur.frag", "--session", "blur.json", "--node", blur_node,
                                 "--algorithm", algorithm, "--out", f"node-{algorithm}")
        assert code == 0, lines
        assert list((case / f"node-{algorithm}").glob("*.frag")), algorithm
    code, out, lines = rrcache(case, "render", "blur.frag", "blur.json", "--node", blur_node, "--frames", "2",
                               "--out", "frames")
    assert code == 0 and "speed-up" in out, lines
    assert (case / "frames" / "frame_0001.png").exists()
