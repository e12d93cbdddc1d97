"""Tests for monitor.offline.groundtruth: USC~ per frame and the target 1 - USC~."""
import itertools
import math

import numpy as np
import pytest

from monitor.alignment import assign_by_centre
from monitor.geometry.boxes import usc
from monitor.offline.groundtruth import NO_TARGETS, OK, score

EMPTY = np.empty((0, 5))

G = np.array([[100, 100, 20, 20, 10.0],   # G0: x [90, 110], y [90, 110]
              [300, 100, 40, 20, 8.0],    # G1: x [280, 320], y [90, 110]
              [600, 100, 10, 10, 25.0],   # G2: beyond 20 m
              [800, 300, 10, 10, 15.0]])  # G3: in range, no prediction left for it
P = np.array([[105, 100, 20, 20, 12.5],   # P0 on G0: x [95, 115]
              [300, 100, 20, 20, 6.0]])   # P1 inside G1: x [290, 310]


def test_hand_made_frame():
    r = score(P, G)
    np.testing.assert_array_equal(r.g_index, [0, 1, 3])
    np.testing.assert_array_equal(r.partner, [0, 1, -1])
    # G0-P0: intersection 15 * 20 = 300, area(G0) 400 -> IoG 0.75; DR min(1, 10 / 12.5) = 0.8
    # G1-P1: P1 inside G1: 400 / 800 -> IoG 0.5; DR min(1, 8 / 6) = 1
    # G3: no prediction -> 0
    np.testing.assert_allclose(r.iog, [0.75, 0.5, 0.0])
    np.testing.assert_allclose(r.depth_ratio, [0.8, 1.0, 0.0])
    np.testing.assert_allclose(r.usc, [0.6, 0.5, 0.0])
    assert r.usc_mean == pytest.approx((0.6 + 0.5 + 0.0) / 3)
    assert r.target == pytest.approx(1 - 1.1 / 3)
    assert r.status == OK and r.n_targets == 3 and r.max_range == 20.0


def test_range_limit_is_configurable_and_inclusive():
    r = score(P, G, max_range=25.0)  # G2 at exactly 25 m now counts
    np.testing.assert_array_equal(r.g_index, [0, 1, 2, 3])
    assert r.usc_mean == pytest.approx(1.1 / 4)
    r = score(P, G, max_range=9.0)  # only G1 (8 m)
    np.testing.assert_array_equal(r.g_index, [1])
    # G1 alone: P1 covers it best (P0 does not overlap it): USC 0.5
    np.testing.assert_array_equal(r.partner, [1])
    assert r.target == pytest.approx(0.5)


def test_no_ground_truth_in_range_has_no_target():
    for frame in (score(P, G, max_range=5.0), score(P, EMPTY), score(EMPTY, EMPTY)):
        assert frame.status == NO_TARGETS and frame.n_targets == 0
        assert math.isnan(frame.usc_mean) and math.isnan(frame.target)


def test_no_predictions_is_full_risk():
    r = score(EMPTY, G)
    np.testing.assert_array_equal(r.partner, [-1, -1, -1])
    assert r.usc_mean == 0.0 and r.target == 1.0 and r.status == OK


def test_pairing_maximises_usc_where_centre_distance_would_not():
    # G0 at x = 0 with P0 lying on it, G1 at x = 100 that nothing covers, P1 at x = -60.
    # On centre distance G0-P1 + G1-P0 = 60 + 99 = 159 beats G0-P0 + G1-P1 = 1 + 160 = 161,
    # which scores G0 as missed although P0 covers it.
    g = np.array([[0, 0, 10, 10, 5.0], [100, 0, 10, 10, 5.0]])
    p = np.array([[1, 0, 10, 10, 5.0], [-60, 0, 10, 10, 5.0]])
    np.testing.assert_array_equal(assign_by_centre(g, p), [1, 0])
    r = score(p, g)
    np.testing.assert_array_equal(r.partner, [0, -1])  # G1: no P covers it
    # G0 x [-5, 5] & P0 x [-4, 6] -> 9 * 10 = 90 of 100; DR 1
    np.testing.assert_allclose(r.usc, [0.9, 0.0])
    assert r.target == pytest.approx(1 - 0.45)


def test_pairing_is_one_to_one():
    # two G side by side under one wide P: it covers one of them, not both
    g = np.array([[0, 0, 10, 10, 5.0], [10, 0, 10, 10, 5.0]])
    p = np.array([[5, 0, 20, 10, 5.0]])
    r = score(p, g)
    assert sorted(r.partner.tolist()) == [-1, 0]
    np.testing.assert_allclose(sorted(r.usc), [0.0, 1.0])


def _random_boxes(rng, n, extent, sides, depths) -> np.ndarray:
    """n boxes: centres uniform in [0, extent], sides in ``sides``, depths in ``depths``."""
    return np.column_stack([rng.uniform(0, extent[0], n), rng.uniform(0, extent[1], n),
                            rng.uniform(*sides, (n, 2)), rng.uniform(*depths, n)])


def _best_total_usc(p, g) -> float:
    """The largest summed USC of any one-to-one pairing, by trying every one."""
    best = 0.0
    k = min(len(p), len(g))
    for rows in itertools.permutations(range(len(g)), k):
        for cols in itertools.permutations(range(len(p)), k):
            best = max(best, sum(usc(p[j], g[i]) for i, j in zip(rows, cols)))
    return best


def test_summed_usc_is_the_best_of_every_pairing():
    rng = np.random.default_rng(3)
    for _ in range(40):
        n, m = rng.integers(0, 5, size=2)
        g = _random_boxes(rng, m, (100, 50), (5, 60), (1, 19))  # all within 20 m
        p = _random_boxes(rng, n, (100, 50), (5, 60), (1, 30))
        r = score(p, g)
        assert r.usc.sum() == pytest.approx(_best_total_usc(p, g), abs=1e-12)
        paired = r.partner >= 0
        assert len(set(r.partner[paired].tolist())) == int(paired.sum())  # each P once
        np.testing.assert_allclose(r.usc[paired], usc(p[r.partner[paired]], g[paired]))


@pytest.mark.parametrize("p, g, kwargs, message", [
    (P, [[0, 0, 0, 5, 5.0]], {}, r"G\[0, 2\] \(w\) = 0.0: .*positive area"),
    ([[0, 0, 1, 1, -1.0]], G, {}, r"P\[0, 4\] \(d\) = -1.0"),
    (P, G, {"max_range": 0.0}, r"max_range = 0.0"),
])
def test_bad_input_is_rejected(p, g, kwargs, message):
    with pytest.raises(ValueError, match=message):
        score(p, g, **kwargs)


def test_scores_bounded_on_random_frames():
    rng = np.random.default_rng(7)
    for _ in range(50):
        n, m = rng.integers(0, 8, size=2)
        g = _random_boxes(rng, m, (400, 200), (1, 80), (0, 40))
        p = _random_boxes(rng, n, (400, 200), (0, 80), (0, 40))
        r = score(p, g)
        assert r.n_targets == int((g[:, 4] <= 20.0).sum())
        assert np.all((r.usc >= 0.0) & (r.usc <= 1.0))
        assert np.all(r.usc <= r.iog) and np.all(r.usc <= r.depth_ratio)
        if r.n_targets:
            assert 0.0 <= r.target <= 1.0
