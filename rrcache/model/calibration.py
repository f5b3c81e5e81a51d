"""Learning from validation: a per-profile calibration of the predicted PSNR against measured.

Every validated selection is a measured point of the error model over the whole session: the
PSNR the models predicted for it (``predicted``) beside the PSNR validation measured
(``measured``). The models' misses are mostly a factor on the error (Marble: the measured error
about twice the predicted at every level), which is a shift in dB, so the calibration is a shift:

    PSNR_calibrated = PSNR_predicted + d

with ``d`` the mean of (measured − predicted) over the node's own points when it has any (the
same node at another Δn misses by about the same factor), else over the profile's points of the
same family (:func:`family`: cached nodes and sets of them, whose models are the node models,
apart from amortized estimators, whose models are another kind) when those all miss the same way
(all above, or all below, the prediction), else 0. A node does not borrow a shift the points
disagree on: on many_lights a cached node missed by −5.5 dB and an estimator by +10.6 dB, and
the estimator predicted with the node's shift missed by 16.2 dB, further than the models alone;
on Trashcan every node missed by −7 to −8 dB, and a node without points of its own predicted
with the others' shift missed by under 1 dB. Its ± (:meth:`Calibration.spread_for`) comes from
the node's own points when it has any, else from the points of its family: the RMS of their
residuals around the shift (each point left out of its own shift), at least
:data:`MIN_SPREAD_DB`; :data:`ONE_POINT_SPREAD_DB` for one point, and at least that for a
borrowed shift (no surer than a point of the node's own); 0 with none (no shift is applied then
either). One point's 1.5 dB: a node's window check (training frames) against its
validations (the whole session, other Δn) differed by 0.0–1.3 dB on the default profiles at
3f32fb5 (Marble n2442 0.5, 0.5, 0.5; the temple's n2495 1.3; Trashcan's n715 0.0). Why not the
family's spread for a node with points of its own: the family's says how far one node's shift is
from another's (the demo scene: n935 −7.1 dB, n959 −1.4 dB, a ± of 5.7 dB that kept n935, with
its own point, from every level). Taken over every point, a family without peers would count its
first point's whole miss as the ± of the others: on Trashcan, after the window check (−7.4 dB, a
cached node) and an estimator (−8.5 dB), that made a ± of 8 dB and no cached node could be
offered for any level.

The calibration is refitted as points arrive (:meth:`Calibration.add` returns the new one):
validation uses it to re-check the next levels' choices and the candidates after a miss
(:mod:`rrcache.profiler.validate`), and the profile keeps it (``profile.json``:
``calibration``) so that ``rrcache select`` predicts with it. :func:`prediction_errors` says how
far the predictions were from the measurements, raw and as calibrated when each was made.

>>> cal = Calibration().add("n1", 45.0, 40.7).add("n2", 40.9, 36.6)
>>> round(cal.shift("n1"), 2), round(cal.shift("n3"), 2), cal.shift("est:e1")
(-4.3, -4.3, 0.0)
>>> Calibration().add("n1", 40.0, 38.0).add("n2", 40.0, 41.0).shift("n3")  # they disagree
0.0
>>> round(cal.predict("n3", 50.0)[0], 1)
45.7
>>> Calibration().predict("n1", 41.0)
(41.0, 0.0)
>>> Calibration.from_json(cal.to_json()) == cal
True
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

#: the least ± of a calibrated prediction (dB), and the ± while a single point is known
MIN_SPREAD_DB = 0.5
ONE_POINT_SPREAD_DB = 1.5


@dataclass(frozen=True)
class CalibrationPoint:
    """One validated selection: ``key`` (what it caches, as text), ``node`` (the node it caches,
    None for other kinds), the raw model's ``predicted`` PSNR and the ``measured`` one (dB)."""

    key: str
    node: Optional[str]
    predicted: float
    measured: float

    def to_json(self) -> dict:
        return {"key": self.key, "node": self.node, "predicted": self.predicted, "measured": self.measured}


@dataclass(frozen=True)
class Calibration:
    """The points so far (see the module docstring); immutable: :meth:`add` returns a new one."""

    points: tuple = field(default=())

    def add(self, node: Optional[str], predicted: float, measured: float, key: Optional[str] = None) -> "Calibration":
        """This calibration with one more point of ``node`` (None: a choice of no single node)
        under ``key`` (what is cached; default the node; a point of the same key replaces the
        earlier one in its place: the points stay in the order they were first measured, which
        :func:`replay` follows). Points whose PSNRs are not both finite carry nothing and are left
        out."""
        key = str(key if key is not None else node)
        if not (predicted is not None and measured is not None and math.isfinite(predicted)
                and math.isfinite(measured)):
            return self
        point = CalibrationPoint(key, node, float(predicted), float(measured))
        if any(p.key == key for p in self.points):
            return Calibration(tuple(point if p.key == key else p for p in self.points))
        return Calibration(self.points + (point,))

    def _own(self, node: Optional[str]) -> tuple:
        """The points of ``node`` itself (none for None)."""
        return tuple(p for p in self.points if node is not None and p.node == node)

    def _kin(self, node: Optional[str]) -> tuple:
        """The points of ``node``'s family (:func:`family`)."""
        return tuple(p for p in self.points if family(p.node) == family(node))

    def _shift_of(self, points) -> float:
        return float(np.mean([p.measured - p.predicted for p in points])) if points else 0.0

    def shift(self, node: Optional[str] = None) -> float:
        """``d`` (dB) for ``node``: its own points' mean miss, else that of its family's points
        when they all miss the same way, else 0 (see the module docstring)."""
        own = self._own(node)
        if own:
            return self._shift_of(own)
        kin = self._kin(node)
        misses = [p.measured - p.predicted for p in kin]
        if all(d < 0 for d in misses) or all(d > 0 for d in misses):
            return self._shift_of(kin)
        return 0.0

    def spread_for(self, node: Optional[str] = None) -> float:
        """The ± (dB) of a calibrated prediction for ``node`` (see the module docstring): from
        its own points when it has any, else from its family's; 0 while the family has none.

        >>> cal = Calibration().add("n1", 45.0, 37.6).add("est:e1", 37.8, 29.3)
        >>> cal.spread_for("n2"), cal.spread_for("est:e2"), Calibration().spread_for("n1")
        (1.5, 1.5, 0.0)
        >>> cal = Calibration().add("n1", 55.6, 48.5).add("n2", 30.2, 28.7)  # two nodes' checks
        >>> cal.spread_for("n1"), round(cal.spread_for("n3"), 2)
        (1.5, 5.6)
        >>> Calibration().add("n1", 40.0, 35.0).add("n2", 40.0, 34.8).add("n3", 40.0, 35.1).spread_for("n9")
        1.5
        """
        own = self._own(node)
        if own:
            return self._spread_of(own)
        kin = self._kin(node)  # a borrowed shift is no surer than a point of the node's own
        return max(ONE_POINT_SPREAD_DB, self._spread_of(kin)) if kin else 0.0

    def _spread_of(self, points: tuple) -> float:
        """The RMS of ``points``' residuals, each predicted with the shift of the others
        (:meth:`shift`), at least :data:`MIN_SPREAD_DB`; :data:`ONE_POINT_SPREAD_DB` for one
        point, 0 for none."""
        if len(points) <= 1:
            return ONE_POINT_SPREAD_DB if points else 0.0
        residuals = []
        for i, p in enumerate(points):
            others = Calibration(points[:i] + points[i + 1:])
            residuals.append(p.measured - (p.predicted + others.shift(p.node)))
        return max(MIN_SPREAD_DB, float(math.sqrt(np.mean(np.square(residuals)))))

    @property
    def spread(self) -> float:
        """The ± (dB) of a cached node's calibrated prediction (:meth:`spread_for`)."""
        return self.spread_for(None)

    def predict(self, node: Optional[str], predicted: float) -> tuple[float, float]:
        """(calibrated PSNR, its ±) of a raw prediction for ``node``."""
        if predicted is None or not math.isfinite(predicted):
            return predicted, 0.0
        return float(predicted + self.shift(node)), self.spread_for(node)

    def to_json(self) -> dict:
        """The points, ``shift`` and ``spread`` (those of a cached node without points of its own)."""
        return {"points": [p.to_json() for p in self.points], "shift": self.shift(), "spread": self.spread}

    @classmethod
    def from_json(cls, data: Optional[dict]) -> "Calibration":
        if not data:
            return cls()
        return cls(tuple(CalibrationPoint(str(p["key"]), p.get("node"), float(p["predicted"]), float(p["measured"]))
                         for p in data.get("points", ())))


def replay(calibration: "Calibration") -> list[tuple[str, float, float]]:
    """``(key, calibrated, measured)`` of every point of ``calibration``, its PSNR as the rule of
    this module predicts it from the points before it (in the order they were measured): how a
    profile made under an earlier rule would have been calibrated under this one, for the same
    points (a different calibration may have chosen other candidates to measure).

    >>> cal = Calibration().add("n1", 45.0, 40.0).add("est:e1", 40.0, 44.0).add("n2", 40.0, 36.0)
    >>> replay(cal)
    [('n1', 45.0, 40.0), ('est:e1', 40.0, 44.0), ('n2', 35.0, 36.0)]
    """
    points = calibration.points
    return [(p.key, p.predicted + Calibration(points[:i]).shift(p.node), p.measured) for i, p in enumerate(points)]


def family(node: Optional[str]) -> str:
    """The family of a calibration group (:func:`rrcache.profiler.validate.calibration_group`):
    ``estimator`` for an amortized estimator (``est:e1``), else ``cache`` (a node, a set of
    nodes ``n1+n2``, or None).

    >>> family("est:e1"), family("n12+n40"), family("n3")
    ('estimator', 'cache', 'cache')
    """
    return "estimator" if node is not None and str(node).startswith("est:") else "cache"


def prediction_errors(pairs) -> dict:
    """``{"n", "mean", "worst"}`` of |predicted − measured| (dB) over ``pairs`` of (predicted,
    measured) PSNRs (pairs with a missing or infinite value left out; None figures without any).

    >>> prediction_errors([(45.0, 40.7), (40.9, 36.6), (35.8, 35.0)])
    {'n': 3, 'mean': 3.13, 'worst': 4.3}
    """
    d = [abs(p - m) for p, m in pairs if p is not None and m is not None and math.isfinite(p) and math.isfinite(m)]
    if not d:
        return {"n": 0, "mean": None, "worst": None}
    return {"n": len(d), "mean": round(float(np.mean(d)), 2), "worst": round(float(max(d)), 2)}
