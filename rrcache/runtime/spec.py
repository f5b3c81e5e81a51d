"""The variant spec: one frozen record of what is compiled and what the runtime needs.

A :class:`VariantSpec` names the kind of choice (``kind``, a name of :mod:`rrcache.kinds`), what it
caches (``nodes``, or the ``estimator`` of an amortized loop), how it is compiled (``algorithm``,
``filter``, ``payload``, ``pack_depth``, the amortization's ``samples``/``history``/``phase``) and how
the runtime runs it (``periods``, one per node; ``block``, ``refresh``, ``depth_epsilon``; adaptive
refresh's ``threshold``/``fast_period``/``spread``; amortization's ``blend``). The compiler returns it
with the passes (``Variant.spec``), the runtime takes it whole (``CacheRuntime.from_spec``), the
harness runs it (:class:`rrcache.runs.RunSpec`), and :meth:`compiled` is the part the passes depend
on: the key of the compile cache (:func:`rrcache.kinds.compile`), so one compiled variant serves
every period, threshold and blend.

It is a plain record (strings, numbers and tuples): it pickles, hashes and round-trips through JSON.

>>> s = VariantSpec("cache", ("n12",), "two-pass", periods=(16,))
>>> s.compiled() == VariantSpec("cache", ("n12",), "two-pass", periods=(50,)).compiled()
True
>>> VariantSpec.from_json(s.to_json()) == s
True
>>> s.runtime_options()["period"], s.with_runtime(periods=(4,)).periods
(16, (4,))
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Optional

from rrcache.runtime.adaptive import DEFAULT_FAST_PERIOD, DEFAULT_SPREAD
from rrcache.runtime.cache import DEFAULT_BLOCK, DEFAULT_DEPTH_EPSILON, DEFAULT_FILTER, DEFAULT_PERIOD, DEFAULT_REFRESH

#: the fields the runtime takes (changing them needs no new compilation)
RUNTIME_FIELDS = ("periods", "block", "refresh", "depth_epsilon", "threshold", "fast_period", "spread", "blend")


@dataclass(frozen=True)
class VariantSpec:
    """What is compiled and how it runs (see the module docstring)."""

    kind: str
    #: the cached nodes' ids, in the order of ``periods`` (empty for an amortized loop)
    nodes: tuple = ()
    algorithm: str = "three-pass"
    filter: str = DEFAULT_FILTER
    payload: str = "f4"
    pack_depth: bool = False
    #: an amortized loop: its estimator id, m, history and phase
    estimator: Optional[str] = None
    samples: int = 0
    history: str = "blend"
    phase: str = "frame"
    # ---- the runtime's
    #: one refresh period per node (empty: the runtime's default for each)
    periods: tuple = ()
    block: int = DEFAULT_BLOCK
    refresh: str = DEFAULT_REFRESH
    depth_epsilon: float = DEFAULT_DEPTH_EPSILON
    #: adaptive refresh (a variant compiled for it needs one; any other takes none)
    threshold: Optional[float] = None
    fast_period: int = DEFAULT_FAST_PERIOD
    spread: float = DEFAULT_SPREAD
    #: an amortized loop's λ
    blend: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "nodes", tuple(str(n) for n in self.nodes))
        object.__setattr__(self, "periods", tuple(int(p) for p in self.periods))

    def compiled(self) -> "VariantSpec":
        """This spec with the runtime's fields at their defaults: what the passes depend on."""
        defaults = {f.name: f.default for f in dataclasses.fields(self) if f.name in RUNTIME_FIELDS}
        return dataclasses.replace(self, **defaults)

    def with_runtime(self, **changes) -> "VariantSpec":
        """This spec with runtime fields changed (``periods=``, ``block=``, ``threshold=`` …);
        ValueError for a field the passes depend on."""
        wrong = sorted(set(changes) - set(RUNTIME_FIELDS))
        if wrong:
            raise ValueError(f"{wrong} are compiled into the passes, not the runtime's: make another spec")
        return dataclasses.replace(self, **changes)

    @property
    def period(self):
        """The period the runtime is given: one int for one node (the default when none is
        set), the tuple of periods for several."""
        if len(self.periods) > 1:
            return self.periods
        if not self.periods:
            return (DEFAULT_PERIOD,) * len(self.nodes) if len(self.nodes) > 1 else DEFAULT_PERIOD
        return self.periods[0]

    def runtime_options(self) -> dict:
        """The runtime's keyword arguments this spec sets (:class:`rrcache.runtime.CacheRuntime`)."""
        out = {"period": self.period, "block": self.block, "refresh": self.refresh,
               "depth_epsilon": self.depth_epsilon, "blend": self.blend}
        if self.threshold is not None:
            out.update(threshold=float(self.threshold), fast_period=int(self.fast_period), spread=float(self.spread))
        return out

    def manifest_runtime(self) -> dict:
        """The cache options a written variant's manifest records (``"runtime"``): the refresh
        pattern, and adaptive refresh's threshold, fast period and spread when it has them."""
        out = {"block": self.block, "refresh": self.refresh, "depth_epsilon": self.depth_epsilon}
        if self.threshold is not None:
            out.update(threshold=float(self.threshold), fast_period=int(self.fast_period), spread=float(self.spread))
        return out

    def to_json(self) -> dict:
        out = dataclasses.asdict(self)
        out["nodes"], out["periods"] = list(self.nodes), list(self.periods)
        return out

    @classmethod
    def from_json(cls, data: dict) -> "VariantSpec":
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"unknown variant spec fields {unknown}")
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in data.items()})
