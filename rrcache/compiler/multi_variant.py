"""The compiled variant of k ≥ 2 cached nodes (:func:`rrcache.compiler.instance_nodes`).

A :class:`MultiVariant` is a :class:`~rrcache.compiler.variant.Variant` whose ``nodes`` lists
every cached node (id, type, text, components, place, and the node it is nested in) in the order
the runtime's periods follow; ``components`` is then one count per node (what
:class:`rrcache.runtime.multi.MultiCacheRuntime` takes as ``payload_components`` beside one period
per node), and the one-node fields ``node_id``, ``node_type`` and ``node_text`` are None (read
``nodes``). Its manifest has ``"nodes"`` (each with the period it runs with) instead of ``"node"``,
and ``"period"`` is the list of periods.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional, Sequence

from rrcache.compiler.variant import Variant
from rrcache.runtime.cache import DEFAULT_PERIOD
from rrcache.runtime.multi import MultiCacheRuntime


@dataclass
class MultiVariant(Variant):
    """Several nodes cached with one algorithm (see the module docstring)."""

    nodes: list = field(default_factory=list)

    runtime_class = MultiCacheRuntime

    def describe(self) -> str:
        """``nodes n1 'a' + n2 'b'``."""
        return "nodes " + " + ".join(f"{n.get('id')} '{n.get('text')}'" for n in self.nodes)

    @property
    def node_count(self) -> int:
        return len(self.nodes)

    def periods(self, period: Optional[Sequence[int]] = None) -> list[int]:
        """One period per node: ``period`` checked for its length, or the default for each."""
        if period is None:
            return [DEFAULT_PERIOD] * self.node_count
        if isinstance(period, int):
            return [int(period)] * self.node_count
        values = [int(p) for p in period]
        if len(values) != self.node_count:
            raise ValueError(f"{self.node_count} periods expected (one per node), not {len(values)}")
        return values

    def manifest(self, period=None, runtime: Optional[dict] = None) -> dict:
        """As :meth:`Variant.manifest`, with ``"nodes"`` (each with its ``"period"``) and
        ``"period"`` the list of periods.

        >>> from rrcache.compiler.variant import PassSource
        >>> v = MultiVariant("one-pass", None, None, None, (1, 3), "bilinear", "f4",
        ...                  {"single": PassSource("vs", "fs")},
        ...                  nodes=[{"id": "n1", "type": "float"}, {"id": "n2", "type": "vec3"}])
        >>> m = v.manifest([50, 4])
        >>> m["period"], [(n["id"], n["period"]) for n in m["nodes"]], "node" in m
        ([50, 4], [('n1', 50), ('n2', 4)], False)
        """
        periods = self.periods(period)
        out = super().manifest(None, runtime)
        del out["node"]
        out["nodes"] = [dict(node, period=p) for node, p in zip(self.nodes, periods)]
        out["period"] = periods
        return out
