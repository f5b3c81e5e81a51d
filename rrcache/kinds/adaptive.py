"""Kind ``adaptive``: one cached node refreshed by how fast its value changes
(:mod:`rrcache.runtime.adaptive`): an entry whose value changed by at least a threshold when last
recomputed is recomputed every ``fast_period`` frames, the others every ``period`` (the max age).

Its part is :class:`AdaptiveNode`; it is compiled as the node's variant with ``adaptive=True``
(:func:`rrcache.compiler.instance`) and measured beside the original at each threshold
(:mod:`rrcache.profiler.adaptive`), each point kept in the store's ``adaptive_point`` table.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar, Optional

from rrcache.errors import RRCacheError
from rrcache.kinds.base import Kind, id_of, only as _only, text_of, whole
from rrcache.runtime.cache import DEFAULT_FILTER
from rrcache.runtime.spec import VariantSpec


@dataclass(frozen=True)
class AdaptiveNode:
    """Part ``adaptive``: node ``node`` cached with adaptive refresh
    (:mod:`rrcache.runtime.adaptive`): an entry whose value had changed by at least
    ``threshold`` when last recomputed is recomputed every ``fast_period`` frames, the others
    every ``period`` frames (the max age). ``text`` is the node's expression, for people.

    >>> AdaptiveNode("n215", 100, 0.01, 8).describe()
    'n215 adaptive ≥0.01 Δf=8 Δn=100'
    """

    KIND: ClassVar[str] = "adaptive"

    node: str
    period: int
    threshold: float
    fast_period: int = 4
    spread: float = 0.0
    text: Optional[str] = field(default=None, compare=False)

    def key(self) -> tuple:
        return (self.KIND, self.node, int(self.period), float(self.threshold), int(self.fast_period),
                float(self.spread))

    def describe(self) -> str:
        spread = f" spread {self.spread:g}" if self.spread else ""
        return f"{self.node} adaptive ≥{self.threshold:g} Δf={self.fast_period} Δn={self.period}{spread}"

    @classmethod
    def from_json(cls, data: dict, where: str) -> "AdaptiveNode":
        _only(data, ("kind", "node", "period", "threshold", "fast_period", "spread", "text"), where)
        node = id_of(data, "node", where, "n42")
        period, fast_period = whole(data, "period", where), whole(data, "fast_period", where, 4)
        for key in ("threshold", "spread"):
            value = data.get(key, 0.0 if key == "spread" else None)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise RRCacheError("must be a finite number >= 0", f"{where}.{key}")
        return cls(node, period, float(data["threshold"]), fast_period, float(data.get("spread", 0.0)),
                   text_of(data, where))


class AdaptiveKind(Kind):
    name = "adaptive"
    part = AdaptiveNode
    title = "one cached node with adaptive refresh"
    tables = """
-- adaptive_point: one node with adaptive refresh at one threshold (max age `period`, fast
--   period `fast_period`) measured beside the original as validation measures
--   (rrcache.profiler.adaptive): the error over the validation frames drawn exactly, the time
--   ratio (variant / original, median frame times) in the timing format; speedups: the timed
--   repeats' speed-ups as a JSON list.
CREATE TABLE IF NOT EXISTS adaptive_point (
    node TEXT NOT NULL,
    period INTEGER NOT NULL,
    threshold REAL NOT NULL,
    fast_period INTEGER NOT NULL,
    algorithm TEXT NOT NULL,
    error REAL NOT NULL,
    psnr REAL NOT NULL,
    time_ratio REAL NOT NULL,
    hit_rate REAL NOT NULL,
    speedups TEXT NOT NULL,
    wall_s REAL NOT NULL,
    PRIMARY KEY (node, period, threshold, fast_period, algorithm)
);
"""

    def spec(self, parts, algorithm, filter=None, **runtime) -> VariantSpec:
        (p,) = parts
        return VariantSpec(self.name, (p.node,), algorithm, filter or DEFAULT_FILTER, periods=(int(p.period),),
                           threshold=float(p.threshold),
                           fast_period=int(p.fast_period), spread=float(p.spread), **runtime)

    def compile(self, work, spec: VariantSpec):
        from rrcache.compiler import instance

        return instance(work.table, spec.nodes[0], spec.algorithm, spec.filter, spec.payload, work.vertex,
                        pack_depth=spec.pack_depth, adaptive=True)

    def training(self, subject, settings, algorithm, filter=DEFAULT_FILTER) -> list:
        """``subject`` = (node, period, thresholds, fast_period): each threshold measured beside the
        original (``compare``)."""
        node, period, thresholds, fast_period = subject
        base = VariantSpec(self.name, (node,), algorithm, filter, periods=(int(period),), fast_period=int(fast_period),
                           **settings.cache_options())
        return [("compare", base.with_runtime(threshold=float(t)), ("adaptive", node, int(period), float(t)))
                for t in thresholds]

    def collect(self, store, result) -> None:
        store.add_adaptive_point(result)

    def cells(self, selection, profile=None, texts=False):
        p = selection.parts[0]
        what = p.text if texts else (f"{p.node}: {p.text}" if p.text else p.node)
        return what, f"{p.period} (adaptive ≥{p.threshold:g}, Δf={p.fast_period})"

    def sentence(self, selection, profile) -> str:
        p = selection.parts[0]
        return (f"cache {p.node} ({profile.node(p.node).text}) every Δn = {int(p.period)} frames at most, every "
                f"{p.fast_period} where its value changed by ≥ {p.threshold:g} (adaptive refresh)")

    def sentence_html(self, selection, profile) -> str:
        from rrcache.kinds.single import _cache_sentence

        p = selection.parts[0]
        return (_cache_sentence(p, profile) + f" at most, every <b>{p.fast_period}</b> where its value changed by "
                f"<b>≥ {p.threshold:g}</b> (adaptive refresh)")

    def report_html(self, selection, profile) -> str:
        import html

        p = selection.parts[0]
        return (f"cache <b>{html.escape(p.node)}</b> every Δn = {p.period} frames at most, every {p.fast_period} where "
                f"its value changed by ≥ {p.threshold:g} (adaptive refresh): <code>{html.escape(p.text or '')}</code>")

    def plot_label(self, selection) -> tuple:
        p = selection.parts[0]
        return p.node, int(p.period)

    def summary(self, selection, profile=None) -> dict:
        p = selection.parts[0]
        return {"node": p.node, "period": int(p.period), "kind": self.name, "threshold": float(p.threshold),
                "fast_period": int(p.fast_period), "spread": float(p.spread)}


KIND = AdaptiveKind()
