"""The profiling run: train, select, validate, and write the profile folder (main paper §4, Fig. 3).

:func:`profile` (``rrcache.profile``, ``rrcache profile``) is the orchestrator: it sits above
the data it writes (:mod:`rrcache.profiles`) and the report that shows it (:mod:`rrcache.report`),
and nothing below imports it. Into the output folder it writes:

- ``profile.sqlite``: every measurement (:mod:`rrcache.profiles.store`); rerunning with the same
  arguments resumes from it, skipping what is stored;
- ``optimized/e1`` … ``optimized/e4``: the shader files of each selection;
- ``tradeoff.png``/``.svg``, ``hitrate.png``, ``validation.png`` (:mod:`rrcache.report.plots`) and
  ``report.html`` (:mod:`rrcache.report.html`), unless ``plots=False``;
- ``profile.json`` (:mod:`rrcache.profiles.document`), last and once.

>>> p = profile("marble.frag", "marble.json", settings=TrainingSettings(budget_s=60))   # doctest: +SKIP
>>> [s.label for s in p.selections]                                                     # doctest: +SKIP
['e1', 'e2', 'e3', 'e4']
"""
from __future__ import annotations

import os
import sqlite3
import time
import warnings
from pathlib import Path
from typing import Mapping, Optional

from rrcache import kinds
from rrcache.atomic import OutputFolder
from rrcache.errors import RRCacheError
from rrcache.harness.execute import Bench, LocalExecutor
from rrcache.glsl.frontend import file_records
from rrcache.profiler.lock import LOCK_NAME, StoreLock
from rrcache.harness.timing import UNRELIABLE_NOISE
from rrcache.model.psnr import frame_spread
from rrcache.profiler.train import ProgressFn, TrainingResult, train
from rrcache.profiles.document import JSON_NAME, NodeProfile, Profile, _fit_json
from rrcache.profiles.settings import TrainingSettings
from rrcache.profiles.store import STORE_NAME, ProfileStore, StoreKey
from rrcache.selection import Selection
from rrcache.choice import write as choice_write


def default_out_dir(shader_path, session_path) -> Path:
    """``<shader stem>-<session stem>.rrprofile`` in the current folder.

    >>> default_out_dir("shaders/marble.glsl", "sessions/orbit.json").name
    'marble-orbit.rrprofile'
    """
    return Path.cwd() / f"{Path(shader_path).stem}-{Path(session_path).stem}.rrprofile"


def profile(shader_path, session_path, out_dir=None, settings: Optional[TrainingSettings] = None,
            defines: Optional[Mapping[str, str]] = None, progress: Optional[ProgressFn] = None,
            fresh: bool = False, plots: bool = True, include_dirs=(), wait: bool = False,
            vertex=None, adaptive=None, executor=None, max_flip: Optional[float] = None) -> Profile:
    """Profile ``shader_path`` over the session file ``session_path`` into ``out_dir`` (see the
    module docstring) and return the :class:`~rrcache.profiles.document.Profile`. Resumes from a
    store in ``out_dir`` trained with the same shader, session and settings; ``fresh=True``
    moves it aside first. Another process profiling into the same folder holds its lock: this one
    raises an error naming it, or with ``wait=True`` waits. ``vertex`` is the user's vertex shader
    file (None: the session's ``"vertex"``, else generated). ``progress`` receives :class:`~rrcache.profiler.train.ProgressEvent`
    objects. A ``KeyboardInterrupt`` leaves the store consistent (every finished run stays) and
    propagates. ``adaptive`` (thresholds): after validation, each selection's node is measured
    with adaptive refresh at these thresholds and replaced where that was measured faster at the
    same level (:mod:`rrcache.profiler.adaptive`). ``executor``: a callable ``(work, session) ->
    executor`` making what runs the training's :class:`~rrcache.runs.RunSpec` s (its
    ``run(specs, on_frame=None)`` yields a :class:`~rrcache.runs.RunResult` per spec, in any order;
    ``close()``); default: in this process (:class:`~rrcache.harness.execute.LocalExecutor`). A
    factory with a ``capacity`` (runs made at once: a Dask cluster's workers,
    :class:`rrcache.cluster.client.Cluster`) buys a larger default plan
    (:mod:`rrcache.profiler.capacity`); an executor with a ``record(capacity)`` has it kept in
    ``Profile.cluster``. ``max_flip``: a fifth level, ``flip``, of mean FLIP at most this
    (:func:`rrcache.profiler.validate.flip_level`; docs/levels.md).

    >>> p = profile("noise.frag", "orbit.json", "out/", TrainingSettings(periods=(2, 4, 8)))  # doctest: +SKIP
    """
    # the run's warnings are kept in profile.json (the report shows them) and raised again at
    # the end for the caller
    raised: list = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                prof = _profile(shader_path, session_path, out_dir, settings, caught, defines=defines,
                                progress=progress, fresh=fresh, plots=plots, include_dirs=include_dirs, wait=wait,
                                vertex=vertex, adaptive=adaptive, executor=executor, max_flip=max_flip)
            finally:
                raised = list(caught)
    finally:
        for w in raised:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return prof


def _profile(shader_path, session_path, out_dir, settings, caught: list, *, defines, progress, fresh, plots,
             include_dirs, wait, vertex, adaptive, executor, max_flip: Optional[float] = None) -> Profile:
    import rrcache
    from rrcache.pipeline import load_for_session
    from rrcache.session import load_session

    session = load_session(session_path)
    work = load_for_session(shader_path, session, defines, include_dirs, vertex=vertex)
    settings = settings or TrainingSettings()
    capacity = None
    if executor is not None and getattr(executor, "capacity", None):
        # an executor that makes several runs at once buys a larger default plan: more training
        # frames and more nodes (rrcache.profiler.capacity)
        from rrcache.profiler.capacity import scaled

        settings, capacity = scaled(settings, session, int(executor.capacity))
    resolved = settings.resolved(session)
    from rrcache.profiler.amortize import estimator_table

    estimator_table(work)  # a malformed '#pragma rrcache estimator': said before anything is trained
    out = Path(out_dir) if out_dir is not None else default_out_dir(shader_path, session_path)
    if out.exists() and not out.is_dir():
        raise RRCacheError("the output path is a file, not a folder", str(out), hint="give a folder with --out")
    key = StoreKey(work.hash, session.hash, resolved.key_hash(), rrcache.__version__, resolved.key_json())
    # one writer per folder: taken before the store is opened (or moved aside by --fresh)
    lock = StoreLock.acquire(out / LOCK_NAME, wait=wait)
    try:
        store = ProfileStore.open(out / STORE_NAME, key, fresh=fresh)
        started = time.time()
        compiled = sum(kinds.compile_counts().values())
        make_executor, runner = executor, None
        try:
            store.begin_run()
            verdict = None
            if not work.table.nodes:  # nothing a cache can hold: the answer is the original, why, its frame time
                result, verdict = _original_only(work, session, resolved), no_node_verdict(work)
                runner = None
            else:
                if resolved.measure_terms:  # the order of sums whose weights do not fold, measured once
                    from rrcache.profiler.terms import scores_for

                    scores = scores_for(work, session, store, progress)
                    if scores:
                        work = load_for_session(shader_path, session, defines, include_dirs, vertex=vertex,
                                                term_scores=scores)
                # one executor for every stage: the shader's variants compiled once (rrcache.kinds.compile),
                # the original's reference frames rendered once
                runner = make_executor(work, session) if make_executor is not None else LocalExecutor(Bench(work, session))
                result = train(work, session, resolved, store, progress, executor=runner)
            prof = _assemble(work, session, shader_path, session_path, resolved, result, store, out, verdict)
            prof.term_scores = dict(work.term_scores)
            if runner is not None:
                prof.sets = _sets(prof, work, session, resolved, store, progress, runner)
                # amortized sampling: the estimators' models, on the same front as the nodes
                from rrcache.profiler.amortize import train_estimators
                prof.estimators = train_estimators(work, session, resolved, store, result, progress, executor=runner)
                if hasattr(runner, "release"):  # the training's reference frames are not needed again
                    runner.release()
            prof.selections = _selections(prof, work, session, resolved, result, store, progress, max_flip, runner)
            if adaptive and prof.selections and resolved.validate:
                from rrcache.profiler.adaptive import extend

                prof.selections = extend(prof, work, session, resolved, tuple(adaptive),
                                         window=result.plan.timing_window if result.plan is not None else None,
                                         store=store, executor=runner)
            prof.warnings = list(dict.fromkeys(str(w.message) for w in caught))
            _write_outputs(prof, out, work, plots)
            # how many variants this invocation compiled (each at most once: the compile cache)
            prof.counts = dict(prof.counts, compiles=sum(kinds.compile_counts().values()) - compiled)
            store.end_run("done")
            _add_times(prof, store, time.time() - started)
            if hasattr(runner, "record"):  # where the runs were made (a Dask cluster's workers)
                prof.cluster = runner.record(capacity)
            prof.write(out)
        except KeyboardInterrupt:
            _end_quietly(store, "interrupted")
            raise
        except BaseException:
            _end_quietly(store, "failed")
            raise
        finally:
            if runner is not None:
                runner.close()
        store.close()
    finally:
        lock.release()
    return prof


def _end_quietly(store, status: str) -> None:
    """Log how the run ended if the store can still be written (a full disk may forbid it; the
    error that stopped the run is the one to report)."""
    try:
        store.end_run(status)
    except (RRCacheError, OSError, sqlite3.Error):
        pass
    finally:
        store.close()


def _add_times(prof: Profile, store, run_wall_s: float) -> None:
    """The wall time of this invocation (``run_wall_s``) and the precomputation time: every
    invocation on this store added up (``precompute_s``), so a resumed profile counts the time of
    its earlier runs too (an invocation killed outright left no finish time and is not counted)."""
    log = store.run_log()
    prof.run_wall_s = run_wall_s
    prof.precompute_s = sum(float(r["finished"]) - float(r["started"]) for r in log if r["finished"] is not None)
    prof.invocations = len(log)


def _assemble(work, session, shader_path, session_path, settings, result: TrainingResult, store,
              out: Path, verdict: Optional[dict] = None) -> Profile:
    """The profile of a training result, before its selections (read back from its own
    document, so that what the run goes on with is what a reader gets); ``verdict``: the answer
    when nothing was trained for a reason other than the ceiling's."""
    by_id = {n.id: n for n in work.table.nodes}
    nodes = []
    for nid in result.order:
        entry = by_id[nid]
        node = NodeProfile(nid, entry.type, entry.line, entry.column, entry.text, list(entry.call_chain),
                           int(entry.cost), trained=nid in result.trained, note=result.notes.get(nid),
                           file=getattr(entry, "file", None))
        runs = [r for r in store.error_runs(nid) if r.period in settings.periods]
        node.periods = [r.period for r in runs]
        node.errors = [r.mean_error for r in runs]
        node.hit_rates = [r.hit_rate for r in runs]
        node.psnrs = [r.psnr for r in runs]
        # how much each run's mean error depends on the frames it covered (the PSNR's ±)
        node.frame_spreads = [frame_spread([f.mean_error for f in store.error_frames(nid, r.period) if not f.left_out])
                              for r in runs]
        if node.trained:
            ef, pf = result.error_fits[nid], result.perf_fits[nid]
            node.alpha, node.lam = float(ef.alpha), float(ef.lam)
            node.error_quality, node.error_r2 = str(ef.quality), float(ef.r2)
            node.t_hit, node.t_miss, node.perf_quality = float(pf.t_hit), float(pf.t_miss), str(pf.quality)
            node.error_fit, node.perf_fit = _fit_json(ef), _fit_json(pf)
        nodes.append(node)
    hit = result.hit_fit
    plan = result.plan
    draft = Profile(
        shader=str(Path(shader_path).resolve()), session=str(Path(session_path).resolve()),
        shader_hash=work.hash, session_hash=session.hash, settings=settings,
        shader_files=file_records(work.shader),
        vertex=os.path.abspath(work.vertex.path) if work.vertex is not None else None,
        vertex_hash=work.vertex.hash if work.vertex is not None else None,
        algorithm=(plan.algorithm if plan is not None and plan.algorithm else settings.fixed_algorithm),
        algorithm_times=dict((plan.algorithm_times if plan is not None else None) or {}),
        filter=(plan.filter if plan is not None and plan.filter else "bilinear"),
        nodes=nodes, defines=dict(work.defines), include_dirs=list(work.include_dirs), plan=plan.to_json() if plan is not None else None,
        untrained=list(result.untrained), budget_stopped=result.budget_stopped,
        mu=float(hit.mu) if hit is not None else None, mu_quality=str(hit.quality) if hit is not None else None,
        hit_fit=_fit_json(hit), overhead_ms=result.overhead_ms, original_ms=result.original_ms,
        pixels=result.pixels, training_wall_s=result.spent_s, counts=dict(result.counts),
        ceiling=result.ceiling.to_json() if result.ceiling is not None else None,
        verdict=verdict if verdict is not None else (_verdict(result.ceiling) if result.stopped else None),
        timing_noise=result.noise, timing_reliable=result.noise <= UNRELIABLE_NOISE,
        psnr_offset_db=_psnr_offset(store, settings, result))
    prof = Profile.from_json(draft.to_json(), str(out / JSON_NAME))
    prof.path = out
    return prof


def _sets(prof: Profile, work, session, settings, store, progress, executor=None) -> list:
    """The sets of several cached nodes predicted to improve the front, the few picked trained
    (:mod:`rrcache.profiler.sets`)."""
    from rrcache.profiler.sets import train_sets

    return train_sets(prof, work, session, settings, store, progress, max_sets=settings.max_sets, executor=executor)


def _psnr_offset(store, settings, result: TrainingResult) -> float:
    """The dB from the training runs' PSNRs (error window) to those of the region validation
    measures (the timing window when there is one, else the frame):
    :func:`rrcache.model.psnr.coverage_offset_db` of the covered fractions."""
    import statistics

    from rrcache.model.psnr import coverage_offset_db
    from rrcache.profiler.train import _window_pixels

    plan = result.plan
    runs = [r for nid in result.trained for r in store.error_runs(nid) if r.frames > 0]
    if plan is None or not runs:
        return 0.0
    width, height = settings.resolution
    error_window = plan.error_window
    train_area = error_window[2] * error_window[3] if error_window else width * height
    train_covered = statistics.mean(r.covered / r.frames for r in runs)
    if plan.timing_window is not None:
        inside = _window_pixels(store, result.trained, settings)
        check_covered = statistics.mean(inside.values()) if inside else 0.0
        check_area = plan.timing_window[2] * plan.timing_window[3]
    else:
        check_covered, check_area = result.pixels, width * height
    return coverage_offset_db(train_covered, train_area, check_covered, check_area)


def _selections(prof: Profile, work, session, settings, result: TrainingResult, store, progress,
                max_flip: Optional[float] = None, executor=None) -> list:
    """The e1..e4 selections: measured beside the original when ``settings.validate``
    (:mod:`rrcache.profiler.validate`, its renders run by ``executor``), else predicted only;
    none without a trained node. Training in a window is checked first either way
    (:mod:`rrcache.profiler.window_check`)."""
    if not result.trained:
        return []
    choices = prof.threshold_selections()
    from rrcache.profiler.validate import Validator

    validator = Validator(work, session, settings, store, progress,
                          window=result.plan.timing_window if result.plan is not None else None,
                          candidates=prof.front_candidates, executor=executor)
    if result.plan is not None and result.plan.error_window is not None:  # trained in a window: check it first
        from rrcache.profiler.window_check import ROUNDS, check_window

        try:
            for _ in range(ROUNDS):  # the checks move the predictions: the levels' choices again, new ones checked
                before = {c.key for c in choices}
                check_window(validator, choices, result.plan.error_frames(settings.frames),
                             estimators=settings.validate)
                if validator.calibration.points:
                    prof.calibration = validator.calibration.to_json()
                    choices = prof.threshold_selections()
                if {c.key for c in choices} <= before:
                    break
        except BaseException:
            validator.close()
            raise
    if not settings.validate:  # predicted only: with what the window check taught the models
        validator.close()
        return choices
    measured = validator.run(choices)
    if max_flip is not None:  # a level of mean FLIP, answered from the measurements above first
        from rrcache.profiler.validate import flip_level

        flip = flip_level(prof, validator, float(max_flip))
        store.add_validation(flip)
        measured.append(flip)
    if any(s.multi for s in measured):  # a set stands only where it beats the single choice it displaced
        from rrcache.profiler.sets import keep_faster

        measured = keep_faster(prof, work, session, settings, store, measured, progress,
                               result.plan.timing_window if result.plan is not None else None, executor)
    prof.calibration = calibration_record(validator)
    prof.measured = [s.replace(files=None) for s in validator.measured.values()]
    # the counts were taken before validation: count the validations now
    prof.counts = dict(prof.counts, validations=store.counts()["validations"])
    return measured


def calibration_record(validator) -> dict:
    """``Profile.calibration`` from a finished validation: the calibration's points, shift and
    spread, and the PSNR predictions' error over every measured choice, raw (the models alone)
    and calibrated (as predicted when it was measured, by the points before it)."""
    from rrcache.model.calibration import prediction_errors

    rows = [s for s in validator.measured.values() if s.parts and not s.exact and s.predicted_psnr is not None
            and s.measured_psnr is not None]
    record = validator.calibration.to_json()
    record["raw"] = prediction_errors([(s.predicted_psnr - float(s.calibration_db or 0.0), s.measured_psnr)
                                       for s in rows])
    record["calibrated"] = prediction_errors([(s.predicted_psnr, s.measured_psnr) for s in rows])
    return record


def _verdict(ceiling) -> dict:
    """What profile.json says when the ceiling stopped the profile before training."""
    return {"choice": "original", "ceiling": ceiling.speedup, "min_gain": ceiling.min_gain,
            "answer": f"keep the original shader: no cached variant can reach {ceiling.min_gain:.2f}× here "
                      f"(ceiling {ceiling.speedup:.2f}×)",
            "reason": ceiling.reason(), "changes": ceiling.changes()}


def _original_only(work, session, settings) -> TrainingResult:
    """The training result of a shader with nothing to train: the original's frame time (the
    median over the timing frames at full resolution) and covered pixels, nothing else."""
    import statistics

    from rrcache.harness.renderer import Renderer
    from rrcache.profiler.train import timing_frame_indices

    full = tuple(int(v) for v in session.resolution)
    with Renderer(work.prepared, session, full, color_format=settings.timing_format) as renderer:
        frames = [renderer.render_frame(i) for i in timing_frame_indices(session.frames, settings.timing_frames)]
    result = TrainingResult(order=[], trained=[], untrained=[], stopped=True)
    if frames:
        result.original_ms = float(statistics.median(f.ms for f in frames))
        result.pixels = float(statistics.mean(f.covered_pixels for f in frames))
    return result


def no_node_verdict(work) -> dict:
    """The answer for a shader with no value a cache can hold (``work.table.nodes`` empty): keep
    the original, why (the analysis's reasons, counted) and what would change it. A shader whose
    every per-pixel value depends on the screen position (a Book of Shaders sketch of
    ``gl_FragCoord``) is said to be one.

    >>> from types import SimpleNamespace as NS
    >>> table = NS(nodes=[], excluded=[NS(reason="screen")] * 3 + [NS(reason="uniform")], shader=None)
    >>> no_node_verdict(NS(table=table))["answer"]
    'keep the original shader: every value it computes per pixel depends on the screen position (gl_FragCoord), which a surface cache cannot hold'
    """
    from collections import Counter

    counts = Counter(x.reason for x in work.table.excluded)
    per_pixel = {r: n for r, n in counts.items() if r not in ("uniform", "type", "duplicate")}
    listed = ", ".join(f"{n} {r}" for r, n in counts.most_common())
    if per_pixel and set(per_pixel) <= {"screen", "derivative"} and counts.get("screen"):
        answer = ("keep the original shader: every value it computes per pixel depends on the screen position "
                  "(gl_FragCoord), which a surface cache cannot hold")
        reason = (f"a reverse reprojection cache keeps values of surface points and fetches them where the surface "
                  f"was last frame; every value this shader computes per pixel is a function of the pixel's "
                  f"position on the screen, so none of them belongs to a surface (the analysis left out {listed})")
    elif counts:
        answer = "keep the original shader: none of the values it computes can be cached"
        reason = f"the analysis left every value out ({listed}; 'rrcache nodes SHADER --all' says why for each)"
    else:
        answer = "keep the original shader: it computes no value a cache could hold"
        reason = "its colour comes from inputs and constants alone"
    return {"choice": "original", "ceiling": None, "min_gain": None, "answer": answer, "reason": reason,
            "changes": ["compute the costly values from surface inputs (v_position, v_objectPosition, v_texcoord, "
                        "v_normal) rather than gl_FragCoord: a reprojection cache follows surfaces as they move",
                        "a screen-space effect is better served by rendering it at a lower resolution or caching it "
                        "in a screen-space texture of your own",
                        "'rrcache nodes SHADER --all' lists every value left out and the reason"]}


def _write_outputs(prof: Profile, out: Path, work, plots: bool) -> None:
    """The shader files of each selection, then (with ``plots``) the plots, the report's frames
    (rendered here, once: :mod:`rrcache.profiler.frames`) and the report, which reads them."""
    kept = []
    # every file by rrcache.atomic's rule: a link placed in the folder (optimized -> elsewhere) is
    # refused, never followed, and the old files of a selection are removed only inside it
    with OutputFolder(out) as root, root.folder("optimized") as optimized:
        for sel in prof.selections:
            with optimized.folder(sel.label) as folder:
                folder.remove_files()
                choice_write(prof, sel, folder, work=work)
            kept.append(sel.replace(files=f"optimized/{sel.label}"))
        answered = prof.verdict is not None  # stopped before training: nothing to plot, the answer to report
        if answered:
            with optimized.folder("original") as folder:
                choice_write(prof, Selection.original(float(prof.original_ms or 0.0)), folder)
    prof.selections = kept
    prof.path = out
    if plots:
        from rrcache.profiler.frames import write_frames
        from rrcache.report import write_report
        from rrcache.report.plots import write_plots

        if not answered:
            prof.plots = [str(Path(p).relative_to(out)) for p in write_plots(prof, out)]
            write_frames(prof, out, work)
        write_report(prof, out)
