"""The refresh bounds (rrcache/bench/refresh_bound.py): the oracles keep what a level affords and
no other ranking keeps more; one real run of the Trashcan's reordered sum."""
import math

import numpy as np
import pytest

from rrcache.bench.refresh_bound import (FrameErrors, frame_errors, kept_hit_rate, measure, per_block_periods,
                                         speedup_bound)

SIZE = (16, 16)


def _random_frames(seed: int, count: int = 3, size=SIZE, scale: float = 0.05):
    """Heavy-tailed errors (as the Trashcan's) on 80% hits; the first two rows are not covered."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        covered = np.ones(size, bool)
        covered[:2] = False
        hits = (rng.random(size) < 0.8) & covered
        se = np.where(hits, rng.random(size) ** 6 * scale, 0.0)
        spread = np.where(hits, rng.random(size), 0.0)
        out.append(FrameErrors(se, hits, spread, int(covered.sum()), float(se.sum())))
    return out


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_oracle_keeps_at_least_what_ranking_by_contrast_keeps(seed):
    frames = _random_frames(seed)
    for block in (1, 2, 4):
        for level in (20.0, 25.0, 30.0, 35.0):
            oracle = kept_hit_rate(frames, level, block, "oracle")
            contrast = kept_hit_rate(frames, level, block, "contrast")
            # greedy by error per hit is optimal up to the one block it stops at
            assert oracle >= contrast - block * block / sum(f.covered for f in frames)


def test_the_contrast_rule_refreshes_the_largest_spread_first():
    # two hits: the one of larger spread errs less; the contrast rule refreshes it all the same
    se = np.array([[0.01, 0.09]])
    f = FrameErrors(se, np.ones((1, 2), bool), np.array([[0.1, 0.9]]), 2)
    level = 10 * math.log10(2 / 0.05)  # a budget of 0.05: one of the two must go
    assert kept_hit_rate([f], level, 1, "oracle") == 0.5
    assert kept_hit_rate([f], level, 1, "contrast") == 0.5
    f.spread = np.array([[0.9, 0.1]])  # now the spread points at the cheap hit: the costly one stays
    assert kept_hit_rate([f], level, 1, "contrast") == 0.0


def test_a_stricter_level_keeps_fewer_hits_and_a_loose_one_keeps_them_all():
    frames = _random_frames(7)
    hits = sum(int(f.hits.sum()) for f in frames) / sum(f.covered for f in frames)
    rates = [kept_hit_rate(frames, level) for level in (0.0, 20.0, 30.0, 40.0, 60.0)]
    assert rates == sorted(rates, reverse=True)
    assert rates[0] == pytest.approx(hits)
    assert rates[-1] < hits
    # blocks refresh whole: never more kept than pixel by pixel
    assert kept_hit_rate(frames, 30.0, 4) <= kept_hit_rate(frames, 30.0, 1)


def test_the_budget_is_over_every_pixel_and_the_rate_over_covered_ones():
    frames = _random_frames(11, count=1, size=(32, 32))
    f = frames[0]
    level = 30.0
    order = np.sort(f.se[f.hits])
    budget = f.se.size * 10 ** (-level / 10)  # every pixel of the frame, covered or not
    count = int(np.searchsorted(np.cumsum(order), budget, side="right"))
    assert 0 < count < len(order)
    assert order[:count].sum() <= budget < order[:count + 1].sum()
    assert kept_hit_rate(frames, level) == pytest.approx(count / f.covered)
    assert f.covered < f.se.size


def test_blocks_that_do_not_fill_the_edge_count_as_refreshed():
    hits = np.ones((5, 5), bool)
    f = FrameErrors(np.zeros((5, 5)), hits, np.zeros((5, 5)), 25)
    assert kept_hit_rate([f], 30.0, 1) == 1.0
    assert kept_hit_rate([f], 30.0, 2) == pytest.approx(16 / 25)
    assert kept_hit_rate([f], 30.0, 4) == pytest.approx(16 / 25)
    assert per_block_periods({4: [f]}, 30.0, 2)[0] == pytest.approx(16 / 25)


def test_a_period_per_block_keeps_more_as_periods_are_added_and_no_more_than_the_frame_oracle():
    # errors grow with the period: the long period's hits err more
    short = _random_frames(3, scale=0.01)
    long = _random_frames(3, scale=0.2)
    for f in long:  # more hits at the long period: every covered pixel (rows 2 on)
        f.hits[2:] = True
    for level in (25.0, 30.0):
        alone, _ = per_block_periods({4: short}, level, 4)
        both, counts = per_block_periods({4: short, 16: long}, level, 4)
        assert both >= alone - 16 / sum(f.covered for f in short)
        # every block that hits somewhere is counted once (the uncovered rows 0-1 share blocks
        # with covered rows 2-3)
        assert sum(counts.values()) == (SIZE[0] // 4) * (SIZE[1] // 4)
        _, by_pixel = per_block_periods({4: short, 16: long}, level, 1)
        assert sum(by_pixel.values()) == (SIZE[0] - 2) * SIZE[1]  # uncovered pixels never hit
        # one period for the whole run can only keep less than choosing anew in every frame
        assert alone <= kept_hit_rate(short, level, 4) + 16 / sum(f.covered for f in short)


def test_speedup_bound_is_the_original_at_no_hits_and_the_limit_at_all_hits():
    assert speedup_bound(0.0, 0.3) == 1.0
    assert speedup_bound(1.0, 0.25) == 4.0


def test_frame_errors_leave_misses_and_uncovered_pixels_out_of_the_hits():
    img = np.full((4, 4, 4), 0.5, np.float32)
    ref = np.zeros_like(img)
    hit_map = np.zeros((4, 4), bool)
    hit_map[:2] = True
    mask = np.ones((4, 4), bool)
    mask[0, 0] = False
    f = frame_errors(img, ref, hit_map, mask)
    assert f.covered == 15
    assert int(f.hits.sum()) == 7
    assert f.se[f.hits] == pytest.approx(0.25)
    assert not f.se[~f.hits].any() and not f.spread[~f.hits].any()
    assert f.total_se == pytest.approx(16 * 0.25)  # the frame's error counts misses too


def test_a_real_run_of_the_reordered_sum(gl_ctx):
    bound = measure("shaders/trashcan.glsl", "sessions/trashcan.json", "n1931", periods=[2, 4], frames=5,
                    level_db=0.0, resolution=(64, 48), blocks=(1, 4), hit_cost=0.3)
    assert bound.hit_cost_source == "given"
    assert bound.frames == 5 and bound.resolution == [64, 48]
    assert [r["period"] for r in bound.runs] == [2, 4]
    for run in bound.runs:
        assert 0.0 < run["measured_hit_rate"] < 1.0
        # pooled PSNR never above the mean of per-frame PSNRs
        assert run["pooled_psnr"] <= run["measured_psnr"] + 1e-6
        rows = {(r["block"], r["rule"]): r for r in run["rows"]}
        assert set(rows) == {(1, "oracle"), (1, "contrast"), (4, "oracle"), (4, "contrast")}
        # at 0 dB every hit is affordable: the oracle keeps exactly the run's hits
        assert rows[(1, "oracle")]["hit_rate"] == pytest.approx(run["measured_hit_rate"], abs=1e-9)
        assert rows[(1, "oracle")]["speedup_bound"] == pytest.approx(speedup_bound(run["measured_hit_rate"], 0.3))
    # every block takes the period of most hits when the level affords everything
    assert [r["block"] for r in bound.per_block] == [1, 4]
    assert bound.per_block[0]["hit_rate"] >= bound.runs[1]["measured_hit_rate"] - 1e-9
    strict = measure("shaders/trashcan.glsl", "sessions/trashcan.json", "n1931", periods=[4], frames=5,
                     level_db=bound.runs[1]["pooled_psnr"] + 3.0, resolution=(64, 48), blocks=(1,), hit_cost=0.3)
    kept = {r["rule"]: r["hit_rate"] for r in strict.runs[0]["rows"]}
    assert math.isfinite(strict.runs[0]["pooled_psnr"])
    assert 0.0 < kept["oracle"] < strict.runs[0]["measured_hit_rate"]
    assert kept["contrast"] <= kept["oracle"] + 1.0 / (64 * 48 * 4)
    assert strict.per_block == []  # one period: nothing to choose between
