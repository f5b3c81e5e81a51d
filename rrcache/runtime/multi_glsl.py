"""The GLSL of a cache holding several nodes (k ≥ 2), each with its own payload, inverse depth,
refresh period and phase.

Node ``j`` (0-based) has its own textures and its own copy of every per-node name of the
one-node runtime (:mod:`rrcache.runtime.glsl`, :mod:`rrcache.runtime.refresh`) with the suffix
``_j``: ``rr_prevPayload_j``, ``rr_prevInvDepth_j``, ``rr_curPayload_j``, ``rr_period_j``,
``rr_refreshPhase_j``, ``rr_seed_j``, ``rr_refreshScale_j``, and the functions ``rr_hit_j()``,
``rr_refreshNow_j()``, ``rr_previous_j()``, ``rr_current_j()``; outputs ``rr_outPayload_j`` and
``rr_outInvDepth_j``. What every node shares is declared once: ``rr_prevClip``, ``rr_valid``,
``rr_depthEpsilon``, ``rr_uv`` and the block layout (``rr_blockShift``, ``rr_tiled``,
``rr_blockColumns``). The functions are the one-node ones with the names renamed, so the hit
test, the refresh rule and the filters are the same code.

Why one inverse depth per node: a node whose statement does not run at a pixel (it sits in a
branch not taken there, or after an early ``return``) writes no value there, and its entry must
then miss next frame while the other nodes' entries stay valid. With k = 1 the shared inverse
depth says it; with several nodes each needs its own (the payload's spare channels cannot hold
it: a 16-bit payload's precision is below the depth test's tolerance).

>>> text = lookup_glsl(2, "bilinear")
>>> text.count("bool rr_hit_0()"), text.count("bool rr_hit_1()"), text.count("in vec4 rr_prevClip;")
(1, 1, 1)
>>> output_glsl(2, 1).splitlines()[2]
'layout(location = 3) out vec4 rr_outPayload_1;'
"""
from __future__ import annotations

import re

from rrcache.runtime import glsl as G
from rrcache.runtime.refresh import REFRESH_GLSL

#: names of the one-node runtime that each node has its own copy of
PER_NODE = ("rr_prevPayload", "rr_prevInvDepth", "rr_curPayload", "rr_period", "rr_refreshPhase",
            "rr_seed", "rr_refreshScale", "rr_hit", "rr_blockRank", "rr_refreshNow", "rr_previous", "rr_current",
            "rr_outPayload", "rr_outInvDepth", "rr_edgeWeights", "rr_edgeBase", "rr_edgeFull", "rr_planeTexels")

_PER_NODE_RE = re.compile(r"\b(" + "|".join(PER_NODE) + r")\b")

_SHARED = """\
// ---- rrcache reverse reprojection cache, several nodes (rrcache.runtime.multi) ----
in vec4 rr_prevClip;
uniform bool rr_valid;
uniform float rr_depthEpsilon;
uniform int rr_blockShift;
uniform bool rr_tiled;
uniform int rr_blockColumns;
vec2 rr_uv;
"""

_SHARED_UNIFORMS = ("rr_blockShift", "rr_tiled", "rr_blockColumns")


def suffixed(name: str, j: int) -> str:
    """``rr_period`` → ``rr_period_1``."""
    return f"{name}_{j}"


def rename(text: str, j: int) -> str:
    """The one-node GLSL ``text`` with every per-node name given node ``j``'s suffix."""
    return _PER_NODE_RE.sub(lambda m: suffixed(m.group(1), j), text)


def _drop_lines(text: str, names) -> str:
    """``text`` without the declaration lines of the shared names (declared once in _SHARED)."""
    keep = []
    for line in text.splitlines():
        s = line.strip()
        if s.startswith(("in vec4 rr_prevClip", "vec2 rr_uv", "// ----")):
            continue
        if s.startswith("uniform") and any(re.search(rf"\b{n}\b", s) for n in names):
            continue
        keep.append(line)
    return "\n".join(keep) + "\n"


def _node_lookup(j: int, filter: str) -> str:
    one = REFRESH_GLSL + G.lookup_glsl(filter).replace(REFRESH_GLSL, "")
    one = _drop_lines(one, _SHARED_UNIFORMS + ("rr_valid", "rr_depthEpsilon"))
    return rename(one, j)


def lookup_glsl(k: int, filter: str = "bilinear") -> str:
    """The declarations and functions of a pass that reads the previous frame's cache of ``k``
    nodes: per node ``rr_hit_j()``, ``rr_refreshNow_j()``, ``rr_previous_j()`` (valid after
    ``rr_hit_j()`` returned true: every ``rr_hit_j`` sets the shared ``rr_uv``)."""
    return _SHARED + "".join(_node_lookup(j, filter) for j in range(k))


def current_glsl(k: int) -> str:
    """``rr_current_j()`` for every node (three-pass, final pass)."""
    return "".join(rename(G.current_glsl(), j) for j in range(k))


def output_glsl(k: int, first_location: int = 0) -> str:
    """The cache outputs: node j's payload at ``first_location + 2j``, its inverse depth next."""
    return "".join(rename(G.output_glsl(first_location + 2 * j), j) for j in range(k))
