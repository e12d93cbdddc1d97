"""Tests for monitor.geometry.boxes: validation, the paper's measures, the range limit."""
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from monitor.geometry.boxes import (DEFAULT_RANGE_M, as_boxes, centre_distances, depth_ratio, iog,
                           iou, range_mask, rdd, usc, within_range)


def box(cx, cy, w, h, d=5.0):
    return np.array([cx, cy, w, h, d], dtype=float)


def _coord():
    return st.floats(-1000.0, 1000.0)


def _size(min_size):
    # sizes not far below the coordinates' precision (1e-13 at 1000), or exactly 0
    positive = st.floats(max(min_size, 1e-3), 500.0)
    return positive if min_size > 0 else st.one_of(st.just(0.0), positive)


def boxes_strategy(min_size=0.0):
    return st.builds(box, _coord(), _coord(), _size(min_size), _size(min_size),
                     st.floats(0.0, 100.0))


# ---------------------------------------------------------------- hand-computed cases


def test_iou_partial_overlap_by_hand():
    # a: x [8, 12], y [9, 11]; b: x [9, 13], y [9, 11]
    # intersection 3 * 2 = 6; union 8 + 8 - 6 = 10
    assert iou(box(10, 10, 4, 2), box(11, 10, 4, 2)) == pytest.approx(0.6)


def test_iou_containment_by_hand():
    # a: 4 x 4 = 16 contains b: 2 x 2 = 4 -> 4 / 16
    assert iou(box(0, 0, 4, 4), box(0, 0, 2, 2)) == pytest.approx(0.25)


def test_iou_disjoint_and_touching_are_zero():
    assert iou(box(0, 0, 2, 2), box(10, 0, 2, 2)) == 0.0
    assert iou(box(0, 0, 2, 2), box(2, 0, 2, 2)) == 0.0  # x [-1, 1] and [1, 3] share an edge


def test_iou_broadcasts_and_returns_float_for_single_boxes():
    a = np.stack([box(0, 0, 2, 2), box(1, 0, 2, 2), box(5, 5, 1, 1)])
    b = np.stack([box(0, 0, 2, 2), box(0, 1, 2, 2)])
    out = iou(a[:, None], b[None, :])
    assert out.shape == (3, 2)
    expected = [[iou(x, y) for y in b] for x in a]
    np.testing.assert_array_equal(out, expected)
    # a[1] vs b[1]: x [0, 2] & [-1, 1] -> 1; y [-1, 1] & [0, 2] -> 1; union 4 + 4 - 1 = 7
    assert out[1, 1] == pytest.approx(1 / 7)
    assert isinstance(iou(a[0], b[0]), float)


def test_degenerate_boxes_have_iou_zero_even_with_themselves():
    line = box(5, 5, 0, 4)
    assert iou(line, line) == 0.0
    assert iou(line, box(5, 5, 10, 10)) == 0.0
    point = box(0, 0, 0, 0)
    assert iou(point, point) == 0.0


def test_iog_by_hand():
    # p: x [9, 13], g: x [8, 12], both y [9, 11]: intersection 6, area(g) = 8
    assert iog(box(11, 10, 4, 2), box(10, 10, 4, 2)) == pytest.approx(0.75)
    # p contains g: intersection = area(g)
    assert iog(box(0, 0, 10, 10), box(1, 1, 2, 2)) == 1.0
    # a degenerate prediction covers nothing
    assert iog(box(10, 10, 0, 2), box(10, 10, 4, 2)) == 0.0


def test_iog_of_zero_area_ground_truth_is_an_error():
    with pytest.raises(ValueError, match=r"g\[1, 2\] \(w\) = 0.0.*positive area"):
        iog(np.stack([box(0, 0, 1, 1)] * 2), np.stack([box(0, 0, 1, 1), box(0, 0, 0, 1)]))
    with pytest.raises(ValueError, match=r"g\[3\] \(h\)"):
        iog(box(0, 0, 1, 1), box(0, 0, 1, 0))


def test_rdd_by_hand():
    assert rdd(6.0, 5.0) == pytest.approx(0.2)  # (6 - 5) / 5
    assert rdd(2.0, 5.0) == pytest.approx(-0.6)  # (2 - 5) / 5
    assert rdd(15.0, 5.0) == 1.0  # min(1, (15 - 5) / 5 = 2)
    assert rdd(0.0, 5.0) == -1.0  # a prediction at the ego: (0 - 5) / 5
    np.testing.assert_allclose(rdd([6.0, 2.0], 5.0), [0.2, -0.6])


def test_rdd_needs_positive_d_s_and_nonnegative_d_p():
    with pytest.raises(ValueError, match=r"d_s = 0.0: .*> 0"):
        rdd(1.0, 0.0)
    with pytest.raises(ValueError, match=r"d_s\[1\] = -2.0"):
        rdd(1.0, [1.0, -2.0])
    with pytest.raises(ValueError, match=r"d_p = -1.0: .*>= 0"):
        rdd(-1.0, 2.0)
    with pytest.raises(ValueError, match=r"d_p\[0\] = nan"):
        rdd([np.nan], 2.0)
    with pytest.raises(ValueError, match="d_s = inf"):
        rdd(1.0, np.inf)


def test_depth_ratio_by_hand():
    assert depth_ratio(4.0, 2.0) == 0.5  # prediction twice as far: 2 / 4
    assert depth_ratio(2.0, 4.0) == 1.0  # min(1, 4 / 2)
    assert depth_ratio(0.0, 3.0) == 1.0  # a prediction at the ego is not too far
    assert depth_ratio(0.0, 0.0) == 1.0  # d_p <= d_g
    assert depth_ratio(3.0, 0.0) == 0.0  # 0 / 3
    with pytest.raises(ValueError, match="d_g"):
        depth_ratio(1.0, -1.0)


def test_usc_by_hand():
    # IoG 0.75 (see test_iog_by_hand), DR = min(1, 5 / 6): 0.75 * 5 / 6 = 0.625
    assert usc(box(11, 10, 4, 2, 6.0), box(10, 10, 4, 2, 5.0)) == pytest.approx(0.625)
    # closer prediction: DR = min(1, 5 / 4) = 1
    assert usc(box(11, 10, 4, 2, 4.0), box(10, 10, 4, 2, 5.0)) == pytest.approx(0.75)
    with pytest.raises(ValueError, match="g"):
        usc(box(0, 0, 1, 1), box(0, 0, 0, 0))


def test_centre_distances_by_hand():
    a = np.stack([box(0, 0, 1, 1), box(10, 10, 1, 1)])
    b = np.stack([box(3, 4, 1, 1), box(10, 10, 5, 5), box(0, 0, 9, 9)])
    # (0,0)-(3,4): 5; (0,0)-(10,10): sqrt(200); (10,10)-(3,4): sqrt(49 + 36)
    expected = [[5.0, np.sqrt(200.0), 0.0], [np.sqrt(85.0), 0.0, np.sqrt(200.0)]]
    np.testing.assert_allclose(centre_distances(a, b), expected)
    assert centre_distances(a, np.empty((0, 5))).shape == (2, 0)


# ---------------------------------------------------------------------- validation


def test_as_boxes_accepts_and_converts():
    a = np.zeros((3, 5))
    assert as_boxes(a) is a  # already float64 C-contiguous: no copy
    ints = as_boxes([[1, 2, 3, 4, 5]])
    assert ints.dtype == np.float64 and ints.tolist() == [[1.0, 2.0, 3.0, 4.0, 5.0]]
    assert as_boxes(np.empty((0, 5))).shape == (0, 5)
    assert as_boxes(np.zeros((2, 5), dtype=np.float32)).dtype == np.float64


@pytest.mark.parametrize("value, kwargs, message", [
    (np.zeros((2, 4)), {}, r"S has shape \(2, 4\), expected \(n, 5\)"),
    (np.zeros(5), {}, r"S has shape \(5,\)"),
    (np.zeros((1, 2, 5)), {}, r"S has shape \(1, 2, 5\)"),
    ([["a"] * 5], {}, r"S has dtype <U1"),
    (np.zeros((1, 5), dtype=bool), {}, r"S has dtype bool"),
    (np.zeros((1, 5), dtype=complex), {}, r"S has dtype complex128"),
    ([[0, 0, 1, 1, 1], [0, np.nan, 1, 1, 1]], {}, r"S\[1, 1\] \(cy\) = nan: must be finite"),
    ([[np.inf, 0, 1, 1, 1]], {}, r"S\[0, 0\] \(cx\) = inf"),
    ([[0, 0, -1, 1, 1]], {}, r"S\[0, 2\] \(w\) = -1.0: .*>= 0 pixels"),
    ([[0, 0, 1, -1, 1]], {}, r"S\[0, 3\] \(h\) = -1.0"),
    ([[0, 0, 1, 1, -0.5]], {}, r"S\[0, 4\] \(d\) = -0.5: distances must be >= 0"),
    ([[0, 0, 1, 1, 0]], {"positive_depth": True}, r"S\[0, 4\] \(d\) = 0.0: .*> 0 metres"),
    ([[0, 0, 0, 1, 1]], {"positive_area": True}, r"S\[0, 2\] \(w\) = 0.0: .*positive area"),
    ([[0, 0, 1, 0, 1]], {"positive_area": True}, r"S\[0, 3\] \(h\) = 0.0: .*positive area"),
])
def test_as_boxes_errors_name_the_argument_and_the_entry(value, kwargs, message):
    with pytest.raises(ValueError, match=message):
        as_boxes(value, "S", **kwargs)


def test_zero_sizes_and_depths_are_valid_by_default():
    assert as_boxes([[0, 0, 0, 0, 0]]).shape == (1, 5)


# --------------------------------------------------------------------- range limit


def test_within_range_keeps_rows_at_or_below_the_limit():
    b = np.array([[0, 0, 1, 1, 5.0], [1, 0, 1, 1, 20.0], [2, 0, 1, 1, 20.0001],
                  [3, 0, 1, 1, 30.0]])
    assert DEFAULT_RANGE_M == 20.0
    np.testing.assert_array_equal(within_range(b), b[:2])
    np.testing.assert_array_equal(range_mask(b), [True, True, False, False])
    np.testing.assert_array_equal(within_range(b, max_range=25.0), b[:3])
    np.testing.assert_array_equal(within_range(b, max_range=np.inf), b)
    assert within_range(np.empty((0, 5))).shape == (0, 5)
    out = within_range(b, max_range=100.0)
    out[0, 0] = 99.0
    assert b[0, 0] == 0.0  # a new array, not a view


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan])
def test_within_range_rejects_a_bad_limit(bad):
    with pytest.raises(ValueError, match="max_range"):
        within_range(np.zeros((1, 5)), bad)


def test_within_range_validates_boxes():
    with pytest.raises(ValueError, match=r"boxes\[0, 4\] \(d\) = nan"):
        within_range([[0, 0, 1, 1, np.nan]])


# ------------------------------------------------------------------------ properties


def _iou_reference(a, b):
    """Slow, obviously-correct IoU with Python floats."""
    iw = max(0.0, min(a[0] + a[2] / 2, b[0] + b[2] / 2) - max(a[0] - a[2] / 2, b[0] - b[2] / 2))
    ih = max(0.0, min(a[1] + a[3] / 2, b[1] + b[3] / 2) - max(a[1] - a[3] / 2, b[1] - b[3] / 2))
    union = a[2] * a[3] + b[2] * b[3] - iw * ih
    return iw * ih / union if union > 0 else 0.0


@given(boxes_strategy(), boxes_strategy())
def test_iou_symmetric_bounded_and_matches_reference(a, b):
    value = iou(a, b)
    assert value == iou(b, a)
    assert 0.0 <= value <= 1.0
    assert value == pytest.approx(_iou_reference(a, b), abs=1e-9)


@given(boxes_strategy(min_size=1e-3))
def test_iou_of_a_box_with_itself_is_one(a):
    assert iou(a, a) == 1.0


@given(boxes_strategy(min_size=1e-2), boxes_strategy(min_size=1e-2), _coord(), _coord())
def test_iou_translation_invariant(a, b, tx, ty):
    shift = np.array([tx, ty, 0.0, 0.0, 0.0])
    assert iou(a + shift, b + shift) == pytest.approx(iou(a, b), abs=1e-9)


@given(boxes_strategy(), boxes_strategy(min_size=1e-3))
def test_iog_bounded_and_at_least_iou(p, g):
    value = iog(p, g)
    assert 0.0 <= value <= 1.0
    assert value >= iou(p, g)  # union >= area(g)
    assert 0.0 <= usc(p, g) <= value


@given(st.floats(0.0, 1e4), st.floats(1e-6, 1e4))
def test_rdd_and_depth_ratio_bounded(d_p, d_s):
    assert -1.0 <= rdd(d_p, d_s) <= 1.0
    assert 0.0 <= depth_ratio(d_p, d_s) <= 1.0
    assert 0.0 <= depth_ratio(d_s, d_p) <= 1.0


def test_measures_are_defined_on_empty_frames():
    empty = np.empty((0, 5))
    assert iou(empty, empty).shape == (0,)
    assert iog(empty, empty).shape == (0,)
    assert rdd(np.empty(0), np.empty(0)).shape == (0,)
