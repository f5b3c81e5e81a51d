"""Kind ``nodes``: k ≥ 2 nodes of the shader cached at once, each with its own payload and its own
refresh period (docs/multinode.md; :func:`rrcache.compiler.instance_nodes`).

It has no part of its own: a selection of several :class:`~rrcache.kinds.single.CachedNode` parts
is one (``n12 Δn=50 + n40 Δn=4``). Training runs a set at its one period combination (an error run
and a timing run: :mod:`rrcache.profiler.sets`), kept in the store's ``set_run`` table. No frames
are shown for it (the report's images show one cached value).
"""
from __future__ import annotations

from rrcache.kinds.base import Kind
from rrcache.kinds.single import CachedNode
from rrcache.runtime.cache import DEFAULT_FILTER
from rrcache.runtime.spec import VariantSpec


class NodesKind(Kind):
    name = "nodes"
    title = "several cached nodes"
    has_frames = False
    marker = "*"
    tables = """
-- set_run: a set of k >= 2 cached nodes at one period each (rrcache.profiler.sets; `nodes` and
--   `periods` JSON lists in the same order), as the set stage recorded it: its SetOption as JSON
--   (the prediction, and the error and timing runs' figures once trained, or the note saying why
--   it was not trained).
CREATE TABLE IF NOT EXISTS set_run (
    nodes TEXT NOT NULL,
    periods TEXT NOT NULL,
    record TEXT NOT NULL,
    PRIMARY KEY (nodes, periods)
);
"""

    def claims(self, parts) -> bool:
        return len(parts) >= 2 and all(isinstance(p, CachedNode) for p in parts)

    def spec(self, parts, algorithm, filter=None, **runtime) -> VariantSpec:
        return VariantSpec(self.name, tuple(p.node for p in parts), algorithm, filter or DEFAULT_FILTER,
                           periods=tuple(int(p.period) for p in parts), **runtime)

    def compile(self, work, spec: VariantSpec):
        from rrcache.compiler import instance_nodes

        return instance_nodes(work.table, list(spec.nodes), spec.algorithm, spec.filter, spec.payload, work.vertex)

    def training(self, subject, settings, algorithm, filter=DEFAULT_FILTER) -> list:
        """``subject``: (node ids, periods) of one set: an error run and a timing run."""
        nodes, periods = subject
        spec = VariantSpec(self.name, tuple(nodes), algorithm, filter, periods=tuple(periods),
                           **settings.cache_options())
        key = ("set", tuple(nodes), tuple(int(p) for p in periods))
        return [("error", spec, key), ("timing", spec, key)]

    def describe(self, parts) -> str:
        return " + ".join(p.describe() for p in parts)

    def cells(self, selection, profile=None, texts=False):
        if texts:
            what = " + ".join(p.text or p.node for p in selection.parts)
        elif profile is not None:  # ids with their expressions
            what = " + ".join(f"{p.node}: {p.text or profile.node(p.node).text}" for p in selection.parts)
        else:
            what = " + ".join(p.node for p in selection.parts)
        return what, " + ".join(str(p.period) for p in selection.parts)

    def sentence(self, selection, profile) -> str:
        texts = "; ".join(profile.node(p.node).text for p in selection.parts)
        return f"cache {self.describe(selection.parts)} ({texts})"

    def sentence_html(self, selection, profile) -> str:
        import html

        return "cache " + " + ".join(f"<b>{html.escape(p.node)}</b> every Δn = {p.period}" for p in selection.parts)

    def report_html(self, selection, profile) -> str:
        import html

        return "cache " + " + ".join(f"<b>{html.escape(p.node)}</b> every Δn = {p.period} frames"
                                     + (f" (<code>{html.escape(p.text)}</code>)" if p.text else "")
                                     for p in selection.parts)

    def plot_label(self, selection) -> tuple:
        return "+".join(p.node for p in selection.parts), [int(p.period) for p in selection.parts]

    def summary(self, selection, profile=None) -> dict:
        nodes = [p.node for p in selection.parts]
        periods = [int(p.period) for p in selection.parts]
        return {"node": "+".join(nodes), "period": periods, "nodes": nodes, "periods": periods}


KIND = NodesKind()
