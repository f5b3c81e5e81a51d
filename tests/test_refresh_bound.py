"""The refresh bound (rrcache/bench/refresh_bound.py): the oracle keeps what a level affords and no
rule that ranks otherwise keeps more; one real run of the Trashcan's reordered sum."""
import math

import numpy as np
import pytest

from rrcache.bench.refresh_bound import FrameErrors, frame_errors, kept_hit_rate, measure, speedup_bound


def _random_frames(seed: int, count: int = 3, size=(16, 16)):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        hits = rng.random(size) < 0.8
        se = np.where(hits, rng.random(size) ** 6 * 0.05, 0.0)  # heavy-tailed, as the Trashcan's
        spread = np.where(hits, rng.random(size), 0.0)
        out.append(FrameErrors(se, hits, spread, size[0] * size[1]))
    return out


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_oracle_keeps_at_least_what_ranking_by_contrast_keeps(seed):
    frames = _random_frames(seed)
    for block in (1, 2, 4):
        for level in (20.0, 25.0, 30.0, 35.0):
            oracle = kept_hit_rate(frames, level, block, "oracle")
            contrast = kept_hit_rate(frames, level, block, "contrast")
            # greedy by error per hit is optimal up to the one block it stops at
            assert oracle >= contrast - block * block / (16 * 16 * 3)


def test_a_stricter_level_keeps_fewer_hits_and_a_loose_one_keeps_them_all():
    frames = _random_frames(7)
    hits = sum(int(f.hits.sum()) for f in frames) / sum(f.covered for f in frames)
    rates = [kept_hit_rate(frames, level) for level in (0.0, 20.0, 30.0, 40.0, 60.0)]
    assert rates == sorted(rates, reverse=True)
    assert rates[0] == pytest.approx(hits)
    assert rates[-1] < hits
    # blocks refresh whole: never more kept than pixel by pixel
    assert kept_hit_rate(frames, 30.0, 4) <= kept_hit_rate(frames, 30.0, 1)


def test_the_kept_hits_error_is_within_the_level():
    frames = _random_frames(11, count=1, size=(32, 32))
    f = frames[0]
    level = 30.0
    kept = kept_hit_rate(frames, level)
    # refresh the worst hits by hand until the pooled error fits; the share left is the oracle's
    order = np.sort(f.se[f.hits])
    budget = f.se.size * 10 ** (-level / 10)
    count = int(np.searchsorted(np.cumsum(order), budget, side="right"))
    assert kept == pytest.approx(count / f.covered)
    assert order[:count].sum() <= budget < order[:count + 1].sum()


def test_speedup_bound_is_the_original_at_no_hits_and_the_limit_at_all_hits():
    assert speedup_bound(0.0, 0.3) == 1.0
    assert speedup_bound(1.0, 0.25) == 4.0


def test_frame_errors_leave_misses_and_uncovered_pixels_out():
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


def test_a_real_run_of_the_reordered_sum(gl_ctx):
    bound = measure("shaders/trashcan.glsl", "sessions/trashcan.json", "n1931", period=4, frames=5,
                    level_db=0.0, resolution=(64, 48), blocks=(1, 4), hit_cost=0.3)
    assert bound.hit_cost_source == "given"
    assert bound.frames == 5 and bound.resolution == [64, 48]
    assert 0.0 < bound.measured_hit_rate < 1.0
    # pooled PSNR never above the mean of per-frame PSNRs
    assert bound.pooled_psnr <= bound.measured_psnr + 1e-6
    rows = {(r["block"], r["rule"]): r for r in bound.rows}
    assert set(rows) == {(1, "oracle"), (1, "contrast"), (4, "oracle"), (4, "contrast")}
    # at 0 dB every hit is affordable: the oracle keeps exactly the run's hits
    assert rows[(1, "oracle")]["hit_rate"] == pytest.approx(bound.measured_hit_rate, abs=1e-9)
    assert rows[(1, "oracle")]["speedup_bound"] == pytest.approx(speedup_bound(bound.measured_hit_rate, 0.3))
    strict = measure("shaders/trashcan.glsl", "sessions/trashcan.json", "n1931", period=4, frames=5,
                     level_db=bound.pooled_psnr + 3.0, resolution=(64, 48), blocks=(1,), hit_cost=0.3)
    kept = {r["rule"]: r["hit_rate"] for r in strict.rows}
    assert math.isfinite(strict.pooled_psnr)
    assert 0.0 < kept["oracle"] < strict.measured_hit_rate
    assert kept["contrast"] <= kept["oracle"] + 1.0 / (64 * 48 * 4)
