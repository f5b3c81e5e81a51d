"""What a kind of choice is: the :class:`Kind` protocol every module of :mod:`rrcache.kinds` fills.

A kind owns its **part** (the frozen record a :class:`~rrcache.selection.Selection` holds, with its
JSON and checks), how a selection of it becomes a :class:`~rrcache.runtime.spec.VariantSpec`
(:meth:`Kind.spec`) and compiled passes (:meth:`Kind.compile`), the runs its training plans
(:meth:`Kind.training`), its store tables and how a run result is written there
(:attr:`Kind.tables`, :meth:`Kind.collect`), and how it is shown (:meth:`Kind.describe`,
:meth:`Kind.cells`, :meth:`Kind.summary`, :meth:`Kind.shown_frame`). Nothing outside the kind's
module asks which kind it holds: it asks the registry (:func:`rrcache.kinds.kind_of`) and calls
these methods.
"""
from __future__ import annotations

import html
from abc import ABC, abstractmethod
from typing import ClassVar, Optional

from rrcache.errors import RRCacheError
from rrcache.runtime.cache import DEFAULT_FILTER
from rrcache.runtime.spec import VariantSpec


def only(data: dict, keys: tuple, where: str) -> None:
    """RRCacheError naming the first key of a part's JSON ``data`` that is not in ``keys``."""
    unknown = sorted(set(data) - set(keys))
    if unknown:
        raise RRCacheError(f"unknown key {unknown[0]!r} (known: {', '.join(keys)})", where)


def text_of(data: dict, where: str) -> Optional[str]:
    """A part's ``text`` (None when absent); RRCacheError unless a string or null."""
    text = data.get("text")
    if text is not None and not isinstance(text, str):
        raise RRCacheError("must be a string or null", f"{where}.text")
    return text


def whole(data: dict, key: str, where: str, default=None) -> int:
    """A part's whole number ``key`` ≥ 1 (``default`` when absent); RRCacheError otherwise."""
    value = data.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise RRCacheError("must be a whole number >= 1", f"{where}.{key}")
    return value


def id_of(data: dict, key: str, where: str, example: str) -> str:
    """A part's id ``key`` (a non-empty string such as ``example``); RRCacheError otherwise."""
    value = data.get(key)
    if not isinstance(value, str) or not value:
        raise RRCacheError(f"must be {'an' if key[0] in 'aeiou' else 'a'} {key} id (a string such as '{example}')",
                           f"{where}.{key}")
    return value


class Kind(ABC):
    """One kind of choice (see the module docstring). Subclasses set the class attributes and
    override what differs; an instance is registered in :mod:`rrcache.kinds`."""

    #: the registry's name (``VariantSpec.kind``)
    name: ClassVar[str] = ""
    #: the part class it owns (its ``KIND`` is the JSON tag), or None for a kind made of other
    #: kinds' parts (several nodes: several ``cache`` parts)
    part: ClassVar[Optional[type]] = None
    #: what it is, for people ("one cached node")
    title: ClassVar[str] = ""
    #: its tables in the profile store (commented DDL; part of the store's one schema)
    tables: ClassVar[str] = ""
    #: the images of one frame can be shown for it (the report, the notebooks)
    has_frames: ClassVar[bool] = True
    #: the selection caches one node whose algorithms and all-hit limit the bench compares
    one_node: ClassVar[bool] = False
    #: the marker of its measured point on the fronts' plot (rrcache.report.sets_plot)
    marker: ClassVar[str] = "s"
    #: what the report adds to the note of its frame (how long the cache ran before it)
    settled_note: ClassVar[str] = ""

    # ---------------------------------------------------------------- what it is
    def claims(self, parts: tuple) -> bool:
        """Whether ``parts`` (a selection's, non-empty) are a choice of this kind: by default
        exactly one part of :attr:`part`."""
        return self.part is not None and len(parts) == 1 and isinstance(parts[0], self.part)

    @abstractmethod
    def spec(self, parts: tuple, algorithm: str, filter: Optional[str] = None, **runtime) -> VariantSpec:
        """The variant spec of ``parts`` run with ``algorithm``, the profile's cache ``filter`` where
        the kind caches nodes with it (None: the default; an amortized loop's part names its own),
        and the runtime's fields ``runtime`` (``block``, ``refresh``, ``depth_epsilon``)."""

    @abstractmethod
    def compile(self, work, spec: VariantSpec):
        """The compiled :class:`~rrcache.compiler.variant.Variant` of ``spec`` over ``work`` (a
        :class:`~rrcache.pipeline.ShaderWork`); :func:`rrcache.kinds.compile` caches it."""

    # ---------------------------------------------------------------- training and the store
    def training(self, subject, settings, algorithm: str, filter: str = DEFAULT_FILTER) -> list:
        """The runs training ``subject`` with ``settings`` (a
        :class:`~rrcache.profiles.settings.TrainingSettings`), ``algorithm`` and the profile's cache
        ``filter`` plans:
        ``(measure, spec, key)`` each (``measure`` of :data:`rrcache.runs.MEASURES`; ``key``
        what the collector files the result under). Kinds without training return []."""
        return []

    def collect(self, store, result) -> None:
        """Write one :class:`~rrcache.runs.RunResult` of this kind's training into ``store``
        (the collector's one call: :class:`rrcache.profiler.collect.Collector`)."""
        raise RRCacheError(f"{self.title} keeps no training runs", "store")

    # ---------------------------------------------------------------- showing it
    def describe(self, parts: tuple) -> str:
        """One line: ``n12 Δn=16``."""
        return ", ".join(p.describe() for p in parts)

    def cells(self, selection, profile=None, texts: bool = False) -> tuple[str, str]:
        """The (what, period) cells of a table row (the profile summary, the notebooks, the
        bench); with the ``profile``, what it needs to say more (an estimator's N); ``texts``:
        the expressions rather than the ids (the bench's tables)."""
        return self.describe(selection.parts), "–"

    def summary(self, selection, profile=None) -> dict:
        """The JSON fields ``rrcache select --json`` prints for ``selection`` beside the figures."""
        return {"kind": self.name, "describe": self.describe(selection.parts)}

    def shown_frame(self, selection, variant, frames: int) -> int:
        """The frame whose images show ``selection`` (its cache in the steady state), at most the
        session's last (``frames`` - 1)."""
        period = max(selection.periods or (0,))
        return min(int(frames) - 1, int(period) + 2)

    def sentence(self, selection, profile) -> str:
        """What ``selection`` does, in words (``rrcache select``)."""
        return self.describe(selection.parts)

    def sentence_html(self, selection, profile) -> str:
        """One line of HTML saying what ``selection`` does (the notebooks' explorer)."""
        return html.escape(self.describe(selection.parts))

    def report_html(self, selection, profile) -> str:
        """The report's line of HTML saying what ``selection`` caches."""
        return self.sentence_html(selection, profile)

    def plot_label(self, selection) -> tuple:
        """(what, period) of ``selection`` in the report's chart data."""
        return self.describe(selection.parts), None

    def anchor(self, parts) -> Optional[str]:
        """The id of the place in the shader the choice changes (a node, an estimator's loop)."""
        return getattr(parts[0], "node", None)

    def payload_captions(self, selection, variant) -> dict:
        """Captions of the images that show something else for this kind (the payload)."""
        return {}

    def __repr__(self) -> str:
        return f"<kind {self.name}>"
