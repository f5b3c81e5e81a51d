"""Running a :class:`~rrcache.runs.RunSpec`: :func:`execute`, the one function that turns a run into
its :class:`~rrcache.runs.RunResult`, and the in-process executor.

:class:`Bench` is what a process keeps to run many specs of one shader over one session: the
shader work and the session (loaded once per process or worker: :func:`rrcache.pipeline.load_bench`), the compiled
variants (:func:`rrcache.kinds.compile`), the original's reference frames of the error runs
(rendered once per frame set, window and resolution), the timed original of each timing set-up,
and the last cached renderer (one renderer serves every period, threshold and blend of a variant:
:meth:`~rrcache.harness.cached.CachedRenderer.respec`). An executor runs specs on a bench;
:class:`LocalExecutor` does it in this process, in order. Another executor (a Dask one, say) needs
only to build a bench per worker with :func:`rrcache.pipeline.load_bench` (from a plain
:class:`rrcache.pipeline.WorkSource`) and call :func:`execute` there: specs and results are plain
records.

>>> bench = load_bench(WorkSource("shaders/marble.glsl", "sessions/marble.json"))      # doctest: +SKIP
>>> result = execute(RunSpec("error", spec, tuple(range(8)), (640, 480)), bench)      # doctest: +SKIP
"""
from __future__ import annotations

import dataclasses
import math
import time
from typing import Callable, Iterable, Iterator, Optional

from rrcache import kinds
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.metrics import mean_l2, psnr
from rrcache.harness.renderer import Renderer
from rrcache.harness.segments import restart, run_order, warmup_of
from rrcache.runs import PSNR_CAP, FrameRow, RunResult, RunSpec

#: ``on_frame(spec, units)``: progress, ``units`` frames of ``spec.cost`` done
FrameCallback = Callable[[RunSpec, int], None]


class Bench:
    """A process's state for running specs over one shader work and session (see the module
    docstring). Close it (or use ``with``) to release its GL objects."""

    def __init__(self, work, session):
        self.work = work
        self.session = session
        self._references: dict = {}
        self._originals: dict = {}
        self._cached: Optional[tuple] = None

    # ---------------------------------------------------------------- what the runs share
    def references(self, spec: RunSpec, on_frame: Optional[FrameCallback] = None) -> list:
        """The original's frames of an error run's frames, window and resolution (rendered once)."""
        key = (spec.frames, spec.resolution, spec.window)
        if key not in self._references:
            refs = []
            with Renderer(self.work.prepared, self.session, spec.resolution, window=spec.window) as renderer:
                for index in spec.frames:
                    refs.append(renderer.render_frame(index))
                    if on_frame is not None:
                        on_frame(spec, 1)
            self._references[key] = refs
        return self._references[key]

    def original(self, spec: RunSpec) -> Renderer:
        """The timed original of a timing set-up (resolution, window, format, clock), kept."""
        key = (spec.resolution, spec.window, spec.color_format, spec.clock)
        if key not in self._originals:
            self._originals[key] = Renderer(self.work.prepared, self.session, spec.resolution, window=spec.window,
                                            color_format=spec.color_format, clock=spec.clock)
        return self._originals[key]

    def cached(self, spec: RunSpec) -> tuple[CachedRenderer, float]:
        """The cached renderer of ``spec`` and the seconds it took to make (0 when the last one
        serves: same passes, size, window, format and clock; its runtime fields are set anew)."""
        key = (spec.variant.compiled(), spec.resolution, spec.window, spec.color_format, spec.clock)
        if self._cached is not None and self._cached[0] == key:
            renderer = self._cached[1]
            renderer.respec(spec.variant)
            return renderer, 0.0
        self.release_cached()
        start = time.perf_counter()
        variant = kinds.compile(self.work, spec.variant)
        renderer = CachedRenderer(variant, self.session, self.work.prepared, spec.resolution, spec.variant,
                                  window=spec.window, color_format=spec.color_format, clock=spec.clock)
        self._cached = (key, renderer)
        return renderer, time.perf_counter() - start

    def release_cached(self) -> None:
        if self._cached is not None:
            self._cached[1].release()
            self._cached = None

    def close(self) -> None:
        """Release every renderer (the compiled variants stay in the compile cache)."""
        self.release_cached()
        for renderer in self._originals.values():
            renderer.release()
        self._originals.clear()
        self._references.clear()

    def __enter__(self) -> "Bench":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def execute(spec: RunSpec, bench: Bench, on_frame: Optional[FrameCallback] = None) -> RunResult:
    """Run ``spec`` on ``bench`` and return what it measured (see :mod:`rrcache.runs` for what each
    measure renders), with when it ran (``started``/``finished``; ``host`` is an executor's to
    set). ``on_frame(spec, units)`` after each step, for progress."""
    started = time.time()
    result = _execute(spec, bench, on_frame)
    return dataclasses.replace(result, started=started, finished=time.time())


def _execute(spec: RunSpec, bench: Bench, on_frame: Optional[FrameCallback]) -> RunResult:
    step = (lambda n=1: on_frame(spec, n)) if on_frame is not None else (lambda n=1: None)
    start = time.perf_counter()
    if spec.measure == "reference":
        refs = bench.references(spec, on_frame)
        rows = tuple(FrameRow(r.index, covered=int(r.covered_pixels), ms=float(r.ms)) for r in refs)
        return RunResult(spec, rows, time.perf_counter() - start)
    if spec.variant is None:  # the original alone, timed
        original = bench.original(spec)
        rows = []
        for index in spec.frames:
            got = original.render_frame(index)
            rows.append(FrameRow(index, covered=int(got.covered_pixels), ms=float(got.ms)))
            step()
        return RunResult(spec, tuple(rows), time.perf_counter() - start, notes=tuple(original.notes))
    if spec.measure == "compare":
        return _compare(spec, bench, step, start)
    refs = bench.references(spec) if spec.measure == "error" else None
    cached, setup_s = bench.cached(spec)
    original = bench.original(spec) if spec.measure == "timing" else None
    rows: list = []
    cached.reset()
    if spec.measure == "error":
        complete = _error_rows(spec, cached, refs, rows, step)
    else:  # timing (beside the original) or overhead (alone): each frame after a warm-up frame
        complete = True
        for index in spec.frames:
            ref = original.render_frame(index) if original is not None else None
            cached.reset()
            cached.render_frame(index - 1)
            got = cached.render_frame(index)
            rows.append(FrameRow(index, hits=got.hits, misses=got.misses, covered=int(got.covered_pixels),
                                 ms=float(got.ms), original_ms=float(ref.ms) if ref is not None else math.nan))
            step(3 if original is not None else 1)
            if spec.strict_payload and cached.payload_dtype != spec.variant.payload:
                complete = False
                break
    return RunResult(spec, tuple(rows), time.perf_counter() - start, setup_s, cached.payload_dtype,
                     tuple(cached.notes) + ((cached.payload_note,) if cached.payload_note else ()), complete)


def _error_rows(spec: RunSpec, cached: CachedRenderer, refs: list, rows: list, step) -> bool:
    """An error run's rows into ``rows``: its frames against the original's ``refs``, segment by
    segment, each later one after its warm-up (:mod:`rrcache.harness.segments`; frames 0..N−1 are
    one segment from an empty cache, as validation renders them). False when ``strict_payload``
    stopped it."""
    by_index = dict(zip(spec.frames, refs))
    for segment in run_order(spec.frames, warmup_of(spec.variant)):
        restart(cached, segment[0][0])
        for index, compared in segment:
            got = cached.render_frame(index)
            if not compared:
                continue
            ref = by_index[index]
            err, left_out = mean_l2(got.image, ref.image, ref.mask)
            rows.append(FrameRow(index, float(err), min(float(psnr(got.image, ref.image)), PSNR_CAP), got.hits,
                                 got.misses, int(got.covered_pixels), int(left_out), float(got.ms)))
            step()
            if spec.strict_payload and cached.payload_dtype != spec.variant.payload:
                return False
    return True


def _compare(spec: RunSpec, bench: Bench, step, start: float) -> RunResult:
    from rrcache.harness.cached import compare
    from rrcache.harness.perceptual import FrameQuality

    variant = kinds.compile(bench.work, spec.variant)
    setup = time.perf_counter() - start
    quality = FrameQuality(spec.flip_frames) if spec.flip_frames or spec.temporal else None

    def on_frame(row, got, ref):
        if quality is not None:
            quality.add(row.index, got.image, ref.image)
        step(2)

    # the session's own size is asked as such (a target too large then names the session's file)
    size = None if spec.resolution == tuple(bench.session.resolution) else spec.resolution
    result = compare(variant, bench.session, bench.work.prepared, spec.frames, spec.variant,
                     resolution=size, window=spec.window, color_format=spec.color_format,
                     clock=spec.clock, on_frame=on_frame)
    rows = tuple(FrameRow(f.index, float(f.mean_error), min(float(f.psnr), PSNR_CAP), f.hits, f.misses, int(f.covered),
                          int(f.left_out), float(f.ms), float(f.original_ms)) for f in result.frames)
    return RunResult(spec, rows, time.perf_counter() - start, setup, result.payload_dtype, tuple(result.notes),
                     flips=tuple(quality.flips) if quality is not None else (),
                     temporal_psnr=quality.temporal_psnr if quality is not None and spec.temporal else None)


class LocalExecutor:
    """Runs specs in this process, in order, on one :class:`Bench` (``on_frame`` for progress).

    The executor interface (what another executor provides too): :meth:`run` takes the specs (and
    an ``on_frame`` for this call's progress, else the executor's) and yields one
    :class:`~rrcache.runs.RunResult` per spec (here in order, as each finishes; a caller that
    stops iterating stops the runs not begun); a ``KeyboardInterrupt`` stops it between frames
    (the results already yielded stand); :meth:`close` releases what it holds. Optional:
    :meth:`release` drops what the runs so far kept (reference frames, renderers) and leaves the
    executor usable; the profile calls it when training is over, before validation."""

    def __init__(self, bench: Bench, on_frame: Optional[FrameCallback] = None):
        self.bench = bench
        self.on_frame = on_frame

    def run(self, specs: Iterable[RunSpec], on_frame: Optional[FrameCallback] = None) -> Iterator[RunResult]:
        for spec in specs:
            yield execute(spec, self.bench, on_frame or self.on_frame)

    def release(self) -> None:
        self.bench.close()  # a bench closed stays usable: what it keeps is made again when asked

    def close(self) -> None:
        self.bench.close()
