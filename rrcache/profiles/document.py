"""``profile.json``: the profile document, its declared shape, and reading and writing it.

A profile folder (written by :func:`rrcache.profile`, :mod:`rrcache.profiler.run`) holds
``profile.sqlite`` (every measurement, :mod:`rrcache.profiles.store`), the plots, the report, the
shader files of the selections and this document: the fitted models per node, μ, the overhead,
the original's frame time and the selections (:class:`rrcache.selection.Selection`).

The shape is declared once, by the dataclasses below (:class:`Profile`, :class:`NodeProfile`,
and :class:`~rrcache.selection.Selection` for each selection): each field's type and, in its
metadata, its range. :func:`load_profile` checks a document against them before anything uses
it (types, finite numbers, ranges, unknown and missing keys, the version
:data:`PROFILE_VERSION`) and refuses a bad one with the key path::

    profile.json: nodes[3].alpha: must be a finite number >= 0

:meth:`Profile.write` writes it (once per profiling run, atomically); :meth:`Profile.select`
re-selects for any error threshold from the models alone, in milliseconds.

>>> p = load_profile("marble-marble.rrprofile")        # doctest: +SKIP
>>> choice = p.select(0.02)                            # doctest: +SKIP
>>> choice.node, choice.period, round(choice.predicted_speedup, 1)   # doctest: +SKIP
('n102', 35, 2.7)
"""
from __future__ import annotations

import dataclasses
import json
import math
import os
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

from rrcache import atomic
from rrcache.errors import RRCacheError, printable
from rrcache.model import choose as _choose
from rrcache.model.choose import speedup_range  # noqa: F401 (re-exported)
from rrcache.jsonable import finite_json
from rrcache.model.sets import SetOption
from rrcache.profiles.amortize import SLOTS_PAYLOADS, EstimatorProfile
from rrcache.profiles.settings import TrainingSettings
from rrcache.selection import AmortizedLoop, Selection, parts_from_json

#: the version of the document's shape; a document of another version is refused
PROFILE_VERSION = 2
JSON_NAME = "profile.json"
#: the labels of the selections a profile keeps, from the smallest error threshold up
LABELS = _choose.LABELS

_HINT = "the file is damaged, edited or from another rrcache version; run 'rrcache profile' again"


def _range(default=dataclasses.MISSING, *, minimum=None, maximum=None, factory=dataclasses.MISSING):
    """A dataclass field whose numbers (or list items) must lie in [minimum, maximum]."""
    meta = {"minimum": minimum, "maximum": maximum}
    if factory is not dataclasses.MISSING:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


@dataclass
class NodeProfile:
    """One cacheable node in a profile: where it is, its static cost, and (when ``trained``) its
    fitted models: error α, λ (``lam``) with their fit quality and R², per-pixel times t_hit,
    t_miss (ms) with the performance fit's quality, and the measured error runs (``periods``,
    ``errors``, ``hit_rates``, ``psnrs``, ``frame_spreads``); ``note`` says why an untrained node
    was not trained."""

    id: str
    type: str
    line: int = _range(minimum=0)
    column: int = _range(minimum=0)
    text: str = ""
    call_chain: list[str] = field(default_factory=list)
    cost: int = _range(0, minimum=0)
    trained: bool = False
    alpha: Optional[float] = _range(None, minimum=0)
    lam: Optional[float] = _range(None, minimum=0)
    error_quality: Optional[str] = None
    error_r2: Optional[float] = None
    t_hit: Optional[float] = _range(None, minimum=0)
    t_miss: Optional[float] = _range(None, minimum=0)
    perf_quality: Optional[str] = None
    periods: list[int] = _range(minimum=1, factory=list)
    errors: list[float] = _range(minimum=0, factory=list)
    hit_rates: list[float] = _range(minimum=0, maximum=1, factory=list)
    psnrs: list[float] = field(default_factory=list)
    #: per training run, how much its mean error depends on the frames it covered
    #: (:func:`rrcache.model.psnr.frame_spread`, log10 units): part of the predicted PSNR's ±
    frame_spreads: list[float] = _range(minimum=0, factory=list)
    error_fit: dict = field(default_factory=dict)
    perf_fit: dict = field(default_factory=dict)
    note: Optional[str] = None
    file: Optional[str] = None  # the included file the node was written in (None: the shader itself)


def _fit_json(fit) -> dict:
    if fit is None:
        return {}
    if dataclasses.is_dataclass(fit):
        data = {f.name: getattr(fit, f.name) for f in dataclasses.fields(fit)}
    else:
        data = {k: v for k, v in vars(fit).items() if not k.startswith("_")}
    return finite_json(data)


def _fit_from_json(cls, data: dict, where: str):
    if not data:
        return None
    try:
        names = {f.name for f in dataclasses.fields(cls)} if dataclasses.is_dataclass(cls) else set(data)
        values = {k: (float("nan") if v is None and k not in ("quality", "dropped") else v)
                  for k, v in data.items() if k in names}
        return cls(**values)
    except (TypeError, ValueError) as err:
        raise RRCacheError(f"cannot read a fitted model ({err})", where, hint=_HINT) from None


@dataclass
class Profile:
    """A trained profile: the document's fields (see the module docstring) and, outside the
    document, ``path`` (the folder it was read from or written to).

    ``nodes`` costliest first (the training order, then the skipped nodes); ``selections`` e1..e4;
    ``algorithm`` the cache algorithm trained and validated with (``algorithm_times``: what
    ``auto`` measured, each as a fraction of the original's time); ``plan`` the training windows
    (:mod:`rrcache.profiler.plan`); ``counts`` what the last run computed and skipped;
    ``run_wall_s``, ``precompute_s`` (every run on the store added up) and ``invocations``.
    """

    shader: str
    session: str
    shader_hash: str
    session_hash: str
    settings: TrainingSettings
    algorithm: str
    nodes: list[NodeProfile]
    defines: dict[str, str] = field(default_factory=dict)
    #: the -I folders of the profiling command (the session's own "include_dirs" come with it)
    include_dirs: list[str] = field(default_factory=list)
    algorithm_times: dict[str, float] = _range(minimum=0, factory=dict)
    #: the cache filter trained and validated with (``auto`` settings: measured,
    #: :mod:`rrcache.profiler.filters`; the plan keeps what each candidate measured)
    filter: str = "bilinear"
    #: the measured order of the shader's sums (``measure_terms``: rrcache.profiler.terms), which
    #: the node ids refer to: whatever loads the shader for this profile must pass it on
    term_scores: dict = field(default_factory=dict)
    plan: Optional[dict] = None
    untrained: list[str] = field(default_factory=list)
    budget_stopped: bool = False
    mu: Optional[float] = _range(None, minimum=0, maximum=1)
    mu_quality: Optional[str] = None
    hit_fit: dict = field(default_factory=dict)
    overhead_ms: Optional[float] = _range(None, minimum=0)
    original_ms: Optional[float] = _range(None, minimum=0)
    pixels: float = _range(0.0, minimum=0)
    training_wall_s: Optional[float] = _range(None, minimum=0)
    counts: dict[str, int] = _range(minimum=0, factory=dict)
    selections: list[Selection] = field(default_factory=list)
    plots: list[str] = field(default_factory=list)
    run_wall_s: Optional[float] = _range(None, minimum=0)
    precompute_s: Optional[float] = _range(None, minimum=0)
    invocations: int = _range(0, minimum=0)
    #: every file the shader read, ``[{"path", "sha256"}]`` (``rrcache.glsl.frontend.file_records``)
    shader_files: list[dict] = field(default_factory=list)
    vertex: Optional[str] = None  # the user's vertex shader file, or None (generated)
    vertex_hash: Optional[str] = None
    #: the measured ceiling (:class:`rrcache.model.ceiling.Ceiling` as JSON; :attr:`measured_ceiling`)
    ceiling: Optional[dict] = None
    #: when the ceiling stopped the profile before training: ``choice`` ("original"), ``ceiling``,
    #: ``min_gain``, ``answer``, ``reason``, ``changes``
    verdict: Optional[dict] = None
    #: the relative noise of the original's repeated timing-run times (1.4826 × MAD / median, the
    #: median over the timing frames) and whether it was low enough to rely on (≤ 10%)
    timing_noise: Optional[float] = _range(None, minimum=0)
    timing_reliable: bool = True
    #: dB added to the training runs' PSNRs (measured in the error window) to predict the PSNR
    #: of what validation measures (the frame, or the timing window): the covered fractions
    #: differ (:func:`rrcache.model.psnr.coverage_offset_db`)
    psnr_offset_db: float = 0.0
    #: what validation taught the models (rrcache.model.calibration): ``points`` (each validated
    #: choice's raw predicted and measured PSNR), the ``shift`` and ``spread`` (dB) of the
    #: calibration they make, applied to the PSNR predictions of :meth:`psnr_fits`, and the
    #: predictions' error on them, ``raw`` and ``calibrated`` (as each was predicted when it was
    #: measured): ``{"n", "mean", "worst"}`` of |predicted − measured| dB. Empty before validation.
    calibration: dict = field(default_factory=dict)
    #: every choice validation measured, shipped or refused at a level, with its measured figures
    #: (``rrcache select`` and the explorer answer from these where they can:
    #: :mod:`rrcache.profiles.measured`)
    measured: list[Selection] = field(default_factory=list)
    #: the sets of cached nodes predicted to improve the single-node front, the trained ones with
    #: their measurements (:mod:`rrcache.profiler.sets`); selection returns a trained one where it
    #: was measured faster at the level
    sets: list[SetOption] = field(default_factory=list)
    #: the shader's estimators and their amortized-sampling models (:mod:`rrcache.profiles.amortize`;
    #: absent in documents written before amortization was profiled: none)
    estimators: list[EstimatorProfile] = field(default_factory=list)
    #: the warnings the profiling run raised (a session shorter than the largest period, a
    #: texture it could not decode ...), in order; :func:`rrcache.profiles.notices.run_warnings`
    #: adds the ones its measurements imply
    warnings: list[str] = field(default_factory=list)
    #: the Dask cluster the runs were made on (rrcache.cluster.executor.DaskExecutor.record: workers, hosts,
    #: what their capacity bought, the hosts of the timed runs); None: made in one process
    cluster: Optional[dict] = None
    path: Optional[Path] = field(default=None, compare=False, metadata={"document": False})

    def __post_init__(self):
        self._table = None
        self._loo: dict[str, float] = {}

    @property
    def _where(self) -> str:
        return str(self.path / JSON_NAME) if self.path is not None else JSON_NAME

    # ------------------------------------------------------------------ models
    @property
    def trained_nodes(self) -> list[NodeProfile]:
        return [n for n in self.nodes if n.trained]

    def node(self, node_id: str) -> NodeProfile:
        for n in self.nodes:
            if n.id == node_id:
                return n
        raise RRCacheError(f"no node '{node_id}' in this profile", self._where,
                           hint="the profile lists its nodes in profile.json")

    def texts(self) -> dict[str, str]:
        """Node id → expression text."""
        return {n.id: n.text for n in self.nodes}

    def fits(self):
        """``(error_fits, perf_fits, hit_fit)`` rebuilt as :mod:`rrcache.model` objects (trained
        nodes only, in the order of :attr:`trained_nodes`)."""
        from rrcache.model import ErrorFit, HitRateFit, PerfFit

        trained = self.trained_nodes
        index = {n.id: i for i, n in enumerate(self.nodes)}
        errors = [_fit_from_json(ErrorFit, n.error_fit, f"{self._where}: nodes[{index[n.id]}].error_fit")
                  for n in trained]
        perfs = [_fit_from_json(PerfFit, n.perf_fit, f"{self._where}: nodes[{index[n.id]}].perf_fit")
                 for n in trained]
        return errors, perfs, _fit_from_json(HitRateFit, self.hit_fit, f"{self._where}: hit_fit")

    @property
    def measured_ceiling(self):
        """The measured :class:`~rrcache.model.ceiling.Ceiling` (None when not measured)."""
        from rrcache.model.ceiling import Ceiling

        return Ceiling.from_json(self.ceiling)

    @property
    def table(self):
        """The ``rrcache.model.ModelTable`` of the trained nodes (built once)."""
        if self._table is None:
            from rrcache.model import ModelTable

            errors, perfs, hit = self.fits()
            if self.verdict is not None:
                raise RRCacheError(f"no node was trained: {self.verdict['answer']}", self._where,
                                   hint="; ".join(self.verdict["changes"]))
            if hit is None or not errors:
                raise RRCacheError("this profile has no trained node", self._where,
                                   hint="run 'rrcache profile' with a larger --budget")
            self._table = ModelTable.from_fits([n.id for n in self.trained_nodes], errors, perfs, hit,
                                               self.pixels, self.original_ms)
        return self._table

    def select(self, max_error: float) -> Selection:
        """:func:`rrcache.model.choose.select` of this profile."""
        return _choose.select(self, max_error)



    def threshold_selections(self, labels=LABELS) -> list[Selection]:
        """:func:`rrcache.model.choose.threshold_selections` of this profile."""
        return _choose.threshold_selections(self, labels=labels)

    def psnr_fits(self) -> list:
        """The PSNR model of each trained node (:func:`rrcache.model.psnr.fit_psnr` on its
        training runs, shifted by :attr:`psnr_offset_db` to the region validation measures, and
        by the node's shift of the validation's calibration, :meth:`calibrated`), in the order of
        :attr:`trained_nodes`."""
        import dataclasses as dc

        from rrcache.model.psnr import fit_psnr

        fits = [fit_psnr(n.errors, n.psnrs) for n in self.trained_nodes]
        off = float(self.psnr_offset_db or 0.0)
        cal = self.calibrated()
        shifts = [off + (cal.shift(n.id) if cal.points else 0.0) for n in self.trained_nodes]
        return [dc.replace(f, a=f.a + d) if d and f.quality != "no_data" else f for f, d in zip(fits, shifts)]

    def calibrated(self):
        """The :class:`rrcache.model.calibration.Calibration` validation left in :attr:`calibration`."""
        from rrcache.model.calibration import Calibration

        return Calibration.from_json(self.calibration)

    def select_psnr(self, min_psnr: float) -> Selection:
        """:func:`rrcache.model.choose.select_psnr` of this profile."""
        return _choose.select_psnr(self, min_psnr)

    def adopt(self, choice: Selection, **changes) -> Selection:
        """:func:`rrcache.model.choose.adopt` of this profile."""
        return _choose.adopt(self, choice, **changes)

    def predictions(self, choice: Selection) -> dict:
        """:func:`rrcache.model.choose.predictions` of this profile."""
        return _choose.predictions(self, choice)


    def front_candidates(self, choice: Selection) -> list[Selection]:
        """:func:`rrcache.model.choose.front_candidates` of this profile."""
        return _choose.front_candidates(self, choice)

    def uncovered_share(self) -> float:
        """The share of the validation frames the error runs did not cover (``plan``'s
        ``error_segments``; a plan without them trained on the first ``settings.frames``).

        >>> p = Profile("s", "t", "", "", TrainingSettings(frames=64, validation_frames=150), "two-pass", [])
        >>> round(p.uncovered_share(), 3)
        0.573
        """
        total = self.settings.validation_frames
        if not total:
            return 0.0
        segments = (self.plan or {}).get("error_segments")
        if segments:
            covered = {i for start, n in segments for i in range(int(start), int(start) + int(n))}
        else:
            covered = set(range(int(self.settings.frames or 0)))
        return 1.0 - len(covered & set(range(int(total)))) / float(total)

    # ------------------------------------------------------------------ amortized sampling
    def estimator(self, estimator_id: str) -> EstimatorProfile:
        for e in self.estimators:
            if e.id == estimator_id:
                return e
        raise RRCacheError(f"no estimator '{estimator_id}' in this profile", self._where,
                           hint="the profile lists its estimators in profile.json")

    def amortized_options(self) -> list[Selection]:
        """:func:`rrcache.model.choose.amortized_options` of this profile."""
        return _choose.amortized_options(self)





    # ------------------------------------------------------------------ the document
    def to_json(self) -> dict:
        """The document (JSON-able; non-finite numbers become null)."""
        return {"rrcache_profile": PROFILE_VERSION, **finite_json(_to_json(self))}

    def write(self, folder=None) -> Path:
        """Write ``profile.json`` into ``folder`` (default :attr:`path`), atomically."""
        out = Path(folder) if folder is not None else self.path
        if out is None:
            raise ValueError("Profile.write needs a folder")
        self.path = out
        atomic.write_text(out / JSON_NAME, json.dumps(self.to_json(), indent=2) + "\n")
        return out / JSON_NAME

    @classmethod
    def from_json(cls, data: Any, file: str = JSON_NAME) -> "Profile":
        """The profile of a document; :class:`RRCacheError` ``<file>: <key path>: <what is
        wrong>`` for anything the declared shape does not allow."""
        if not isinstance(data, dict) or "rrcache_profile" not in data:
            raise RRCacheError("not an rrcache profile (no 'rrcache_profile' key)", file,
                               hint="give the profile.json that 'rrcache profile' wrote")
        version = data["rrcache_profile"]
        if version != PROFILE_VERSION:
            raise RRCacheError(f"profile version {version!r}; this rrcache reads {PROFILE_VERSION}", file,
                               hint="run 'rrcache profile' again with this rrcache")
        body = {k: v for k, v in data.items() if k != "rrcache_profile"}
        prof = _read_dataclass(cls, body, "", file)
        _check_models(prof, file)
        return prof

    def __repr__(self) -> str:
        ms = f"original {self.original_ms:.2f} ms" if isinstance(self.original_ms, float) else "no timing"
        return f"Profile({self.shader!r}, {len(self.trained_nodes)}/{len(self.nodes)} nodes trained, {ms})"


def _document_fields(cls):
    return [f for f in dataclasses.fields(cls) if f.metadata.get("document", True)]


def _to_json(value):
    if isinstance(value, Selection):
        return value.to_json()
    if isinstance(value, TrainingSettings):
        return value.to_json()
    if dataclasses.is_dataclass(value):
        return {f.name: _to_json(getattr(value, f.name)) for f in _document_fields(value)}
    if isinstance(value, dict):
        return {k: _to_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_to_json(v) for v in value]
    return value


def _fail(file: str, path: str, message: str) -> RRCacheError:
    return RRCacheError(message, f"{file}: {path}" if path else file, hint=_HINT)


def _bounds(meta) -> str:
    low, high = meta.get("minimum"), meta.get("maximum")
    if low is not None and high is not None:
        return f" in [{low}, {high}]"
    if low is not None:
        return f" >= {low}"
    if high is not None:
        return f" <= {high}"
    return ""


def _read(value, tp, path: str, file: str, meta):
    """``value`` checked against the type hint ``tp`` (and the field's range ``meta``)."""
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is typing.Union:
        inner = [a for a in args if a is not type(None)]
        if value is None:
            return None
        return _read(value, inner[0], path, file, meta)
    if tp is bool:
        if not isinstance(value, bool):
            raise _fail(file, path, "must be true or false")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int) or not _in_range(value, meta):
            raise _fail(file, path, "must be a whole number" + _bounds(meta))
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or not _in_range(value, meta):
            raise _fail(file, path, "must be a finite number" + _bounds(meta))
        return float(value)
    if tp is str:
        if not isinstance(value, str):
            raise _fail(file, path, "must be a string")
        return value
    if tp is dict or origin is dict:
        if not isinstance(value, dict):
            raise _fail(file, path, "must be an object")
        if not args:
            return dict(value)
        return {k: _read(v, args[1], f"{path}.{k}", file, meta) for k, v in value.items()}
    if origin is list or origin is tuple:
        if not isinstance(value, list):
            raise _fail(file, path, "must be a list")
        items = [_read(v, args[0], f"{path}[{i}]", file, meta) for i, v in enumerate(value)]
        return items if origin is list else tuple(items)
    if tp is TrainingSettings:
        try:
            return TrainingSettings.from_json(value, "settings")
        except RRCacheError as err:  # "settings: block: ..." with the file in front
            raise RRCacheError(err.message, f"{file}: {path}", hint=err.hint) from None
    if dataclasses.is_dataclass(tp):
        return _read_dataclass(tp, value, path, file)
    raise TypeError(f"no reader for {tp!r}")  # a shape declared with a type this module cannot check


#: the numbers of the fitted models' dictionaries (``error_fit``, ``perf_fit``, ``hit_fit``) the
#: selection computes with: each must be a finite number in its range
_MODEL_NUMBERS = {
    "error_fit": {"alpha": (0, None), "lam": (0, None)},
    "perf_fit": {"t_hit": (0, None), "t_miss": (0, None), "t_overhead": (0, None)},
    "hit_fit": {"mu": (0, 1)},
}
#: a node's lists of its measured runs, one value per entry of its ``periods``
_RUN_LISTS = ("errors", "hit_rates", "psnrs", "frame_spreads")
#: what a trained node must carry (null only for a node that was not trained)
_TRAINED_NUMBERS = ("alpha", "lam", "t_hit", "t_miss")


def _check_models(prof: "Profile", file: str) -> None:
    """The checks the field types cannot say: a trained node has its α, λ, t_hit and t_miss, and
    the fitted models' numbers (what :meth:`Profile.fits` rebuilds the models from) are finite and
    in range: a NaN, infinite, negative or null one is refused with its key path."""
    def check(data, kind, at):
        for key, (low, high) in _MODEL_NUMBERS[kind].items():
            if key not in data:
                continue
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or not _in_range(value, {"minimum": low, "maximum": high}):
                raise _fail(file, f"{at}.{key}", "must be a finite number" + _bounds({"minimum": low, "maximum": high}))

    for i, node in enumerate(prof.nodes):
        # one value per measured period in each of a node's run lists (frame_spreads: or none, in
        # documents written before rrcache kept them)
        for name in _RUN_LISTS:
            got, want = len(getattr(node, name)), len(node.periods)
            if got != want and not (name == "frame_spreads" and got == 0):
                raise _fail(file, f"nodes[{i}].{name}", f"has {got} value{'s' if got != 1 else ''}, but "
                            f"nodes[{i}].periods has {want} (one value per period)")
        if node.trained:
            for name in _TRAINED_NUMBERS:
                if getattr(node, name) is None:
                    raise _fail(file, f"nodes[{i}].{name}", "must be a finite number >= 0 for a trained node")
            for kind in ("error_fit", "perf_fit"):
                if not getattr(node, kind):
                    raise _fail(file, f"nodes[{i}].{kind}", "is missing for a trained node")
                check(getattr(node, kind), kind, f"nodes[{i}].{kind}")
    if prof.hit_fit:
        check(prof.hit_fit, "hit_fit", "hit_fit")
    for i, est in enumerate(prof.estimators):
        _check_estimator(est, f"estimators[{i}]", "blend", file)
        if est.slots is not None:
            if est.slots.payload not in SLOTS_PAYLOADS:
                raise _fail(file, f"estimators[{i}].slots.payload", f"must be one of {', '.join(SLOTS_PAYLOADS)}")
            _check_estimator(est.slots, f"estimators[{i}].slots", "slots", file)


#: the keys of a trained estimator history's fits (what :meth:`EstimatorProfile.model` rebuilds
#: its models from), and the numbers among them the selection computes with (finite, ≥ 0)
_ESTIMATOR_FITS = {
    "blend": {"error_fit": (("a", "b", "total", "r2", "rms", "n", "quality"), ("a", "b")),
              "time_fit": (("fixed_ms", "t_sample", "rms", "n", "quality"), ("fixed_ms", "t_sample"))},
    "slots": {"error_fit": (("samples", "base", "b", "total", "r2", "rms", "n", "quality"), ("b",)),
              "time_fit": (("fixed_ms", "t_sample", "rms", "n", "quality"), ("fixed_ms", "t_sample"))},
}


def _check_estimator(runs, at: str, history: str, file: str) -> None:
    """A trained history of an estimator (its record, or its ``slots``) has its fits' keys, their
    numbers finite and ≥ 0 (the slots floors ``base`` one per whole ``samples`` ≥ 1), and no
    unknown key in them."""
    if not runs.trained:
        return
    for kind, (keys, numbers) in _ESTIMATOR_FITS[history].items():
        data = getattr(runs, kind)
        where = f"{at}.{kind}"
        if not data:
            raise _fail(file, where, "is missing for a trained estimator")
        unknown = sorted(set(data) - set(keys))
        if unknown:
            raise _fail(file, f"{where}.{unknown[0]}", "unknown key")
        missing = [k for k in keys if k not in data]
        if missing:
            raise _fail(file, f"{where}.{missing[0]}", "is missing")
        for key in numbers:
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise _fail(file, f"{where}.{key}", "must be a finite number >= 0")
        for key in ("total", "n"):
            if key in data and (isinstance(data[key], bool) or not isinstance(data[key], int) or data[key] < 0):
                raise _fail(file, f"{where}.{key}", "must be a whole number >= 0")
    if history == "slots":
        fit = runs.error_fit
        samples, base = fit["samples"], fit["base"]
        if not isinstance(samples, list) or not all(isinstance(m, int) and not isinstance(m, bool) and m >= 1
                                                    for m in samples):
            raise _fail(file, f"{at}.error_fit.samples", "must be a list of whole numbers >= 1")
        if not isinstance(base, list) or len(base) != len(samples):
            raise _fail(file, f"{at}.error_fit.base", "must be a list of one number per sample count")
        for j, c in enumerate(base):
            if isinstance(c, bool) or not isinstance(c, (int, float)) or not math.isfinite(c) or c < 0:
                raise _fail(file, f"{at}.error_fit.base[{j}]", "must be a finite number >= 0")


def _in_range(value, meta) -> bool:
    low, high = meta.get("minimum"), meta.get("maximum")
    return (low is None or value >= low) and (high is None or value <= high)


def _read_dataclass(cls, value, path: str, file: str, skip=()):
    if not isinstance(value, dict):
        raise _fail(file, path, "must be an object")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in _document_fields(cls) if f.name not in skip}
    unknown = sorted(set(value) - set(fields) - set(skip))
    if unknown:
        raise _fail(file, f"{path}.{unknown[0]}" if path else unknown[0], "unknown key")
    kwargs = {}
    for name, f in fields.items():
        at = f"{path}.{name}" if path else name
        if name not in value:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise _fail(file, at, "is missing")
            continue
        if f.metadata.get("parts"):  # the tagged parts of a Selection (rrcache.selection)
            try:
                kwargs[name] = parts_from_json(value[name], at)
            except RRCacheError as err:
                raise _fail(file, err.where, err.message) from None
            continue
        kwargs[name] = _read(value[name], hints[name], at, file, f.metadata)
    return cls(**kwargs)


# ---------------------------------------------------------------------- reading
def filter_line(prof: Profile) -> str:
    """The profile's cache filter, and with ``auto`` what was measured on the first node: 'plane
    (auto, node n12: bilinear Δn=2 58% of the original's time at 44.1 dB, Δn=26 …; plane …)'."""
    return filter_text(prof.filter, (prof.plan or {}).get("filter_times") if prof.settings.filter == "auto" else None)


def filter_text(chosen: str, times) -> str:
    """``chosen``, with what ``auto`` measured (``plan.filter_times``) when given."""
    if not times:
        return chosen
    parts = []
    for name, points in times.items():
        if isinstance(points, dict):  # one point (profiles of 2026-12-06 morning)
            points = [points]
        parts.append(f"{name} " + ", ".join(f"Δn={q.get('period', '?')} {q['time']:.0%} of the original's time at "
                                            f"{q['psnr']:.1f} dB" for q in points))
        # the same equal-time rule decided it: rrcache.profiler.filters.pick
    return f"{chosen} (auto: {'; '.join(parts)})"


def algorithm_line(prof: Profile) -> str:
    """The profile's algorithm, and with ``auto`` how it was decided: 'two-pass (auto, from the
    ceiling: two-pass 1.47× against three-pass 0.85× ...)', or what a timing measured
    ('two-pass (auto: two-pass 0.377, three-pass 0.41 of the original's time)')."""
    reason = (prof.plan or {}).get("algorithm_reason")
    if prof.settings.algorithm == "auto" and reason:
        return f"{prof.algorithm} (auto, from {reason})"
    times = prof.algorithm_times or {}
    if prof.settings.algorithm != "auto" or not times:
        return prof.algorithm
    measured = ", ".join(f"{name} {value:.3f}" for name, value in sorted(times.items(), key=lambda kv: kv[1]))
    return f"{prof.algorithm} (auto: {measured} of the original's time)"


def load_profile(path) -> Profile:
    """The profile in folder ``path`` (or the ``profile.json`` file itself), checked against the
    declared shape (see the module docstring).

    >>> p = load_profile("marble-marble.rrprofile")    # doctest: +SKIP
    """
    from rrcache.budgets import budget
    from rrcache.files import Refused, read_file

    path = Path(path)
    file = path / JSON_NAME if path.is_dir() else path
    if not file.exists() and not file.is_symlink():
        raise RRCacheError("no profile here", str(file), hint="give the folder 'rrcache profile' wrote (--out)")
    try:  # by rrcache.files' rule: a regular file inside the profile's folder, within the budget
        raw = read_file(file, budget.document_bytes, [os.path.realpath(file.parent)]).data
    except Refused as err:
        what = f"it resolves to {printable(err.real)}, outside the profile's folder" if err.kind == "outside" else \
            f"it {err.reason}"
        raise RRCacheError(f"cannot read the profile: {what}", str(file),
                           hint="raise the budget with 'rrcache --max-document-bytes N ...'" if err.kind == "size"
                           else "give the folder 'rrcache profile' wrote (--out)") from None
    try:
        data = json.loads(raw.decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError) as err:
        raise RRCacheError(f"cannot read the profile ({err})", str(file), hint="run 'rrcache profile' again") from None
    except RecursionError:  # JSON nested thousands deep: no profile looks like that
        raise RRCacheError("cannot read the profile (its JSON is nested too deeply)", str(file),
                           hint="run 'rrcache profile' again") from None
    prof = Profile.from_json(data, str(file))
    prof.path = file.parent
    return prof


def _no_constant(name: str):
    raise ValueError(f"{name} is not a JSON number")


def select(profile_or_path, max_error: float) -> Selection:
    """``rrcache.select(profile, max_error)``: the choice for a :class:`Profile` or a profile path.

    >>> rrcache.select("marble-marble.rrprofile", 0.02).period    # doctest: +SKIP
    35
    """
    prof = profile_or_path if isinstance(profile_or_path, Profile) else load_profile(profile_or_path)
    return prof.select(max_error)
