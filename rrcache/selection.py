"""The selection record: what a profile chooses to cache, with its predicted and measured figures.

One :class:`Selection` travels the whole way unchanged in kind: the models choose it
(:func:`rrcache.model.select`), the profile store keeps its measurement
(:mod:`rrcache.profiles.store`), ``profile.json`` holds it (:mod:`rrcache.profiles.document`), the
report and the notebooks show it and the bench measures it again. Each stage only fills in what
it knows: the model the predicted figures, the profile the label, the threshold, the algorithm
and the node's expression text, the validation (or the bench) the measured figures.

*What* is chosen is a tuple of **parts**, each a small frozen dataclass tagged by its ``KIND``
and owned by a kind of choice (:mod:`rrcache.kinds`): no part is the original shader; one
:class:`CachedNode` is one node cached, refreshed every ``period`` frames; several
:class:`CachedNode` parts cache several nodes, each at its own period (kind ``nodes``;
:meth:`Selection.describe` shows ``n12 Δn=50 + n40 Δn=4``); one :class:`AmortizedLoop` an
estimator's samples spread over frames (m of N per frame, blend λ); one :class:`AdaptiveNode` a
node with adaptive refresh. Which kind a selection is, how it compiles, trains, is stored and
shown is the registry's (:func:`rrcache.kinds.kind_of`, :attr:`Selection.choice`): a new kind of
choice is a new module of :mod:`rrcache.kinds`, and the store, the document, the report and the
bench carry it without change.

>>> s = Selection((CachedNode("n12", 16),), predicted_error=0.01, predicted_ms=2.0, predicted_speedup=1.5)
>>> s.kind, s.node, s.period, s.key
('cache', 'n12', 16, (('cache', 'n12', 16),))
>>> Selection.original(4.0).kind, Selection.original(4.0).node
('original', None)
>>> parts_from_json(parts_to_json(s.parts), "parts") == s.parts
True
>>> parts_from_json([{"kind": "cache", "node": "n1", "period": 0}], "selections[2].parts")
Traceback (most recent call last):
    ...
rrcache.errors.RRCacheError: selections[2].parts[0].period: must be a whole number >= 1
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Optional

from rrcache.compiler.slots import AMORTIZE_PAYLOADS, PAYLOAD_COMPONENTS, slots_fit, slots_samples  # noqa: F401
from rrcache.errors import RRCacheError
from rrcache.kinds import kind_of, parts_from_json, parts_to_json  # noqa: F401 (the parts' JSON)
from rrcache.kinds.adaptive import AdaptiveNode  # noqa: F401
from rrcache.kinds.amortize import AmortizedLoop  # noqa: F401
from rrcache.kinds.single import CachedNode
from rrcache.runtime.glsl import FILTERS  # noqa: F401


def _at_least(default, minimum=0):
    """A field whose value (when a number) must be >= ``minimum``: the range
    :mod:`rrcache.profiles.document` checks when it reads the record."""
    return field(default=default, metadata={"minimum": minimum})


@dataclass(frozen=True)
class Selection:
    """A choice of what to cache and its figures (see the module docstring). Each field's type
    and range (its metadata) are the record's declared shape in ``profile.json``.

    - ``parts``: what is cached (empty: the original shader).
    - ``predicted_error`` (mean RGB L2), ``predicted_ms`` (per frame), ``predicted_speedup``
      (the original's ms / ``predicted_ms``): from the models.
    - ``label`` (``e1`` … ``e4``), ``max_error`` (the threshold it was selected at),
      ``algorithm`` (the cache algorithm it runs with): set by the profile.
    - ``measured_*``, ``hit_rate``, ``frames`` (rendered frames), ``speedups`` (one per
      side-by-side repeat): set by a measurement beside the original; None until then.
    - ``files``: the folder of its shader files, relative to the profile folder.
    - ``min_psnr``, ``predicted_psnr`` (± ``predicted_psnr_uncertainty``),
      ``predicted_speedup_range``, ``measured_noise``, ``exact``, ``visible_artifacts``,
      ``fallback``: the PSNR level, the predictions' uncertainty and what validation found
      (see the field comments).
    - ``measured_psnr_uncertainty``, ``measured_error_uncertainty``, ``measured_flip`` (±
      ``measured_flip_uncertainty``), ``measured_temporal_psnr``, ``max_flip``, ``level_met``,
      ``level_note``, ``tries``, ``calibration_db``: whether the level was met as measured, how
      many candidates it took, and the perceptual and temporal measures (docs/levels.md).
    """

    parts: tuple = field(default=(), metadata={"parts": True})
    predicted_error: float = _at_least(0.0)
    predicted_ms: float = _at_least(math.nan)
    predicted_speedup: float = _at_least(1.0)
    label: Optional[str] = None
    max_error: Optional[float] = _at_least(None)
    algorithm: Optional[str] = None
    measured_error: Optional[float] = _at_least(None)
    measured_psnr: Optional[float] = None
    measured_ms: Optional[float] = _at_least(None)
    measured_original_ms: Optional[float] = _at_least(None)
    measured_speedup: Optional[float] = _at_least(None)
    hit_rate: Optional[float] = field(default=None, metadata={"minimum": 0, "maximum": 1})
    frames: int = _at_least(0)
    speedups: tuple[float, ...] = field(default=(), metadata={"minimum": 0})
    files: Optional[str] = None
    #: the PSNR level (dB) it was selected at (None: selected at ``max_error``)
    min_psnr: Optional[float] = None
    #: the PSNR predicted from the error (:mod:`rrcache.model.psnr`) and its ± uncertainty (dB)
    predicted_psnr: Optional[float] = None
    predicted_psnr_uncertainty: Optional[float] = _at_least(None)
    #: the predicted speed-up's range from the performance fits' residuals (low, high)
    predicted_speedup_range: tuple[float, ...] = field(default=(), metadata={"minimum": 0})
    #: the relative noise of the original's frame times while it was measured
    measured_noise: Optional[float] = _at_least(None)
    #: the image is the original's (nothing cached, or every pixel recomputed): PSNR ∞
    exact: bool = False
    #: a choice with visible artifacts: measured mean FLIP at or above the threshold
    #: (rrcache.model.levels.VISIBLE_FLIP), else predicted PSNR below 30 dB
    visible_artifacts: bool = False
    #: why this selection stands instead of the models' first choice: every choice measured before
    #: it at this level and why each was refused (docs/levels.md)
    fallback: Optional[str] = None
    #: the ± (95%) of the measured PSNR (dB) and error: how much the session's mean would move with
    #: other frames like these (rrcache.model.levels.batch_uncertainty)
    measured_psnr_uncertainty: Optional[float] = _at_least(None)
    measured_error_uncertainty: Optional[float] = _at_least(None)
    #: the mean FLIP over the validated frames it was computed on, and its ± (rrcache.harness.perceptual)
    measured_flip: Optional[float] = _at_least(None)
    measured_flip_uncertainty: Optional[float] = _at_least(None)
    #: the PSNR (dB) of the frame-to-frame changes against the original's: smears and lags
    measured_temporal_psnr: Optional[float] = None
    #: the FLIP level it was selected at (None: a PSNR or error level)
    max_flip: Optional[float] = _at_least(None)
    #: whether its measurement meets its level (None: not measured), and why not
    level_met: Optional[bool] = None
    level_note: Optional[str] = None
    #: the candidates measured for its level until one stood (0: nothing measured, the original)
    tries: int = _at_least(0)
    #: the dB the per-profile calibration added to the models' ``predicted_psnr`` when it was
    #: chosen (rrcache.model.calibration; None: none applied)
    calibration_db: Optional[float] = None

    @classmethod
    def original(cls, original_ms: float, **kw) -> "Selection":
        """The original shader: error 0, speed-up 1."""
        return cls((), 0.0, float(original_ms), 1.0, **kw)

    @property
    def choice(self):
        """The kind of choice it is (:class:`rrcache.kinds.base.Kind`, from the registry); None
        for the original shader."""
        return kind_of(self.parts)

    @property
    def kind(self) -> str:
        """``original`` (no part), else its kind's name (``cache``, ``nodes``, ``amortize``,
        ``adaptive``, …: :mod:`rrcache.kinds`)."""
        choice = self.choice
        return "original" if choice is None else choice.name

    @property
    def key(self) -> tuple:
        """What is cached, comparable across stages (the parts without their texts)."""
        return tuple(p.key() for p in self.parts)

    @property
    def measured(self) -> bool:
        """Whether the measured figures are filled in."""
        return self.measured_error is not None

    def _single(self) -> Optional[CachedNode]:
        if not self.parts:
            return None
        if len(self.parts) == 1 and hasattr(self.parts[0], "node") and hasattr(self.parts[0], "period"):
            return self.parts[0]
        raise RRCacheError(f"a selection of kind {self.kind!r} has no single node and period", "selection",
                           hint="read its parts")

    @property
    def node(self) -> Optional[str]:
        """The cached node's id (kind ``cache``); None for the original shader."""
        part = self._single()
        return part.node if part is not None else None

    @property
    def period(self) -> Optional[int]:
        """The cached node's refresh period Δn (kind ``cache``); None for the original shader."""
        part = self._single()
        return int(part.period) if part is not None else None

    @property
    def single_node(self) -> Optional[str]:
        """The id of the one node this selection caches (one part with a node: a cached node,
        adaptive refresh); None for the original, several nodes or an amortized loop."""
        return self.parts[0].node if len(self.parts) == 1 and hasattr(self.parts[0], "node") else None

    @property
    def threshold(self) -> Optional[float]:
        """The adaptive refresh threshold (kind ``adaptive``); None for any other kind.

        >>> Selection((AdaptiveNode("n1", 100, 0.02),), 0.01, 2.0, 1.5).threshold
        0.02
        """
        threshold = getattr(self.parts[0], "threshold", None) if len(self.parts) == 1 else None
        return None if threshold is None else float(threshold)

    @property
    def text(self) -> Optional[str]:
        """The cached node's expression (kind ``cache``, when known); None for the original."""
        part = self._single()
        return part.text if part is not None else None

    @property
    def multi(self) -> bool:
        """Whether several nodes are cached, each at its own period (kind ``nodes``: two or more
        :class:`CachedNode`); :attr:`node`/:attr:`period`/:attr:`text` then raise: read
        :attr:`nodes`/:attr:`periods`, or show :meth:`describe`."""
        return len(self.parts) >= 2 and self.kind == "nodes"

    @property
    def nodes(self) -> tuple:
        """The cached nodes' ids, in part order (empty for the original shader).

        >>> Selection((CachedNode("n12", 50), CachedNode("n40", 4)), 0.01, 2.0, 1.5).nodes
        ('n12', 'n40')
        """
        return tuple(p.node for p in self.parts if hasattr(p, "node"))

    @property
    def periods(self) -> tuple:
        """The cached nodes' refresh periods, in part order."""
        return tuple(int(p.period) for p in self.parts if hasattr(p, "period"))

    def describe(self) -> str:
        """``n12 Δn=16``; several nodes ``n12 Δn=50 + n40 Δn=4``; or ``the original shader``.

        >>> Selection((CachedNode("n12", 50), CachedNode("n40", 4)), 0.01, 2.0, 1.5).describe()
        'n12 Δn=50 + n40 Δn=4'
        """
        if not self.parts:
            return "the original shader"
        return self.choice.describe(self.parts)

    def with_texts(self, texts: dict) -> "Selection":
        """This selection with each part's ``text`` looked up in ``texts`` (node id → expression)."""
        parts = tuple(dataclasses.replace(p, text=texts.get(p.node, p.text)) if hasattr(p, "node") else p
                      for p in self.parts)
        return dataclasses.replace(self, parts=parts)

    def with_measurement(self, measured_error: float, measured_psnr: float, measured_ms: float,
                         measured_original_ms: float, measured_speedup: float, hit_rate: float, frames: int,
                         speedups=()) -> "Selection":
        """This selection with its measured figures."""
        return dataclasses.replace(self, measured_error=measured_error, measured_psnr=measured_psnr,
                                   measured_ms=measured_ms, measured_original_ms=measured_original_ms,
                                   measured_speedup=measured_speedup, hit_rate=hit_rate, frames=int(frames),
                                   speedups=tuple(speedups))

    def replace(self, **changes) -> "Selection":
        return dataclasses.replace(self, **changes)

    def to_json(self) -> dict:
        """The record as JSON (parts as :func:`parts_to_json`; tuples as lists). The reader, with
        its checks, is :mod:`rrcache.profiles.document`'s."""
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        out["parts"] = parts_to_json(self.parts)
        out["speedups"] = list(self.speedups)
        out["predicted_speedup_range"] = list(self.predicted_speedup_range)
        return out

    @property
    def speedup_range(self) -> tuple:
        """(lowest, highest) measured speed-up of the repeats (empty when not measured)."""
        return (min(self.speedups), max(self.speedups)) if self.speedups else ()
