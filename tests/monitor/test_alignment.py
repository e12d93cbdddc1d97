"""Tests for monitor.alignment: Hungarian pairing, thresholds, frame means, empty frames."""
import itertools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from monitor.alignment import (DEFAULT_ALPHA, DEFAULT_BETA, align,
                               assign_by_centre)
from monitor.geometry.boxes import centre_distances

EMPTY = np.empty((0, 5))


def test_hand_made_frame():
    S = np.array([[100, 100, 20, 20, 10.0],   # x [90, 110], y [90, 110]
                  [300, 100, 40, 20, 8.0]])   # x [280, 320], y [90, 110]
    P = np.array([[305, 100, 40, 20, 8.8],    # near S1: centre distance 5
                  [104, 100, 20, 20, 13.0],   # near S0: centre distance 4
                  [500, 500, 10, 10, 5.0]])   # a decoy far from both
    a = align(S, P)
    assert (DEFAULT_ALPHA, DEFAULT_BETA) == (0.3, 0.2) == (a.alpha, a.beta)
    np.testing.assert_array_equal(a.partner, [1, 0])
    # S0-P1: x [90, 110] & [94, 114] -> 16 * 20 = 320; union 400 + 400 - 320 = 480
    #        RDD (13 - 10) / 10 = 0.3: |0.3| >= 0.2, the pair does not count
    # S1-P0: x [280, 320] & [285, 325] -> 35 * 20 = 700; union 800 + 800 - 700 = 900
    #        RDD (8.8 - 8) / 8 = 0.1: counts
    np.testing.assert_allclose(a.pair_iou, [320 / 480, 700 / 900])
    np.testing.assert_allclose(a.pair_rdd, [0.3, 0.1])
    np.testing.assert_array_equal(a.matched, [False, True])
    np.testing.assert_allclose(a.iou, [0.0, 700 / 900])
    np.testing.assert_allclose(a.rdd, [1.0, 0.1])
    assert a.iou_mean == pytest.approx((0.0 + 700 / 900) / 2)
    assert a.rdd_mean == pytest.approx((1.0 + 0.1) / 2)
    assert a.n_objects == 2


def test_inverse_distance_weighting_of_the_hand_made_frame():
    S = np.array([[100, 100, 20, 20, 10.0], [300, 100, 40, 20, 8.0]])
    P = np.array([[305, 100, 40, 20, 8.8], [104, 100, 20, 20, 13.0], [500, 500, 10, 10, 5.0]])
    a = align(S, P, weighting="inverse_distance")
    # weights 1/10 and 1/8, sum 0.225: S0 (unmatched, IoU 0, RDD 1) 0.1 / 0.225 = 4/9,
    # S1 (IoU 7/9, RDD 0.1) 0.125 / 0.225 = 5/9
    assert a.iou_mean == pytest.approx(5 / 9 * 7 / 9)
    assert a.rdd_mean == pytest.approx(4 / 9 * 1.0 + 5 / 9 * 0.1)
    # the per-object terms are those of the plain mean
    plain = align(S, P)
    np.testing.assert_array_equal(a.iou, plain.iou)
    np.testing.assert_array_equal(a.rdd, plain.rdd)
    assert np.isnan(align(EMPTY, P, weighting="inverse_distance").iou_mean)
    with pytest.raises(ValueError, match="weighting = 'nearest', must be one of mean, inverse_distance"):
        align(S, P, weighting="nearest")


def test_relaxed_thresholds_count_more_pairs():
    S = np.array([[100, 100, 20, 20, 10.0]])
    P = np.array([[104, 100, 20, 20, 13.0]])  # IoU 2/3, RDD 0.3 (see the hand-made frame)
    assert not align(S, P).matched[0]
    a = align(S, P, alpha=0.5, beta=0.31)
    assert a.matched[0]
    assert a.iou_mean == pytest.approx(2 / 3) and a.rdd_mean == pytest.approx(0.3)
    assert not align(S, P, alpha=0.7, beta=0.31).matched[0]  # 2/3 <= 0.7


def test_thresholds_are_strict():
    # x [-1, 1] & [0, 2]: intersection 1 * 2 = 2, union 4 + 4 - 2 = 6 -> IoU 1/3
    # RDD (5 - 4) / 4 = 0.25
    S = np.array([[0, 0, 2, 2, 4.0]])
    P = np.array([[1, 0, 2, 2, 5.0]])
    assert align(S, P, alpha=1 / 3 - 1e-9, beta=0.25 + 1e-9).matched[0]
    assert not align(S, P, alpha=1 / 3, beta=0.25 + 1e-9).matched[0]   # IoU > alpha fails
    assert not align(S, P, alpha=1 / 3 - 1e-9, beta=0.25).matched[0]   # |RDD| < beta fails


def test_negative_rdd_counts_by_its_magnitude():
    S = np.array([[0, 0, 10, 10, 10.0]])
    P = np.array([[0, 0, 10, 10, 8.5]])  # RDD (8.5 - 10) / 10 = -0.15, |-0.15| < 0.2
    a = align(S, P)
    assert a.matched[0] and a.rdd_mean == pytest.approx(-0.15) and a.iou_mean == 1.0


def test_assignment_is_optimal_not_greedy():
    # centres on a line: S at 0 and 10, P at 6 and 20.
    # greedy (closest first): S1-P0 (4), then S0-P1 (20): total 24
    # optimal: S0-P0 (6) + S1-P1 (10) = 16
    S = np.array([[0, 0, 4, 4, 5.0], [10, 0, 4, 4, 5.0]])
    P = np.array([[6, 0, 4, 4, 5.0], [20, 0, 4, 4, 5.0]])
    np.testing.assert_array_equal(assign_by_centre(S, P), [0, 1])
    np.testing.assert_array_equal(align(S, P).partner, [0, 1])


def test_more_objects_than_predictions():
    S = np.array([[0, 0, 4, 4, 5.0], [100, 0, 4, 4, 5.0], [200, 0, 4, 4, 5.0]])
    P = np.array([[101, 0, 4, 4, 5.0]])
    a = align(S, P)
    np.testing.assert_array_equal(a.partner, [-1, 0, -1])
    # S1-P0: x [98, 102] & [99, 103] -> 3 * 4 = 12, union 16 + 16 - 12 = 20; RDD 0
    np.testing.assert_allclose(a.pair_iou, [0.0, 0.6, 0.0])
    np.testing.assert_allclose(a.pair_rdd, [1.0, 0.0, 1.0])
    np.testing.assert_array_equal(a.matched, [False, True, False])
    assert a.iou_mean == pytest.approx(0.6 / 3)
    assert a.rdd_mean == pytest.approx(2 / 3)


def test_no_predictions_scores_every_object_worst():
    S = np.array([[0, 0, 4, 4, 5.0], [100, 0, 4, 4, 7.0]])
    a = align(S, EMPTY)
    assert a.n_objects > 0
    np.testing.assert_array_equal(a.partner, [-1, -1])
    assert a.iou_mean == 0.0 and a.rdd_mean == 1.0


@pytest.mark.parametrize("P", [EMPTY, np.array([[0, 0, 4, 4, 5.0]])])
def test_no_objects_has_no_features(P):
    a = align(EMPTY, P)
    assert a.n_objects == 0
    assert math.isnan(a.iou_mean) and math.isnan(a.rdd_mean)
    for arr in (a.partner, a.pair_iou, a.pair_rdd, a.matched, a.iou, a.rdd):
        assert arr.shape == (0,)


def test_prediction_at_distance_zero_is_allowed():
    a = align(np.array([[0, 0, 4, 4, 5.0]]), np.array([[0, 0, 4, 4, 0.0]]))
    assert a.pair_rdd[0] == -1.0 and not a.matched[0]  # (0 - 5) / 5


@pytest.mark.parametrize("S, P, kwargs, message", [
    ([[0, 0, 4, 4, 0.0]], EMPTY, {}, r"S\[0, 4\] \(d\) = 0.0: .*> 0 metres"),
    ([[0, 0, 4, 4, 1.0]], [[0, 0, 4, np.nan, 1.0]], {}, r"P\[0, 3\] \(h\) = nan"),
    (np.zeros((2, 4)), EMPTY, {}, r"S has shape \(2, 4\)"),
    (EMPTY, EMPTY, {"alpha": 1.5}, r"alpha = 1.5"),
    (EMPTY, EMPTY, {"alpha": np.nan}, r"alpha = nan"),
    (EMPTY, EMPTY, {"beta": 0.0}, r"beta = 0.0"),
    (EMPTY, EMPTY, {"beta": np.inf}, r"beta = inf"),
    (EMPTY, EMPTY, {"alpha": "0.3"}, r"alpha = '0.3', must be a number"),
    (EMPTY, EMPTY, {"beta": True}, r"beta = True, must be a number"),
])
def test_bad_input_is_rejected(S, P, kwargs, message):
    with pytest.raises(ValueError, match=message):
        align(S, P, **kwargs)


def test_alignment_is_frozen():
    a = align(np.array([[0, 0, 4, 4, 5.0]]), EMPTY)
    with pytest.raises(AttributeError):
        a.iou_mean = 1.0


# ------------------------------------------------- against a slow, obvious reference


def _reference(S, P, alpha, beta):
    """Brute force over every injective pairing, Python floats."""
    m, n = len(S), len(P)
    dist = [[math.dist(s[:2], p[:2]) for p in P] for s in S]
    best, best_partner = math.inf, None
    if m <= n:
        candidates = ((list(perm)) for perm in itertools.permutations(range(n), m))
    else:
        candidates = ([perm.index(i) if i in perm else -1 for i in range(m)]
                      for perm in itertools.permutations(range(m), n))
    for partner in candidates:
        total = sum(dist[i][j] for i, j in enumerate(partner) if j >= 0)
        if total < best:
            best, best_partner = total, partner
    ious, rdds = [], []
    for i, j in enumerate(best_partner):
        if j < 0:
            ious.append(0.0), rdds.append(1.0)
            continue
        s, p = S[i], P[j]
        iw = max(0.0, min(s[0] + s[2] / 2, p[0] + p[2] / 2) - max(s[0] - s[2] / 2, p[0] - p[2] / 2))
        ih = max(0.0, min(s[1] + s[3] / 2, p[1] + p[3] / 2) - max(s[1] - s[3] / 2, p[1] - p[3] / 2))
        iou = iw * ih / (s[2] * s[3] + p[2] * p[3] - iw * ih)
        rdd = min(1.0, (p[4] - s[4]) / s[4])
        ok = iou > alpha and abs(rdd) < beta
        ious.append(iou if ok else 0.0), rdds.append(rdd if ok else 1.0)
    return best_partner, ious, rdds


def _frame(rng, m):
    return np.column_stack([rng.uniform(0, 200, m), rng.uniform(0, 100, m),
                            rng.uniform(5, 60, m), rng.uniform(5, 60, m),
                            rng.uniform(1, 20, m)])


@pytest.mark.parametrize("seed", range(40))
def test_matches_brute_force_reference(seed):
    rng = np.random.default_rng(seed)
    m, n = rng.integers(0, 6, size=2)
    S = _frame(rng, m)
    P = _frame(rng, n)
    P[: min(m, n)] = S[: min(m, n)] * rng.uniform(0.85, 1.15, (min(m, n), 5))  # near pairs
    a = align(S, P)
    if m == 0:
        assert a.n_objects == 0
        return
    partner, ious, rdds = _reference(S.tolist(), P.tolist(), 0.3, 0.2)
    np.testing.assert_array_equal(a.partner, partner)
    np.testing.assert_allclose(a.iou, ious, atol=1e-12)
    np.testing.assert_allclose(a.rdd, rdds, atol=1e-12)
    assert a.iou_mean == pytest.approx(np.mean(ious)) and a.rdd_mean == pytest.approx(np.mean(rdds))


# ------------------------------------------------------------------------ properties

def _frames():
    row = st.tuples(st.floats(0, 1600), st.floats(0, 900), st.floats(0, 300),
                    st.floats(0, 300), st.floats(0.5, 60))
    return st.lists(row, min_size=1, max_size=12).map(np.array)


@given(_frames(), _frames(), st.randoms(use_true_random=False))
def test_hungarian_cost_no_worse_than_a_random_assignment(S, P, random):
    partner = assign_by_centre(S, P)
    cost = centre_distances(S, P)
    total = sum(cost[i, j] for i, j in enumerate(partner) if j >= 0)
    assert (partner >= 0).sum() == min(len(S), len(P))
    assert len(set(partner[partner >= 0].tolist())) == (partner >= 0).sum()  # injective
    rows = random.sample(range(len(S)), min(len(S), len(P)))
    cols = random.sample(range(len(P)), min(len(S), len(P)))
    assert total <= sum(cost[i, j] for i, j in zip(rows, cols)) + 1e-9


@given(_frames(), _frames(), st.floats(0, 1), st.floats(0.01, 2))
def test_features_bounded(S, P, alpha, beta):
    a = align(S, P, alpha, beta)
    assert 0.0 <= a.iou_mean <= 1.0 and -1.0 <= a.rdd_mean <= 1.0
    assert np.all((a.pair_rdd >= -1.0) & (a.pair_rdd <= 1.0))
    assert np.all((a.pair_iou >= 0.0) & (a.pair_iou <= 1.0))
    assert a.iou_mean == pytest.approx(a.iou.mean()) and a.rdd_mean == pytest.approx(a.rdd.mean())


# ------------------------------------------------------------------ coverage matching

def test_coverage_of_a_hand_made_frame():
    S = np.array([[100, 100, 40, 20, 10.0],    # x [80, 120], y [90, 110], area 800
                  [300, 100, 20, 20, 8.0],     # x [290, 310], area 400
                  [500, 100, 20, 20, 5.0]])    # x [490, 510]: no detection near it
    P = np.array([[85, 100, 30, 20, 9.0],      # x [70, 100]: covers S0's x [80, 100] -> 400
                  [115, 105, 30, 10, 12.0],    # x [100, 130], y [100, 110]: S0's x [100, 120] x 10 -> 200
                  [110, 100, 10, 20, 30.0],    # RDD (30 - 10) / 10 -> 1: too far, takes no part
                  [310, 100, 30, 40, 20.0]])   # x [295, 325]: S1 x [295, 310] -> 300, but RDD 1.5 -> 1
    a = align(S, P, alpha=0.3, beta=1.0, matching="coverage")
    # S0: P0 and P1 take part, their parts inside S0 do not overlap: (400 + 200) / 800 = 0.75;
    #     P0 overlaps S0 most (400 > 200): RDD (9 - 10) / 10 = -0.1
    # S1: its only overlapping detection is 20 m away against 8 m: nothing takes part
    # S2: nothing near it
    np.testing.assert_array_equal(a.partner, [0, -1, -1])
    np.testing.assert_allclose(a.pair_iou, [0.75, 0.0, 0.0])
    np.testing.assert_allclose(a.pair_rdd, [-0.1, 1.0, 1.0])
    np.testing.assert_array_equal(a.matched, [True, False, False])
    assert a.iou_mean == pytest.approx(0.75 / 3) and a.rdd_mean == pytest.approx((-0.1 + 2.0) / 3)
    assert a.matching == "coverage"
    # a looser depth test lets P3 cover S1: 300 / 400, its RDD clipped to 1
    loose = align(S, P, alpha=0.3, beta=2.0, matching="coverage")
    np.testing.assert_allclose(loose.pair_iou[1], 0.75)
    assert loose.pair_rdd[1] == 1.0 and loose.matched[1]
    # inverse-distance weights 1/10, 1/8, 1/5 (sum 0.425)
    weighted = align(S, P, alpha=0.3, beta=1.0, weighting="inverse_distance", matching="coverage")
    assert weighted.iou_mean == pytest.approx(0.1 * 0.75 / 0.425)
    assert weighted.rdd_mean == pytest.approx((0.1 * -0.1 + 0.125 + 0.2) / 0.425)


def test_coverage_counts_overlapping_detections_once_and_is_not_thrown_by_merges():
    S = np.array([[100, 100, 40, 20, 10.0]])           # two cars side by side, merged into one S
    halves = np.array([[90, 100, 20, 20, 10.0], [110, 100, 20, 20, 10.5]])
    assert align(S, halves, beta=1.0, matching="coverage").pair_iou[0] == pytest.approx(1.0)
    # the paper's pairs see one half at IoU 0.5 and leave the other detection unused
    assert align(S, halves).pair_iou[0] == pytest.approx(0.5)
    same = np.array([[100, 100, 40, 20, 10.0], [100, 100, 40, 20, 10.0], [95, 100, 30, 20, 10.0]])
    assert align(S, same, beta=1.0, matching="coverage").pair_iou[0] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="matching = 'greedy', must be one of hungarian, coverage"):
        align(S, halves, matching="greedy")


def _coverage_reference(S, P, alpha, beta, step=0.25):
    """Covered share by counting the centres of a fine grid of cells inside S."""
    cov, rdd, matched = [], [], []
    for s in S:
        x0, x1, y0, y1 = s[0] - s[2] / 2, s[0] + s[2] / 2, s[1] - s[3] / 2, s[1] + s[3] / 2
        xs = np.arange(x0 + step / 2, x1, step)
        ys = np.arange(y0 + step / 2, y1, step)
        X, Y = np.meshgrid(xs, ys)
        inside = np.zeros(X.shape, bool)
        best, best_inter = -1, 0.0
        for j, p in enumerate(P):
            if not min(1.0, (p[4] - s[4]) / s[4]) < beta:
                continue
            inside |= (np.abs(X - p[0]) < p[2] / 2) & (np.abs(Y - p[1]) < p[3] / 2)
            iw = min(x1, p[0] + p[2] / 2) - max(x0, p[0] - p[2] / 2)
            ih = min(y1, p[1] + p[3] / 2) - max(y0, p[1] - p[3] / 2)
            if iw > 0 and ih > 0 and iw * ih > best_inter:
                best, best_inter = j, iw * ih
        c = inside.mean() if inside.size else 0.0
        cov.append(c)
        rdd.append(min(1.0, (P[best][4] - s[4]) / s[4]) if best >= 0 else 1.0)
        matched.append(best >= 0 and c > alpha)
    return np.array(cov), np.array(rdd), np.array(matched)


@pytest.mark.parametrize("seed", range(30))
def test_coverage_matches_a_grid_count(seed):
    rng = np.random.default_rng(seed)
    m, n = rng.integers(1, 5), rng.integers(0, 7)
    # integer corners, so the grid's cell centres never lie on an edge and the count is exact
    S = np.column_stack([rng.integers(0, 40, m) + 0.5 * (w := rng.integers(2, 20, m)),
                         rng.integers(0, 20, m) + 0.5 * (h := rng.integers(2, 12, m)), w, h,
                         rng.uniform(2, 20, m)]).astype(float)
    P = np.column_stack([rng.integers(0, 40, n) + 0.5 * (w := rng.integers(2, 25, n)),
                         rng.integers(0, 20, n) + 0.5 * (h := rng.integers(2, 15, n)), w, h,
                         rng.uniform(1, 40, n)]).astype(float)
    a = align(S, P, 0.3, 0.5, matching="coverage")
    cov, rdd, matched = _coverage_reference(S, P, 0.3, 0.5)
    np.testing.assert_allclose(a.pair_iou, cov, atol=1e-12)
    np.testing.assert_allclose(a.pair_rdd, rdd, atol=1e-12)
    np.testing.assert_array_equal(a.matched, matched)
    assert a.iou_mean == pytest.approx(np.mean(np.where(matched, cov, 0.0)))
    assert a.rdd_mean == pytest.approx(np.mean(np.where(matched, rdd, 1.0)))


@given(_frames(), _frames(), st.floats(0, 1), st.floats(0.01, 2))
def test_coverage_features_bounded(S, P, alpha, beta):
    a = align(S, P, alpha, beta, matching="coverage")
    assert 0.0 <= a.iou_mean <= 1.0 and -1.0 <= a.rdd_mean <= 1.0
    assert np.all((a.pair_iou >= 0.0) & (a.pair_iou <= 1.0))
    assert np.all((a.pair_rdd >= -1.0) & (a.pair_rdd <= 1.0))


# ------------------------------------------------------------------ the known objects

def test_known_objects_of_a_hand_made_frame():
    # the coverage frame above, plus two detections the depth view did not see, one of them
    # beyond the range limit
    S = np.array([[100, 100, 40, 20, 10.0], [300, 100, 20, 20, 8.0], [500, 100, 20, 20, 5.0]])
    P = np.array([[85, 100, 30, 20, 9.0], [115, 105, 30, 10, 12.0], [110, 100, 10, 20, 30.0],
                  [310, 100, 30, 40, 20.0], [700, 100, 20, 20, 15.0], [800, 100, 20, 20, 25.0]])
    a = align(S, P, alpha=0.3, beta=1.0, matching="coverage", objects="known", max_range=20.0)
    depth = align(S, P, alpha=0.3, beta=1.0, matching="coverage")
    # the per-S table is the same either way
    np.testing.assert_array_equal(a.partner, depth.partner)
    np.testing.assert_array_equal(a.pair_iou, depth.pair_iou)
    np.testing.assert_array_equal(a.matched, [True, False, False])
    # P0 partners the counted S0: its terms are S0's, 0.75 and -0.1; P1, P3 (20 m: within)
    # and P4 partner no counted S: 1 and 0; P2 (30 m) and P5 (25 m) are out of range
    np.testing.assert_allclose(a.det_iou, [0.75, 1, 1, 1, 1, 1])
    np.testing.assert_allclose(a.det_rdd, [-0.1, 0, 0, 0, 0, 0])
    np.testing.assert_array_equal(a.det_counted, [True, True, False, True, True, False])
    # terms: the unseen S1 and S2 (0 and 1 each) and the four counted detections
    assert a.n_terms == 6 and a.n_objects == 3
    assert a.iou_mean == pytest.approx((0.75 + 3) / 6)
    assert a.rdd_mean == pytest.approx((2 - 0.1) / 6)
    assert (a.objects, depth.objects) == ("known", "depth") and depth.n_terms == 3
    # a detection beyond the range still counts when it partners a counted S
    far = P.copy()
    far[0, 4] = 21.0  # RDD (21 - 10) / 10 -> 1: not < beta 1.0, P0 would take no part; beta 2 lets it
    b = align(S, far, alpha=0.3, beta=2.0, matching="coverage", objects="known", max_range=20.0)
    assert b.partner[0] == 0 and b.matched[0] and b.det_counted[0]


def test_known_objects_take_the_largest_terms_of_the_s_partnering_a_detection():
    # one detection over two objects side by side (a split view of one car, say)
    S = np.array([[90, 100, 20, 20, 10.0], [110, 100, 20, 20, 12.0]])
    P = np.array([[100, 100, 40, 20, 11.0]])
    a = align(S, P, alpha=0.3, beta=0.2, objects="known", max_range=20.0)  # Hungarian pairs
    # S0-P0: IoU 400 / 800 = 0.5, RDD 0.1 -> counts; S1 is left without a partner
    np.testing.assert_array_equal(a.partner, [0, -1])
    assert a.iou_mean == pytest.approx((0.5 + 0.0) / 2) and a.rdd_mean == pytest.approx((0.1 + 1.0) / 2)
    cov = align(S, P, alpha=0.3, beta=0.2, matching="coverage", objects="known", max_range=20.0)
    # coverage: both S inside P (1.0 each), RDD 0.1 and (11 - 12) / 12: one term, the largest
    assert cov.matched.all() and cov.n_terms == 1
    assert cov.iou_mean == pytest.approx(1.0) and cov.rdd_mean == pytest.approx(0.1)


def test_known_objects_of_empty_frames():
    P = np.array([[100, 100, 20, 20, 10.0]])
    only_detections = align(EMPTY, P, objects="known", max_range=20.0)
    assert only_detections.n_terms == 1 and (only_detections.iou_mean, only_detections.rdd_mean) == (1.0, 0.0)
    nothing = align(EMPTY, np.array([[100, 100, 20, 20, 30.0]]), objects="known", max_range=20.0)
    assert nothing.n_terms == 0 and np.isnan(nothing.iou_mean) and np.isnan(nothing.rdd_mean)
    unseen = align(P, EMPTY, objects="known")
    assert unseen.n_terms == 1 and (unseen.iou_mean, unseen.rdd_mean) == (0.0, 1.0)
    with pytest.raises(ValueError, match="objects = 'all', must be one of depth, known"):
        align(P, P, objects="all")
    with pytest.raises(ValueError, match="objects = 'known' with weighting = 'inverse_distance'"):
        align(P, P, objects="known", weighting="inverse_distance")
    with pytest.raises(ValueError, match=r"max_range = -1, expected a distance > 0 metres"):
        align(P, P, objects="known", max_range=-1)


def _known_reference(S, P, alpha, beta, matching, max_range):
    """The known objects' features written out object by object."""
    a = align(S, P, alpha, beta, matching=matching)  # the per-S table, the paper's population
    terms = [(0.0, 1.0) for i in range(len(S)) if not a.matched[i]]
    for j in range(len(P)):
        mine = [i for i in range(len(S)) if a.matched[i] and a.partner[i] == j]
        if mine:
            terms.append((max(a.pair_iou[i] for i in mine), max(a.pair_rdd[i] for i in mine)))
        elif P[j, 4] <= max_range:
            terms.append((1.0, 0.0))
    if not terms:
        return math.nan, math.nan
    return tuple(np.mean(terms, axis=0))


@given(_frames(), _frames(), st.floats(0, 1), st.floats(0.01, 2), st.sampled_from(["hungarian", "coverage"]),
       st.floats(1, 40))
def test_known_objects_match_a_reference_and_stay_bounded(S, P, alpha, beta, matching, max_range):
    a = align(S, P, alpha, beta, matching=matching, objects="known", max_range=max_range)
    iou, rdd = _known_reference(S, P, alpha, beta, matching, max_range)
    if math.isnan(iou):
        assert a.n_terms == 0 and np.isnan(a.iou_mean) and np.isnan(a.rdd_mean)
        return
    assert a.iou_mean == pytest.approx(iou) and a.rdd_mean == pytest.approx(rdd)
    assert 0.0 <= a.iou_mean <= 1.0 and -1.0 <= a.rdd_mean <= 1.0
