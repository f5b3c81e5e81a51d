"""Profiles: train the models of a shader over a session, and choose what to cache.

:func:`profile` runs the whole profiler (main paper §4, Fig. 3) into an output folder:

- ``profile.sqlite``: every measurement (:mod:`rrcache.profile.store`); rerunning with the same
  arguments resumes from it, skipping what is stored;
- ``profile.json``: the fitted models per node, μ, the overhead, the original's frame time and the
  four validated selections (``rrcache_profile: 1``);
- ``tradeoff.png``/``.svg``, ``hitrate.png``, ``validation.png`` (:mod:`rrcache.profile.plots`);
- ``optimized/e1`` … ``optimized/e4``: the shader files of each selection.

:func:`load_profile` reads a profile back; :meth:`Profile.select` re-selects for any error
threshold from the models alone, in milliseconds (nothing is rendered).

>>> p = profile("marble.frag", "marble.json", settings=TrainingSettings(budget_s=60))   # doctest: +SKIP
>>> p = load_profile("marble-marble.rrprofile")                                         # doctest: +SKIP
>>> choice = p.select(0.02)                                                             # doctest: +SKIP
>>> choice.node, choice.period, round(choice.predicted_speedup, 1)                      # doctest: +SKIP
('n102', 35, 2.7)
"""
from __future__ import annotations

import dataclasses
import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Optional

from rrcache.errors import RRCacheError
from rrcache.harness.timing import UNRELIABLE_NOISE
from rrcache.jsonable import finite_json as _finite
from rrcache.profile.settings import TrainingSettings
from rrcache.profile.store import ProfileStore, StoreKey
from rrcache.profile.train import ProgressFn, TrainingResult, train

PROFILE_VERSION = 1
STORE_NAME = "profile.sqlite"
JSON_NAME = "profile.json"


@dataclass
class NodeProfile:
    """One cacheable node in a profile: where it is, its static cost, and (when ``trained``) its
    fitted models: error α, λ (``lam``) with their fit quality and R², per-pixel times t_hit,
    t_miss (ms) with the performance fit's quality, and the measured error runs (``periods``,
    ``errors``, ``hit_rates``, ``psnrs``); ``note`` says why an untrained node was not trained."""

    id: str
    type: str
    line: int
    column: int
    text: str
    call_chain: list
    cost: int
    trained: bool = False
    alpha: Optional[float] = None
    lam: Optional[float] = None
    error_quality: Optional[str] = None
    error_r2: Optional[float] = None
    t_hit: Optional[float] = None
    t_miss: Optional[float] = None
    perf_quality: Optional[str] = None
    periods: list = field(default_factory=list)
    errors: list = field(default_factory=list)
    hit_rates: list = field(default_factory=list)
    psnrs: list = field(default_factory=list)
    error_fit: dict = field(default_factory=dict)
    perf_fit: dict = field(default_factory=dict)
    note: Optional[str] = None


@dataclass
class SelectionReport:
    """A validated selection: ``label`` (e1..e4) at ``max_error``; ``node`` None = the original;
    predicted and measured error (mean RGB L2), PSNR, frame time and speed-up; ``files`` the
    folder of its shader files (relative to the profile folder)."""

    label: str
    max_error: float
    node: Optional[str]
    period: Optional[int]
    text: Optional[str]
    predicted_error: float
    predicted_ms: float
    predicted_speedup: float
    measured_error: Optional[float] = None
    measured_psnr: Optional[float] = None
    measured_ms: Optional[float] = None
    measured_original_ms: Optional[float] = None
    measured_speedup: Optional[float] = None
    hit_rate: Optional[float] = None
    frames: int = 0
    files: Optional[str] = None


def _fit_json(fit) -> dict:
    if fit is None:
        return {}
    if dataclasses.is_dataclass(fit):
        data = {f.name: getattr(fit, f.name) for f in dataclasses.fields(fit)}
    else:
        data = {k: v for k, v in vars(fit).items() if not k.startswith("_")}
    return _finite(data)


def _fit_from_json(cls, data: dict, where: str):
    if not data:
        return None
    try:
        names = {f.name for f in dataclasses.fields(cls)} if dataclasses.is_dataclass(cls) else set(data)
        values = {k: (float("nan") if v is None and k not in ("quality", "dropped") else v)
                  for k, v in data.items() if k in names}
        return cls(**values)
    except (TypeError, ValueError) as err:
        raise RRCacheError(f"cannot read a fitted model ({err})", where,
                           hint="the profile was written by another rrcache version; run 'rrcache profile' again") from None


class Profile:
    """A trained profile (see the module docstring). ``nodes`` (costliest first), ``selections``
    (e1..e4), ``mu``, ``overhead_ms``, ``original_ms``, ``pixels``, ``settings``, ``path``
    (the folder), ``counts`` (what the last run computed and skipped)."""

    def __init__(self, data: dict, path: Optional[Path] = None):
        where = str(path / JSON_NAME) if path is not None else JSON_NAME
        self.data = data
        self.path = path
        self._where = where
        try:
            self.shader = data["shader"]
            self.session = data["session"]
            self.defines = dict(data.get("defines") or {})
            self.settings = TrainingSettings.from_json(data["settings"], where)
            self.nodes = [NodeProfile(**n) for n in data["nodes"]]
            self.selections = [SelectionReport(**s) for s in data.get("selections", [])]
            self.mu = data["mu"]
            self.mu_quality = data.get("mu_quality")
            self.hit_fit_data = data.get("hit_fit") or {}
            self.overhead_ms = data["overhead_ms"]
            self.original_ms = data["original_ms"]
            self.pixels = data["pixels"]
            self.training_wall_s = data.get("training_wall_s")
            self.counts = data.get("counts", {})
        except (KeyError, TypeError) as err:
            raise RRCacheError(f"not a complete profile ({type(err).__name__}: {err})", where,
                               hint="run 'rrcache profile' again to rewrite it") from None
        self._table = None

    @property
    def ceiling(self):
        """The measured :class:`~rrcache.profile.ceiling.Ceiling` (None in older profiles)."""
        from rrcache.profile.ceiling import Ceiling

        return Ceiling.from_json(self.data.get("ceiling"))

    @property
    def verdict(self) -> Optional[dict]:
        """When the ceiling stopped the profile before training: ``choice`` ("original"),
        ``ceiling``, ``answer``, ``reason``, ``changes``; else None."""
        return self.data.get("verdict")

    @property
    def algorithm(self) -> str:
        """The cache algorithm the profile was trained and validated with (``auto`` settings:
        the one its plan measured faster)."""
        return (self.data.get("plan") or {}).get("algorithm") or self.settings.fixed_algorithm

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

    def fits(self):
        """``(error_fits, perf_fits, hit_fit)`` rebuilt as :mod:`rrcache.model` objects (trained
        nodes only, in the order of :attr:`trained_nodes`)."""
        from rrcache.model import ErrorFit, HitRateFit, PerfFit

        trained = self.trained_nodes
        errors = [_fit_from_json(ErrorFit, n.error_fit, self._where) for n in trained]
        perfs = [_fit_from_json(PerfFit, n.perf_fit, self._where) for n in trained]
        return errors, perfs, _fit_from_json(HitRateFit, self.hit_fit_data, self._where)

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

    def select(self, max_error: float):
        """The (node, Δn ≤ 50) predicted fastest with error ≤ ``max_error`` (an
        ``rrcache.model.Selection``; node None = the original shader). From the models only.

        >>> choice = load_profile("marble-marble.rrprofile").select(0.01)   # doctest: +SKIP
        """
        from rrcache.model import select as model_select

        try:
            level = float(max_error)
        except (TypeError, ValueError):
            level = float("nan")
        if not math.isfinite(level) or level < 0:
            raise RRCacheError(f"{max_error!r} is not an error threshold", "--max-error",
                               hint="give a mean RGB L2 error >= 0, e.g. 0.01 (profile.json lists the e1..e4 levels)")
        if self.verdict is not None:  # the ceiling answered before training: the original
            from rrcache.model import Selection

            return Selection(None, None, 0.0, float(self.original_ms), 1.0)
        return model_select(self.table, level)

    def write_variant(self, choice, out_dir) -> list[str]:
        """Write the shader files of ``choice`` (a selection) into ``out_dir``: the variant's passes
        and ``manifest.json``; for the original shader only a ``manifest.json`` saying so. The
        shader is loaded again and must still have the profiled hash."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        if choice is None or choice.node is None:
            note = (self.verdict["answer"] if self.verdict is not None
                    else "no cached variant is predicted to beat the original at this error")
            path = out / "manifest.json"
            path.write_text(json.dumps({"rrcache_selection": 1, "node": None, "shader": self.shader,
                                        "note": note}, indent=2) + "\n")
            return [str(path)]
        from rrcache.pipeline import load_for_session, variant_for
        from rrcache.session import load_session

        work = load_for_session(self.shader, load_session(self.session), self.defines)
        if work.shader.hash != self.data.get("shader_hash"):
            raise RRCacheError("the shader changed since it was profiled", str(self.shader),
                               hint="run 'rrcache profile' again")
        variant = variant_for(work, choice.node, int(choice.period), self.algorithm)
        return variant.write(out)

    def to_json(self) -> dict:
        return self.data

    def __repr__(self) -> str:
        return (f"Profile({self.shader!r}, {len(self.trained_nodes)}/{len(self.nodes)} nodes trained, "
                f"original {self.original_ms:.2f} ms)" if isinstance(self.original_ms, float) else "Profile(...)")


def algorithm_line(prof: Profile) -> str:
    """The profile's algorithm, and with ``auto`` what was measured: 'two-pass (auto: two-pass
    0.377, three-pass 0.41 of the original's time)'."""
    times = (prof.data.get("plan") or {}).get("algorithm_times") or {}
    if prof.settings.algorithm != "auto" or not times:
        return prof.algorithm
    measured = ", ".join(f"{name} {value:.3f}" for name, value in sorted(times.items(), key=lambda kv: kv[1]))
    return f"{prof.algorithm} (auto: {measured} of the original's time)"


def load_profile(path) -> Profile:
    """The profile in folder ``path`` (or the ``profile.json`` file itself).

    >>> p = load_profile("marble-marble.rrprofile")    # doctest: +SKIP
    """
    path = Path(path)
    file = path / JSON_NAME if path.is_dir() else path
    if not file.exists():
        raise RRCacheError("no profile here", str(file), hint="give the folder 'rrcache profile' wrote (--out)")
    try:
        data = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise RRCacheError(f"cannot read the profile ({err})", str(file), hint="run 'rrcache profile' again") from None
    if not isinstance(data, dict) or "rrcache_profile" not in data:
        raise RRCacheError("not an rrcache profile (no 'rrcache_profile' key)", str(file),
                           hint="give the profile.json that 'rrcache profile' wrote")
    if data["rrcache_profile"] != PROFILE_VERSION:
        raise RRCacheError(f"profile version {data['rrcache_profile']!r}; this rrcache reads {PROFILE_VERSION}",
                           str(file), hint="run 'rrcache profile' again with this rrcache")
    return Profile(data, file.parent)


def select(profile_or_path, max_error: float):
    """``rrcache.select(profile, max_error)``: the choice for a :class:`Profile` or a profile path.

    >>> rrcache.select("marble-marble.rrprofile", 0.02).period    # doctest: +SKIP
    35
    """
    prof = profile_or_path if isinstance(profile_or_path, Profile) else load_profile(profile_or_path)
    return prof.select(max_error)


def default_out_dir(shader_path, session_path) -> Path:
    """``<shader stem>-<session stem>.rrprofile`` in the current folder.

    >>> default_out_dir("shaders/marble.glsl", "sessions/orbit.json").name
    'marble-orbit.rrprofile'
    """
    return Path.cwd() / f"{Path(shader_path).stem}-{Path(session_path).stem}.rrprofile"


def profile(shader_path, session_path, out_dir=None, settings: Optional[TrainingSettings] = None,
            defines: Optional[Mapping[str, str]] = None, progress: Optional[ProgressFn] = None,
            fresh: bool = False, plots: bool = True) -> Profile:
    """Profile ``shader_path`` over the session file ``session_path`` into ``out_dir`` (see the
    module docstring) and return the :class:`Profile`. Resumes from a store in ``out_dir``
    trained with the same shader, session and settings; ``fresh=True`` moves it aside first.
    ``progress`` receives :class:`~rrcache.profile.train.ProgressEvent` objects. A
    ``KeyboardInterrupt`` leaves the store consistent (every finished run stays) and propagates.

    >>> p = profile("noise.frag", "orbit.json", "out/", TrainingSettings(periods=(2, 4, 8)))  # doctest: +SKIP
    >>> [s.label for s in p.selections]                                                      # doctest: +SKIP
    ['e1', 'e2', 'e3', 'e4']
    """
    import rrcache
    from rrcache.pipeline import load_for_session
    from rrcache.session import load_session

    session = load_session(session_path)
    work = load_for_session(shader_path, session, defines)
    resolved = (settings or TrainingSettings()).resolved(session)
    out = Path(out_dir) if out_dir is not None else default_out_dir(shader_path, session_path)
    if out.exists() and not out.is_dir():
        raise RRCacheError("the output path is a file, not a folder", str(out), hint="give a folder with --out")
    key = StoreKey(work.shader.hash, session.hash, resolved.key_hash(), rrcache.__version__, resolved.key_json())
    store = ProfileStore.open(out / STORE_NAME, key, fresh=fresh)
    started = time.time()
    try:
        store.begin_run()
        result = train(work, session, resolved, store, progress)
        prof = _assemble(work, session, shader_path, session_path, resolved, result, store, progress)
        _write_outputs(prof, out, work, plots)
        store.end_run("done")
        _write_times(prof, out, store, time.time() - started)
    except KeyboardInterrupt:
        store.end_run("interrupted")
        store.close()
        raise
    except BaseException:
        try:
            store.end_run("failed")
        finally:
            store.close()
        raise
    store.close()
    return prof


def _write_times(prof: Profile, out: Path, store, run_wall_s: float) -> None:
    """Add to profile.json the wall time of this invocation (``run_wall_s``) and the
    precomputation time: every invocation on this store added up (``precompute_s``), so a
    resumed profile counts the time of its earlier runs too (an invocation killed outright left
    no finish time and is not counted)."""
    total = 0.0
    for row in store.run_log():
        if row["finished"] is not None:
            total += float(row["finished"]) - float(row["started"])
    prof.data["run_wall_s"] = run_wall_s
    prof.data["precompute_s"] = total
    prof.data["invocations"] = len(store.run_log())
    tmp = out / (JSON_NAME + ".tmp")
    tmp.write_text(json.dumps(_finite(prof.data), indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, out / JSON_NAME)


def _assemble(work, session, shader_path, session_path, settings, result: TrainingResult, store, progress) -> Profile:
    by_id = {n.id: n for n in work.table.nodes}
    nodes = []
    for nid in result.order:
        entry = by_id[nid]
        node = NodeProfile(nid, entry.type, entry.line, entry.column, entry.text, list(entry.call_chain),
                           int(entry.cost), trained=nid in result.trained, note=result.notes.get(nid))
        runs = [r for r in store.error_runs(nid) if r.period in settings.periods]
        node.periods = [r.period for r in runs]
        node.errors = [r.mean_error for r in runs]
        node.hit_rates = [r.hit_rate for r in runs]
        node.psnrs = [r.psnr for r in runs]
        if node.trained:
            ef, pf = result.error_fits[nid], result.perf_fits[nid]
            node.alpha, node.lam = float(ef.alpha), float(ef.lam)
            node.error_quality, node.error_r2 = str(ef.quality), float(ef.r2)
            node.t_hit, node.t_miss, node.perf_quality = float(pf.t_hit), float(pf.t_miss), str(pf.quality)
            node.error_fit, node.perf_fit = _fit_json(ef), _fit_json(pf)
        nodes.append(node)
    hit = result.hit_fit
    data = {
        "rrcache_profile": PROFILE_VERSION,
        "shader": str(Path(shader_path).resolve()),
        "session": str(Path(session_path).resolve()),
        "defines": dict(work.defines),
        "shader_hash": work.shader.hash,
        "session_hash": session.hash,
        "settings": settings.to_json(),
        "nodes": [dataclasses.asdict(n) for n in nodes],
        "trained": len(result.trained),
        "untrained": list(result.untrained),
        "budget_stopped": result.budget_stopped,
        "plan": result.plan.to_json() if result.plan is not None else None,
        "mu": float(hit.mu) if hit is not None else None,
        "mu_quality": str(hit.quality) if hit is not None else None,
        "hit_fit": _fit_json(hit),
        "overhead_ms": result.overhead_ms,
        "original_ms": result.original_ms,
        "pixels": result.pixels,
        "training_wall_s": result.spent_s,
        "counts": result.counts,
        "ceiling": result.ceiling.to_json() if result.ceiling is not None else None,
        # the relative noise of the original's repeated timing-run times, and whether the
        # machine's load made the timings unreliable (above 10%)
        "timing_noise": result.noise,
        "timing_reliable": result.noise <= UNRELIABLE_NOISE,
        "verdict": _verdict(result.ceiling) if result.stopped else None,
        "selections": [],
    }
    prof = Profile(_finite(data))
    if result.trained and settings.validate:
        from rrcache.profile.validate import validate

        rows = validate(work, session, settings, store, prof.table, progress,
                        window=result.plan.timing_window if result.plan is not None else None,
                        algorithm=prof.algorithm)
        texts = {n.id: n.text for n in nodes}
        prof.selections = [SelectionReport(r.label, r.max_error, r.node, r.period, texts.get(r.node),
                                           r.predicted_error, r.predicted_ms, r.predicted_speedup, r.measured_error,
                                           r.measured_psnr, r.measured_ms, r.measured_original_ms,
                                           r.measured_speedup, r.hit_rate, r.frames) for r in rows]
        # the counts were taken before validation: take them again
        prof.counts = prof.data["counts"] = dict(result.counts, validations=store.counts()["validations"])
    elif result.trained:
        from rrcache.model import select as model_select, thresholds

        texts = {n.id: n.text for n in nodes}
        for label, level in zip(("e1", "e2", "e3", "e4"), thresholds(prof.table, 4)):
            c = model_select(prof.table, float(level))
            prof.selections.append(SelectionReport(label, float(level), c.node, c.period, texts.get(c.node),
                                                   float(c.predicted_error), float(c.predicted_ms),
                                                   float(c.predicted_speedup)))
    return prof


def _verdict(ceiling) -> dict:
    """What profile.json says when the ceiling stopped the profile before training."""
    return {"choice": "original", "ceiling": ceiling.speedup, "min_gain": ceiling.min_gain,
            "answer": f"keep the original shader: no cached variant can reach {ceiling.min_gain:.2f}× here "
                      f"(ceiling {ceiling.speedup:.2f}×)",
            "reason": ceiling.reason(), "changes": ceiling.changes()}


def _write_outputs(prof: Profile, out: Path, work, plots: bool) -> None:
    from rrcache.pipeline import variant_for

    out.mkdir(parents=True, exist_ok=True)
    for sel in prof.selections:
        folder = out / "optimized" / sel.label
        if folder.exists():
            for old in folder.iterdir():
                if old.is_file():
                    old.unlink()
        if sel.node is None:
            prof.write_variant(sel, folder)
        else:
            variant_for(work, sel.node, int(sel.period), prof.algorithm).write(folder)
        sel.files = str(folder.relative_to(out))
    prof.path = out
    prof._where = str(out / JSON_NAME)
    prof.data["selections"] = [_finite(dataclasses.asdict(s)) for s in prof.selections]
    if prof.verdict is not None:  # stopped before training: nothing to plot or report
        prof.write_variant(None, out / "optimized" / "original")
        plots = False
    if plots:
        from rrcache.profile.plots import write_plots

        prof.data["plots"] = [str(Path(p).relative_to(out)) for p in write_plots(prof, out)]
        from rrcache.report import write_report

        write_report(prof, out, work=work)
    tmp = out / (JSON_NAME + ".tmp")
    tmp.write_text(json.dumps(_finite(prof.data), indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, out / JSON_NAME)
