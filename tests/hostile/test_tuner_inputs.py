"""Hostile data and settings for the tuners: each refused before any work, naming what is wrong."""
import numpy as np
import pytest

import fuzzcore
from fuzzcore.membership import WIDTH_MIN
from fuzzcore.tune import ParticleSwarm, PatternSearch, TermSpace, check_data
from fuzzcore.tune.particleswarm import MAX_SWARM

RULES = "rules/fuzzrisk.yaml"


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load(RULES)


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(3)
    X = np.column_stack([rng.uniform(0, 1, 40), rng.uniform(-1, 1, 40)])
    return X, rng.uniform(0, 1, 40), np.repeat(np.arange(8), 5)


@pytest.mark.parametrize("groups, words", [
    (np.array([0.0, np.nan] * 20), r"2\d? missing label\(s\) \(NaN or None; first: sample 1\)"),
    (np.array(["a", None] * 20, dtype=object), r"missing label\(s\) \(NaN or None; first: sample 1\)"),
    (np.array([1.0, float("nan")] * 20, dtype=object), "missing label"),
    (np.arange(40) + 0.5j, "groups has dtype complex128"),
])
def test_missing_or_meaningless_group_labels_are_refused(fis, data, groups, words):
    X, y, _ = data
    with pytest.raises(ValueError, match=words):
        check_data(fis, X, y, groups)
    with pytest.raises(ValueError, match=words):  # before any search
        PatternSearch(fis, n_folds=2, max_iter=1, seed=0).fit(X, y, groups)


@pytest.mark.parametrize("make, error, words", [
    (lambda X, y: (X + 0j, y), TypeError, "X is complex"),
    (lambda X, y: (X, y + 0j), TypeError, "y is complex"),
    (lambda X, y: (np.ma.masked_array(X, mask=X > 0.9), y), TypeError, "X is a masked array"),
    (lambda X, y: (X.astype(str), y), TypeError, "X is text"),
    (lambda X, y: (X > 0.5, y), TypeError, "X is boolean"),
])
def test_data_that_is_not_real_numbers_is_refused(fis, data, make, error, words):
    X, y = make(*data[:2])
    with pytest.raises(error, match=words):
        check_data(fis, X, y)
    with pytest.raises(error, match=words):
        ParticleSwarm(fis, swarm_size=5, max_iter=1, seed=0).fit(X, y)


def test_a_swarm_too_large_to_fit_is_refused_by_name(fis, data):
    X, y, _ = data
    with pytest.raises(ValueError, match=r"swarm_size = 10000000, must be <= 4096: .* 1\.49e\+06 GiB"):
        ParticleSwarm(fis, swarm_size=10**7, seed=0).fit(X, y)
    assert MAX_SWARM == 4096
    # 16 * 4096^2 bytes = 256 MiB: the largest allowed swarm's neighbour matrices


def test_tuning_never_proposes_a_degenerate_width():
    x = fuzzcore.Variable("x", (0.0, 1.0), (fuzzcore.Term("g", "gaussmf", (0.2, 0.5)),))
    y = fuzzcore.Variable("y", (0.0, 1.0), (fuzzcore.Term("a", "trimf", (0.0, 0.5, 1.0)),))
    system = fuzzcore.FuzzySystem("g", (x,), (y,), (fuzzcore.Rule((1,), (1,)),))
    space = TermSpace(system, ["x"])
    P = np.array([[0.2, 0.5], [1e-200, 0.5], [WIDTH_MIN, 0.5], [2 * WIDTH_MIN, 0.5], [1e160, 0.5]])
    # sigma 1e-200 squares to 0 (a NaN membership at the centre); WIDTH_MIN is the bound itself
    assert space.feasible(P).tolist() == [True, False, False, True, False]
