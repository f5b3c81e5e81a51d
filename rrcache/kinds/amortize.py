"""Kind ``amortize``: an estimator's loop amortized over frames (Nehab et al. 2007 §6): m of its N
terms evaluated per frame where the cache hits, blended with the reprojected estimate by λ
(:func:`rrcache.compiler.amortize.instance_amortized`).

Its part is :class:`AmortizedLoop`; training runs every trained m at each training blend (error
runs) and each m on the timing frames (timing runs) for each history
(:mod:`rrcache.profiler.amortize`), kept in the store's ``amortize_run`` table.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Optional

from rrcache.compiler.slots import AMORTIZE_PAYLOADS
from rrcache.errors import RRCacheError
from rrcache.kinds.base import Kind, id_of, only as _only, text_of, whole
from rrcache.runtime.glsl import FILTERS
from rrcache.runtime.spec import VariantSpec


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
        estimator = id_of(data, "estimator", where, "e1")
        samples = whole(data, "samples", where)
        blend = data.get("blend")
        if isinstance(blend, bool) or not isinstance(blend, (int, float)) or not 0.0 <= blend < 1.0:
            raise RRCacheError("must be a number in [0, 1)", f"{where}.blend")
        history, phase = data.get("history", "blend"), data.get("phase", "frame")
        if history not in ("blend", "slots"):
            raise RRCacheError("must be 'blend' or 'slots'", f"{where}.history")
        if phase not in ("frame", "pixel"):
            raise RRCacheError("must be 'frame' or 'pixel'", f"{where}.phase")
        text = text_of(data, where)
        filter_, payload = data.get("filter", "bilinear"), data.get("payload", "f4")
        if filter_ not in FILTERS:
            raise RRCacheError(f"must be one of {', '.join(FILTERS)}", f"{where}.filter")
        if payload not in AMORTIZE_PAYLOADS:
            raise RRCacheError(f"must be one of {', '.join(AMORTIZE_PAYLOADS)}", f"{where}.payload")
        return cls(estimator, samples, float(blend), history, phase, text, filter_, payload)


class AmortizeKind(Kind):
    name = "amortize"
    part = AmortizedLoop
    title = "an amortized loop"
    settled_note = " (its history settled: the cycle of subsets and the blend's memory)"
    tables = """
-- amortize_run: an estimator's runs (rrcache.profiler.amortize), per history (`blend`, `slots`,
--   `slots/u8` for the slots in 8 bits): kind `error` is one run at (samples m, blend λ) over the
--   training frames (frame -1; mean error and PSNR over the frames after the first, hit rate),
--   kind `timing` one timed frame at m (frame, ms, the original's ms beside it, hits, misses).
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
);
"""

    def spec(self, parts, algorithm, filter=None, **runtime) -> VariantSpec:
        # (its part names its own filter: the profile's, a node cache's, does not apply)
        (p,) = parts
        return VariantSpec(self.name, (), algorithm, p.filter, p.payload, estimator=p.estimator,
                           samples=int(p.samples), history=p.history, phase=p.phase, blend=float(p.blend), **runtime)

    def compile(self, work, spec: VariantSpec):
        from rrcache.compiler.amortize import instance_amortized

        return instance_amortized(work.shader, spec.estimator, spec.algorithm, samples=spec.samples, blend=spec.blend,
                                  phase=spec.phase, history=spec.history, filter=spec.filter,
                                  payload_dtype=spec.payload, vertex=work.vertex)

    def training(self, subject, settings, algorithm, filter=None) -> list:
        """``subject`` = (estimator id, history, payload, [(m, [λ, ...]), ...], timed m list): the
        error runs at each (m, λ) and the timing runs at each timed m."""
        estimator, history, payload, errors, timed = subject
        key = history if payload == "f4" else f"{history}/{payload}"
        base = VariantSpec(self.name, (), algorithm, payload=payload, estimator=estimator, history=history,
                           **settings.cache_options())
        out = [("error", _with(base, m, lam), ("amortize", estimator, key, int(m), float(lam)))
               for m, blends in errors for lam in blends]
        out += [("timing", _with(base, m, 0.0), ("amortize", estimator, key, int(m), 0.0)) for m in timed]
        return out

    def collect(self, store, result) -> None:
        """An estimator's error run (one row of ``amortize_run``: the means over the frames after the
        first) or timing run (a row per timed frame), keyed ``("amortize", estimator, history, m, λ)``."""
        _, estimator, history, m, lam = result.spec.key
        rows = result.frames
        if result.spec.measure == "error":
            steady = rows[1:]
            errs = [r.error for r in steady] or [0.0]
            psnrs = [r.psnr for r in steady] or [100.0]
            hits, misses = sum(r.hits or 0 for r in steady), sum(r.misses or 0 for r in steady)
            rate = hits / (hits + misses) if hits + misses else 0.0
            store.add_amortize_rows([(estimator, history, "error", int(m), float(lam), -1,
                                      float(sum(errs) / len(errs)), float(sum(psnrs) / len(psnrs)), rate, hits,
                                      misses, 0.0, 0.0, float(result.wall_s))])
        else:
            wall = float(result.wall_s) / max(1, len(rows))
            store.add_amortize_rows([(estimator, history, "timing", int(m), 0.0, int(r.frame), 0.0, 0.0, 0.0,
                                      int(r.hits or 0), int(r.misses or 0), float(r.ms), float(r.original_ms), wall)
                                     for r in rows])

    def cells(self, selection, profile=None, texts=False):
        p = selection.parts[0]
        if texts:
            return f"{self.describe(selection.parts)}: {p.text}", "–"
        est = profile.estimator(p.estimator) if profile is not None else None
        of = f"/{est.samples}" if est is not None else ""
        slots = " slots" if p.history == "slots" else ""
        return f"{p.estimator} m={p.samples}{of} λ={p.blend:g}{slots}: {p.text or ''}", "–"

    def summary(self, selection, profile=None) -> dict:
        p = selection.parts[0]
        est = profile.estimator(p.estimator) if profile is not None else None
        return {"node": None, "period": None, "kind": self.name, "estimator": p.estimator, "samples": p.samples,
                "of": est.samples if est is not None else None, "blend": p.blend, "history": p.history,
                "phase": p.phase, "filter": p.filter, "payload": p.payload}

    def sentence(self, selection, profile) -> str:
        p = selection.parts[0]
        return (f"amortize {p.estimator} ({p.text}): {p.samples} of {profile.estimator(p.estimator).samples} terms "
                f"per frame, {history_words(p)}, λ = {p.blend:g}")

    def sentence_html(self, selection, profile) -> str:
        import html

        part = selection.parts[0]
        est = next((e for e in profile.estimators if e.id == part.estimator), None)
        of = f" of {est.samples}" if est is not None else ""
        loop = f" <code>{html.escape(est.text)}</code>" if est is not None and est.text else ""
        how = ("its N/m subset sums kept apart (slots history)" if part.history == "slots"
               else "blended with the reprojected estimate (blend history)")
        return (f"amortize estimator <b>{html.escape(part.estimator)}</b>{loop}: <b>{part.samples}{of}</b> terms "
                f"per frame, {how}, <b>λ = {part.blend:g}</b>")

    def report_html(self, selection, profile) -> str:
        import html

        p = selection.parts[0]
        est = next((e for e in getattr(profile, "estimators", ()) if e.id == p.estimator), None)
        of = f" of its {est.samples}" if est is not None else " of its"
        how = ("each of its N/m subset sums kept apart and blended with its own reprojected value"
               if p.history == "slots" else "blended with the reprojected estimate")
        return (f"amortize estimator <b>{html.escape(p.estimator)}</b>: {p.samples}{of} terms per frame, {how} by "
                f"λ = {p.blend:g} ({html.escape(p.history)} history)"
                + (f" (<code>{html.escape(p.text)}</code>)" if p.text else ""))

    def anchor(self, parts):
        return parts[0].estimator

    def shown_frame(self, selection, variant, frames: int) -> int:
        return settle_frame(frames, (variant.amortized or {}).get("cycle", 1), selection.parts[0].blend)

    def payload_captions(self, selection, variant) -> dict:
        p = selection.parts[0]
        info = variant.amortized or {}
        n, m = info.get("of"), p.samples
        out = {"cached": f"amortized: {m} of {n} terms per frame"}
        if p.history == "slots":
            shown = min(3, variant.components)
            sums = f"{n // m} subset sums" if n else "subset sums"
            out["payload"] = f"the {sums} (slots; {shown} channel(s) shown)"
        else:
            out["payload"] = "running estimate (blend)"
        return out


def history_words(part) -> str:
    """How an amortized choice keeps its history, in words."""
    if part.history == "slots":
        return ("slots history (the N/m subset sums kept apart, each blended with its own"
                + (", in 8 bits by the terms' range)" if part.payload == "u8" else ")"))
    return "blend history (one running estimate)"


#: how far the blend's memory λ^k must fall before an amortized frame is shown
SETTLED = 0.05


def settle_frame(frames: int, cycle: int, blend: float) -> int:
    """The frame shown for an amortized selection: after its ``cycle`` (N/m frames, every subset
    once) and the frames its blend's memory needs (λ^k ≤ 5 %), plus one; at most the session's
    last frame (``frames`` - 1).

    >>> settle_frame(150, 4, 0.6), settle_frame(150, 4, 0.0), settle_frame(12, 2, 0.9)
    (11, 5, 11)
    """
    import math

    memory = math.ceil(math.log(SETTLED) / math.log(blend)) if 0.0 < blend < 1.0 else 0
    return min(int(frames) - 1, int(cycle) + memory + 1)


def _with(base: VariantSpec, m: int, lam: float) -> VariantSpec:
    import dataclasses

    return dataclasses.replace(base, samples=int(m), blend=float(lam))


KIND = AmortizeKind()
