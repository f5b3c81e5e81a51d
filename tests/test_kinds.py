"""The kinds of choice (rrcache.kinds): one class per kind behind one registry, the variant spec the
compiler returns and the runtime takes whole, the compile cache, and a new kind added in one module
(tests/tiled_kind.py: nothing else changes)."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from rrcache import kinds
from rrcache.errors import RRCacheError
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.execute import Bench, LocalExecutor
from rrcache.pipeline import load_for_session
from rrcache.profiler.collect import Collector
from rrcache.profiler.jobs import RunShapes
from rrcache.profiles.settings import TrainingSettings
from rrcache.profiles.store import ProfileStore, StoreKey
from rrcache.runtime.multi import MultiCacheRuntime
from rrcache.runtime.spec import VariantSpec
from rrcache.selection import AdaptiveNode, AmortizedLoop, CachedNode, Selection
from rrcache.session import load_session

SHADER, SESSION = "shaders/glslviewer_basic.glsl", "sessions/marble.json"


@pytest.fixture(scope="module")
def loaded():
    session = load_session(SESSION)
    return load_for_session(SHADER, session), session


def test_the_registry_names_each_kind_by_its_parts():
    assert {k.name for k in kinds.all_kinds()} >= {"cache", "nodes", "amortize", "adaptive"}
    one, two = CachedNode("n1", 4), CachedNode("n2", 50)
    assert kinds.kind_of((one,)).name == "cache" and kinds.kind_of((one, two)).name == "nodes"
    assert kinds.kind_of((AmortizedLoop("e1", 4, 0.6),)).name == "amortize"
    assert kinds.kind_of((AdaptiveNode("n1", 100, 0.01),)).name == "adaptive"
    assert kinds.kind_of(()) is None and Selection.original(1.0).choice is None
    with pytest.raises(RRCacheError, match="no kind of choice caches cache \\+ amortize"):
        kinds.kind_of((one, AmortizedLoop("e1", 4, 0.6)))
    with pytest.raises(RRCacheError, match="unknown kind 'nope'"):
        kinds.parts_from_json([{"kind": "nope"}], "parts")


def test_a_variant_spec_is_what_the_compiler_returns_and_the_runtime_takes(gl_ctx, loaded):
    """The compiler returns the spec with the passes; the runtime is made from a spec whole (one
    node: CacheRuntime; several: MultiCacheRuntime, chosen by the compiled passes, not by the type
    of an argument); a multi-node variant has no faked one-node fields."""
    work, session = loaded
    a, b = sorted(work.table.nodes, key=lambda n: -n.cost)[:2]
    pair = Selection((CachedNode(a.id, 50), CachedNode(b.id, 4)), 0.0, 1.0, 1.0, algorithm="three-pass")
    spec = kinds.spec_for(pair)
    assert spec == VariantSpec("nodes", (a.id, b.id), "three-pass", periods=(50, 4))
    variant = kinds.compile(work, spec)
    assert variant.spec == spec and variant.node_id is None and variant.node_text is None
    assert [n["id"] for n in variant.nodes] == [a.id, b.id] and variant.describe().startswith("nodes ")
    with CachedRenderer(variant, session, work.prepared, (32, 24), spec) as cached:
        assert isinstance(cached.runtime, MultiCacheRuntime) and cached.runtime.period == (50, 4)
    with pytest.raises(ValueError, match="not the one these passes were compiled for"):
        variant.runtime(gl_ctx, {}, (8, 8), VariantSpec("cache", (a.id,)))


def test_the_compile_cache_compiles_a_variant_once(loaded):
    work, _ = loaded
    node = max(work.table.nodes, key=lambda n: n.cost).id
    kinds.clear_compile_cache()
    first = kinds.compile(work, VariantSpec("cache", (node,), "two-pass", periods=(2,)))
    again = kinds.compile(work, VariantSpec("cache", (node,), "two-pass", periods=(50,), block=8))
    assert again.passes is first.passes and again.spec.periods == (50,) and first.spec.periods == (2,)
    kinds.compile(work, VariantSpec("cache", (node,), "three-pass"))
    counts = kinds.compile_counts()
    assert counts[VariantSpec("cache", (node,), "two-pass")] == 1 and sum(counts.values()) == 2


def test_each_chosen_variant_is_compiled_once_per_profile(tmp_path):
    """A profile (training, validation, the selections' files and the report's frames) compiles
    each variant once, and says how many it compiled. Every render of training and validation is
    a run of the profile's one executor."""
    from test_profile import SETTINGS, write_scene
    from test_runs import RecordingExecutor
    from rrcache.harness.execute import Bench
    from rrcache.profiler import profile

    made = []

    def factory(work, session):
        executor = RecordingExecutor(Bench(work, session))
        executor.made = made
        return executor

    shader, session = write_scene(tmp_path)
    kinds.clear_compile_cache()
    prof = profile(shader, session, tmp_path / "out", TrainingSettings(**SETTINGS, budget_s=2.0,
                                                                       validation_frames=4), executor=factory)
    validations = [s for s in made if s.key[:1] == ("validate",)]
    assert {s.measure for s in made} >= {"reference", "error", "timing"}
    # each choice validation measured (which ones depends on this machine's timings): one error
    # run with FLIP and the temporal error, three timed (tests/test_runs.py checks the figures)
    rendered = {s.key[1] for s in validations}
    assert all(s.measure == "compare" for s in validations) and len(validations) == 4 * len(rendered)
    assert sum(1 for s in validations if s.temporal and s.flip_frames) == len(rendered)
    counts = kinds.compile_counts()
    assert counts and max(counts.values()) == 1, counts
    assert prof.counts["compiles"] == sum(counts.values())
    chosen = {kinds.spec_for(s).compiled() for s in prof.threshold_selections() + prof.selections if s.parts}
    assert all(counts[spec] == 1 for spec in chosen), (chosen, counts)
    # which nodes stand depends on this machine's timings: make a trained node the choice, and
    # its files and the report's frames take the variant training compiled
    from rrcache.profiler.run import _write_outputs

    node = prof.trained_nodes[0].id
    prof.selections = [Selection((CachedNode(node, 8),), 0.01, 1.0, 2.0, label="e1", algorithm=prof.algorithm)]
    work = load_for_session(str(shader), load_session(str(session)))
    _write_outputs(prof, tmp_path / "out", work, plots=True)
    assert (tmp_path / "out" / "optimized" / "e1" / "manifest.json").exists()
    assert kinds.compile_counts() == counts and counts[VariantSpec("cache", (node,), prof.algorithm)] == 1


@pytest.fixture
def tiled():
    from tiled_kind import KIND, TiledNode

    kinds.register(KIND)
    yield KIND, TiledNode
    kinds.unregister(KIND.name)


def test_a_new_kind_is_one_module(gl_ctx, loaded, tmp_path, tiled):
    """tests/tiled_kind.py is the whole kind: registered, its selections read and write as any
    other's in profile.json, compile and run with its runtime options, its training runs execute
    and land in its own store table through the collector, and the report and the command line
    describe it, with no other file of rrcache changed."""
    from rrcache.profiles.document import _read_dataclass
    from rrcache.report.data import _plot_label
    from rrcache.report.explore import selections_html

    kind, TiledNode = tiled
    work, session = loaded
    node = max(work.table.nodes, key=lambda n: n.cost)
    sel = Selection((TiledNode(node.id, 8, 4, text=node.text),), 0.01, 2.0, 1.5, label="e2", algorithm="two-pass")
    # the document: written and read back with the document's checks
    assert sel.kind == "tiled" and sel.node == node.id and sel.period == 8
    back = _read_dataclass(Selection, sel.to_json(), "selections[1]", "profile.json")
    assert back == sel and back.describe() == f"{node.id} Δn=8 tiled 4×4"
    with pytest.raises(RRCacheError, match=r"selections\[1\]\.parts\[0\]\.block: must be one of"):
        _read_dataclass(Selection, {**sel.to_json(), "parts": [{"kind": "tiled", "node": "n1", "period": 8,
                                                                "block": 3}]}, "selections[1]", "profile.json")
    # compiled once, run with its own refresh pattern
    spec = kinds.spec_for(sel, block=8, refresh="random", depth_epsilon=1e-3)
    assert spec.refresh == "tiled" and spec.block == 4 and spec.kind == "tiled"
    variant = kinds.compile(work, spec)
    with CachedRenderer(variant, session, work.prepared, (32, 24), spec) as cached:
        cached.render_frame(0)
        assert cached.runtime._refresh_mode == "tiled" and cached.runtime._block == 4
    # its training: planned by the kind, executed, collected into its table
    settings = TrainingSettings(periods=(2, 8), resolution=(32, 24), frames=4, timing_frames=2).resolved(session)
    shapes = RunShapes.of(settings, session, None, (1, 2))
    runs = [shapes.run(measure, v, key) for measure, v, key in kind.training((node.id, 4), settings, "two-pass")]
    key = StoreKey("s", "t", "u", "v")
    with ProfileStore.open(tmp_path / "profile.sqlite", key) as store, Bench(work, session) as bench:
        collector = Collector(store)
        for result in LocalExecutor(bench).run(runs):
            collector.add(result)
        rows = store.conn.execute("SELECT node, period, block, measure FROM tiled_run ORDER BY measure, period").fetchall()
    assert rows == [(node.id, 2, 4, "error"), (node.id, 8, 4, "error"), (node.id, 2, 4, "timing"),
                    (node.id, 8, 4, "timing")]
    # described where selections are shown
    assert f"8 (tiled 4×4)" in selections_html(SimpleNamespace(selections=[sel]))
    assert _plot_label(sel) == {"node": f"{node.id} Δn=8 tiled 4×4", "period": None}
    assert kind.summary(sel) == {"node": node.id, "period": 8, "kind": "tiled", "block": 4}
