"""The selection record: what a profile chooses to cache, with its predicted and measured figures.

One :class:`Selection` travels the whole way unchanged in kind: the models choose it
(:func:`rrcache.model.select`), the profile store keeps its measurement
(:mod:`rrcache.profiles.store`), ``profile.json`` holds it (:mod:`rrcache.profiles.document`), the
report and the notebooks show it and the bench measures it again. Each stage only fills in what
it knows: the model the predicted figures, the profile the label, the threshold, the algorithm
and the node's expression text, the validation (or the bench) the measured figures.

*What* is chosen is a tuple of **parts**, each a small frozen dataclass tagged by its ``KIND``:
no part is the original shader; one :class:`CachedNode` is one node cached, refreshed every
``period`` frames; several :class:`CachedNode` parts cache several nodes, each at its own period
(:attr:`Selection.multi`; :meth:`Selection.describe` shows ``n12 Δn=50 + n40 Δn=4``); one
:class:`AmortizedLoop` an estimator's samples spread over frames (m of N per frame, blend λ).
A new kind of choice (an amortized loop with its (m, λ),
several nodes each with its own period) is a new part class registered in :data:`PART_KINDS`
(its JSON and its validation come with it); the store, the document, the report and the bench
carry it without change, and :func:`rrcache.pipeline.variant_for_selection` is where a kind
becomes a compiled variant.

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
from typing import ClassVar, Optional

from rrcache.errors import RRCacheError


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
        node = data.get("node")
        if not isinstance(node, str) or not node:
            raise RRCacheError("must be a node id (a string such as 'n42')", f"{where}.node")
        period = data.get("period")
        if isinstance(period, bool) or not isinstance(period, int) or period < 1:
            raise RRCacheError("must be a whole number >= 1", f"{where}.period")
        text = data.get("text")
        if text is not None and not isinstance(text, str):
            raise RRCacheError("must be a string or null", f"{where}.text")
        return cls(node, period, text)


@dataclass(frozen=True)
class AmortizedLoop:
    """Part ``amortize``: estimator ``estimator`` (a loop id such as ``e1``, see
    :mod:`rrcache.analysis.estimators`) evaluated at ``samples`` (m) of its iterations per frame
    where the cache hits, blended with the reprojected estimate by ``blend`` (λ in [0, 1));
    ``history`` ``blend`` or ``slots``, ``phase`` ``frame`` or ``pixel``, ``filter`` (how the
    previous frame's estimate is resampled) and ``payload`` (``f4``, ``f2``, or ``u8``: the slots
    in 8 bits by the range of the terms) as in
    :func:`rrcache.compiler.amortize.instance_amortized`. ``text`` is the loop, for people.

    >>> AmortizedLoop("e1", 4, 0.6).describe()
    'e1 m=4 λ=0.6'
    >>> AmortizedLoop("e1", 4, 0.6, "slots", filter="catmull-rom-y", payload="u8").describe()
    'e1 m=4 λ=0.6 slots/frame catmull-rom-y u8'
    """

    KIND: ClassVar[str] = "amortize"

    estimator: str
    samples: int
    blend: float
    history: str = "blend"
    phase: str = "frame"
    text: Optional[str] = field(default=None, compare=False)
    filter: str = "bilinear"
    payload: str = "f4"

    def key(self) -> tuple:
        return (self.KIND, self.estimator, int(self.samples), float(self.blend), self.history, self.phase,
                self.filter, self.payload)

    def describe(self) -> str:
        extra = "" if (self.history, self.phase) == ("blend", "frame") else f" {self.history}/{self.phase}"
        extra += "" if self.filter == "bilinear" else f" {self.filter}"
        extra += "" if self.payload == "f4" else f" {self.payload}"
        return f"{self.estimator} m={self.samples} λ={self.blend:g}{extra}"

    @classmethod
    def from_json(cls, data: dict, where: str) -> "AmortizedLoop":
        _only(data, ("kind", "estimator", "samples", "blend", "history", "phase", "text", "filter", "payload"), where)
        estimator = data.get("estimator")
        if not isinstance(estimator, str) or not estimator:
            raise RRCacheError("must be an estimator id (a string such as 'e1')", f"{where}.estimator")
        samples = data.get("samples")
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
            raise RRCacheError("must be a whole number >= 1", f"{where}.samples")
        blend = data.get("blend")
        if isinstance(blend, bool) or not isinstance(blend, (int, float)) or not 0.0 <= blend < 1.0:
            raise RRCacheError("must be a number in [0, 1)", f"{where}.blend")
        history, phase = data.get("history", "blend"), data.get("phase", "frame")
        if history not in ("blend", "slots"):
            raise RRCacheError("must be 'blend' or 'slots'", f"{where}.history")
        if phase not in ("frame", "pixel"):
            raise RRCacheError("must be 'frame' or 'pixel'", f"{where}.phase")
        text = data.get("text")
        if text is not None and not isinstance(text, str):
            raise RRCacheError("must be a string or null", f"{where}.text")
        filter_, payload = data.get("filter", "bilinear"), data.get("payload", "f4")
        if filter_ not in FILTERS:
            raise RRCacheError(f"must be one of {', '.join(FILTERS)}", f"{where}.filter")
        if payload not in AMORTIZE_PAYLOADS:
            raise RRCacheError(f"must be one of {', '.join(AMORTIZE_PAYLOADS)}", f"{where}.payload")
        return cls(estimator, samples, float(blend), history, phase, text, filter_, payload)


#: the cache's reconstruction filters (their GLSL: rrcache.runtime.glsl), named by selections
FILTERS = ("nearest", "bilinear", "catmull-rom", "catmull-rom-y", "edge", "plane")

#: the payload formats of an amortized choice: 32- or 16-bit floats, or ``u8`` (the slots in 8 bits
#: by the range of the estimator's terms, rrcache.compiler.payload_encoding)
AMORTIZE_PAYLOADS = ("f4", "f2", "u8")

#: the components one payload texel holds (RGBA)
PAYLOAD_COMPONENTS = 4


def slots_fit(total: int, samples: int, components: int, phase: str = "frame") -> Optional[str]:
    """Why the ``slots`` history cannot amortize an estimator of ``total`` (N) terms whose
    accumulators have ``components`` payload components at ``samples`` (m) per frame, or None
    when it can: it needs the ``frame`` phase, m < N dividing N, and room for the N/m subset sums
    in the payload ((N/m) × components ≤ 4). The one rule the compiler
    (:func:`rrcache.compiler.amortize.instance_amortized`), the profiler and the models share.

    >>> slots_fit(16, 4, 1) is None, slots_fit(16, 8, 2) is None
    (True, True)
    >>> print(slots_fit(16, 2, 1))
    the slots history keeps N/m = 8 sums of 1 component(s): more than the payload's 4
    >>> slots_fit(16, 16, 1)
    'the slots history needs m < N dividing N (N = 16, m = 16)'
    """
    n, m, c = int(total), int(samples), int(components)
    if phase != "frame":
        return f"the slots history needs the 'frame' phase, not {phase!r}"
    if m < 1 or m >= n or n % m:
        return f"the slots history needs m < N dividing N (N = {n}, m = {m})"
    if (n // m) * c > PAYLOAD_COMPONENTS:
        return (f"the slots history keeps N/m = {n // m} sums of {c} component(s): more than the payload's "
                f"{PAYLOAD_COMPONENTS}")
    return None


def slots_samples(total: int, components: int) -> list[int]:
    """The m at which the ``slots`` history fits (:func:`slots_fit`), smallest first.

    >>> slots_samples(16, 1), slots_samples(16, 2), slots_samples(12, 1), slots_samples(5, 1)
    ([4, 8], [8], [3, 4, 6], [])
    """
    return [m for m in range(1, int(total)) if slots_fit(total, m, components) is None]


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
        node = data.get("node")
        if not isinstance(node, str) or not node:
            raise RRCacheError("must be a node id (a string such as 'n42')", f"{where}.node")
        for key in ("period", "fast_period"):
            value = data.get(key, 4 if key == "fast_period" else None)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise RRCacheError("must be a whole number >= 1", f"{where}.{key}")
        for key in ("threshold", "spread"):
            value = data.get(key, 0.0 if key == "spread" else None)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise RRCacheError("must be a finite number >= 0", f"{where}.{key}")
        text = data.get("text")
        if text is not None and not isinstance(text, str):
            raise RRCacheError("must be a string or null", f"{where}.text")
        return cls(node, data["period"], float(data["threshold"]), data.get("fast_period", 4),
                   float(data.get("spread", 0.0)), text)


#: part kind -> part class: the one place a new kind of choice is declared
PART_KINDS: dict[str, type] = {CachedNode.KIND: CachedNode, AmortizedLoop.KIND: AmortizedLoop,
                               AdaptiveNode.KIND: AdaptiveNode}


def _only(data: dict, keys: tuple, where: str) -> None:
    unknown = sorted(set(data) - set(keys))
    if unknown:
        raise RRCacheError(f"unknown key {unknown[0]!r} (known: {', '.join(keys)})", where)


def parts_to_json(parts) -> list:
    """The parts as JSON objects, each with its ``kind`` first."""
    return [{"kind": p.KIND, **{k: v for k, v in dataclasses.asdict(p).items()
                                if not (k, v) in _DEFAULT_FIELDS}} for p in parts]


#: fields whose default value is left out of the JSON (added after documents were written with
#: their default behaviour)
_DEFAULT_FIELDS = {("filter", "bilinear"), ("payload", "f4")}


def parts_from_json(data, where: str) -> tuple:
    """The parts of :func:`parts_to_json`'s list; RRCacheError naming ``where[i]`` and the key
    for anything else."""
    if not isinstance(data, list):
        raise RRCacheError("must be a list of parts", where)
    out = []
    for i, item in enumerate(data):
        at = f"{where}[{i}]"
        if not isinstance(item, dict):
            raise RRCacheError("must be an object with a 'kind'", at)
        cls = PART_KINDS.get(item.get("kind"))
        if cls is None:
            raise RRCacheError(f"unknown kind {item.get('kind')!r} (known: {', '.join(PART_KINDS)})", f"{at}.kind")
        out.append(cls.from_json(item, at))
    return tuple(out)


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
    def kind(self) -> str:
        """``original`` (no part), the part's kind for one part, else the kinds joined by ``+``."""
        if not self.parts:
            return "original"
        return "+".join(p.KIND for p in self.parts)

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
        if len(self.parts) == 1 and isinstance(self.parts[0], (CachedNode, AdaptiveNode)):
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
    def threshold(self) -> Optional[float]:
        """The adaptive refresh threshold (kind ``adaptive``); None for any other kind.

        >>> Selection((AdaptiveNode("n1", 100, 0.02),), 0.01, 2.0, 1.5).threshold
        0.02
        """
        if len(self.parts) == 1 and isinstance(self.parts[0], AdaptiveNode):
            return float(self.parts[0].threshold)
        return None

    @property
    def text(self) -> Optional[str]:
        """The cached node's expression (kind ``cache``, when known); None for the original."""
        part = self._single()
        return part.text if part is not None else None

    @property
    def multi(self) -> bool:
        """Whether several nodes are cached, each at its own period (parts: two or more
        :class:`CachedNode`); :attr:`node`/:attr:`period`/:attr:`text` then raise: read
        :attr:`nodes`/:attr:`periods`, or show :meth:`describe`."""
        return len(self.parts) >= 2 and all(isinstance(p, CachedNode) for p in self.parts)

    @property
    def nodes(self) -> tuple:
        """The cached nodes' ids, in part order (empty for the original shader).

        >>> Selection((CachedNode("n12", 50), CachedNode("n40", 4)), 0.01, 2.0, 1.5).nodes
        ('n12', 'n40')
        """
        return tuple(p.node for p in self.parts if isinstance(p, CachedNode))

    @property
    def periods(self) -> tuple:
        """The cached nodes' refresh periods, in part order."""
        return tuple(int(p.period) for p in self.parts if isinstance(p, CachedNode))

    def describe(self) -> str:
        """``n12 Δn=16``; several nodes ``n12 Δn=50 + n40 Δn=4``; or ``the original shader``.

        >>> Selection((CachedNode("n12", 50), CachedNode("n40", 4)), 0.01, 2.0, 1.5).describe()
        'n12 Δn=50 + n40 Δn=4'
        """
        if not self.parts:
            return "the original shader"
        return (" + " if self.multi else ", ").join(p.describe() for p in self.parts)

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
