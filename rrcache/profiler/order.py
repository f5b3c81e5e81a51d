"""The order of training: which cacheable nodes are worth measuring, and in which order.

Brute force (every node, costliest first) spends the budget on near-copies of the costliest
node: in Marble the 20 costliest of 492 nodes are all "the whole noise and a few operations
after it", so the paper's progression (an octave or a partial sum at low thresholds, the whole
noise, the final colour) never gets measured. Two rules replace it:

1. **Too cheap to win.** A node whose static cost (:mod:`rrcache.analysis.cost`) is below
   ``min_saving`` of the shader's costliest node is not trained: caching it saves at most that
   share of the shading, while the cache's own passes cost more than that on every scene we
   measured (with every pixel hitting, the cached pipeline of Marble's final colour still costs
   27–30% of the original). Such nodes are reported as untrained with this reason.
2. **Diversity first.** The remaining nodes are grouped by what their value depends on that
   can change between frames: the varyings their payload pass reads and the per-frame uniforms
   (camera, light, time, keyframed session uniforms). Nodes with the same inputs differ in error
   mostly through how much of the computation they hold, so within a group the order is
   farthest-point over the static cost (the costliest first, then the node whose cost is
   farthest from every node already ordered); across groups it is round-robin, costliest group
   first. So lighting-dependent nodes (the final colour, albedo × diffuse) and the pure noise
   chain (whole noise, partial sums, octaves) are all reached early, and near-duplicates late.
   Nodes must differ in text as well as in cost: a node whose text is that of one already
   ordered in its group (the same expression reached through another call site or unrolled
   iteration) counts as no farther than a copy; and of nodes of equal cost the final colour comes
   first (``vec4(toneMap(c), 1.0)`` costs what its operand does, and it is the one users ask
   about).

3. **Invariant second.** The costliest node whose value depends on no per-frame uniform (only
   varyings: at a surface point it is the same in every frame, so caching it errs only by
   resampling, at any Δn) is trained second, right after the costliest node
   (:func:`invariant_early`). Round-robin reached it second or third on Marble, the temple,
   many_lights and sdf_material, but fifth on chess, where it is the paper's ε1 (the static
   pieces' occlusion, n108): a bench under load whose budget trained three chess nodes never
   measured it (docs/bench_full_run_6.md).

>>> from types import SimpleNamespace as N
>>> nodes = [N(id=f"n{c}", cost=c) for c in (100, 98, 60, 30, 5)]
>>> [n.id for n in diversity_order(nodes, {n.id: "a" for n in nodes})]
['n100', 'n5', 'n60', 'n30', 'n98']
>>> [n.id for n in diversity_order(nodes, {"n100": "b", "n98": "a", "n60": "a", "n30": "a", "n5": "a"})]
['n100', 'n98', 'n5', 'n60', 'n30']
>>> texts = [N(id="n1", cost=70, text="noise(p)"), N(id="n2", cost=30, text="noise(p)"),
...          N(id="n3", cost=50, text="p * 2.0"), N(id="n4", cost=90, text="vec4(c)", final=True),
...          N(id="n5", cost=90, text="c")]
>>> [n.id for n in diversity_order(texts, {})]   # n1 reads like n2, n5 costs what n4 does: last
['n4', 'n2', 'n3', 'n5', 'n1']
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

# what changes between frames (the camera, light and objects' built-ins, keyframed uniforms)
from rrcache.session.changes import per_frame_uniforms  # noqa: E402,F401  (its home; used here)
_INPUT = re.compile(r"^\s*(?:(?:flat|smooth|noperspective|centroid|invariant)\s+)*in\s+\w+\s+(\w+)\s*;", re.M)


@dataclass
class TrainingOrder:
    """``nodes``: the table entries to train, in order; ``skipped``: node id → the reason it is
    not trained; ``signatures``: node id → the inputs its value depends on (sorted names)."""

    nodes: list
    skipped: dict = field(default_factory=dict)
    signatures: dict = field(default_factory=dict)


def cost_filter(nodes, min_saving: float) -> tuple[list, dict]:
    """(nodes worth training, {id: reason} for the others); see rule 1 of the module docstring."""
    if not nodes:
        return [], {}
    top = max(n.cost for n in nodes)
    keep, skipped = [], {}
    for n in nodes:
        if n.cost >= min_saving * top:
            keep.append(n)
        else:
            skipped[n.id] = f"saves {n.cost / top:.0%} of the shader's static cost (< {min_saving:.0%})"
    return keep, skipped


def dependency_map(unit) -> dict[str, set[str]]:
    """For every name assigned or declared with an initialiser anywhere in ``unit`` (after
    inlining: ``main``'s locals), the names its values are computed from (every definition
    counted: conservative)."""
    from rrcache.glsl import ast as A

    deps: dict[str, set[str]] = {}
    for node in unit.walk():
        if isinstance(node, A.Declarator) and node.init is not None:
            deps.setdefault(node.name, set()).update(_names(node.init))
        elif isinstance(node, A.Assign):
            root = node.target
            while isinstance(root, (A.Field, A.Index)):
                root = root.obj
            if isinstance(root, A.Ident):
                reads = _names(node.value) | (_names(node.target) - {root.name})
                if node.op != "=":
                    reads.add(root.name)
                deps.setdefault(root.name, set()).update(reads)
    return deps


def _names(expr) -> set[str]:
    from rrcache.glsl import ast as A

    return {n.name for n in expr.walk() if isinstance(n, A.Ident)}


def signature(expr, deps: dict[str, set[str]], inputs: set[str], changing: set[str]) -> str:
    """The inputs the value of ``expr`` depends on, through the local definitions in ``deps``:
    the shader inputs (varyings) and per-frame uniforms it reaches, as one sorted string."""
    seen, todo = set(), list(_names(expr))
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        todo.extend(deps.get(name, ()))
    return " ".join(sorted(n for n in seen if n in inputs or n in changing))


def shader_inputs(source: str) -> set[str]:
    """The ``in`` variables a core fragment shader declares."""
    return set(_INPUT.findall(source))


def invariant_early(order: list, signatures: dict, changing) -> list:
    """``order`` with its first node whose signature names none of ``changing`` (the per-frame
    uniforms) moved to second place (rule 3 of the module docstring); unchanged when there is
    none or it is first or second.

    >>> from types import SimpleNamespace as N
    >>> nodes = [N(id=i) for i in ("a", "b", "c", "d")]
    >>> sig = {"a": "u_camera v_position", "b": "u_light v_normal", "c": "u_camera", "d": "v_position"}
    >>> [n.id for n in invariant_early(nodes, sig, {"u_camera", "u_light"})]
    ['a', 'd', 'b', 'c']
    """
    changing = set(changing)
    for i, node in enumerate(order):
        if not set(signatures.get(node.id, "").split()) & changing:
            if i <= 1:
                return list(order)
            return [order[0], node] + [n for j, n in enumerate(order[1:], 1) if j != i]
    return list(order)


def diversity_order(nodes, signatures: dict) -> list:
    """Farthest-point order over the static cost within signature groups (rule 2 of the module
    docstring): each step takes the node whose cost is farthest from every node already taken
    *in its group*; a group's first node counts as farther than any distance, so every group's
    costliest node comes first (costliest groups first). Deterministic; ties go to the costlier
    node, then to the table's order."""
    import numpy as np

    ordered = sorted(nodes, key=lambda n: (-n.cost, not getattr(n, "final", False)))
    if not ordered:
        return []
    cost = np.array([n.cost for n in ordered], dtype=np.float64)
    names = [signatures.get(n.id, "") for n in ordered]
    group_of = {name: i for i, name in enumerate(dict.fromkeys(names))}
    group = np.array([group_of[name] for name in names])
    texts = [getattr(n, "text", None) for n in ordered]
    head = float(cost.max()) + 1.0
    novelty = cost + head  # nothing taken in any group yet
    taken = np.zeros(len(ordered), dtype=bool)
    out = []
    for _ in range(len(ordered)):
        score = np.where(taken, -np.inf, novelty)
        pick = int(np.argmax(score))  # first maximum: the costlier (they are sorted), then table order
        taken[pick] = True
        out.append(ordered[pick])
        same = group == group[pick]
        novelty = np.where(same, np.minimum(np.where(novelty > head, np.inf, novelty), np.abs(cost - cost[pick])),
                           novelty)
        if texts[pick] is not None:
            copies = same & np.array([t == texts[pick] for t in texts])
            novelty = np.where(copies, 0.0, novelty)
    return out
