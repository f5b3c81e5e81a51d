"""A profile's amortized-sampling data: the estimators' records in ``profile.json`` and their
runs in ``profile.sqlite``.

:class:`EstimatorProfile` is one estimator of the shader (:mod:`rrcache.analysis.estimators`)
in the document (``Profile.estimators``; a document without the key, written before
amortization was profiled, reads as an empty list): where it is, N, whether it was trained, its
error runs at (m, λ), its timing runs at m, and the fitted models of
:mod:`rrcache.model.amortize` (:meth:`EstimatorProfile.model`), for each history the compiler
offers (:func:`rrcache.compiler.amortize.instance_amortized`): the paper's running ``blend``
(the record's own keys, as before the slots history was profiled) and ``slots`` (the N/m subset
sums kept apart, where they fit: :func:`rrcache.selection.slots_fit`; the record's ``slots``
key, a :class:`HistoryRuns`; a document without it loads as blend only).

The runs are kept in the store's ``amortize_run`` table (the amortize kind's, part of the store's
one schema: :mod:`rrcache.kinds.amortize`, :mod:`rrcache.profiles.store`), keyed by history: one
row per error run (kind ``error``: mean error and PSNR against the original over the training
frames after the first, hit rate) or timed frame (kind ``timing``: the frame's ms, the original's
ms beside it, hits and misses). Rerunning a profile skips what is stored, as for nodes.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional


def _r(default=None, minimum=None, maximum=None, factory=None):
    meta = {"minimum": minimum, "maximum": maximum}
    if factory is not None:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


#: the payloads a slots history is trained in (``HistoryRuns.payload``)
SLOTS_PAYLOADS = ("f4", "u8")


@dataclass
class HistoryRuns:
    """One more history's runs and models of an estimator (``EstimatorProfile.slots``): the
    same keys as the blend history's in :class:`EstimatorProfile` (``trained``, ``note``, the
    error runs, the timed m, the fits, the hit rate and covered pixels; a test keeps the two
    alike), each with its range. The slots history's ``error_fit`` is
    :class:`~rrcache.model.amortize.SlotsErrorFit`'s (``samples``, ``base``, ``b``, ``total``,
    ``r2``, ``rms``, ``n``, ``quality``)."""

    trained: bool = False
    note: Optional[str] = None
    run_samples: list[int] = _r(minimum=1, factory=list)
    run_blends: list[float] = _r(minimum=0, maximum=1, factory=list)
    errors: list[float] = _r(minimum=0, factory=list)
    psnrs: list[float] = field(default_factory=list)
    hit_rates: list[float] = _r(minimum=0, maximum=1, factory=list)
    timed_samples: list[int] = _r(minimum=1, factory=list)
    timed_ms: list[float] = _r(minimum=0, factory=list)
    timed_evaluated: list[float] = _r(minimum=0, factory=list)
    error_fit: dict = field(default_factory=dict)
    time_fit: dict = field(default_factory=dict)
    hit_rate: Optional[float] = _r(minimum=0, maximum=1)
    pixels: Optional[float] = _r(minimum=0)
    #: the payload the runs used: ``u8`` (the slots in 8 bits, where the terms' range is known;
    #: rrcache.profiler.amortize.slots_payload) or ``f4`` (documents from before it: f4)
    payload: str = "f4"


@dataclass
class EstimatorProfile:
    """One estimator in ``profile.json`` (see the module docstring). ``samples`` is N,
    ``components`` its accumulators' payload components (None in documents written before it
    was recorded); the blend history's runs and models are the estimator's own keys, as before
    the slots history was profiled: ``run_samples``/``run_blends``/``errors``/``psnrs``/
    ``hit_rates`` the error runs; ``timed_samples``/``timed_ms`` the median relative frame time
    at each timed m (ms, the original's typical time scale), ``timed_evaluated`` the terms
    evaluated per frame there; ``error_fit`` (a, b, r2, rms, n, quality) and ``time_fit``
    (fixed_ms, t_sample, rms, n, quality) the models; ``hit_rate`` and ``pixels`` the timing
    runs' hit rate and covered pixels. ``slots`` is the slots history's (a
    :class:`HistoryRuns`; None in documents written before it was profiled: blend only)."""

    id: str
    line: Optional[int] = _r(minimum=0)
    column: Optional[int] = _r(minimum=0)
    samples: int = _r(1, minimum=1)
    text: str = ""
    trained: bool = False
    note: Optional[str] = None
    run_samples: list[int] = _r(minimum=1, factory=list)
    run_blends: list[float] = _r(minimum=0, maximum=1, factory=list)
    errors: list[float] = _r(minimum=0, factory=list)
    psnrs: list[float] = field(default_factory=list)
    hit_rates: list[float] = _r(minimum=0, maximum=1, factory=list)
    timed_samples: list[int] = _r(minimum=1, factory=list)
    timed_ms: list[float] = _r(minimum=0, factory=list)
    timed_evaluated: list[float] = _r(minimum=0, factory=list)
    error_fit: dict = field(default_factory=dict)
    time_fit: dict = field(default_factory=dict)
    hit_rate: Optional[float] = _r(minimum=0, maximum=1)
    pixels: Optional[float] = _r(minimum=0)
    components: Optional[int] = _r(minimum=1, maximum=4)
    slots: Optional[HistoryRuns] = None

    def runs(self, history: str = "blend"):
        """The runs and fits of ``history``: this record for ``blend``, :attr:`slots` (None when
        not profiled) for ``slots``."""
        if history == "blend":
            return self
        if history == "slots":
            return self.slots
        raise ValueError(f"history must be 'blend' or 'slots', not {history!r}")

    def model(self, history: str = "blend"):
        """The :class:`~rrcache.model.amortize.AmortizeModel` of ``history`` when it was trained
        (None otherwise)."""
        from rrcache.model.amortize import AmortizeModel, AmortizeTimeFit, anchored, error_fit_from_json
        from rrcache.model.psnr import fit_psnr

        runs = self.runs(history)
        if runs is None or not runs.trained or not runs.error_fit or not runs.time_fit:
            return None
        ef = anchored(error_fit_from_json(history, runs.error_fit), runs.run_samples, runs.run_blends, runs.errors)
        tf = AmortizeTimeFit(**{k: runs.time_fit[k] for k in ("fixed_ms", "t_sample", "rms", "n", "quality")})
        psnr = fit_psnr(runs.errors, runs.psnrs) if runs.errors else None
        return AmortizeModel(self.id, int(self.samples), ef, tf, float(runs.hit_rate or 0.0), float(runs.pixels or 0.0),
                             psnr, self.text, history, self.components, getattr(runs, "payload", "f4"))

    def models(self) -> list:
        """The trained histories' models, blend first."""
        return [m for m in (self.model("blend"), self.model("slots")) if m is not None]


# ---------------------------------------------------------------------- the store's table
# (the table is the amortize kind's, rrcache.kinds.amortize; the store reads and writes it)
def rows(store, estimator: str, kind: str, history: str = "blend") -> list[dict]:
    """The stored rows of ``estimator`` of ``kind`` and ``history``
    (:meth:`rrcache.profiles.store.ProfileStore.amortize_rows`)."""
    return store.amortize_rows(estimator, kind, history)


def spent_s(store) -> float:
    """Seconds the stored amortization runs took (:meth:`~rrcache.profiles.store.ProfileStore.amortize_spent_s`)."""
    return store.amortize_spent_s()
