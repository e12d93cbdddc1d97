"""Tests for monitor.offline.bootstrap: scene resamples and the measures' intervals."""
import math

import numpy as np
import pytest

from monitor.offline.bootstrap import bootstrap_tables, scene_draws
from monitor.offline.measures import FrameTruth, rmse
from monitor.report.tables import interval_cell


def _truth(condition, targets, hazards):
    return [FrameTruth(condition, "ok", t, h, 1, 0, 0, 0, False) for t, h in zip(targets, hazards)]


def test_draws_take_whole_scenes_as_many_as_each_condition_has():
    scenes = ["a", "a", "b", "c", "c", "c", "d"]
    strata = ["x", "x", "x", "y", "y", "y", "y"]
    frames = {"a": [0, 1], "b": [2], "c": [3, 4, 5], "d": [6]}
    draws = scene_draws(scenes, strata, 300, np.random.default_rng(1))
    seen = set()
    for idx in draws:
        # cut the draw into its scenes again: each is one scene's frames, in order
        k, picked = 0, {"x": 0, "y": 0}
        while k < len(idx):
            scene = scenes[idx[k]]
            n = len(frames[scene])
            assert idx[k:k + n].tolist() == frames[scene]
            picked[strata[idx[k]]] += 1
            seen.add(scene)
            k += n
        assert picked == {"x": 2, "y": 2}
    assert seen == set(frames)
    again = scene_draws(scenes, strata, 300, np.random.default_rng(1))
    assert all(np.array_equal(p, q) for p, q in zip(draws, again))


def test_draws_refuse_a_scene_in_two_conditions_and_unequal_lengths():
    with pytest.raises(ValueError, match="scene 'a' has frames in strata 'x' and 'y'"):
        scene_draws(["a", "a"], ["x", "y"], 1, np.random.default_rng(0))
    with pytest.raises(ValueError, match="2 scene names but 1 strata"):
        scene_draws(["a", "a"], ["x"], 1, np.random.default_rng(0))


def test_two_scenes_give_the_interval_of_each_scene_alone():
    # Scene A: 4 hazard frames, 1 alarmed (risk > 0.5), and one hazard-free frame, not alarmed.
    # Scene B: 2 hazard frames, both alarmed, no hazard-free frame. Resampling two scenes gives
    # AA, AB, BA or BB, each a quarter of the time: the central 95 % of the hit rates runs from
    # A's 1/4 to B's 2/2, and the false-alarm rate is undefined on the BB draws.
    risk = np.array([0.9, 0.1, 0.1, 0.1, 0.2, 0.8, 0.7])
    hazard = [True, True, True, True, False, True, True]
    target = [0.6, 0.5, 0.4, 0.5, 0.1, 0.9, 0.8]
    scenes = ["A"] * 5 + ["B"] * 2
    truth = _truth("nominal", target, hazard)
    intervals, paired = bootstrap_tables(truth, scenes, {"rules": risk}, 0.5, 0.5, None, draws=2000, seed=3)
    assert paired == [] and [r["condition"] for r in intervals] == ["nominal", "all"]
    row = intervals[0]
    assert (row["hit_rate_lo"], row["hit_rate_hi"]) == (0.25, 1.0)
    assert (row["false_alarm_rate_lo"], row["false_alarm_rate_hi"]) == (0.0, 0.0)
    missing = int(row["notes"].split("false-alarm rate undefined on ")[1].split(" of ")[0])
    assert 0.2 * 2000 < missing < 0.3 * 2000  # a quarter of the draws are BB
    # an 80 % hit rate needs every hazard of A (three at 0.1) on the draws with a hazard-free
    # frame, so the threshold passes A's hazard-free 0.2 on each: 1 of 1
    assert (row["fpr80_lo"], row["fpr80_hi"]) == (1.0, 1.0)
    # skill = 1 - RMSE / RMSE of the constant 0.5: its extremes are scene A's and scene B's own
    t = np.array(target)
    skill = [1 - rmse(risk[s], t[s]) / rmse(np.full(t[s].shape, 0.5), t[s]) for s in (slice(0, 5), slice(5, 7))]
    assert row["skill_lo"] == pytest.approx(min(skill), abs=1e-12)
    assert row["skill_hi"] == pytest.approx(max(skill), abs=1e-12)


def test_one_scene_gives_the_measure_itself_and_seeds_reproduce():
    risk = np.array([0.9, 0.2, 0.6, 0.7])  # hazards 0.9, 0.6; hazard-free 0.2, 0.7
    truth = _truth("rain", [0.8, 0.3, 0.5, 0.2], [True, False, True, False])
    first = bootstrap_tables(truth, ["s"] * 4, {"r": risk}, 0.4, 0.5, None, draws=50, seed=9)
    row = first[0][0]
    assert row["hit_rate_lo"] == row["hit_rate_hi"] == 1.0
    assert row["false_alarm_rate_lo"] == row["false_alarm_rate_hi"] == 0.5
    assert row["auroc_lo"] == row["auroc_hi"] == 0.75  # 3 of the 4 pairs ordered: 0.6 < 0.7
    assert row["fpr80_lo"] == row["fpr80_hi"] == 0.5  # both hazards: at >= 0.6, passing 0.7
    assert row["pearson_lo"] == row["pearson_hi"] == pytest.approx(np.corrcoef(risk, [0.8, 0.3, 0.5, 0.2])[0, 1])
    assert row["notes"] == ""
    assert first == bootstrap_tables(truth, ["s"] * 4, {"r": risk}, 0.4, 0.5, None, draws=50, seed=9)


def test_paired_differences_cancel_what_the_scenes_share():
    rng = np.random.default_rng(5)
    n = 60
    target = rng.uniform(0, 1, n)
    base = np.clip(target + rng.normal(0, 0.2, n), 0, 1)
    shifted = base * 0.5 + 0.25  # an affine map of the same risk: the same r on every draw
    truth = _truth("snow", target, rng.random(n) < 0.7)
    scenes = [f"s{k // 6}" for k in range(n)]
    _, paired = bootstrap_tables(truth, scenes, {"kb": base, "other": shifted, "same": base.copy()},
                                 float(target.mean()), 0.5, "kb", draws=300, seed=0)
    assert [(r["condition"], r["predictor"]) for r in paired] == [("snow", "other"), ("snow", "same"),
                                                                  ("all", "other"), ("all", "same")]
    for row in paired:
        assert row["against"] == "kb"
        assert abs(row["pearson_diff"]) < 1e-12
        assert max(abs(row["pearson_diff_lo"]), abs(row["pearson_diff_hi"])) < 1e-12
        if row["predictor"] == "same":
            assert row["rmse_diff"] == row["rmse_diff_lo"] == row["rmse_diff_hi"] == 0.0
            assert row["auroc_diff"] == row["auroc_diff_lo"] == row["auroc_diff_hi"] == 0.0
        else:
            assert row["rmse_diff"] == pytest.approx(rmse(shifted, target) - rmse(base, target))
            assert row["rmse_diff_lo"] <= row["rmse_diff"] <= row["rmse_diff_hi"]


@pytest.mark.parametrize("kwargs, message", [
    ({"scenes": ["s"]}, r"2 FrameTruth, 1 scene names"),
    ({"paired_with": "nope"}, r"paired_with = 'nope' is not one of the predictors \['r'\]"),
    ({"draws": 0}, r"draws = 0, must be an integer >= 1"),
    ({"level": 1.0}, r"level = 1.0, must be in \(0, 1\)"),
])
def test_bad_arguments_are_named(kwargs, message):
    args = {"truth": _truth("night", [0.1, 0.2], [True, False]), "scenes": ["s", "s"],
            "risks": {"r": np.array([0.3, 0.4])}, "reference": 0.2, "threshold": 0.5, "paired_with": None}
    draws, level = kwargs.pop("draws", 10), kwargs.pop("level", 0.95)
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        bootstrap_tables(**args, draws=draws, level=level)


def test_interval_cells():
    assert interval_cell(0.5234, 0.41, 0.6, "{:.2f}") == "0.52 [0.41, 0.60]"
    assert interval_cell(0.25, 0.0, 1.0, "{:.0%}") == "25% [0%, 100%]"
    assert interval_cell(math.nan, math.nan, math.nan, "{:.2f}") == "- [-]"
    assert interval_cell(0.1, math.nan, 0.2, "{:+.3f}") == "+0.100 [-]"
