"""Automatic simplification in the manner of Pellacini 2005 (main paper §5.4): replace
expressions of the shader by their mean value over the session.

- :func:`simplified_shader`: the analysed shader (calls inlined, loops unrolled; the unit the node
  ids of :mod:`rrcache.analysis` refer to) with chosen nodes replaced by constants
  ``float(c)``/``vecN(c0, ...)``, rewritten to core GLSL, type-checked and pruned by the
  compiler's dead-code elimination (:func:`rrcache.compiler.prune.prune`), so everything that
  only fed a replaced node disappears. A node inside another replaced node is simply gone.
  With no node replaced it is the analysed shader itself, which renders as the original.
- :func:`static_cost`: the static cost (:mod:`rrcache.analysis.cost`) of a pruned unit's
  ``main``: every expression that contributes to the outputs, each counted once (after
  unrolling, a loop left in the code counts one iteration).
- :func:`node_means`: the mean of a node over the covered pixels of sample frames: the node's
  one-pass cache variant (another algorithm where the node is not valid for one-pass) refreshed
  every frame (Δn = 1) computes it at every covered pixel, and the payload is read back.
- :func:`rank_candidates`: per candidate node, the error of replacing it alone (mean RGB L2
  against the original over the sample frames) and the static cost it saves; ranked by error
  per saved cost, smallest first (Pellacini's greedy criterion).
- :func:`tune_simplification`: the first ``k`` nodes of that ranking replaced, the smallest
  ``k`` whose speed-up (measured side by side with the original) reaches the target
  (:func:`rrcache.alternatives.search.first_reaching`). Optionally the ranking is first
  thinned by :func:`greedy_sequence`, which skips a node that would take the static cost
  below a floor (the bench uses half the cost the target speed-up suggests, static cost
  taken as proportional to time), so that the last step does not overshoot by far.

The ranking is computed once from single-node replacements, not re-evaluated after each
step as a full greedy search would: each evaluation compiles and renders a shader, and this
keeps the cost linear in the candidates. The means are those of the original shader.

>>> from rrcache.pipeline import load_for_session
>>> from rrcache.session import load_session
>>> work = load_for_session("shaders/glslviewer_basic.glsl", load_session("sessions/marble.json"))
>>> node = [n for n in work.table.nodes if n.type == "vec3"][0]
>>> s = simplified_shader(work, {node.id: (0.5, 0.25, 0.125)})
>>> s.prepared.source.count("vec3(0.5, 0.25, 0.125)")
1
"""
from __future__ import annotations

import copy
import hashlib
import math
from dataclasses import dataclass, field
from typing import Callable, Mapping, Optional, Sequence

import numpy as np

from rrcache.analysis.cacheable import find_node
from rrcache.analysis.cost import op_cost
from rrcache.glsl.ast import main_function, substitute, walk
from rrcache.compiler.locate import NODE_TYPES
from rrcache.compiler.prune import prune
from rrcache.errors import GLSLError, RRCacheError, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.legacy import to_core
from rrcache.glsl.printer import print_with_map
from rrcache.glsl.semantic import check
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.metrics import mean_l2
from rrcache.compiler.prepared import PreparedShader, declarations
from rrcache.harness.renderer import Renderer
from rrcache.compiler.vertex import VARYINGS
from rrcache.alternatives.measure import compare_renderers
from rrcache.alternatives.search import SearchResult, first_reaching


@dataclass
class Simplified:
    """A simplified shader: ``prepared`` (for the harness), ``unit`` (checked, pruned core
    unit), ``replaced`` (node ids substituted), ``subsumed`` (ids inside a replaced node),
    ``cost`` (:func:`static_cost`)."""

    prepared: PreparedShader
    unit: A.TranslationUnit
    replaced: list
    subsumed: list
    cost: int


def constant(type_name: str, values: Sequence[float]) -> A.Expr:
    """``float(c)`` or ``vecN(c0, ...)`` (non-finite values become 0).

    >>> from rrcache.glsl.printer import print_expr
    >>> print_expr(constant("vec2", (0.25, -1.0)))
    'vec2(0.25, -1.0)'
    """
    n = NODE_TYPES.get(type_name)
    if n is None:
        raise UnsupportedShaderError(f"a {type_name} node cannot be replaced by a constant", None,
                                     "only float and vec2-4 nodes are simplified")
    vals = [float(v) if math.isfinite(float(v)) else 0.0 for v in list(values)[:n]]
    if len(vals) != n:
        raise RRCacheError(f"{len(vals)} values for a {type_name}", "simplification",
                           hint=f"give {n} values")
    return A.Call(type_name, [A.FloatLit(v) for v in vals])


def static_cost(unit: A.TranslationUnit) -> int:
    """The static cost of ``main`` of a checked unit (see the module docstring)."""
    main = main_function(unit)
    if main is None:
        return 0
    return int(sum(op_cost(n) for n in walk(main.body, decl_types=False) if isinstance(n, A.Expr)))


def simplified_shader(work, constants: Mapping[str, Sequence[float]]) -> Simplified:
    """``work`` (:class:`rrcache.pipeline.ShaderWork`) with each node id of ``constants``
    replaced by that value (see the module docstring)."""
    analysed = work.table.shader
    path = str(getattr(analysed, "path", None) or work.prepared.path)
    memo: dict = {}
    unit = copy.deepcopy(analysed.unit, memo)
    main = main_function(unit)
    replaced, subsumed = [], []
    for node_id, values in constants.items():
        node = find_node(analysed, node_id)
        t = getattr(node, "type", None)
        type_name = t.glsl_name() if t is not None else None
        target = memo.get(id(node))
        value = constant(type_name, values)
        value.loc = node.loc
        if target is not None and substitute(main.body, lambda n, target=target: n is target, lambda n: value) == 1:
            replaced.append(node_id)
        else:
            subsumed.append(node_id)
    core = to_core(unit)
    try:
        check(core, path)
    except GLSLError as err:
        raise UnsupportedShaderError(f"the simplified shader does not type-check: {err.message}", err.loc,
                                     "this is a bug in rrcache's simplification; please report it") from None
    prune(core)
    text, line_map = print_with_map(core)
    uniforms, inputs = declarations(core)
    used = set(work.prepared.inputs)
    inputs = {name: d for name, d in inputs.items() if name in VARYINGS or name in used}
    digest = hashlib.sha256((work.prepared.hash + "\0" + text).encode()).hexdigest()
    prepared = PreparedShader(source=text, path=path, hash=digest, line_map=list(line_map), uniforms=uniforms,
                              inputs=inputs, defines=dict(work.prepared.defines))
    return Simplified(prepared, core, replaced, subsumed, static_cost(core))


def node_means(work, session, node_ids: Sequence[str], frames: Sequence[int], resolution,
               progress: Optional[Callable[[str], None]] = None) -> dict[str, tuple[float, ...]]:
    """``{node id: mean value over the covered pixels of frames}`` (see the module docstring)."""
    from rrcache.pipeline import variant_for

    means = {}
    entries = {n.id: n for n in work.table.nodes}
    for node_id in node_ids:
        # one-pass computes the node at every covered pixel in one pass; a value after an
        # implicit-LOD lookup or a derivative is valid only in the multi-pass algorithms
        valid = getattr(entries.get(node_id), "algorithms", None) or ("one-pass",)
        variant = variant_for(work, node_id, "one-pass" if "one-pass" in valid else valid[0])
        total = np.zeros(4)
        count = 0
        with CachedRenderer(variant, session, work.prepared, resolution, period=1, keep_payload=True) as r:
            for index in frames:
                got = r.render_frame(index)
                values = got.payload[got.mask][:, :variant.components].astype(np.float64)
                values = values[np.isfinite(values).all(axis=1)]
                total[:variant.components] += values.sum(axis=0)
                count += len(values)
        means[node_id] = tuple(float(v) for v in (total[:variant.components] / max(count, 1)))
        if progress is not None:
            progress(node_id)
    return means


@dataclass
class Candidate:
    """A node replaced alone: its ``mean``, the ``error`` (mean RGB L2 over the sample frames)
    and the static cost it ``saved``; ``score`` = error per saved cost."""

    id: str
    text: str
    mean: tuple
    error: float
    saved: int

    @property
    def score(self) -> float:
        return self.error / self.saved if self.saved > 0 else math.inf


def rank_candidates(work, session, node_ids: Sequence[str], frames: Sequence[int], resolution,
                    progress: Optional[Callable[[str], None]] = None) -> list[Candidate]:
    """The candidates ranked by error per saved static cost (those saving nothing left out)."""
    texts = {n.id: n.text for n in work.table.nodes}
    base = simplified_shader(work, {}).cost
    means = node_means(work, session, node_ids, frames, resolution, progress)
    with Renderer(work.prepared, session, resolution) as original:
        refs = [original.render_frame(i) for i in frames]
    ranked = []
    for node_id in node_ids:
        simple = simplified_shader(work, {node_id: means[node_id]})
        saved = base - simple.cost
        if saved <= 0:
            continue
        with Renderer(simple.prepared, session, resolution) as r:
            errors = [mean_l2(r.render_frame(ref.index).image, ref.image, ref.mask)[0] for ref in refs]
        ranked.append(Candidate(node_id, texts.get(node_id, node_id), means[node_id], float(np.mean(errors)), saved))
        if progress is not None:
            progress(node_id)
    ranked.sort(key=lambda c: (c.score, c.id))
    return ranked


@dataclass
class SimplificationResult:
    """The tuned simplification: ``search`` (k = nodes replaced), the ``ranking``, the chosen
    ``shader``."""

    search: SearchResult
    ranking: list = field(default_factory=list)
    shader: Optional[Simplified] = None


def prefix_shader(work, ranking: Sequence[Candidate], k: int) -> Simplified:
    """The first ``k`` candidates of ``ranking`` replaced by their means."""
    return simplified_shader(work, {c.id: c.mean for c in ranking[:k]})


def greedy_sequence(work, ranking: Sequence[Candidate], cost_floor: float) -> list[Candidate]:
    """The candidates of ``ranking`` in order, leaving out each one that would bring the static
    cost of the shader with it and those before it replaced below ``cost_floor`` (a candidate
    that alone removes most of the shader would otherwise overshoot an equal-time target by
    far), and those that save nothing more once the earlier ones are replaced."""
    chosen: list[Candidate] = []
    cost = simplified_shader(work, {}).cost
    for c in ranking:
        trial = prefix_shader(work, chosen + [c], len(chosen) + 1).cost
        if cost_floor <= trial < cost:
            chosen.append(c)
            cost = trial
    return chosen


def tune_simplification(work, session, ranking: Sequence[Candidate], size, frames, target_speedup: float,
                        rel_tol: float = 0.05, progress: Optional[Callable[[int, float], None]] = None,
                        cost_floor: Optional[float] = None) -> SimplificationResult:
    """The fewest nodes of ``ranking`` to replace for the measured speed-up (over ``frames``,
    side by side with the original at ``size``) to reach ``target_speedup``. With
    ``cost_floor`` the ranking is first filtered by :func:`greedy_sequence` (when nothing is
    left, the candidate saving least is used alone)."""
    if not ranking:
        raise RRCacheError("no node can be simplified", str(work.prepared.path),
                           hint="no cacheable node saves static cost when replaced by a constant")
    if cost_floor is not None:
        # nothing fits above the floor: the gentlest single replacement
        ranking = greedy_sequence(work, ranking, cost_floor) or [min(ranking, key=lambda c: (c.saved, c.id))]
    with Renderer(work.prepared, session, size) as original:
        def measure(k: int) -> float:
            with Renderer(prefix_shader(work, ranking, k).prepared, session, size) as simple:
                speedup = compare_renderers(original, simple, frames).speedup
            if progress is not None:
                progress(k, speedup)
            return speedup

        search = first_reaching(measure, target_speedup, len(ranking), rel_tol)
    return SimplificationResult(search, list(ranking), prefix_shader(work, ranking, int(search.value)))
