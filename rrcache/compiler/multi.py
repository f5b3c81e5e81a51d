"""Compile a variant caching k ≥ 2 nodes: :func:`instance_nodes`.

The passes are those of the one-node compiler's algorithms, assembled for several nodes by
:mod:`rrcache.compiler.multi_passes` (what each pass does, and what a nested pair means, is
explained there) from the unit of :mod:`rrcache.compiler.multi_locate`; printing and the vertex
shaders are the one-node emitter's. One node is :func:`rrcache.compiler.instance` (the k = 1
variant's text is unchanged by any of this).
"""
from __future__ import annotations

from typing import Any, Sequence

from rrcache.deep import deep
from rrcache.compiler.checks import check_algorithm
from rrcache.compiler.emit import emit_pass
from rrcache.compiler.multi_locate import prepare_nodes
from rrcache.compiler.multi_passes import build_multi_pass, has_discard, node_order
from rrcache.compiler.multi_variant import MultiVariant
from rrcache.compiler.variant import PassSource
from rrcache.runtime.cache import ALGORITHMS, DEFAULT_FILTER, PAYLOAD_DTYPES
from rrcache.runtime.glsl import FILTERS
from rrcache.runtime.spec import VariantSpec


def _table_entry(analysed: Any, node_id: Any):
    for n in getattr(analysed, "nodes", None) or ():
        if n.id == node_id or n.node is node_id:
            return n
    return None


@deep
def instance_nodes(analysed: Any, node_ids: Sequence[Any], algorithm: str = "three-pass",
                   filter: str = DEFAULT_FILTER, payload_dtype: str = "f4", vertex=None) -> MultiVariant:
    """Compile the variant of ``analysed`` that caches every node of ``node_ids`` (at least two;
    ids of the node table, or expression nodes), each with its own payload and, at run time, its
    own period (:class:`rrcache.runtime.CacheRuntime` with ``period=(Δn_0, Δn_1, …)`` in this
    order). Raises :class:`~rrcache.errors.UnsupportedShaderError` for a node that cannot be
    cached, or not with ``algorithm`` (:func:`rrcache.compiler.check_algorithm`), or a nest that
    cannot be compiled."""
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {tuple(ALGORITHMS)}, not {algorithm!r}")
    if filter not in FILTERS:
        raise ValueError(f"filter must be one of {FILTERS}, not {filter!r}")
    if payload_dtype not in PAYLOAD_DTYPES:
        raise ValueError(f"payload_dtype must be one of {PAYLOAD_DTYPES}, not {payload_dtype!r}")
    node_ids = list(node_ids)
    if len(node_ids) < 2:
        raise ValueError("instance_nodes caches two nodes or more; use instance for one")
    for node_id in node_ids:
        check_algorithm(analysed, node_id, algorithm)
    loc = prepare_nodes(analysed, node_ids)
    # a node that needs derivatives (invalid for one-pass) is computed outside any branch
    derivative = {j for j, node_id in enumerate(node_ids)
                  if "one-pass" in getattr(_table_entry(analysed, node_id), "invalid", {})}
    passes, uniforms, samplers, runtime, forms = {}, {}, {}, {}, {}
    user_vertex = vertex
    # three-pass: two passes per node (hit_j: copy where node j hits; node_j: compute where it
    # misses, culled by the depth test), since llvmpipe runs both sides of a branch and the rest of
    # a shader after a discard in lock-step; a shader that can discard keeps one pass 2 over the
    # union (the hit passes could not reproduce its discards), and so does a node that needs
    # derivatives (undefined after a non-uniform discard)
    layout = ("per-node" if algorithm == "three-pass" and not has_discard(loc) and not derivative
              else "union")
    if layout == "per-node":
        steps = [(f"{kind}_{j}", f"{kind}_{j}") for j in node_order(loc) for kind in ("hit", "node")]
        steps.append(("shade", "shade"))
    else:
        steps = [(name, name) for name in ALGORITHMS[algorithm]]
    for name, kind in steps:
        built = build_multi_pass(loc, kind, filter, derivative)
        out = emit_pass(built.unit, built.runtime_glsl, built.spec.lookup, user_vertex)
        passes[name] = PassSource(out.vertex, out.fragment, out.line_map)
        uniforms[name], samplers[name], runtime[name] = out.uniforms, out.samplers, out.runtime
        forms[name] = built.form
    ids = [i if isinstance(i, (int, str)) else None for i in node_ids]
    nodes = [{
        "id": ids[n.index], "type": n.type_name, "text": n.text, "components": n.components,
        "location": str(n.loc) if n.loc else None,
        "inside": ids[n.parent] if n.parent is not None else None,
    } for n in loc.nodes]
    spec = VariantSpec("nodes", tuple(ids) if all(i is not None for i in ids) else (), algorithm, filter, payload_dtype)
    return MultiVariant(
        algorithm=algorithm, node_id=None, node_type=None, node_text=None,
        components=tuple(n.components for n in loc.nodes), filter=filter,
        payload_dtype=payload_dtype, passes=passes, uniforms=uniforms, samplers=samplers,
        runtime_uniforms=runtime, forms=forms, node_loc=loc.nodes[0].loc, shader_path=loc.path,
        vertex_path=getattr(user_vertex, "path", None), nodes=nodes, spec=spec)
