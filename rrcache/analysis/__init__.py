"""Analysis passes over a checked shader, one pass per module.

``inline_calls`` → ``unroll_loops`` → ``expand_compound_assignments`` give the *analysed* program
(:func:`analyse`), on which :func:`cacheable_nodes` enumerates the nodes a reprojection cache can
hold (ids resolved by :func:`find_node`). The weights of the static cost model are in
:mod:`rrcache.analysis.cost`.

>>> from rrcache.glsl.frontend import parse_shader
>>> table = cacheable_nodes(parse_shader("varying vec3 n;\\n"
...                                      "void main() { gl_FragColor = vec4(sin(n), 1.0); }"))
>>> [(x.id, x.text, x.final) for x in table.nodes]
[('n2', 'vec4(sin(n), 1.0)', True)]
"""
from rrcache.analysis.cacheable import (
    REASONS, CacheableNode, ExcludedNode, NodeTable, cacheable_nodes, find_node,
)
from rrcache.analysis.compound import expand_compound_assignments
from rrcache.analysis.cost import CACHE_LOOKUP_COST, CHEAP_BELOW
from rrcache.analysis.inline import inline_calls
from rrcache.analysis.pipeline import analyse
from rrcache.analysis.unroll import unroll_loops

__all__ = ["REASONS", "CacheableNode", "ExcludedNode", "NodeTable", "CACHE_LOOKUP_COST", "CHEAP_BELOW",
           "analyse", "cacheable_nodes", "expand_compound_assignments", "find_node",
           "inline_calls", "unroll_loops"]
