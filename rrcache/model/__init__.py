"""The models of the main paper §4.2–4.5 and the selection over them (pure numpy/scipy/nlopt).

- :mod:`~rrcache.model.error`: ε̂(Δn) = α(1 − e^{−λ(Δn−1)}) per node (:func:`fit_error`,
  :func:`fit_errors`, :class:`ErrorFit`), Nelder–Mead through nlopt;
- :mod:`~rrcache.model.hitrate`: γ(Δn) = μ(1 − 1/Δn) per shader and session
  (:func:`fit_hit_rate`, :class:`HitRateFit`);
- :mod:`~rrcache.model.performance`: t = h·t_hit + m·t_miss + t_overhead per node, bounded least
  squares with the rank deficiency handled (:func:`fit_performance`, :class:`PerfFit`);
- :mod:`~rrcache.model.predict`: frame time t_overhead + M(γ t_hit + (1 − γ) t_miss)
  (:func:`predict_ms`, :func:`predict_speedup`);
- :mod:`~rrcache.model.selection`: :class:`ModelTable` (precomputed grids), :func:`select`,
  :func:`pareto_front`, :func:`thresholds`, :func:`selection_benchmark`.

Every fit is deterministic, never raises for numeric input and never returns NaN; each carries a
``quality`` flag (``"ok"`` or what went wrong) and ``flags`` (all conditions found).

>>> from rrcache.model import fit_error, fit_hit_rate, fit_performance, ModelTable, select
>>> ef = fit_error([2, 10, 50], [0.01, 0.04, 0.05])
>>> hf = fit_hit_rate([2, 10, 50], [0.45, 0.81, 0.88])
>>> pf = fit_performance([1e4, 4e4, 8e4], [9e4, 6e4, 2e4], [9.2, 6.5, 2.9], overhead_ms=0.1)
>>> table = ModelTable.from_fits(["n0"], [ef], [pf], hf, pixels=1e5, original_ms=10.0)
>>> choice = select(table, 0.045)
>>> choice.node, choice.predicted_speedup > 1
('n0', True)
"""
from rrcache.model.error import ErrorFit, fit_error, fit_errors
from rrcache.model.hitrate import HitRateFit, fit_hit_rate
from rrcache.model.performance import PerfFit, fit_performance
from rrcache.model.predict import predict_ms, predict_speedup
from rrcache.model.selection import (FrontPoint, ModelTable, Selection, pareto_front, select,
                                     selection_benchmark, synthetic_table, thresholds)

__all__ = [
    "ErrorFit", "fit_error", "fit_errors",
    "HitRateFit", "fit_hit_rate",
    "PerfFit", "fit_performance",
    "predict_ms", "predict_speedup",
    "FrontPoint", "ModelTable", "Selection", "pareto_front", "select", "selection_benchmark",
    "synthetic_table", "thresholds",
]
