"""Tests for monitor.offline.measures: every measure against values worked out by hand."""
import json
import math

import numpy as np
import pytest
from scipy import stats

import fuzzcore
from monitor.offline.evaluation import Observation
from monitor.offline.groundtruth import score
from monitor.offline.measures import (
    FrameTruth, HazardCriterion, alarm_rates, auprc, auroc, coverage, depth_view_quality,
    fpr_at_tpr, frame_rows, frame_truth, pearson, risk_quality, rmse, roc_curve, rule_base_risk, skill, spearman,
)
from monitor.risk_monitor import INVALID_INPUT, NO_OBJECTS, OK, RiskReport
from monitor.shipped import shipped_rules

# --- ranking measures --------------------------------------------------------------------

SCORES = [0.1, 0.4, 0.35, 0.8]
LABELS = [0, 0, 1, 1]


def test_auroc_is_the_share_of_correctly_ordered_pairs():
    # positives 0.35, 0.8; negatives 0.1, 0.4: pairs (0.35 > 0.1) yes, (0.35 > 0.4) no,
    # (0.8 > 0.1) yes, (0.8 > 0.4) yes -> 3 / 4
    assert auroc(SCORES, LABELS) == pytest.approx(0.75)


def test_auroc_counts_ties_one_half():
    # positives 0.5, 0.9; negatives 0.5, 0.2: (0.5 vs 0.5) tie 1/2, (0.5 > 0.2) 1,
    # (0.9 > 0.5) 1, (0.9 > 0.2) 1 -> 3.5 / 4
    assert auroc([0.5, 0.5, 0.2, 0.9], [1, 0, 0, 1]) == pytest.approx(0.875)
    # every score equal: no information, 1/2
    assert auroc([0.3] * 5, [1, 0, 1, 0, 0]) == pytest.approx(0.5)


def test_auprc_is_the_stepwise_average_precision():
    # by decreasing score: 0.8 (+) P 1 R 1/2; 0.4 (-) P 1/2 R 1/2; 0.35 (+) P 2/3 R 1; 0.1 (-)
    # AP = (1/2 - 0) * 1 + 0 * 1/2 + (1 - 1/2) * 2/3 + 0 = 5/6
    assert auprc(SCORES, LABELS) == pytest.approx(5 / 6)


def test_auprc_takes_tied_scores_as_one_threshold():
    # 0.9 (+): P 1, R 1/2; 0.5 (one +, one -) together: TP 2 of 3, P 2/3, R 1; 0.2: R stays 1
    # AP = 1/2 * 1 + 1/2 * 2/3 = 5/6
    assert auprc([0.5, 0.5, 0.2, 0.9], [1, 0, 0, 1]) == pytest.approx(5 / 6)


def test_roc_curve_points():
    fpr, tpr, thr = roc_curve([0.5, 0.5, 0.2, 0.9], [1, 0, 0, 1])
    # thresholds inf, 0.9, 0.5, 0.2: (0, 0), (0, 1/2), (1/2, 1), (1, 1)
    np.testing.assert_allclose(thr, [np.inf, 0.9, 0.5, 0.2])
    np.testing.assert_allclose(fpr, [0, 0, 0.5, 1])
    np.testing.assert_allclose(tpr, [0, 0.5, 1, 1])
    # the trapezoids under it give the AUROC again
    assert np.sum(np.diff(fpr) * (tpr[1:] + tpr[:-1]) / 2) == pytest.approx(0.875)


def test_fpr_at_a_tpr():
    # the three positives are all caught first at threshold 0.6: scores >= 0.6 are
    # 0.9 (+), 0.8 (+), 0.7 (-), 0.6 (+) -> FP 1 of 3 negatives
    assert fpr_at_tpr([0.9, 0.8, 0.7, 0.6, 0.5, 0.4], [1, 1, 0, 1, 0, 0]) == pytest.approx(1 / 3)
    # separable: 0
    assert fpr_at_tpr([0.9, 0.8, 0.2], [1, 1, 0]) == 0.0
    # five positives: 4 of them (TPR 0.8) at >= 0.5, passing the negative 0.7 (1 of 3); all
    # five (TPR >= 0.95) at >= 0.3, passing 0.7 and 0.4 (2 of 3)
    scores, labels = [0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2], [1, 1, 0, 1, 1, 0, 1, 0]
    assert fpr_at_tpr(scores, labels, 0.80) == pytest.approx(1 / 3)
    assert fpr_at_tpr(scores, labels) == pytest.approx(2 / 3)


def test_alarm_rates_use_strictly_above_the_threshold():
    # hazards 0.5 (no alarm: not > 0.5), 0.9 (alarm) -> hit 1/2; non-hazards 0.6 (alarm),
    # 0.1, 0.2 -> false alarms 1/3
    hit, false = alarm_rates([0.5, 0.9, 0.6, 0.1, 0.2], [1, 1, 0, 0, 0], 0.5)
    assert hit == pytest.approx(0.5) and false == pytest.approx(1 / 3)


def test_ranking_measures_are_nan_without_both_classes():
    for labels in ([0, 0, 0], [1, 1, 1]):
        assert math.isnan(auroc([0.1, 0.2, 0.3], labels))
        assert math.isnan(fpr_at_tpr([0.1, 0.2, 0.3], labels))
    assert math.isnan(auprc([0.1, 0.2, 0.3], [0, 0, 0]))
    assert auprc([0.1, 0.2, 0.3], [1, 1, 1]) == 1.0  # every alarm is a hazard
    hit, false = alarm_rates([0.1, 0.9], [0, 0], 0.5)
    assert math.isnan(hit) and false == 0.5


def test_ranking_measures_reject_bad_input():
    with pytest.raises(ValueError, match="same length"):
        auroc([0.1, 0.2], [1])
    with pytest.raises(ValueError, match="finite"):
        auroc([0.1, np.nan], [1, 0])


# --- correlation and error ---------------------------------------------------------------

def test_pearson_and_spearman_by_hand_and_as_scipy():
    x, y = [1, 2, 2, 3], [1, 3, 2, 4]
    # ranks of x with the tie averaged: 1, 2.5, 2.5, 4; ranks of y: 1, 3, 2, 4. Both have
    # mean 2.5; deviations (-1.5, 0, 0, 1.5) and (-1.5, 0.5, -0.5, 1.5):
    # sum of products 4.5, sums of squares 4.5 and 5 -> rho = 4.5 / sqrt(22.5)
    assert spearman(x, y) == pytest.approx(4.5 / math.sqrt(22.5))
    assert spearman(x, y) == pytest.approx(stats.spearmanr(x, y).statistic)
    # Pearson on the values: deviations (-1, 0, 0, 1) and (-1.5, 0.5, -0.5, 1.5):
    # products 1.5 + 1.5 = 3, squares 2 and 5 -> 3 / sqrt(10)
    assert pearson(x, y) == pytest.approx(3 / math.sqrt(10))
    assert math.isnan(pearson([1, 2], [2, 1]))        # too few
    assert math.isnan(pearson([1, 1, 1], [1, 2, 3]))  # constant


def test_skill_uses_the_given_reference_not_the_test_mean():
    target = [0.2, 0.4, 0.6, 0.8]
    pred = [0.3, 0.4, 0.5, 0.8]
    # errors 0.1, 0, -0.1, 0 -> MSE 0.02 / 4 = 0.005
    assert rmse(pred, target) == pytest.approx(math.sqrt(0.005))
    # the training mean 0.4: errors -0.2, 0, 0.2, 0.4 -> MSE 0.24 / 4 = 0.06
    # skill = 1 - sqrt(0.005 / 0.06) = 1 - sqrt(1 / 12)
    assert skill(pred, target, 0.4) == pytest.approx(1 - math.sqrt(1 / 12))
    # the constant itself has skill 0, a perfect predictor 1
    assert skill([0.4] * 4, target, 0.4) == pytest.approx(0.0)
    assert skill(target, target, 0.4) == pytest.approx(1.0)
    assert math.isnan(skill([], [], 0.4))


# --- coverage of the ground truth --------------------------------------------------------

G = np.array([[100, 100, 20, 20, 10.0],   # G0: x [90, 110], y [90, 110]
              [300, 100, 40, 20, 8.0]])   # G1: x [280, 320], y [90, 110]
P = np.array([[105, 100, 20, 20, 12.5],   # on G0: IoG 300 / 400 = 0.75, DR 10 / 12.5 = 0.8 (not > 0.8)
              [300, 100, 20, 20, 6.0]])   # inside G1: IoG 400 / 800 = 0.5 (not > 0.5), DR 1
S = np.array([[100, 100, 20, 20, 9.0],    # on G0: IoG 1, band 9 / 10 = 0.9; IoS 1
              [300, 100, 80, 20, 8.0],    # around G1: IoG 1, band 1; IoS 800 / 1600 = 0.5 (not > 0.5)
              [700, 100, 50, 50, 5.0]])   # a wall: on nothing


def test_coverage_by_hand():
    covered, found, on_truth = coverage(P, S, G, HazardCriterion())
    np.testing.assert_array_equal(covered, [False, False])
    np.testing.assert_array_equal(found, [True, True])
    np.testing.assert_array_equal(on_truth, [True, False, False])
    # looser thresholds: P0 covers G0 (DR 0.8 > 0.75) and P1 covers G1 (IoG 0.5 > 0.4);
    # S1 is on G1 (IoS 0.5 > 0.4)
    covered, _, on_truth = coverage(P, S, G, HazardCriterion(min_iog=0.4, min_dr=0.75))
    np.testing.assert_array_equal(covered, [True, True])
    np.testing.assert_array_equal(on_truth, [True, True, False])
    # a depth view that reads too near is outside the band: 7 / 10 = 0.7
    _, found, _ = coverage(P, np.array([[100, 100, 20, 20, 7.0]]), G, HazardCriterion())
    np.testing.assert_array_equal(found, [False, False])


def test_coverage_of_empty_frames():
    empty = np.zeros((0, 5))
    covered, found, on_truth = coverage(empty, empty, G, HazardCriterion())
    assert not covered.any() and not found.any() and on_truth.shape == (0,)
    covered, found, on_truth = coverage(P, S, empty, HazardCriterion())
    assert covered.shape == found.shape == (0,) and not on_truth.any()


def test_hazard_criterion_is_validated():
    with pytest.raises(ValueError, match="min_iog = 1.5"):
        HazardCriterion(min_iog=1.5)
    with pytest.raises(ValueError, match="min_dr"):
        HazardCriterion(min_dr=-0.1)


def _observation(status, S_, P_, G_, risk=0.3, iou=0.5, rdd=0.1):
    report = RiskReport(risk=risk, status=status, S=S_, P=P_, iou=iou if status == OK else np.nan,
                        rdd=rdd if status == OK else np.nan)
    return Observation("scene", "nominal", 0, 0.0, report, G_, P_, score(P_, G_))


def test_frame_truth_of_an_ok_and_an_invalid_frame():
    t = frame_truth(_observation(OK, S, P, G))
    # no G covered by P -> hazard; S finds both (so the hazard is in view), one S of three
    # is on a G
    assert t == FrameTruth("nominal", OK, score(P, G).target, True, 2, 2, 3, 1, True)
    # the detections cover both G: no hazard, so none in view though S finds both
    P_good = np.array([[100, 100, 20, 20, 10.0], [300, 100, 40, 20, 7.0]])
    t = frame_truth(_observation(OK, S, P_good, G))
    assert (t.hazard, t.found, t.hazard_in_view) == (False, 2, False)
    # P covers G0 only, and S finds only G0 (S0): the missed G1 is not in view
    P_g0 = np.array([[100, 100, 20, 20, 10.0]])
    t = frame_truth(_observation(OK, S[[0, 2]], P_g0, G))
    assert (t.hazard, t.found, t.hazard_in_view) == (True, 1, False)
    # ... and S finds G1 (S1) as well: in view
    assert frame_truth(_observation(OK, S, P_g0, G)).hazard_in_view
    # an invalid frame has no depth view: S counts for nothing
    t = frame_truth(_observation(INVALID_INPUT, S, P, G, risk=1.0))
    assert (t.objects, t.found, t.gts, t.hazard, t.hazard_in_view) == (0, 0, 2, True, False)


def test_rule_base_risk_keeps_the_reported_risk_of_frames_without_features():
    fis = fuzzcore.load(shipped_rules())
    obs = [_observation(OK, S, P, G, iou=0.7, rdd=0.05),
           _observation(NO_OBJECTS, np.zeros((0, 5)), P, G, risk=0.0),
           _observation(INVALID_INPUT, S, P, G, risk=1.0)]
    risk = rule_base_risk(obs, fis, fail_safe_risk=1.0)
    np.testing.assert_allclose(risk, [fis.infer(iou=0.7, rdd=0.05), 0.0, 1.0])


def test_frame_rows_hold_each_frames_truth_and_risks_as_strict_json():
    obs = [_observation(OK, S, P, G, iou=0.7, rdd=0.05), _observation(INVALID_INPUT, S, P, G, risk=1.0)]
    truth = [frame_truth(ob) for ob in obs]
    rows = frame_rows(obs, truth, {"a": np.array([0.4, 1.0])}, test_scenes={"scene"})
    assert json.loads(json.dumps(rows, allow_nan=False)) == rows
    assert [(r["split"], r["status"], r["iou"], r["rdd"], r["risk"]) for r in rows] == [
        ("test", OK, 0.7, 0.05, {"a": 0.4}), ("test", INVALID_INPUT, None, None, {"a": 1.0})]
    assert (rows[1]["objects"], rows[1]["found"], rows[1]["hazard"], rows[1]["hazard_in_view"]) == \
        (0, 0, True, False)  # no view
    assert rows[0]["hazard_in_view"]
    assert rows[0]["target"] == score(P, G).target and rows[0]["detections"] == len(P)
    assert frame_rows(obs, truth, {"a": np.zeros(2)}, test_scenes=())[0]["split"] == "train"
    with pytest.raises(ValueError, match=r"2 observations, 2 FrameTruth and risks of \[3\] frames"):
        frame_rows(obs, truth, {"a": np.zeros(3)}, test_scenes=())


def _truth(target, hazard, status=OK, gts=1, found=0, objects=0, on_truth=0, in_view=False):
    return FrameTruth("nominal", status, target, hazard, gts, found, objects, on_truth, in_view)


def test_risk_quality_on_a_small_table():
    truth = [_truth(0.9, True, in_view=True), _truth(0.2, False), _truth(np.nan, False, NO_OBJECTS, gts=0),
             _truth(0.6, True, INVALID_INPUT), _truth(0.1, False)]
    risk = [0.8, 0.3, 0.0, 1.0, 0.6]
    q = risk_quality(risk, truth, reference=0.5, threshold=0.5)
    assert (q["frames"], q["targets"], q["hazards"]) == (5, 4, 2)
    # frames with a target: risk (0.8, 0.3, 1.0, 0.6) against (0.9, 0.2, 0.6, 0.1)
    t, r = np.array([0.9, 0.2, 0.6, 0.1]), np.array([0.8, 0.3, 1.0, 0.6])
    assert q["pearson"] == pytest.approx(np.corrcoef(r, t)[0, 1])
    # errors -0.1, 0.1, 0.4, 0.5 -> MSE 0.43 / 4; constant 0.5: 0.4, -0.3, 0.1, -0.4 -> 0.42 / 4
    assert q["rmse"] == pytest.approx(math.sqrt(0.43 / 4))
    assert q["skill"] == pytest.approx(1 - math.sqrt(0.43 / 0.42))
    # every frame ranks: hazards 0.8, 1.0 over non-hazards 0.3, 0.0, 0.6: 6 of 6 pairs
    assert q["auroc"] == 1.0 and q["auprc"] == 1.0 and q["fpr80"] == 0.0 and q["fpr95"] == 0.0
    # alarms (> 0.5): both hazards; non-hazards 0.6 only -> 1/3
    assert q["hit_rate"] == 1.0 and q["false_alarm_rate"] == pytest.approx(1 / 3)
    assert q["hit_in_view"] == 1.0  # the one hazard frame in view, 0.8
    assert q["auroc_in_view"] == 1.0  # 0.8 over the non-hazards 0.3, 0.0, 0.6
    assert q["alarm_rate"] == pytest.approx(3 / 5)
    assert q["notes"] == ""


def test_the_hit_rate_and_auroc_in_view_count_the_hazard_frames_in_view_alone():
    truth = [_truth(0.5, True, in_view=True), _truth(0.5, True, in_view=True),
             _truth(0.5, True, in_view=True), _truth(0.5, True), _truth(0.1, False), _truth(0.1, False)]
    q = risk_quality([0.7, 0.25, 0.9, 0.2, 0.3, 0.1], truth, reference=0.5, threshold=0.5)
    # alarms (> 0.5) on 0.7 and 0.9: 2 of the 3 in view, 2 of the 4 hazard frames
    assert q["hit_in_view"] == pytest.approx(2 / 3) and q["hit_rate"] == pytest.approx(2 / 4)
    # in view against the hazard-free 0.3 and 0.1: 0.7 and 0.9 beat both, 0.25 beats 0.1: 5 of
    # 6 pairs; the frame out of view, 0.2, beats 0.1 only: 1 of 2. Over all hazard frames 6 of
    # 8 pairs, the in-view share 3 / 4 times 5 / 6 plus 1 / 4 times 1 / 2
    assert q["auroc_in_view"] == pytest.approx(5 / 6)
    assert q["auroc"] == pytest.approx(6 / 8) and 6 / 8 == pytest.approx(3 / 4 * 5 / 6 + 1 / 4 * 1 / 2)
    q = risk_quality([0.7, 0.2], [_truth(0.5, True), _truth(0.1, False)], reference=0.5, threshold=0.5)
    assert math.isnan(q["hit_in_view"]) and math.isnan(q["auroc_in_view"])
    assert "no hazard frame in view: no hit rate or AUROC in view" in q["notes"]
    q = risk_quality([0.7, 0.2], [_truth(0.5, True, in_view=True), _truth(0.5, True)], reference=0.5,
                     threshold=0.5)
    assert math.isnan(q["auroc_in_view"]) and "only hazard frames: no AUROC (nor in view)" in q["notes"]


def test_risk_quality_says_why_a_measure_is_undefined():
    truth = [_truth(0.2, False), _truth(0.3, False), _truth(0.4, False)]
    q = risk_quality([0.5, 0.5, 0.5], truth, reference=0.3, threshold=0.5)
    assert math.isnan(q["auroc"]) and math.isnan(q["hit_rate"]) and math.isnan(q["fpr80"]) \
        and math.isnan(q["fpr95"])
    assert math.isnan(q["pearson"]) and q["false_alarm_rate"] == 0.0
    assert "no hazard frame" in q["notes"] and "constant risk" in q["notes"]
    with pytest.raises(ValueError, match="one per frame"):
        risk_quality([0.5], truth, reference=0.3, threshold=0.5)


def test_depth_view_quality_and_status_shares():
    truth = [_truth(0.5, False, OK, gts=3, found=2, objects=4, on_truth=1),
             _truth(0.5, True, NO_OBJECTS, gts=1, found=0, objects=0),
             _truth(np.nan, False, OK, gts=0, objects=2, on_truth=0),
             _truth(1.0, True, INVALID_INPUT, gts=2),
             _truth(0.8, True, OK, gts=2, found=1, objects=1, on_truth=1, in_view=True)]
    q = depth_view_quality(truth)
    # found 2 of 3 + 1 + 2 + 2 = 8 G, 1 of them by the last frame; 2 of 7 S on a G
    assert q["recall"] == pytest.approx(3 / 8) and q["precision"] == pytest.approx(2 / 7)
    assert (q[OK], q[NO_OBJECTS], q[INVALID_INPUT]) == (0.6, 0.2, 0.2)
    assert q["hazards_in_view"] == pytest.approx(1 / 3)  # of the three hazard frames
    nothing = depth_view_quality([_truth(np.nan, False, gts=0)])
    assert math.isnan(nothing["recall"]) and math.isnan(nothing["hazards_in_view"])
