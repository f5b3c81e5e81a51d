"""The unit of measurement (rrcache.runs, rrcache.harness.execute): one RunSpec → one RunResult,
executed by one function; specs and results are plain records an executor can ship anywhere."""
from __future__ import annotations

import math
import pickle
import subprocess
import sys

import numpy as np
import pytest

from rrcache.harness.cached import CachedRenderer
from rrcache.harness.execute import Bench, LocalExecutor, execute
from rrcache.harness.metrics import mean_l2
from rrcache.harness.renderer import Renderer
from rrcache.kinds import compile as compile_spec
from rrcache.pipeline import WorkSource, load_bench, load_for_session
from rrcache.runs import PSNR_CAP, RunResult, RunSpec
from rrcache.runtime.spec import VariantSpec
from rrcache.session import load_session

SHADER, SESSION = "shaders/glslviewer_basic.glsl", "sessions/marble.json"
SIZE = (48, 36)


@pytest.fixture(scope="module")
def bench():
    session = load_session(SESSION)
    work = load_for_session(SHADER, session)
    with Bench(work, session) as b:
        yield b


def _node(bench):
    return max(bench.work.table.nodes, key=lambda n: n.cost).id


class RecordingExecutor(LocalExecutor):
    """The local executor, keeping every spec it was given in ``made`` (in order)."""

    def __init__(self, bench):
        super().__init__(bench)
        self.made: list = []

    def run(self, specs, on_frame=None):
        specs = list(specs)
        self.made.extend(specs)
        return super().run(specs, on_frame)


def test_an_error_run_measures_what_the_renderers_measure(gl_ctx, bench):
    """An error run's rows are the error of each frame of the cached variant (from an empty
    cache, in order) against the original's frame, as the harness computes it by hand."""
    spec = VariantSpec("cache", (_node(bench),), "two-pass", periods=(2,))
    result = execute(RunSpec("error", spec, (0, 1, 2, 3), SIZE), bench)
    assert result.complete and [r.frame for r in result.frames] == [0, 1, 2, 3]
    with Renderer(bench.work.prepared, bench.session, SIZE) as original, \
            CachedRenderer(compile_spec(bench.work, spec), bench.session, bench.work.prepared, SIZE, spec) as cached:
        for row, index in zip(result.frames, range(4)):
            ref, got = original.render_frame(index), cached.render_frame(index)
            assert row.error == pytest.approx(float(mean_l2(got.image, ref.image, ref.mask)[0]))
            assert (row.hits, row.misses, row.covered) == (got.hits, got.misses, got.covered_pixels)
    assert result.frames[0].hits == 0 and result.steady_error == pytest.approx(
        np.mean([r.error for r in result.frames[1:]]))
    assert all(r.psnr <= PSNR_CAP for r in result.frames)


def test_one_renderer_serves_every_period(gl_ctx, bench):
    """Consecutive runs of one compiled variant reuse the renderer (no setup), and each starts
    from an empty cache: the same run twice measures the same."""
    base = VariantSpec("cache", (_node(bench),), "three-pass")
    runs = [RunSpec("error", base.with_runtime(periods=(p,)), (0, 1, 2), SIZE) for p in (1, 4, 1)]
    a, b, c = list(LocalExecutor(bench).run(runs))
    assert a.setup_s > 0 and b.setup_s == 0 and c.setup_s == 0
    assert [r.error for r in a.frames] == [r.error for r in c.frames]
    assert a.frames[2].error == 0.0 and b.frames[2].error > 0.0  # Δn = 1 recomputes everything


@pytest.mark.parametrize("window", [None, (40, 30, 160, 120)])
def test_a_run_on_a_used_renderer_measures_what_a_fresh_one_does(gl_ctx, window):
    """The cache's reset clears its targets: a run after another run on the same renderer (the
    training's runs share one) gives the per-frame errors of the same run on a new renderer, to
    the bit, in a window too."""
    session = load_session(SESSION)
    work = load_for_session(SHADER, session)
    node = max(work.table.nodes, key=lambda n: n.cost).id
    base = VariantSpec("cache", (node,), "three-pass")
    first, second = (RunSpec("error", base.with_runtime(periods=(p,)), tuple(range(6)), (320, 240), window)
                     for p in (2, 50))
    with Bench(work, session) as used:
        _, after = LocalExecutor(used).run([first, second])
    with Bench(work, session) as fresh:
        alone = execute(second, fresh)
    assert after.setup_s == 0 and [r.error for r in after.frames] == [r.error for r in alone.frames]


def test_timing_runs_time_each_frame_beside_the_original(gl_ctx, bench):
    spec = VariantSpec("cache", (_node(bench),), "two-pass", periods=(8,))
    timing = execute(RunSpec("timing", spec, (1, 3), SIZE, color_format="rgba8"), bench)
    assert [r.frame for r in timing.frames] == [1, 3] and timing.spec.timed
    assert all(r.ms > 0 and r.original_ms > 0 and r.hits is not None for r in timing.frames)
    alone = execute(RunSpec("timing", None, (1, 3), SIZE, color_format="rgba8"), bench)
    assert all(r.ms > 0 and math.isnan(r.original_ms) and r.covered > 0 for r in alone.frames)
    overhead = execute(RunSpec("overhead", spec, (1,), (8, 8), color_format="rgba8"), bench)
    assert overhead.frames[0].ms > 0 and math.isnan(overhead.frames[0].original_ms)
    compared = execute(RunSpec("compare", spec, (0, 1, 2), SIZE), bench)
    assert len(compared.frames) == 3 and compared.ms > 0 and compared.original_ms > 0


def test_a_compare_run_measures_flip_and_the_temporal_error_as_validation_does(gl_ctx, bench):
    """A compare run asked for FLIP on some frames and the temporal error gives what
    rrcache.harness.perceptual computes on the same renders by hand (validation's figures); the
    errors and hits are the harness's compare's; other runs cannot ask for them."""
    from rrcache.harness.cached import compare
    from rrcache.harness.perceptual import FrameQuality

    spec = VariantSpec("cache", (_node(bench),), "two-pass", periods=(3,))
    frames = (0, 1, 2, 3, 4)
    run = execute(RunSpec("compare", spec, frames, SIZE, flip_frames=(1, 4), temporal=True), bench)
    quality = FrameQuality((1, 4))
    by_hand = compare(compile_spec(bench.work, spec), bench.session, bench.work.prepared, frames, spec,
                      resolution=SIZE, on_frame=lambda row, got, ref: quality.add(row.index, got.image, ref.image))
    assert [r.error for r in run.frames] == [float(f.mean_error) for f in by_hand.frames]
    assert [(r.hits, r.misses) for r in run.frames] == [(f.hits, f.misses) for f in by_hand.frames]
    assert len(run.flips) == 2 and list(run.flips) == pytest.approx(quality.flips)
    assert run.temporal_psnr == pytest.approx(quality.temporal_psnr)
    plain = execute(RunSpec("compare", spec, frames, SIZE), bench)
    assert plain.flips == () and plain.temporal_psnr is None
    with pytest.raises(ValueError, match="compare runs"):
        RunSpec("error", spec, frames, SIZE, flip_frames=(1,))


def test_specs_and_results_are_plain_records(gl_ctx, bench):
    """Pickled and back they are equal (what a distributed executor ships), and a timing run says
    it is one (a distributed executor keeps those alone on a host)."""
    spec = RunSpec("error", VariantSpec("nodes", ("n1", "n2"), periods=(50, 4)), range(3), SIZE, key=("set", "x"))
    assert pickle.loads(pickle.dumps(spec)) == spec and hash(spec) == hash(pickle.loads(pickle.dumps(spec)))
    assert not spec.timed and RunSpec("timing", None, (1,), SIZE).timed
    result = execute(RunSpec("error", VariantSpec("cache", (_node(bench),), periods=(2,)), (0, 1), SIZE), bench)
    back = pickle.loads(pickle.dumps(result))  # (NaN times: compared as what they pickle to)
    assert isinstance(back, RunResult) and repr(back) == repr(result) and back.spec == result.spec
    with pytest.raises(ValueError, match="measure must be one of"):
        RunSpec("guess", None, (0,), SIZE)


def test_a_worker_loads_its_bench_from_a_work_source(tmp_path):
    """A fresh process given only the pickled WorkSource and RunSpec (what a Dask worker gets)
    measures what this process measures."""
    session = load_session(SESSION)
    work = load_for_session(SHADER, session)
    source = WorkSource.of(work, session)
    spec = RunSpec("error", VariantSpec("cache", (max(work.table.nodes, key=lambda n: n.cost).id,), periods=(4,)),
                   (0, 1, 2), SIZE)
    (tmp_path / "job.pkl").write_bytes(pickle.dumps((source, spec)))
    code = ("import pickle, sys\nfrom rrcache.pipeline import load_bench\nfrom rrcache.harness.execute import execute\n"
            "source, spec = pickle.loads(open(sys.argv[1], 'rb').read())\n"
            "with load_bench(source) as bench:\n    result = execute(spec, bench)\n"
            "open(sys.argv[2], 'wb').write(pickle.dumps(result))\n")
    proc = subprocess.run([sys.executable, "-c", code, str(tmp_path / "job.pkl"), str(tmp_path / "out.pkl")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    there = pickle.loads((tmp_path / "out.pkl").read_bytes())
    with load_bench(source) as bench:
        here = execute(spec, bench)
    assert [r.error for r in there.frames] == [r.error for r in here.frames]
    assert [(r.hits, r.misses) for r in there.frames] == [(r.hits, r.misses) for r in here.frames]


def test_validation_measures_through_the_executor_it_is_given(gl_ctx, bench, tmp_path):
    """Validation's renders are compare runs of the executor given (the profile's): one error run
    with FLIP and the temporal error over the validation frames, three timed repeats; the
    measured selection holds what they measured."""
    from rrcache.profiler.validate import REPEATS, validate
    from rrcache.profiles import TrainingSettings
    from rrcache.profiles.store import ProfileStore, StoreKey
    from rrcache.selection import CachedNode, Selection

    node = _node(bench)
    settings = TrainingSettings(periods=(2, 4), resolution=SIZE, validation_frames=5).resolved(bench.session)
    choice = Selection((CachedNode(node, 4),), 0.01, 1.0, 2.0, label="e1", max_error=0.02, algorithm="two-pass")
    key = StoreKey("s" * 64, "t" * 64, settings.key_hash(), "0", settings.key_json())
    executor = RecordingExecutor(bench)
    made = executor.made
    with ProfileStore.open(tmp_path / "v.sqlite", key) as store:
        [row] = validate(bench.work, bench.session, settings, store, [choice], fallback=False, executor=executor)
    assert [s.measure for s in made] == ["compare"] * (1 + REPEATS)
    error = made[0]
    assert error.temporal and error.flip_frames and error.frames == tuple(range(5))
    assert error.resolution == tuple(bench.session.resolution) and error.variant.periods == (4,)
    assert all(s.color_format == settings.timing_format and not s.flip_frames for s in made[1:])
    assert row.parts == choice.parts and row.frames == 5 and row.measured_flip is not None
    assert len(row.speedups) == REPEATS and row.measured_temporal_psnr is not None
    # the executor given stays open (it is the profile's): it still runs
    assert next(executor.run([RunSpec("compare", error.variant, (0, 1), SIZE)])).frames
