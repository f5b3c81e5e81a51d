"""A profile's amortized-sampling data: the estimators' records in ``profile.json`` and their
runs in ``profile.sqlite``.

:class:`EstimatorProfile` is one estimator of the shader (:mod:`rrcache.analysis.estimators`)
in the document (``Profile.estimators``; a document without the key, written before
amortization was profiled, reads as an empty list): where it is, N, whether it was trained, its
error runs at (m, λ), its timing runs at m, and the fitted models of
:mod:`rrcache.model.amortize` (:meth:`EstimatorProfile.model`).

The runs are kept in the store in a table of their own, ``amortize_run`` (created when first
written, so stores made before it still open; the store's schema is otherwise unchanged): one
row per error run (kind ``error``: mean error and PSNR against the original over the training
frames after the first, hit rate) or timed frame (kind ``timing``: the frame's ms, the original's
ms beside it, hits and misses). Rerunning a profile skips what is stored, as for nodes.
"""
from __future__ import annotations

import sqlite3
from dataclasses import dataclass, field
from typing import Optional

AMORTIZE_TABLE = """
CREATE TABLE IF NOT EXISTS amortize_run (
    estimator TEXT NOT NULL,
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
    PRIMARY KEY (estimator, kind, samples, blend, frame)
)"""


def _r(default=None, minimum=None, maximum=None, factory=None):
    meta = {"minimum": minimum, "maximum": maximum}
    if factory is not None:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


@dataclass
class EstimatorProfile:
    """One estimator in ``profile.json`` (see the module docstring). ``samples`` is N;
    ``run_samples``/``run_blends``/``errors``/``psnrs``/``hit_rates`` the error runs;
    ``timed_samples``/``timed_ms`` the median relative frame time at each timed m (ms, the
    original's typical time scale), ``timed_evaluated`` the terms evaluated per frame there;
    ``error_fit`` (a, b, r2, rms, n, quality) and ``time_fit`` (fixed_ms, t_sample, rms, n,
    quality) the models; ``hit_rate`` and ``pixels`` the timing runs' hit rate and covered pixels."""

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

    def model(self):
        """The :class:`~rrcache.model.amortize.AmortizeModel` of a trained estimator (None
        otherwise)."""
        from rrcache.model.amortize import AmortizeErrorFit, AmortizeModel, AmortizeTimeFit
        from rrcache.model.psnr import fit_psnr

        if not self.trained or not self.error_fit or not self.time_fit:
            return None
        ef = AmortizeErrorFit(**{k: self.error_fit[k] for k in ("a", "b", "total", "r2", "rms", "n", "quality")})
        tf = AmortizeTimeFit(**{k: self.time_fit[k] for k in ("fixed_ms", "t_sample", "rms", "n", "quality")})
        psnr = fit_psnr(self.errors, self.psnrs) if self.errors else None
        return AmortizeModel(self.id, int(self.samples), ef, tf, float(self.hit_rate or 0.0), float(self.pixels or 0.0),
                             psnr, self.text)


# ---------------------------------------------------------------------- the store's table
def _ensure(store) -> None:
    store.conn.execute(AMORTIZE_TABLE)
    store.conn.commit()


def has_table(store) -> bool:
    return store.conn.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'amortize_run'"
                              ).fetchone() is not None


def add_rows(store, rows: list[tuple]) -> None:
    """Rows of ``amortize_run`` (in its column order), in one transaction through the store's
    writer (a full disk is refused there with what to do)."""
    _ensure(store)
    store._write([(f"INSERT OR REPLACE INTO amortize_run VALUES ({', '.join('?' * 13)})", tuple(r)) for r in rows])


def rows(store, estimator: str, kind: str) -> list[dict]:
    """The stored rows of ``estimator`` of ``kind`` (``error`` or ``timing``)."""
    if not has_table(store):
        return []
    try:
        cur = store.conn.execute("SELECT * FROM amortize_run WHERE estimator = ? AND kind = ? "
                                 "ORDER BY samples, blend, frame", (estimator, kind))
        names = [d[0] for d in cur.description]
        return [dict(zip(names, r)) for r in cur.fetchall()]
    except sqlite3.DatabaseError:
        return []


def spent_s(store) -> float:
    """Seconds the stored amortization runs took (they count against the training budget)."""
    if not has_table(store):
        return 0.0
    return float(store.conn.execute("SELECT COALESCE(SUM(wall_s), 0) FROM amortize_run").fetchone()[0])
