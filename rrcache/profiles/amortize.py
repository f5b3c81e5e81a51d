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

The runs are kept in the store in a table of their own, ``amortize_run`` (created when first
written, so stores made before it still open; the store's schema is otherwise unchanged), keyed
by history (a table written before the ``history`` column reads as blend rows, and is rebuilt
with the column, its rows ``blend``, before it is first written again): one row per error run (kind ``error``: mean error and PSNR against the original over the training
frames after the first, hit rate) or timed frame (kind ``timing``: the frame's ms, the original's
ms beside it, hits and misses). Rerunning a profile skips what is stored, as for nodes.
"""
from __future__ import annotations

import sqlite3
from dataclasses import dataclass, field
from typing import Optional

from rrcache.errors import RRCacheError

AMORTIZE_TABLE = """
CREATE TABLE IF NOT EXISTS amortize_run (
    estimator TEXT NOT NULL,
    history TEXT NOT NULL DEFAULT 'blend',
    kind TEXT NOT NULL,
    samples INTEGER NOT NULL,
    blend REAL NOT NULL,
    frame INTEGER NOT NULL,
    mean_error REAL NOT NULL,
    psnr REAL NOT NULL,
    hit_rate REAL NOT NULL,
    hits INTEGER NOT NULL,
    misses INTEGER NOT NULL,
    ms REAL NOT NULL,
    original_ms REAL NOT NULL,
    wall_s REAL NOT NULL,
    PRIMARY KEY (estimator, history, kind, samples, blend, frame)
)"""
#: the columns a row is given in (:func:`add_rows`); the table of stores written before the
#: slots history has them all but ``history`` (its rows are the blend history's)
COLUMNS = ("estimator", "history", "kind", "samples", "blend", "frame", "mean_error", "psnr", "hit_rate", "hits",
           "misses", "ms", "original_ms", "wall_s")


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
        from rrcache.model.amortize import AmortizeModel, AmortizeTimeFit, error_fit_from_json
        from rrcache.model.psnr import fit_psnr

        runs = self.runs(history)
        if runs is None or not runs.trained or not runs.error_fit or not runs.time_fit:
            return None
        ef = error_fit_from_json(history, runs.error_fit)
        tf = AmortizeTimeFit(**{k: runs.time_fit[k] for k in ("fixed_ms", "t_sample", "rms", "n", "quality")})
        psnr = fit_psnr(runs.errors, runs.psnrs) if runs.errors else None
        return AmortizeModel(self.id, int(self.samples), ef, tf, float(runs.hit_rate or 0.0), float(runs.pixels or 0.0),
                             psnr, self.text, history, self.components, getattr(runs, "payload", "f4"))

    def models(self) -> list:
        """The trained histories' models, blend first."""
        return [m for m in (self.model("blend"), self.model("slots")) if m is not None]


# ---------------------------------------------------------------------- the store's table
def _columns(store) -> list[str]:
    return [r[1] for r in store.conn.execute("PRAGMA table_info(amortize_run)").fetchall()]


def _migrate(store) -> None:
    """A table written before the slots history (no ``history`` column, and a primary key
    without it) rebuilt with the column, its rows the blend history's, in one transaction;
    run before the first write, so reading an old store never changes it."""
    conn = store.conn
    conn.execute("BEGIN IMMEDIATE")
    try:
        conn.execute("ALTER TABLE amortize_run RENAME TO amortize_run_old")
        conn.execute(AMORTIZE_TABLE)
        old = [c for c in COLUMNS if c != "history"]
        conn.execute(f"INSERT INTO amortize_run ({', '.join(old)}, history) "
                     f"SELECT {', '.join(old)}, 'blend' FROM amortize_run_old")
        conn.execute("DROP TABLE amortize_run_old")
        conn.execute("COMMIT")
    except BaseException:
        if conn.in_transaction:
            conn.execute("ROLLBACK")
        raise


def _ensure(store) -> None:
    if has_table(store):
        if "history" not in _columns(store):
            try:
                _migrate(store)
            except sqlite3.Error as err:
                raise RRCacheError(f"cannot add the history column to the amortize_run table: {err}", str(store.path),
                                   hint="free some disk space or make the folder writable, then run the profile "
                                        "again") from None
        return
    store.conn.execute(AMORTIZE_TABLE)
    store.conn.commit()


def has_table(store) -> bool:
    return store.conn.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'amortize_run'"
                              ).fetchone() is not None


def add_rows(store, rows: list[tuple]) -> None:
    """Rows of ``amortize_run`` (in :data:`COLUMNS` order, the history second), in one
    transaction through the store's writer (a full disk is refused there with what to do)."""
    _ensure(store)
    store._write([(f"INSERT OR REPLACE INTO amortize_run ({', '.join(COLUMNS)}) VALUES "
                   f"({', '.join('?' * len(COLUMNS))})", tuple(r)) for r in rows])


def rows(store, estimator: str, kind: str, history: str = "blend") -> list[dict]:
    """The stored rows of ``estimator`` of ``kind`` (``error`` or ``timing``) and ``history``
    (``blend`` or ``slots``; a store written before the history column has blend rows only)."""
    if not has_table(store):
        return []
    try:
        if "history" not in _columns(store):
            if history != "blend":
                return []
            cur = store.conn.execute("SELECT *, 'blend' AS history FROM amortize_run WHERE estimator = ? AND kind = ? "
                                     "ORDER BY samples, blend, frame", (estimator, kind))
        else:
            cur = store.conn.execute("SELECT * FROM amortize_run WHERE estimator = ? AND kind = ? AND history = ? "
                                     "ORDER BY samples, blend, frame", (estimator, kind, history))
        names = [d[0] for d in cur.description]
        return [dict(zip(names, r)) for r in cur.fetchall()]
    except sqlite3.DatabaseError:
        return []


def spent_s(store) -> float:
    """Seconds the stored amortization runs took (they count against the training budget)."""
    if not has_table(store):
        return 0.0
    return float(store.conn.execute("SELECT COALESCE(SUM(wall_s), 0) FROM amortize_run").fetchone()[0])
