"""The adaptive refresh options of ``rrcache render`` and ``rrcache instance``
(:mod:`rrcache.runtime.adaptive`): ``--adaptive THRESHOLD``, ``--fast-period``, ``--spread``."""
from __future__ import annotations

import math

import click

from rrcache.budgets import MAX_PERIOD
from rrcache.runtime.adaptive import DEFAULT_FAST_PERIOD, DEFAULT_SPREAD


def _threshold(ctx, param, value):
    if value is not None and not (math.isfinite(value) and value >= 0.0):
        raise click.BadParameter("must be a finite number >= 0 (0 refreshes every entry at the fast period)")
    return value


def adaptive_options(fn):
    """``--adaptive THRESHOLD``, ``--fast-period N``, ``--spread PIXELS``."""
    fn = click.option("--spread", type=click.FloatRange(min=0.0, max=64.0), default=DEFAULT_SPREAD,
                      show_default=True,
                      help="With --adaptive: an entry also sees the volatility this many pixels away "
                           "(a volatile region grows by it each fast period; 0: off).")(fn)
    fn = click.option("--fast-period", type=click.IntRange(min=1, max=MAX_PERIOD), default=DEFAULT_FAST_PERIOD,
                      show_default=True,
                      help="With --adaptive: volatile entries are recomputed every N frames (the budget: at "
                           "most 1/Δn + 1/N of the entries refresh per frame).")(fn)
    fn = click.option("--adaptive", type=float, default=None, metavar="THRESHOLD", callback=_threshold,
                      help="Refresh adaptively: an entry whose value had changed by at least THRESHOLD when it "
                           "was last recomputed is recomputed every --fast-period frames, the others every "
                           "--period frames (the max age); docs/adaptive.md.")(fn)
    return fn


def check_adaptive(threshold, nodes, algorithm: str) -> None:
    """``--adaptive`` needs one ``--node`` and the three-pass or two-pass algorithm (exit 2)."""
    if threshold is None:
        return
    if not nodes:
        raise click.BadParameter("needs --node (the node whose cache refreshes adaptively)", param_hint="--adaptive")
    if len(nodes) > 1:
        raise click.BadParameter("runs with one --node (several nodes refresh by their periods)",
                                 param_hint="--adaptive")
    if algorithm == "one-pass":
        raise click.BadParameter("runs with --algorithm three-pass or two-pass, not one-pass",
                                 param_hint="--adaptive")


def adaptive_kwargs(opts: dict) -> dict:
    """The runtime's adaptive arguments from the command's options (empty without --adaptive)."""
    if opts.get("threshold") is None:
        return {}
    return {"threshold": float(opts["threshold"]), "fast_period": int(opts["fast_period"]),
            "spread": float(opts["spread"])}
