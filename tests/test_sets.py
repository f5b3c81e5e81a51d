"""Sets of several cached nodes in the profiler (:mod:`rrcache.model.sets`,
:mod:`rrcache.profiler.sets`).

- the combination rule: one node is its own single-node prediction; disjoint nodes add their
  differences from the original; a nested inner node's saving is taken back once where the outer
  hits; the union layout's lock-step share γ_U makes a set slower than the per-node layout;
- the search finds the pairs (and triples) that improve a front of disjoint nodes, every one
  predicted faster than each single option of no larger error, and none when the same nodes
  nest (their savings overlap);
- the choice: a trained set stands in for the single-node choice only when admissible and
  measured faster; ``pick`` respects the levels and its limit;
- on the tiny scene of ``test_profile`` (real GL, real nlopt): which node feeds which; a pair
  trained through the profiler's stage (error within the sum rule's bound, time measured, kept in
  the store and not trained again); ``profile.json`` keeps the sets and reads a document without
  them; the set validated beside the original with the fallback of today; the tradeoff plot.
"""
from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest

from rrcache.model import ModelTable, synthetic_table
from rrcache.model.sets import SetOption, better, pick, search, set_prediction
from rrcache.profiles import TrainingSettings, load_profile
from rrcache.profiles.document import Profile
from scene_files import SETTINGS, write_scene


def _table(nested: bool = False):
    """Two nodes that each save half of a pixel's cost (t_miss 1.05, t_hit 0.55 ms per pixel,
    one pixel, original 1 ms), errors 0.01 at long periods, and a third, cheap node."""
    return ModelTable(["a", "b", "c"], alpha=[0.01, 0.01, 0.002], lam=[0.3, 0.3, 0.3],
                      t_hit=[0.55, 0.55, 0.95], t_miss=[1.05, 1.05, 1.05], t_overhead=[0.0, 0.0, 0.0],
                      mu=0.9, pixels=1.0, original_ms=1.0)


def test_one_node_is_its_single_prediction():
    t = synthetic_table(6, seed=4)
    for i in range(6):
        for p in (2, 7, 50):
            e, ms = set_prediction(t, [i], [p])
            assert e == pytest.approx(float(t.E[i, p - 1])) and ms == pytest.approx(float(t.T[i, p - 1]))


def test_disjoint_nodes_add_their_savings_and_nesting_takes_one_back():
    t = _table()
    e, ms = set_prediction(t, [0, 1], [10, 20])
    assert e == pytest.approx(float(t.E[0, 9] + t.E[1, 19]))
    assert ms == pytest.approx(float(t.T[0, 9] + t.T[1, 19] - t.original_ms))
    # b inside a: where a hits, a's saving already held b's computation
    _, nested = set_prediction(t, [0, 1], [10, 20], feeds={(1, 0)})
    gamma_a = 0.9 * (1 - 1 / 10)
    assert nested == pytest.approx(ms + gamma_a * 0.5)
    # the union layout saves only where both hit
    _, union = set_prediction(t, [0, 1], [10, 20], layout="union")
    assert union > ms


def test_search_finds_the_pairs_that_improve_the_front():
    t = _table()
    found = search(t)
    assert found and all(len(o.nodes) >= 2 for o in found)
    for o in found:
        rows = [t.node_ids.index(n) for n in o.nodes]
        e, ms = set_prediction(t, rows, o.periods)
        assert (o.predicted_error, o.predicted_ms) == pytest.approx((e, ms))
        # faster than every single option (and the original) of no larger error, by the margin
        singles = [float(t.T[i, j]) for i in range(3) for j in range(1, 50) if t.E[i, j] <= e] + [t.original_ms]
        assert ms <= min(singles) * (1 - 0.03) + 1e-12
    assert any(set(o.nodes) == {"a", "b"} for o in found)
    # nested, a and b overlap: the pair saves no more than the outer alone
    assert not any(set(o.nodes) == {"a", "b"} for o in search(t, feeds={(1, 0)}))


def test_triples_only_where_they_pay():
    # three disjoint nodes, each saving a third of the pixel's cost: a triple beats every pair
    t = ModelTable(["a", "b", "c"], alpha=[0.01] * 3, lam=[0.3] * 3, t_hit=[0.7] * 3, t_miss=[1.02] * 3,
                   t_overhead=[0.0] * 3, mu=0.9, pixels=1.0, original_ms=1.0)
    found = search(t, max_nodes=3)
    triples = [o for o in found if len(o.nodes) == 3]
    assert triples and {tuple(sorted(o.nodes)) for o in triples} == {("a", "b", "c")}
    for o in triples:
        e, ms = set_prediction(t, [0, 1, 2], [o.periods[o.nodes.index(n)] for n in "abc"])
        assert (o.predicted_error, o.predicted_ms) == pytest.approx((e, ms))
    assert not [o for o in search(t, max_nodes=2) if len(o.nodes) == 3]
    # nested in a chain (a inside b inside c): each inner's saving is already in its outer's, and
    # no pair or triple pays
    assert search(t, feeds={(0, 1), (1, 2), (0, 2)}) == []


def test_better_and_pick():
    opt = SetOption(["a", "b"], [10, 20], predicted_error=0.02, predicted_ms=0.3, predicted_psnr=38.0, gain=2.0)
    from rrcache.selection import Selection, CachedNode

    single = Selection((CachedNode("a", 50),), 0.01, 0.55, 1 / 0.55)
    assert better(single, [opt], 1.0, max_error=0.05) is None  # not trained
    opt.trained, opt.trained_error, opt.trained_ms, opt.trained_psnr = True, 0.018, 0.4, 39.0
    assert better(single, [opt], 1.0, max_error=0.05) is opt
    assert better(single, [opt], 1.0, max_error=0.01) is None  # not admissible
    assert better(single, [opt], 1.0, min_psnr=40.0) is None
    assert better(single.replace(predicted_ms=0.35), [opt], 1.0, max_error=0.05) is None  # not faster
    sel = opt.selection(1.0, label="e3")
    assert sel.multi and sel.nodes == ("a", "b") and sel.periods == (10, 20)
    assert sel.predicted_ms == 0.4 and sel.predicted_speedup == pytest.approx(2.5)
    other = SetOption(["a", "c"], [5, 5], predicted_error=0.005, predicted_ms=0.5, gain=1.2)
    third = SetOption(["b", "c"], [5, 5], predicted_error=0.005, predicted_ms=0.6, gain=1.1)
    # at error 0.01 only `other` is admissible and faster than the level's single choice (0.7 ms)
    assert pick([opt, other, third], [(0.01, None, 0.7)], limit=1) == [other]
    assert [o.nodes for o in pick([opt, other, third], [(0.01, None, 0.7)], limit=2)] == [["a", "c"], ["a", "b"]]


# ---------------------------------------------------------------------- real GL on the tiny scene
@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    from rrcache.pipeline import load_for_session
    from rrcache.profiler import profile
    from rrcache.session import load_session

    folder = tmp_path_factory.mktemp("sets")
    shader, session_path = write_scene(folder)
    prof = profile(shader, session_path, folder / "out", TrainingSettings(**SETTINGS, validate=False, max_sets=2))
    session = load_session(session_path)
    return prof, load_for_session(shader, session), session, folder


def _by_text(work, start):
    return next(n.id for n in work.table.nodes if n.text.startswith(start))


def _exact(work, text):
    return next(n.id for n in work.table.nodes if n.text == text)


def test_feeds_follows_expressions_and_variables(tiny, gl_ctx):
    from rrcache.profiler.sets import feeds

    _, work, _, _ = tiny
    noise = _exact(work, "0.5 + 0.25 * wave(p, 1.0) + 0.125 * wave(p, 2.1) + 0.0625 * wave(p, 4.3)")
    inner = _exact(work, "0.5 + 0.25 * wave(p, 1.0) + 0.125 * wave(p, 2.1)")
    albedo = _by_text(work, "mix(vec3(0.9")
    color = _by_text(work, "albedo * (0.2")
    rel = feeds(work.table, [noise, albedo, color])
    assert (0, 1) in rel          # n is read by the albedo through the variable n
    assert (1, 2) in rel and (0, 2) in rel
    assert (1, 0) not in rel and (2, 1) not in rel and (2, 0) not in rel
    assert feeds(work.table, [noise, inner]) == {(1, 0)}   # inside the expression


def test_a_pair_is_trained_kept_and_validated(tiny, gl_ctx, monkeypatch):
    from rrcache.profiler import sets as stage
    from rrcache.profiler.validate import slower_beyond_noise, validate
    from rrcache.profiles.store import ProfileStore, read_store

    prof, work, session, folder = tiny
    albedo = _by_text(work, "mix(vec3(0.9")
    wave = next(n for n in prof.trained_nodes if n.text.startswith("0.0625 * wave"))
    option = SetOption([albedo, wave.id], [8, 4])
    settings = prof.settings
    store_path = folder / "out" / "profile.sqlite"
    from rrcache.profiles.store import StoreKey
    import rrcache

    key = StoreKey(prof.shader_hash, prof.session_hash, settings.key_hash(), rrcache.__version__, settings.key_json())
    store = ProfileStore.open(store_path, key)
    try:
        stage.train_options(prof, work, session, settings, store, [option])
    finally:
        store.close()
    assert option.trained, option.note
    e_a = prof.node(albedo).errors[prof.node(albedo).periods.index(8)]
    e_b = wave.errors[wave.periods.index(4)]
    # the error rule: at most the sum of the singles' measured errors, at least the larger one's half
    assert 0.5 * max(e_a, e_b) <= option.trained_error <= 1.10 * (e_a + e_b), (option.trained_error, e_a, e_b)
    assert option.trained_ms > 0 and option.trained_psnr > 20 and option.trained_s > 0
    # kept: a second stage reads it back without rendering
    monkeypatch.setattr(stage, "train_set", lambda *a, **k: (_ for _ in ()).throw(AssertionError("rendered again")))
    again = SetOption([albedo, wave.id], [8, 4])
    store = ProfileStore.open(store_path, key)
    try:
        stage.train_options(prof, work, session, settings, store, [again])
    finally:
        store.close()
    assert again.trained and again.trained_error == option.trained_error and again.trained_ms == option.trained_ms
    monkeypatch.undo()

    # profile.json keeps the set; a document without "sets" still loads
    prof.sets = [option]
    prof.write(folder / "doc")
    back = load_profile(folder / "doc")
    assert back.sets == [option]
    data = json.loads((folder / "doc" / "profile.json").read_text())
    del data["sets"]
    assert Profile.from_json(data).sets == []

    # selection: the set where it is admissible and measured faster than the single choice
    back.sets = [option]
    level = option.trained_error
    alone = Profile.from_json(data).select(level)
    chosen = back.select(level)
    faster = option.trained_ms < min(alone.predicted_ms, back.original_ms) if alone.parts else \
        option.trained_ms < back.original_ms
    assert chosen.multi == faster
    if chosen.multi:
        assert chosen.periods == (8, 4) and chosen.predicted_ms == option.trained_ms

    # rrcache select returns it the same way
    proc = subprocess.run([sys.executable, "-m", "rrcache", "select", str(folder / "doc"), "--max-error", repr(level),
                           "--json"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    answer = json.loads(proc.stdout)
    assert (answer.get("nodes") == [albedo, wave.id]) == faster
    assert answer["period"] == ([8, 4] if faster else alone.period)

    # validation as for any choice (docs/levels.md): measured beside the original, standing only
    # where its quality meets the level and its repeats clear the gain worth having
    from rrcache.model.levels import speed_miss

    sel = option.selection(float(prof.original_ms), label="e3", max_error=level, algorithm=prof.algorithm)
    with ProfileStore.open(store_path, key) as store:
        out = validate(work, session, dataclasses.replace(settings, validation_frames=6), store, [sel],
                       candidates=back.front_candidates)
    stood = out[0]
    assert stood.measured
    if stood.multi:
        assert stood.measured_error > 0 and not slower_beyond_noise(stood.speedups)
        assert speed_miss(stood.speedups, settings.min_gain) is None and stood.level_met
    else:
        assert albedo in stood.fallback and any(why in stood.fallback for why in (
            "slower than the original in every repeat", "below the gain worth having",
            "a repeat measured it slower than the original", "above the level"))
    with read_store(store_path) as store:
        assert any(v.multi for v in store.validations())
    if stood.multi:
        # a set stands only where it measured at least the single choice it displaced
        from rrcache.profiler.sets import keep_faster

        back.path = folder / "out"
        with ProfileStore.open(store_path, key) as store:
            kept = keep_faster(back, work, session, dataclasses.replace(settings, validation_frames=6), store,
                               [stood])[0]
            single = next(v for v in store.validations() if v.label == "e3~single")
        assert single.measured and not single.multi
        if stood.measured_speedup >= single.measured_speedup:
            assert kept.multi and kept.key == stood.key
        else:
            assert kept.key == single.key and "below the single-node choice" in kept.fallback


def test_the_tradeoff_plot_shows_sets(tiny, tmp_path):
    from rrcache.report.plots import plot_tradeoff

    prof, _, _, _ = tiny
    ids = [n.id for n in prof.trained_nodes[:2]]
    opt = SetOption(ids, [8, 4], predicted_error=0.01, predicted_ms=float(prof.original_ms) * 0.9, gain=1.1,
                    trained=True, trained_error=0.012, trained_ms=float(prof.original_ms) * 0.95, trained_psnr=35.0)
    prof.sets = [opt]
    try:
        paths = plot_tradeoff(prof, tmp_path)
    finally:
        prof.sets = []
    png = next(p for p in paths if str(p).endswith(".png"))
    assert open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n"


def test_the_bench_keeps_a_set_only_where_it_beats_the_single_choice(tiny):
    """The bench profiles without validation and measures the selections itself; it applies the
    profiler's keep-faster rule to its own measurements (Marble's two-node e4 measured 2.78x
    beside a 3.47x single node in a full bench). The rule is checked here with given speed-ups
    standing for the bench's measurements (tests/test_bench_paper.py runs the real ones)."""
    from rrcache.profiler.sets import prefer_singles, single_choices

    prof, work, _session, _folder = tiny
    albedo = _by_text(work, "mix(vec3(0.9")
    wave = next(n for n in prof.trained_nodes if n.text.startswith("0.0625 * wave"))
    option = SetOption([albedo, wave.id], [8, 4], trained=True, trained_error=0.001, trained_ms=0.5,
                       trained_psnr=45.0)
    back = Profile.from_json(prof.to_json())
    back.sets = [option]
    single = single_choices(back)["e3"]  # (on this tiny scene, the original shader)
    assert not single.multi
    pair = option.selection(float(back.original_ms), label="e3", max_error=single.max_error)
    assert pair.multi

    def measured(speedup):
        def measure(sel):
            return sel.with_measurement(0.001, 45.0, 1.0, speedup, speedup, 0.9, 10, (speedup,) * 3)
        return measure

    seen = []
    slow_pair = measured(1.5)(pair)
    out = prefer_singles(back, [slow_pair], lambda s: seen.append(s.label) or measured(2.0)(s))
    assert seen == ["e3~single"] and out[0].key == single.key and out[0].label == "e3"
    assert "measured 1.50× (1.50–1.50), below the single-node choice's 2.00×" in out[0].fallback
    fast_pair = measured(2.5)(pair)
    assert prefer_singles(back, [fast_pair], measured(2.0)) == [fast_pair]
    # no set: nothing measured again
    assert prefer_singles(back, [measured(2.0)(single)], lambda s: 1 / 0)[0].key == single.key


def test_the_explorer_measures_a_set_it_cannot_show(tiny, gl_ctx):
    """A level whose choice is several nodes at once: the notebook's explorer shows why there
    are no frames and still measures it (a fresh-clone CI run's demo profile chose a set at load
    4, and the explorer raised instead)."""
    from rrcache.explorer import Explorer

    prof, work, _, _ = tiny
    albedo = _by_text(work, "mix(vec3(0.9")
    wave = next(n for n in prof.trained_nodes if n.text.startswith("0.0625 * wave"))
    option = SetOption([albedo, wave.id], [8, 4])
    option.trained, option.trained_error, option.trained_ms, option.trained_psnr = True, 0.01, 1e-3, 40.0
    chosen = option.selection(float(prof.original_ms), max_error=1.0, algorithm=prof.algorithm)
    assert chosen.multi and not chosen.choice.has_frames
    prof = dataclasses.replace(prof)
    prof.select = lambda max_error: chosen.replace(max_error=max_error)
    ui = Explorer(prof, value=1.0, measure=True)
    assert ui.error is None, ui.status.value
    assert ui.choice.key == chosen.key and ui.images is None
    assert len(ui.frames.children) == 1 and "has no frames here" in ui.frames.children[0].value
    m = ui.measured
    assert m is not None and not m["stored"] and m["frames"] > 0 and 0 < m["hit_rate"] < 1
    assert "rendering" not in ui.summary.value and "speed-up <b>" in ui.summary.value
