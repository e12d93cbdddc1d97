"""fuzzcore.tune data handling: the feature CSV reader, data checks, folds, early stopping."""
import numpy as np
import pytest

import fuzzcore
from fuzzcore.tune import EarlyStopping, check_data, fold_labels, read_csv

RULES = "rules/fuzzrisk.yaml"


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load(RULES)


def _write(tmp_path, text, name="f.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# --------------------------------------------------------------------------- read_csv
def test_read_csv_keeps_usable_rows_and_counts_skipped(tmp_path):
    path = _write(tmp_path, "scene,frame,condition,iou,rdd,target\n"
                            "s1,0,nominal,0.5,0.1,0.25\n"
                            "s1,1,nominal,,,0.4\n"          # no features
                            "s1,2,nominal,0.3,0.2,\n"       # no target
                            "\n"                            # blank line: ignored
                            "s2,0,rain,0.0,1.0,NaN\n"       # no target, spelled NaN
                            "s2,1,rain,1,-0.5,0.75\n")
    table = read_csv(path, ["iou", "rdd"])
    np.testing.assert_array_equal(table.X, [[0.5, 0.1], [1.0, -0.5]])
    np.testing.assert_array_equal(table.y, [0.25, 0.75])
    np.testing.assert_array_equal(table.groups, ["s1", "s2"])
    np.testing.assert_array_equal(table.columns["condition"], ["nominal", "rain"])
    np.testing.assert_array_equal(table.lines, [2, 7])
    assert (table.n_no_target, table.n_no_features) == (2, 1)


def test_read_csv_column_order_follows_inputs_and_group_is_optional(tmp_path):
    path = _write(tmp_path, "target,rdd,iou\n0.5,0.2,0.9\n")
    table = read_csv(path, ["iou", "rdd"])
    np.testing.assert_array_equal(table.X, [[0.9, 0.2]])
    assert table.groups is None


@pytest.mark.parametrize("text, words", [
    ("iou,target\n0.5,0.2\n", ["missing column", "rdd"]),
    ("iou,rdd,target\n0.5,abc,0.2\n", ["line 2", "'rdd'", "'abc'"]),
    ("iou,rdd,target\n0.5,0.1,inf\n", ["line 2", "'target'", "finite"]),
    ("iou,rdd,target\n0.5,0.1\n", ["line 2", "2 cells, expected 3"]),
    ("iou,rdd,target,iou\n", ["repeated column", "iou"]),
    ("", ["empty"]),
    ("iou,rdd,target\n0.5,0.1,\n", ["no usable row", "1 without a target"]),
    ("scene,iou,rdd,target\n,0.5,0.1,0.3\n", ["line 2", "'scene'", "empty group"]),
])
def test_read_csv_errors_name_file_line_and_column(tmp_path, text, words):
    path = _write(tmp_path, text)
    with pytest.raises(ValueError) as info:
        read_csv(path, ["iou", "rdd"])
    message = str(info.value)
    assert str(path) in message
    for word in words:
        assert word in message


def test_read_csv_missing_file_is_an_oserror(tmp_path):
    with pytest.raises(OSError):
        read_csv(tmp_path / "nope.csv", ["iou", "rdd"])


# --------------------------------------------------------------------------- check_data
def test_check_data_accepts_and_shapes(fis):
    X, Y, groups = check_data(fis, [[0.1, 0.2], [0.3, 0.4]], [0.5, 0.6], ["a", "b"])
    assert X.shape == (2, 2) and Y.shape == (2, 1) and X.flags.c_contiguous
    np.testing.assert_array_equal(Y[:, 0], [0.5, 0.6])


@pytest.mark.parametrize("X, y, groups, words", [
    (np.zeros((3, 3)), np.zeros(3), None, ["X has shape (3, 3)", "iou, rdd"]),
    (np.zeros((3, 2)), np.zeros(4), None, ["y has shape (4,)", "(3,)"]),
    (np.zeros((0, 2)), np.zeros(0), None, ["no rows"]),
    (np.array([[0.1, 0.2], [np.nan, 0.0], [0.3, 0.3]]), np.zeros(3), None, ["X has 1 row", "row 1"]),
    (np.zeros((3, 2)), np.array([0.1, np.inf, 0.2]), None, ["y has 1 row", "row 1"]),
    (np.zeros((3, 2)), np.array([0.1, 1.5, -0.2]), None, ["2 target(s) outside", "[0, 1]", "'risk'", "row 1"]),
    (np.zeros((3, 2)), np.zeros(3), ["a", "b"], ["groups has shape (2,)"]),
])
def test_check_data_refuses_bad_data(fis, X, y, groups, words):
    with pytest.raises(ValueError) as info:
        check_data(fis, X, y, groups)
    for word in words:
        assert word in str(info.value)


# --------------------------------------------------------------------------- folds
def test_fold_labels_without_groups_are_balanced_and_seeded():
    labels = fold_labels(23, 5, np.random.default_rng(4))
    np.testing.assert_array_equal(np.bincount(labels), [5, 5, 5, 4, 4])
    np.testing.assert_array_equal(labels, fold_labels(23, 5, np.random.default_rng(4)))
    assert not np.array_equal(labels, fold_labels(23, 5, np.random.default_rng(5)))


def test_fold_labels_never_split_a_group():
    rng = np.random.default_rng(0)
    groups = np.repeat([f"scene-{k}" for k in range(12)], rng.integers(1, 30, 12))
    labels = fold_labels(groups.shape[0], 5, np.random.default_rng(1), groups)
    for g in np.unique(groups):
        assert np.unique(labels[groups == g]).shape[0] == 1
    assert set(labels) == set(range(5))
    # greedy dealing: no fold is heavier than the lightest plus the largest group
    sizes = np.bincount(labels)
    assert sizes.max() - sizes.min() <= np.unique(groups, return_counts=True)[1].max()


def test_fold_labels_need_enough_groups_and_samples():
    with pytest.raises(ValueError, match="only 3 groups"):
        fold_labels(6, 5, np.random.default_rng(0), np.array(list("aabbcc")))
    with pytest.raises(ValueError, match="only 4 samples"):
        fold_labels(4, 5, np.random.default_rng(0))


def _stopping(costs, tol, window):
    """An EarlyStopping whose validation cost of point [k] is costs[k]."""
    return EarlyStopping(lambda P: np.array([costs[int(P[0, 0])]]), tol=tol, window=window)


def test_early_stopping_rule_by_hand():
    costs = [1.0, 0.8, 0.86, 0.93]
    # window 1: 0.86 <= 1.1 * 0.8 = 0.88 and 0.93 <= 1.1 * 0.86 = 0.946: never stops
    stop = _stopping(costs, tol=0.1, window=1)
    assert [stop.update(np.array([float(k)])) for k in range(4)] == [False, False, False, False]
    # window 2: 0.93 > 1.1 * min(0.8, 0.86) = 0.88: stops at the last point
    stop = _stopping(costs, tol=0.1, window=2)
    assert [stop.update(np.array([float(k)])) for k in range(4)] == [False, False, False, True]
    # the point handed on is the best seen, not the last
    assert stop.best_value == 0.8 and stop.best_x[0] == 1.0
    assert stop.values == costs
