"""Kind ``cache``: one node of the shader held in the reprojection cache and recomputed every Δn
frames (Sitthi-amorn et al. 2008a; :func:`rrcache.compiler.instance`).

Its part is :class:`CachedNode`; training runs it at every training period (error runs) and every
timing period (timing runs), which the store keeps in its node tables (``error_run``,
``timing_run``: :mod:`rrcache.profiles.store`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Optional

from rrcache.errors import RRCacheError
from rrcache.kinds.base import Kind, id_of, only as _only, text_of, whole
from rrcache.runtime.cache import DEFAULT_FILTER
from rrcache.runtime.spec import VariantSpec


@dataclass(frozen=True)
class CachedNode:
    """Part ``cache``: the value of node ``node`` (an id such as ``n42``) held in the
    reprojection cache and recomputed every ``period`` frames (Δn ≥ 1). ``text`` is the node's
    expression, for people (left out of :attr:`key` and of equality)."""

    KIND: ClassVar[str] = "cache"

    node: str
    period: int
    text: Optional[str] = field(default=None, compare=False)

    def key(self) -> tuple:
        return (self.KIND, self.node, int(self.period))

    def describe(self) -> str:
        return f"{self.node} Δn={self.period}"

    @classmethod
    def from_json(cls, data: dict, where: str) -> "CachedNode":
        _only(data, ("kind", "node", "period", "text"), where)
        return cls(id_of(data, "node", where, "n42"), whole(data, "period", where), text_of(data, where))


class CacheKind(Kind):
    name = "cache"
    part = CachedNode
    title = "one cached node"
    one_node = True

    def spec(self, parts, algorithm, filter=None, **runtime) -> VariantSpec:
        (p,) = parts
        return VariantSpec(self.name, (p.node,), algorithm, filter or DEFAULT_FILTER, periods=(int(p.period),), **runtime)

    def compile(self, work, spec: VariantSpec):
        from rrcache.compiler import instance

        return instance(work.table, spec.nodes[0], spec.algorithm, spec.filter, spec.payload, work.vertex,
                        pack_depth=spec.pack_depth)

    def training(self, subject, settings, algorithm, filter=DEFAULT_FILTER) -> list:
        """A node (``subject``, its id) at each training period (error) and timing period (timing)."""
        base = VariantSpec(self.name, (subject,), algorithm, filter, **settings.cache_options())
        return ([("error", base.with_runtime(periods=(p,)), ("node", subject, p)) for p in settings.periods]
                + [("timing", base.with_runtime(periods=(p,)), ("node", subject, p)) for p in settings.timing_periods])

    def collect(self, store, result) -> None:
        store.add_node_result(result)

    def cells(self, selection, profile=None, texts=False):
        p = selection.parts[0]
        if texts:
            return p.text, str(p.period)
        return (f"{p.node}: {p.text}" if p.text else p.node), str(p.period)

    def summary(self, selection, profile=None) -> dict:
        p = selection.parts[0]
        return {"node": p.node, "period": int(p.period)}

    def sentence(self, selection, profile) -> str:
        p = selection.parts[0]
        return f"cache {p.node} ({profile.node(p.node).text}) every Δn = {int(p.period)} frames"

    def sentence_html(self, selection, profile) -> str:
        return _cache_sentence(selection.parts[0], profile)

    def report_html(self, selection, profile) -> str:
        import html

        p = selection.parts[0]
        return f"cache <b>{html.escape(p.node)}</b> every Δn = {p.period} frames: <code>{html.escape(p.text or '')}</code>"

    def plot_label(self, selection) -> tuple:
        p = selection.parts[0]
        return p.node, int(p.period)


def _cache_sentence(p, profile) -> str:
    import html

    return (f"cache <b>{html.escape(p.node)}</b> <code>{html.escape(profile.node(p.node).text)}</code> "
            f"every <b>Δn = {p.period}</b> frames")


KIND = CacheKind()
