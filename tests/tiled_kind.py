"""A kind of choice added in one module (tests/test_kinds.py shows it works end to end): one node
cached with the *tiled* refresh pattern in blocks of its own size, instead of the profile's.

Everything the kind is lives here: its part (with its JSON and checks), its variant spec, how it
compiles (the one-node passes), what its runtime runs with (the tiled pattern, its block), the runs
its training plans, its store table and how a run's result is written there, and how it is
described. Nothing else in rrcache changes: the registry takes it (``rrcache.kinds.register``), and
the document, the store, the executor, the report and the command line ask the registry.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Optional

from rrcache.errors import RRCacheError
from rrcache.kinds.base import Kind, only
from rrcache.runtime.refresh import BLOCK_SIZES
from rrcache.runtime.spec import VariantSpec


@dataclass(frozen=True)
class TiledNode:
    """Part ``tiled``: node ``node`` refreshed every ``period`` frames in ``block`` × ``block``
    tiles swept in order (the ``tiled`` pattern) rather than at random."""

    KIND: ClassVar[str] = "tiled"

    node: str
    period: int
    block: int = 8
    text: Optional[str] = field(default=None, compare=False)

    def key(self) -> tuple:
        return (self.KIND, self.node, int(self.period), int(self.block))

    def describe(self) -> str:
        return f"{self.node} Δn={self.period} tiled {self.block}×{self.block}"

    @classmethod
    def from_json(cls, data: dict, where: str) -> "TiledNode":
        only(data, ("kind", "node", "period", "block", "text"), where)
        if not isinstance(data.get("node"), str) or not data["node"]:
            raise RRCacheError("must be a node id", f"{where}.node")
        period, block = data.get("period"), data.get("block", 8)
        if isinstance(period, bool) or not isinstance(period, int) or period < 1:
            raise RRCacheError("must be a whole number >= 1", f"{where}.period")
        if block not in BLOCK_SIZES:
            raise RRCacheError(f"must be one of {', '.join(map(str, BLOCK_SIZES))}", f"{where}.block")
        return cls(data["node"], period, block, data.get("text"))


class TiledKind(Kind):
    name = "tiled"
    part = TiledNode
    title = "one cached node refreshed in tiles"
    one_node = True
    tables = """
-- tiled_run: a tiled node's error run (mean error over the frames after the first) or timing run
--   (median frame time, and the original's beside it) at one period.
CREATE TABLE IF NOT EXISTS tiled_run (
    node TEXT NOT NULL,
    period INTEGER NOT NULL,
    block INTEGER NOT NULL,
    measure TEXT NOT NULL,
    value REAL NOT NULL,
    original_ms REAL,
    PRIMARY KEY (node, period, block, measure)
);
"""

    def spec(self, parts, algorithm, filter=None, **runtime) -> VariantSpec:
        (p,) = parts
        runtime.update(refresh="tiled", block=int(p.block))
        return VariantSpec(self.name, (p.node,), algorithm, filter or "bilinear", periods=(int(p.period),), **runtime)

    def compile(self, work, spec: VariantSpec):
        from rrcache.compiler import instance

        return instance(work.table, spec.nodes[0], spec.algorithm, spec.filter, spec.payload, work.vertex)

    def training(self, subject, settings, algorithm, filter="bilinear") -> list:
        node, block = subject
        options = dict(settings.cache_options(), refresh="tiled", block=int(block))
        return [(measure, VariantSpec(self.name, (node,), algorithm, filter, periods=(p,), **options),
                 ("tiled", node, p, int(block))) for measure in ("error", "timing") for p in settings.periods]

    def collect(self, store, result) -> None:
        _, node, period, block = result.spec.key
        if result.spec.measure == "error":
            value, original = result.steady_error, None
        else:
            value, original = result.ms, result.original_ms
        store.write([("INSERT OR REPLACE INTO tiled_run VALUES (?, ?, ?, ?, ?, ?)",
                      (node, period, block, result.spec.measure, value, original))])

    def cells(self, selection, profile=None, texts=False):
        p = selection.parts[0]
        return (p.text if texts else p.node), f"{p.period} (tiled {p.block}×{p.block})"

    def summary(self, selection, profile=None) -> dict:
        p = selection.parts[0]
        return {"node": p.node, "period": int(p.period), "kind": self.name, "block": int(p.block)}


KIND = TiledKind()
