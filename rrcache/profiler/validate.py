"""Validation: each level's selection rendered beside the original, and a level that means what it
says (docs/levels.md).

After training, :class:`Validator` (``validate``) takes the labelled selections of the profile
(:meth:`rrcache.profiles.Profile.threshold_selections`: by default predicted PSNR ≥ 45, 40, 35,
30 dB) and measures each in ``compare`` runs (:class:`rrcache.runs.RunSpec`, run by the profile's
executor or an in-process one), side by side with the original at the session's full
resolution, alternating frame by frame (main paper §4.4, Fig. 6).
Shaders timed in a window (:mod:`rrcache.profiler.plan`) are validated in the same window.

**What is measured.** Over ``validation_frames`` consecutive frames drawn exactly (``rgba32f``,
as the error runs the models were trained on): the error, the PSNR with its uncertainty
(:func:`rrcache.model.levels.batch_uncertainty` over the per-frame PSNRs), the hit rate, the
mean FLIP on :data:`~rrcache.harness.perceptual.FLIP_FRAMES` frames spread over them and the
temporal error (the PSNR of the frame-to-frame changes, :mod:`rrcache.harness.perceptual`). The
speed-up :data:`REPEATS` times in the settings' timing format (``rgba8`` by default, as
applications draw), each over :data:`SHORT_FRAMES` consecutive frames, the stretches spread over
the validation frames; the measured speed-up is their median, ``speedups`` keeps each,
``measured_noise`` the noisiest run's frame-to-frame noise of the original.

**A level that means what it says.** A measured selection stands at its level only when it
passes both rules of :mod:`rrcache.model.levels`: its measured quality misses the level by no
more than the measurement's uncertainty, and its measured speed-up clears the gain worth having
(``--min-gain``) with every repeat at least 1.0. Otherwise the next candidate is measured: the
fastest of the level's candidates (``candidates(choice)``: the predicted Pareto front at the
level, fastest first) that the *calibrated* models (:mod:`rrcache.model.calibration`, refitted
with every measured point) predict to meet the level with the calibration's margin, up to
:data:`MAX_TRIES` measured candidates per level. A choice measured already (for another level,
or by an earlier run of the same store) is not rendered again. When none stands, the original
shader stands for that level, its ``fallback`` listing every choice measured and why each was
refused (docs/levels.md says why the original and not the best measured choice). The models'
choices of the later levels are checked against the calibration before they are measured, so a
level whose first choice the calibrated model already predicts to miss goes straight to one it
does not.

With ``fallback=False`` each choice is measured as chosen and only marked: ``level_met`` False
and ``level_note`` saying why.

A selection of the original shader is not rendered: its image is exact (PSNR ∞) and its speed-up 1.

>>> rows = validate(work, session, settings, store, prof.threshold_selections(), candidates=prof.front_candidates)  # doctest: +SKIP
>>> [(r.label, r.describe(), r.tries, r.fallback) for r in rows]                                                  # doctest: +SKIP
[('e1', 'the original shader', 3, 'n104 Δn=50: measured 40.7 ± 0.3 dB, below the level 45 dB; ...'), ...]
"""
from __future__ import annotations

import json
import math
import statistics
from typing import Callable, Optional

import numpy as np

from rrcache.gl.formats import ERROR_FORMAT
from rrcache.harness.cached import runtime_spec
from rrcache.harness.execute import Bench, LocalExecutor
from rrcache.harness.perceptual import flip_frame_indices
from rrcache.harness.timing import frame_noise
from rrcache.model.calibration import Calibration
from rrcache.model.levels import VISIBLE_FLIP, batch_uncertainty, quality_miss, speed_miss
from rrcache.pipeline import ShaderWork, variant_for_selection
from rrcache.profiler.train import PSNR_CAP, ProgressEvent, ProgressFn
from rrcache.profiles.settings import TrainingSettings
from rrcache.profiles.store import ProfileStore
from rrcache.runs import RunResult, RunSpec
from rrcache.selection import Selection

#: side-by-side measurements of each selection, and the frames of each after the first
REPEATS = 3
SHORT_FRAMES = 24
#: at most this many candidates are measured for one level (the models' first choice included)
MAX_TRIES = 3
#: kept for callers of the earlier rule: further candidates after the first
MAX_FALLBACKS = MAX_TRIES - 1
#: the store's meta key of the figures its validation table has no column for
EXTRA_META = "validation_figures"
#: the measured figures kept in EXTRA_META, per selection
_EXTRA_FIELDS = ("speedups", "measured_noise", "measured_psnr_uncertainty", "measured_error_uncertainty",
                 "measured_flip", "measured_flip_uncertainty", "measured_temporal_psnr", "exact")


def slower_beyond_noise(speedups) -> bool:
    """Whether every repeat measured the selection slower than the original.

    >>> slower_beyond_noise([0.94, 0.97, 0.92]), slower_beyond_noise([0.97, 1.01, 0.95])
    (True, False)
    """
    return bool(speedups) and max(speedups) < 1.0


def calibration_group(sel: Selection) -> Optional[str]:
    """What a selection's calibration point is grouped by: its node (one cached node), its
    estimator (``est:e1``) or its nodes joined by ``+`` (a set); None for the original.

    >>> from rrcache.selection import CachedNode
    >>> calibration_group(Selection((CachedNode("n3", 8),), 0.01, 1.0, 2.0))
    'n3'
    """
    if not sel.parts:
        return None
    if sel.kind == "amortize":
        return f"est:{sel.parts[0].estimator}"
    if sel.multi:
        return "+".join(sel.nodes)
    return sel.node


def _key_text(sel: Selection) -> str:
    return json.dumps(sel.key)


class Validator:
    """One profile's validation (see the module docstring): ``run(choices)`` returns the
    selections that stand; :attr:`calibration` is the calibration after every measured point,
    :attr:`measured` every measurement by what it caches. ``executor`` runs the renders (the
    profile's; None: one in this process, closed at the end of :meth:`run`)."""

    def __init__(self, work: ShaderWork, session, settings: TrainingSettings, store: ProfileStore,
                 progress: Optional[ProgressFn] = None, window=None,
                 candidates: Optional[Callable[[Selection], list[Selection]]] = None, fallback: bool = True,
                 calibration: Optional[Calibration] = None, executor=None):
        self.work, self.session, self.settings, self.store = work, session, settings, store
        self.executor, self._own_executor = executor, executor is None
        self.progress, self.window, self.candidates, self.fallback = progress, window, candidates, fallback
        self.calibration = calibration or Calibration()
        self.frames = list(range(settings.validation_frames))
        self.short = self.frames[:max(2, min(SHORT_FRAMES, len(self.frames)))]
        self.per = len(self.frames) + REPEATS * len(self.short)
        self.measured: dict[tuple, Selection] = {}
        self._stored = {row.key: row for row in store.validations() if row.parts}
        self._extras = self._read_extras()
        self.state = {"done": 0, "total": 0}
        self._counted: set = set()  # the choices whose frames the total counts

    # ------------------------------------------------------------------ measuring
    def _read_extras(self) -> dict:
        raw = self.store.meta().get(EXTRA_META)
        try:
            data = json.loads(raw) if raw else {}
        except ValueError:
            data = {}
        return data if isinstance(data, dict) else {}

    def _keep_extras(self, sel: Selection) -> None:
        self._extras[_key_text(sel)] = {k: (list(v) if isinstance(v, tuple) else v)
                                        for k in _EXTRA_FIELDS for v in [getattr(sel, k)]}
        self.store.set_meta(EXTRA_META, json.dumps(self._extras, allow_nan=False, default=_no_nan))

    def _from_store(self, choice: Selection) -> Selection:
        m = self._stored[choice.key]
        extra = self._extras.get(_key_text(choice), {})
        exact = bool(extra.get("exact", m.exact or m.measured_error == 0.0))
        sel = choice.with_measurement(m.measured_error, None if exact else m.measured_psnr, m.measured_ms,
                                      m.measured_original_ms, m.measured_speedup, m.hit_rate, m.frames,
                                      tuple(extra.get("speedups") or (m.measured_speedup,)))
        values = {k: extra.get(k) for k in _EXTRA_FIELDS if k not in ("speedups", "exact")}
        return self._flagged(sel.replace(exact=exact, **values))

    @staticmethod
    def _flagged(sel: Selection) -> Selection:
        """``visible_artifacts`` from what was measured: FLIP at or above
        :data:`~rrcache.model.levels.VISIBLE_FLIP` (docs/levels.md)."""
        flip = sel.measured_flip
        return sel.replace(visible_artifacts=bool(flip is not None and flip >= VISIBLE_FLIP and not sel.exact))

    def _step(self, detail: str, units: int = 2) -> None:
        self.state["done"] += units
        if self.progress is not None:
            self.progress(ProgressEvent("validate", self.state["done"], max(self.state["total"], self.state["done"]),
                                        detail))

    def measure(self, choice: Selection) -> Selection:
        """``choice`` with its measured figures (rendered, or from an earlier measurement)."""
        if choice.key in self.measured:
            m = self.measured[choice.key]
            return choice.with_measurement(m.measured_error, m.measured_psnr, m.measured_ms, m.measured_original_ms,
                                           m.measured_speedup, m.hit_rate, m.frames, m.speedups).replace(
                **{k: getattr(m, k) for k in _EXTRA_FIELDS if k != "speedups"},
                visible_artifacts=m.visible_artifacts)
        if choice.key in self._stored:
            sel = self._from_store(choice)
            self.measured[choice.key] = sel
            return sel
        if choice.key not in self._counted:  # a candidate run() did not count in advance
            self._counted.add(choice.key)
            self.state["total"] += 2 * self.per
        variant, period = variant_for_selection(self.work, choice)
        spec = runtime_spec(variant, None, period=period, **self.settings.cache_options())
        size = tuple(self.session.resolution)
        what = f"{choice.label}: {choice.describe()}"
        key = ("validate", _key_text(choice))
        # the error over every validation frame, drawn exactly (rgba32f) as the error runs are, with
        # FLIP on frames spread over them and the temporal error
        runs = [RunSpec("compare", spec, self.frames, size, self.window, ERROR_FORMAT, key=key + ("error",),
                        label=f"{what} error", flip_frames=tuple(flip_frame_indices(self.frames)), temporal=True)]
        # the speed-up in the timing format, REPEATS times over stretches spread over the frames
        for repeat in range(REPEATS):
            start = (len(self.frames) - len(self.short)) * repeat // max(1, REPEATS - 1)
            runs.append(RunSpec("compare", spec, self.frames[start:start + len(self.short)], size, self.window,
                                self.settings.timing_format, self.settings.clock, key=key + ("timing", repeat),
                                label=f"{what} timing [{repeat + 1}/{REPEATS}]"))
        results = {r.spec.key: r for r in self._executor().run(runs, on_frame=lambda run, n: self._step(run.label, n))}
        exact_run = _Figures(results[key + ("error",)])
        timed = [_Figures(results[key + ("timing", repeat)]) for repeat in range(REPEATS)]
        speedups = tuple(r.speedup for r in timed)
        exact = exact_run.mean_error == 0.0
        steady = exact_run.steady
        psnr = None if exact else min(exact_run.psnr, PSNR_CAP)  # exact: PSNR ∞, kept as null
        sel = choice.with_measurement(exact_run.mean_error, psnr,
                                      statistics.median(r.ms_per_frame for r in timed),
                                      statistics.median(r.original_ms_per_frame for r in timed),
                                      float(statistics.median(speedups)), exact_run.result.hit_rate,
                                      len(exact_run.result.frames), speedups)
        flips, temporal = exact_run.result.flips, exact_run.result.temporal_psnr
        sel = sel.replace(
            measured_noise=max(frame_noise([f.original_ms for f in r.result.frames[1:]]) for r in timed), exact=exact,
            measured_psnr_uncertainty=None if exact else batch_uncertainty([min(f.psnr, PSNR_CAP) for f in steady]),
            measured_error_uncertainty=batch_uncertainty([f.error for f in steady]),
            measured_flip=float(np.mean(flips)) if flips else None,
            measured_flip_uncertainty=batch_uncertainty(list(flips)) if flips else None,
            measured_temporal_psnr=None if temporal is None or not math.isfinite(temporal) else min(temporal, PSNR_CAP))
        sel = self._flagged(sel)
        self.measured[choice.key] = sel
        self._keep_extras(sel)
        return sel

    def _executor(self):
        if self.executor is None:
            self.executor = LocalExecutor(Bench(self.work, self.session))
        return self.executor

    def close(self) -> None:
        """Close the executor made here (the caller's stays open)."""
        if self._own_executor and self.executor is not None:
            self.executor.close()
            self.executor = None

    # ------------------------------------------------------------------ the levels
    def _learn(self, sel: Selection) -> None:
        """Add ``sel``'s measured point to the calibration (raw prediction against measurement)."""
        if sel.parts and not sel.exact and sel.predicted_psnr is not None and sel.measured_psnr is not None:
            raw = sel.predicted_psnr - float(sel.calibration_db or 0.0)
            self.calibration = self.calibration.add(calibration_group(sel), raw, sel.measured_psnr,
                                                    key=sel.describe())

    def _calibrated(self, sel: Selection) -> Selection:
        """``sel`` with its predicted PSNR as the current calibration predicts it (the shift it
        applied in ``calibration_db``)."""
        if not sel.parts or sel.predicted_psnr is None or sel.exact:
            return sel
        raw = sel.predicted_psnr - float(sel.calibration_db or 0.0)
        value, spread = self.calibration.predict(calibration_group(sel), raw)
        if not self.calibration.points:
            return sel
        base = float(sel.predicted_psnr_uncertainty or 0.0)
        return sel.replace(predicted_psnr=value, calibration_db=value - raw,
                           predicted_psnr_uncertainty=math.sqrt(base * base + spread * spread))

    def _admissible(self, sel: Selection) -> bool:
        """Whether the calibrated models predict ``sel`` to meet its PSNR level with the
        calibration's margin (always, before any point, or for a level of another kind)."""
        if sel.min_psnr is None or not self.calibration.points or not sel.parts or sel.exact:
            return True
        if sel.predicted_psnr is None:
            return False
        return sel.predicted_psnr - self.calibration.spread_for(calibration_group(sel)) >= sel.min_psnr

    def miss(self, sel: Selection) -> Optional[str]:
        """Why the measured ``sel`` may not stand at its level, or None."""
        if not sel.parts:
            return None
        quality = quality_miss(sel.measured_psnr, float(sel.measured_psnr_uncertainty or 0.0), sel.min_psnr,
                               sel.measured_error, float(sel.measured_error_uncertainty or 0.0), sel.max_error,
                               sel.measured_flip, float(sel.measured_flip_uncertainty or 0.0), sel.max_flip,
                               exact=sel.exact)
        if quality is not None:
            return quality
        return speed_miss(sel.speedups or (sel.measured_speedup,), self.settings.min_gain)

    def _pool(self, choice: Selection) -> list[Selection]:
        pool = [choice]
        if self.fallback and self.candidates is not None:
            pool += [c for c in self.candidates(choice) if c.key != choice.key and c.parts]
        return pool

    def level(self, choice: Selection) -> Selection:
        """The selection that stands at ``choice``'s level (see the module docstring)."""
        if not choice.parts:
            return _original(choice).replace(level_met=True, tries=0)
        if not self.fallback:
            sel = self.measure(self._calibrated(choice))
            self._learn(sel)
            why = self.miss(sel)
            return sel.replace(tries=1, level_met=why is None, level_note=why)
        pool = [choice] + sorted(self._pool(choice)[1:], key=lambda c: c.predicted_ms)
        refused: list[tuple[Selection, str]] = []
        rendered = 0
        while True:
            done = {s.key for s, _ in refused}
            nxt = next((c for c in (self._calibrated(c) for c in pool if c.key not in done) if self._admissible(c)),
                       None)
            if nxt is None:
                break
            fresh = nxt.key not in self.measured and nxt.key not in self._stored
            if fresh and rendered >= MAX_TRIES:
                break
            rendered += int(fresh)
            sel = self.measure(nxt)
            self._learn(sel)
            why = self.miss(sel)
            if why is None:
                sel = sel.replace(tries=len(refused) + 1, level_met=True)
                if refused:
                    sel = sel.replace(fallback=f"{_refusals(refused)}; so {described(sel)} stands "
                                               f"(candidate {len(refused) + 1})")
                return sel
            refused.append((sel, why))
            # every measurement is kept in the store (the refused ones under their own label)
            self.store.add_validation(sel.replace(label=f"{choice.label}~{len(refused)}"))
        original = _original(choice).replace(level_met=True, tries=len(refused))
        if refused:
            return original.replace(fallback=f"{_refusals(refused)}; so the original shader stands")
        shift = self.calibration.shift(calibration_group(choice))
        return original.replace(
            fallback=f"{described(choice)} and every other candidate are predicted below the level once calibrated "
                     f"by the choices measured before ({shift:+.1f} dB); so the original shader stands")

    def run(self, choices: list[Selection]) -> list[Selection]:
        """Measure each labelled choice (see the module docstring); store every measurement and
        return the selections that stand, in order."""
        # what ran before (the window check) stays counted
        new = {c.key for c in choices if c.parts} - set(self._stored) - self._counted
        self._counted |= new
        self.state["total"] = self.state["done"] + 2 * self.per * len(new)
        out = []
        try:
            for choice in choices:
                sel = self.level(choice)
                self.store.add_validation(sel)
                out.append(sel)
        finally:
            self.close()
        return out


class _Figures:
    """A compare run's summary as :class:`rrcache.harness.cached.Comparison` gives it (the mean
    error and PSNR of the steady frames, the median times and their ratio)."""

    def __init__(self, result: RunResult):
        self.result = result
        self.steady = result.steady
        self.mean_error = float(np.mean([f.error for f in self.steady]))
        self.psnr = float(np.mean([min(f.psnr, PSNR_CAP) for f in self.steady]))
        self.ms_per_frame = statistics.median(f.ms for f in self.steady)
        self.original_ms_per_frame = statistics.median(f.original_ms for f in self.steady)
        self.speedup = self.original_ms_per_frame / self.ms_per_frame if self.ms_per_frame > 0 else float("nan")


def flip_level(prof, validator: "Validator", max_flip: float, label: str = "flip") -> Selection:
    """The selection that stands at a mean-FLIP level ``max_flip`` (``rrcache profile
    --max-flip``), after the PSNR levels were validated: FLIP is measured, not modelled, so the
    measured choices that meet it (and the gain) are the first answer; else the models' choice at
    the PSNR the measured choices relate to that FLIP (:func:`rrcache.profiles.measured.flip_psnr`),
    validated at the FLIP level like any level (up to :data:`MAX_TRIES` candidates of the front
    at that PSNR, fastest first), and failing those the original."""
    from rrcache.profiles.measured import flip_psnr

    gain = validator.settings.min_gain
    measured = [m for m in validator.measured.values() if m.parts]
    meeting = [m for m in measured if quality_miss(measured_flip=m.measured_flip, max_flip=max_flip,
                                                   flip_uncertainty=float(m.measured_flip_uncertainty or 0.0),
                                                   exact=m.exact) is None
               and speed_miss(m.speedups or (m.measured_speedup,), gain) is None]
    needed = flip_psnr([(m.measured_psnr, m.measured_flip) for m in measured if not m.exact], max_flip)
    model = prof.select_psnr(needed) if needed is not None else None
    best = max(meeting, key=lambda m: float(m.measured_speedup or 0.0), default=None)
    if best is not None and (model is None or not model.parts
                             or float(best.measured_speedup) >= float(model.predicted_speedup)):
        return best.replace(label=label, max_flip=max_flip, min_psnr=None, tries=0, level_met=True, fallback=None,
                            level_note=None)
    if model is None:  # nothing to relate FLIP to: the original stands, saying so
        base = prof.select_psnr(45.0)
        return _original(base.replace(label=label, min_psnr=None, max_flip=max_flip)).replace(
            level_met=True, fallback=f"no measured choice has mean FLIP ≤ {max_flip:g}, and too few were measured to "
                                     "relate FLIP to PSNR; so the original shader stands")
    choice = model.replace(label=label, min_psnr=None, max_flip=max_flip)

    def candidates(c: Selection) -> list[Selection]:
        return [x.replace(min_psnr=None, max_flip=max_flip)
                for x in prof.front_candidates(c.replace(min_psnr=needed)) if x.key != c.key]

    validator.candidates = candidates
    try:
        return validator.level(choice)
    finally:
        validator.close()  # an executor it made for these renders (the profile's stays open)


def _no_nan(value):
    raise TypeError(f"not JSON: {value!r}")


def _refusals(refused) -> str:
    return "; ".join(f"{described(s)}: {why}" for s, why in refused)


def described(sel: Selection, width: int = 40) -> str:
    """``sel`` for people: a cached node with its expression (cut to ``width`` characters),
    ``n2442 (mix(stone, u_veinColor, vein)) Δn=7``; other kinds as :meth:`Selection.describe`.

    >>> from rrcache.selection import CachedNode
    >>> described(Selection((CachedNode("n7", 4, "mix(a, b, t)"),), 0.01, 1.0, 2.0))
    'n7 (mix(a, b, t)) Δn=4'
    """
    if sel.kind == "cache" and sel.text:
        text = sel.text if len(sel.text) <= width else sel.text[:width - 1] + "…"
        return f"{sel.node} ({text}) Δn={sel.period}"
    return sel.describe()


def validate(work: ShaderWork, session, settings: TrainingSettings, store: ProfileStore, choices: list[Selection],
             progress: Optional[ProgressFn] = None, window=None,
             candidates: Optional[Callable[[Selection], list[Selection]]] = None,
             fallback: bool = True, calibration: Optional[Calibration] = None, executor=None) -> list[Selection]:
    """Measure each of ``choices`` (labelled selections with their algorithm) beside the original
    inside ``window`` when given and return the selections that stand at their levels (see the
    module docstring; ``fallback=False`` keeps every choice as measured, marked; ``executor``:
    what runs the renders, None for one in this process)."""
    return Validator(work, session, settings, store, progress, window, candidates, fallback, calibration,
                     executor).run(choices)


def _original(choice: Selection) -> Selection:
    """The original shader as a measured selection at ``choice``'s level: exact, speed-up 1."""
    base = Selection.original(float(choice.predicted_ms) if not choice.parts else float("nan"))
    original = choice if not choice.parts else base.replace(
        label=choice.label, max_error=choice.max_error, min_psnr=choice.min_psnr, max_flip=choice.max_flip,
        algorithm=choice.algorithm, predicted_ms=choice.predicted_ms * choice.predicted_speedup)
    return original.with_measurement(0.0, None, float(original.predicted_ms), float(original.predicted_ms),
                                     1.0, 0.0, 0).replace(exact=True, predicted_psnr=None,
                                                          predicted_psnr_uncertainty=0.0, visible_artifacts=False,
                                                          predicted_error=0.0, predicted_speedup=1.0,
                                                          predicted_speedup_range=(1.0, 1.0), calibration_db=None)
