"""The instancing compiler: one cached node of an analysed shader → the shaders of every pass.

Given the analysed shader (every call inlined into ``main``, constant loops unrolled; see
:mod:`rrcache.analysis`) and the id of a cacheable node E, :func:`instance` emits the passes of
the chosen algorithm (Sitthi-amorn et al. 2008a §3, docs/design.md §3) as ``#version 330 core``
fragment shaders with the runtime's GLSL (:mod:`rrcache.runtime.glsl`), each pruned to what the
pass needs, and their generated vertex shaders:

- ``three-pass``: ``reproject`` (hit: write the reprojected payload; miss: ``discard``),
  ``payload`` (compute E where pass 1 left no depth), ``shade`` (the shader with E replaced by
  this frame's payload);
- ``two-pass``: ``hit`` (shade hits completely, cache included) and ``miss``;
- ``one-pass``: ``single`` (a dynamic branch).

One file per pass of the compiler: :mod:`~rrcache.compiler.locate` (find E and its statement S),
:mod:`~rrcache.compiler.replace`, :mod:`~rrcache.compiler.hoist`,
:mod:`~rrcache.compiler.feeders` (one-pass only), :mod:`~rrcache.compiler.outputs`,
:mod:`~rrcache.compiler.prune` (dead-code elimination), :mod:`~rrcache.compiler.passes`
(assembly per algorithm), :mod:`~rrcache.compiler.emit` (printing),
:mod:`~rrcache.compiler.variant` (the result).

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("#version 330\\nin vec3 v_normal; uniform float u_k; out vec4 c;\\n"
...                  "void main() { float d = dot(v_normal, v_normal); c = vec4(d * u_k); }")
>>> node = [n for n in s.unit.walk() if isinstance(n, A.Call) and n.name == "dot"][0]
>>> v = instance(s, node)
>>> sorted(v.passes), v.node_type, v.uniforms["payload"]
(['payload', 'reproject', 'shade'], 'float', ['u_modelMatrix', 'u_modelViewProjectionMatrix', 'u_normalMatrix'])
"""
from __future__ import annotations

from typing import Any, Union

from rrcache.errors import UnsupportedShaderError
from rrcache.deep import deep
from rrcache.glsl import ast as A
from rrcache.compiler.checks import check_algorithm
from rrcache.compiler.emit import emit_pass
from rrcache.compiler.locate import prepare
from rrcache.compiler.passes import build_pass
from rrcache.compiler.variant import PassSource, Variant
from rrcache.runtime.cache import ALGORITHMS, DEFAULT_FILTER, PAYLOAD_DTYPES
from rrcache.runtime.glsl import FILTERS, depth_channel_for
from rrcache.runtime.spec import VariantSpec

__all__ = ["instance", "instance_nodes", "check_algorithm", "Variant", "PassSource"]


@deep
def instance(analysed: Any, node_id: Union[int, A.Expr], algorithm: str = "three-pass",
             filter: str = DEFAULT_FILTER, payload_dtype: str = "f4", vertex=None, pack_depth: bool = False,
             adaptive: bool = False) -> Variant:
    """Compile the variant of ``analysed`` that caches node ``node_id`` with ``algorithm``.

    ``analysed`` is what the analysis returns (a checked, inlined and unrolled shader);
    ``node_id`` an id of its node table (or the expression node itself). ``filter`` is the
    payload reconstruction filter (``nearest``, ``bilinear``, ``catmull-rom``) and
    ``payload_dtype`` the cache precision (``f4``, or ``f2`` for half floats), recorded for the
    runtime. ``vertex`` is the user's vertex shader (a
    :class:`rrcache.compiler.user_vertex.UserVertex`; None: generated). Raises
    :class:`~rrcache.errors.UnsupportedShaderError` (at the node's place) for a node that cannot
    be cached, or that the node table says ``algorithm`` cannot cache (:func:`check_algorithm`).
    ``pack_depth``: keep the inverse depth in the payload's free channel when it has one
    (:func:`rrcache.runtime.glsl.depth_channel_for`; the variant's ``depth_channel``, which the
    runtime must be given); False (the default): its own render target. Packing saves a render
    target and a fetch but measured no faster on llvmpipe (docs/profiler_trust.md §9); it is
    there to be measured elsewhere (``rrcache bench-cache --breakdown --payloads f4,f4-packed``).
    ``adaptive``: the passes keep each entry's volatility and refresh by it
    (:mod:`rrcache.runtime.adaptive`; three-pass and two-pass only); the runtime then takes a
    ``threshold``. Not with ``pack_depth``.
    """
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {tuple(ALGORITHMS)}, not {algorithm!r}")
    if filter not in FILTERS:
        raise ValueError(f"filter must be one of {FILTERS}, not {filter!r}")
    if payload_dtype not in PAYLOAD_DTYPES:
        raise ValueError(f"payload_dtype must be one of {PAYLOAD_DTYPES}, not {payload_dtype!r}")
    if adaptive and algorithm == "one-pass":
        raise ValueError("adaptive refresh runs with the three-pass and two-pass algorithms, not one-pass")
    if adaptive and pack_depth:
        raise ValueError("adaptive refresh keeps the inverse depth in its own target: not with pack_depth")
    check_algorithm(analysed, node_id, algorithm)
    loc = prepare(analysed, node_id)
    depth_channel = depth_channel_for(loc.components, payload_dtype) if pack_depth else None
    passes: dict[str, PassSource] = {}
    uniforms: dict[str, list[str]] = {}
    samplers: dict[str, list[str]] = {}
    runtime: dict[str, list[str]] = {}
    forms: dict[str, str] = {}
    for name in ALGORITHMS[algorithm]:
        built = build_pass(loc, name, filter, depth_channel, adaptive)
        out = emit_pass(built.unit, built.runtime_glsl, built.spec.lookup or (adaptive and built.spec.cache), vertex)
        passes[name] = PassSource(out.vertex, out.fragment, out.line_map)
        uniforms[name], samplers[name], runtime[name] = out.uniforms, out.samplers, out.runtime
        forms[name] = built.form
    return Variant(
        algorithm=algorithm, node_id=node_id if not isinstance(node_id, A.Node) else None,
        node_type=loc.type_name, node_text=loc.text, components=loc.components, filter=filter,
        payload_dtype=payload_dtype, passes=passes, uniforms=uniforms, samplers=samplers,
        runtime_uniforms=runtime, forms=forms, node_loc=loc.loc, shader_path=loc.path,
        vertex_path=getattr(vertex, "path", None), depth_channel=depth_channel, adaptive=bool(adaptive),
        spec=VariantSpec("adaptive" if adaptive else "cache", (node_id,) if isinstance(node_id, (int, str)) else (),
                         algorithm, filter, payload_dtype, pack_depth))


from rrcache.compiler.multi import instance_nodes  # noqa: E402  (k >= 2 nodes)
