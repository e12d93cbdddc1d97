"""The paper's tables (monitor.offline.evaluation) on hand-built frames.

Every box is a 10 x 10 pixel square on the row y = 100, so a pair's IoU depends only on the
horizontal shift s between their centres: the overlap is (10 - s) * 10 and the union
200 - (10 - s) * 10, so IoU = (10 - s) / (10 + s):

    s = 0 -> 1,   s = 2 -> 8/12 = 2/3,   s = 4 -> 6/14 = 3/7,   s = 5 -> 5/15 = 1/3.

RDD of an object X against a prediction P is (d_P - d_X) / d_X. Boxes of different objects
are 100 pixels or more apart, so the Hungarian assignment pairs the obvious boxes (its
cost is the sum of the shifts, each < 10, against >= 90 for any other pairing).
The paper's two settings: (alpha, beta) = (0.5, 0.1) and (0.3, 0.2).
"""
import math

import numpy as np
import pytest

from fuzzcore import FuzzySystem, Rule, Term, Variable
from monitor.offline.evaluation import (PAPER_THRESHOLDS, Observation, correlation_table,
                                        detection_analysis, feature_rows, recall_table,
                                        rmse_table)
from monitor.offline.groundtruth import score
from monitor.risk_monitor import INVALID_INPUT, NO_OBJECTS, OK, RiskReport

EMPTY = np.empty((0, 5))


def box(x, d):
    """A 10 x 10 box centred at (x, 100), d metres away."""
    return [x, 100.0, 10.0, 10.0, d]


def boxes(*rows):
    return np.array(rows, dtype=float).reshape(-1, 5)


def observation(S, P, G, status=OK, iou=math.nan, rdd=math.nan, index=0):
    report = RiskReport(risk=0.5, status=status, iou=iou, rdd=rdd, S=S, P=P)
    return Observation(scene="scene", condition="nominal", index=index, timestamp=0.5 * index,
                       report=report, G=G, P=P, truth=score(P, G))


def test_paper_thresholds():
    assert PAPER_THRESHOLDS == ((0.5, 0.1), (0.3, 0.2))


# --------------------------------------------------------------------------- Table I
def correlation_frames():
    """Three frames with one S, one G and the prediction P = box(100, 10) each.

    frame  S shift, d_S   G shift, d_G    IoU(S,P) RDD(S,P)   IoU(G,P) RDD(G,P)
    a      0, 10          0, 10           1        0          1        0
    b      2, 10          5, 9.5          2/3      0          1/3      x
    c      5, 9.5         2, 10           1/3      x          2/3      0
    with x = (10 - 9.5) / 9.5 = 1/19 ~ 0.053: |x| < 0.1 < 0.2.
    """
    P = boxes(box(100, 10))
    return [
        observation(boxes(box(100, 10)), P, boxes(box(100, 10)), index=0),
        observation(boxes(box(102, 10)), P, boxes(box(105, 9.5)), index=1),
        observation(boxes(box(105, 9.5)), P, boxes(box(102, 10)), index=2),
    ]


def test_correlation_table_by_hand():
    excluded = [
        # no features without S, without G, or with an invalid frame: left out
        observation(EMPTY, boxes(box(100, 10)), boxes(box(100, 10)), status=NO_OBJECTS, index=3),
        observation(boxes(box(100, 10)), boxes(box(100, 10)), EMPTY, index=4),
        observation(boxes(box(100, 10)), boxes(box(100, 10)), boxes(box(100, 10)),
                    status=INVALID_INPUT, index=5),
    ]
    rows = correlation_table(correlation_frames() + excluded)
    assert [(r["alpha"], r["beta"], r["frames"]) for r in rows] == [(0.5, 0.1, 3), (0.3, 0.2, 3)]

    # (0.5, 0.1): IoU 1/3 does not count (<= 0.5): that object scores IoU 0, RDD 1.
    #   IoU~ u(S) = [1, 2/3, 0], v(G) = [1, 0, 2/3]; means 5/9; deviations
    #   u' = [4/9, 1/9, -5/9], v' = [4/9, -5/9, 1/9];
    #   r = (16 - 5 - 5)/81 / ((16 + 1 + 25)/81) = 6/42 = 1/7
    #   RDD~ u = [0, 0, 1] (c's S unmatched), v = [0, 1, 0] (b's G unmatched): means 1/3,
    #   u' = [-1/3, -1/3, 2/3], v' = [-1/3, 2/3, -1/3]; r = (1 - 2 - 2)/9 / (6/9) = -1/2
    assert rows[0]["iou_r"] == pytest.approx(1 / 7, abs=1e-12)
    assert rows[0]["rdd_r"] == pytest.approx(-0.5, abs=1e-12)
    # (0.3, 0.2): every pair counts.
    #   IoU~ u = [1, 2/3, 1/3], v = [1, 1/3, 2/3]; means 2/3; u' = [1/3, 0, -1/3],
    #   v' = [1/3, -1/3, 0]; r = (1/9) / (2/9) = 1/2
    #   RDD~ u = [0, 0, x], v = [0, x, 0]: as above with x for 1, r = -1/2
    assert rows[1]["iou_r"] == pytest.approx(0.5, abs=1e-12)
    assert rows[1]["rdd_r"] == pytest.approx(-0.5, abs=1e-12)


def test_correlation_needs_three_frames_and_spread():
    two = correlation_table(correlation_frames()[:2], thresholds=[(0.3, 0.2)])
    assert two[0]["frames"] == 2 and math.isnan(two[0]["iou_r"]) and math.isnan(two[0]["rdd_r"])
    # three identical frames: no spread, no correlation (not a division by zero)
    same = [correlation_frames()[0]] * 3
    flat = correlation_table(same, thresholds=[(0.3, 0.2)])
    assert flat[0]["frames"] == 3 and math.isnan(flat[0]["iou_r"])


# --------------------------------------------------------------------------- Tables II, III
def detection_frames():
    """One frame with five ground truths (d = 10 each) and what each view found.

    G   at x   P (detector)                    S (depth view)
    g0  100    p0 = box(100, 10): IoU 1, RDD 0    s0 = box(102, 10.5): IoU 2/3, RDD 0.05
    g1  200    p1 = box(204, 11.5): IoU 3/7,      -
                 RDD 0.15
    g2  300    -                                  s2 = box(300, 10): IoU 1, RDD 0
    g3  400    -                                  s3 = box(400, 10): IoU 1, RDD 0
    g4  500    -                                  -
    (RDD = (d_X - d_G) / d_G: (10.5 - 10)/10 = 0.05, (11.5 - 10)/10 = 0.15.)

    Plus frames that must not count: an invalid frame (its ground truth is not counted)
    and a frame without ground truth.
    """
    G = boxes(box(100, 10), box(200, 10), box(300, 10), box(400, 10), box(500, 10))
    P = boxes(box(100, 10), box(204, 11.5))
    S = boxes(box(102, 10.5), box(300, 10), box(400, 10))
    return [
        observation(S, P, G, index=0),
        observation(S, P, G, status=INVALID_INPUT, index=1),
        observation(boxes(box(100, 10)), P, EMPTY, index=2),
    ]


def test_recall_table_by_hand():
    # (0.3, 0.2): P recovers g0 (IoU 1) and g1 (3/7 > 0.3, 0.15 < 0.2): 2 of 5;
    #             S recovers g0 (2/3, 0.05), g2, g3: 3 of 5
    assert recall_table(detection_frames(), 0.3, 0.2) == {"gts": 5, "recall_s": 3 / 5,
                                                          "recall_p": 2 / 5}
    # (0.5, 0.1): g1's detection no longer counts (3/7 <= 0.5): P 1 of 5; S unchanged
    # (2/3 > 0.5 and 0.05 < 0.1)
    assert recall_table(detection_frames(), 0.5, 0.1) == {"gts": 5, "recall_s": 3 / 5,
                                                          "recall_p": 1 / 5}
    nothing = recall_table(detection_frames()[1:], 0.3, 0.2)
    assert nothing["gts"] == 0 and math.isnan(nothing["recall_s"]) and math.isnan(nothing["recall_p"])


def test_detection_analysis_by_hand():
    # (0.3, 0.2): TPs g0, g1; S approves g0 only. FNs g2, g3, g4; S identifies g2, g3.
    assert detection_analysis(detection_frames(), 0.3, 0.2) == {
        "tps": 2, "approved_tps": 1, "fns": 3, "identified_fns": 2}
    # (0.5, 0.1): TP g0 (approved); FNs g1 .. g4, of which S identifies g2, g3.
    assert detection_analysis(detection_frames(), 0.5, 0.1) == {
        "tps": 1, "approved_tps": 1, "fns": 4, "identified_fns": 2}


# --------------------------------------------------------------------------- RMSE
def identity_system():
    """Sugeno: one rule that always fires fully, z = 1 * iou + 0 * rdd + 0, so risk = iou."""
    always = Term("any", "trapmf", [-2.0, -2.0, 2.0, 2.0])
    inputs = (Variable("iou", (0.0, 1.0), (always,)), Variable("rdd", (-1.0, 1.0), (always,)))
    output = Variable("risk", (0.0, 1.0), (Term("z", "linear", [1.0, 0.0, 0.0]),))
    return FuzzySystem("identity", inputs, (output,), (Rule((1, 1), (1,)),), type="sugeno",
                       and_method="prod", defuzzifier="wtaver")


def constant_system(value):
    always = Term("any", "trapmf", [-2.0, -2.0, 2.0, 2.0])
    inputs = (Variable("iou", (0.0, 1.0), (always,)), Variable("rdd", (-1.0, 1.0), (always,)))
    output = Variable("risk", (0.0, 1.0), (Term("c", "constant", [value]),))
    return FuzzySystem("constant", inputs, (output,), (Rule((1, 1), (1,)),), type="sugeno",
                       and_method="prod", defuzzifier="wtaver")


def rmse_frames():
    """Targets 1 - USC~ with USC = IoG(P, G) * min(1, d_G / d_P), G = box(100, 10):

    frame  P                 IoG           DR                  target   iou (report)
    r0     box(100, 10)      1             1                   0        0.2
    r1     box(105, 12.5)    50/100 = 0.5  10/12.5 = 0.8       0.6      0.5
    r2     none              0             -                   1        0.7
    r3     (no G in range: target NaN, left out)                        0.4
    r4     (status no-objects: no features, left out)
    """
    G = boxes(box(100, 10))
    S = boxes(box(100, 10))
    far = boxes(box(100, 30))  # beyond the 20 m range: no target
    return [
        observation(S, boxes(box(100, 10)), G, iou=0.2, rdd=0.0, index=0),
        observation(S, boxes(box(105, 12.5)), G, iou=0.5, rdd=0.1, index=1),
        observation(S, EMPTY, G, iou=0.7, rdd=1.0, index=2),
        observation(S, boxes(box(100, 30)), far, iou=0.4, rdd=0.0, index=3),
        observation(EMPTY, boxes(box(100, 10)), G, status=NO_OBJECTS, index=4),
    ]


def test_targets_by_hand():
    targets = [ob.target for ob in rmse_frames()]
    assert targets[:3] == pytest.approx([0.0, 0.6, 1.0], abs=1e-15)
    assert math.isnan(targets[3])


def test_feature_rows_keep_ok_frames():
    rows = feature_rows(rmse_frames())
    assert [(r["scene"], r["frame"], r["condition"], r["iou"]) for r in rows] == [
        ("scene", 0, "nominal", 0.2), ("scene", 1, "nominal", 0.5), ("scene", 2, "nominal", 0.7),
        ("scene", 3, "nominal", 0.4)]  # r3 has features; only the RMSE needs a target
    assert math.isnan(rows[3]["target"])


def test_rmse_table_by_hand():
    identity, half = rmse_table(rmse_frames(), {"identity": identity_system(),
                                                "half": constant_system(0.5)})
    # identity: risk = iou = 0.2, 0.5, 0.7 against 0, 0.6, 1: errors 0.2, -0.1, -0.3
    #   RMSE sqrt((0.04 + 0.01 + 0.09) / 3) = sqrt(0.14 / 3); MAE 0.6 / 3 = 0.2
    assert identity["rules"] == "identity" and identity["frames"] == 3
    assert identity["rmse"] == pytest.approx(math.sqrt(0.14 / 3), abs=1e-15)
    assert identity["mae"] == pytest.approx(0.2, abs=1e-15)
    # constant 0.5: errors 0.5, -0.1, -0.5: RMSE sqrt(0.51 / 3) = sqrt(0.17); MAE 1.1 / 3
    assert half["frames"] == 3
    assert half["rmse"] == pytest.approx(math.sqrt(0.17), abs=1e-15)
    assert half["mae"] == pytest.approx(1.1 / 3, abs=1e-15)


def test_rmse_without_frames_is_nan_not_zero():
    (row,) = rmse_table(rmse_frames()[3:], {"identity": identity_system()})
    assert row["frames"] == 0 and math.isnan(row["rmse"]) and math.isnan(row["mae"])
