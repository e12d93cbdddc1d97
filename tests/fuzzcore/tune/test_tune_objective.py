"""fuzzcore.tune parameter spaces and the batched objective, against fis.evaluate."""
import dataclasses

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import fuzzcore
from fuzzcore.tune import Objective, RuleSpace, TermSpace
from fuzzcore.tune.rule_tables import firing_strengths

RULES = "rules/fuzzrisk.yaml"


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load(RULES)


@pytest.fixture(scope="module")
def data(fis):
    rng = np.random.default_rng(7)
    n = 400
    X = np.column_stack([rng.uniform(0, 1, n), rng.uniform(-1, 1, n)])
    X[:60] = [0.0, 1.0]  # repeated rows, as unmatched frames give
    y = np.clip(fis.evaluate(X)[:, 0] + rng.normal(0, 0.1, n), 0, 1)
    return X, y


def _rmse(system, X, y):
    return np.sqrt(np.mean((system.evaluate(X)[:, 0] - y) ** 2))


def _mae(system, X, y):
    return np.mean(np.abs(system.evaluate(X)[:, 0] - y))


def _moved(space, rng, n, step):
    """Candidates: every vertex of the start moved by up to ``step`` * scale, then each
    term's vertices sorted and clipped into the range (all terms here are vertex kinds)."""
    P = space.x0 + rng.uniform(-step, step, (n, space.n_params)) * space.scale
    P = np.clip(P, space.lower, space.upper)
    terms = [name.split("[")[0] for name in space.names]
    for term in dict.fromkeys(terms):
        columns = [k for k, t in enumerate(terms) if t == term]
        P[:, columns] = np.sort(P[:, columns], axis=1)
    assert space.feasible(P).all()
    return P


# --------------------------------------------------------------------------- spaces
def test_term_space_lists_every_parameter_in_order(fis):
    space = TermSpace(fis)
    assert space.n_params == 33
    assert space.names[:4] == ("iou.low[0]", "iou.low[1]", "iou.low[2]", "iou.low[3]")
    assert space.names[-1] == "risk.high[3]"
    np.testing.assert_array_equal(space.x0[:4], [0.0, 0.0, 0.25, 0.5])
    fblob, _, _ = fis.packed
    np.testing.assert_array_equal(fblob[space.f_positions], space.x0)
    assert space.refresh
    only = TermSpace(fis, ["rdd"])
    assert only.n_params == 11 and not only.refresh
    assert only.names[0] == "rdd.low[0]"


def test_term_space_constraints(fis):
    space = TermSpace(fis, ["iou"])  # low trapmf 0..3, medium trimf 4..6, high trapmf 7..10
    x0 = space.x0

    def with_value(k, v):
        p = x0.copy()
        p[k] = v
        return p

    P = np.array([x0,
                  with_value(2, 0.3),     # low: c inside [b, d]
                  with_value(5, 0.2),     # medium peak below its left foot
                  with_value(0, -0.1),    # below the range
                  with_value(10, 1.2),    # above the range
                  with_value(6, 0.25),    # medium: zero width (c == a)
                  with_value(1, np.nan)])
    np.testing.assert_array_equal(space.feasible(P), [True, True, False, False, False, False, False])
    with pytest.raises(ValueError, match="violates"):
        space.to_system(with_value(5, 0.2))


def test_term_space_keeps_terms_in_order(fis):
    ordered, free = TermSpace(fis, ["rdd"]), TermSpace(fis, ["rdd"], keep_order=False)
    # rdd: low trapmf 0..3 [-1, -1, -0.5, 0], medium trimf 4..6 [-0.5, 0, 0.5], high trapmf 7..10
    p = ordered.x0.copy()
    p[5] = -0.6  # medium's peak (both its shoulders) left of low's right shoulder (-0.5)
    p[4] = -0.7
    assert free.feasible(p[None])[0] and not ordered.feasible(p[None])[0]
    p = ordered.x0.copy()
    p[3] = 0.45  # low's right foot moves right, still left of medium's (0.5): allowed
    assert ordered.feasible(p[None])[0]
    p[3] = 0.6   # ... past it: low would reach further right than medium
    assert free.feasible(p[None])[0] and not ordered.feasible(p[None])[0]


def test_term_space_round_trips_and_writes_terms(fis):
    space = TermSpace(fis)
    assert space.to_system(space.x0) == fis
    p = space.x0.copy()
    p[space.names.index("rdd.medium[1]")] = 0.1
    tuned = space.to_system(p)
    assert tuned.inputs[1].terms[1].params == (-0.5, 0.1, 0.5)
    assert tuned.rules == fis.rules


def test_term_space_refuses_what_it_cannot_keep_valid(fis):
    with pytest.raises(ValueError, match="unknown: speed"):
        TermSpace(fis, ["speed"])
    with pytest.raises(TypeError, match="sequence of names"):
        TermSpace(fis, "iou")
    low = fis.inputs[0].terms[0]
    crisp = dataclasses.replace(fis.inputs[0], terms=(dataclasses.replace(low, params=(0.2, 0.2, 0.2, 0.2)),)
                                + fis.inputs[0].terms[1:])
    with pytest.raises(ValueError, match="zero width"):
        TermSpace(dataclasses.replace(fis, inputs=(crisp, fis.inputs[1])))


def test_term_space_point_outside_the_range_may_stay_there(fis):
    wide = dataclasses.replace(fis.inputs[0].terms[0], params=(-0.4, -0.1, 0.25, 0.5))
    var = dataclasses.replace(fis.inputs[0], terms=(wide,) + fis.inputs[0].terms[1:])
    space = TermSpace(dataclasses.replace(fis, inputs=(var, fis.inputs[1])), ["iou"])
    assert space.lower[0] == -0.4 and space.upper[0] == 1.0
    p = space.x0.copy()
    p[0] = -0.41
    assert not space.feasible(p[None])[0]


def test_rule_space_slots_rounding_and_systems(fis):
    space = RuleSpace(fis)
    np.testing.assert_array_equal(space.x0, [3, 3, 3, 2, 1, 1, 2, 2, 1])
    assert space.names[0] == "rule 1 -> risk"
    # each value owns [v - 0.5, v + 0.5); the ends clip to the choices
    np.testing.assert_array_equal(space.round(np.array([[0.5, 1.49, 1.5, 2.5, 3.49, 3.5, 0.7, 2.0, 3.0]])),
                                  [[1, 1, 2, 3, 3, 3, 1, 2, 3]])
    learned = space.to_system(np.array([1, 2, 3, 1, 2, 3, 1, 2, 3.0]))
    assert [r.consequent[0] for r in learned.rules] == [1, 2, 3, 1, 2, 3, 1, 2, 3]
    assert [r.antecedent for r in learned.rules] == [r.antecedent for r in fis.rules]
    assert not space.feasible(np.array([[1, 2, 3, 1, 2, 3, 1, 2, 2.5]]))[0]
    with pytest.raises(ValueError, match="not valid"):
        space.to_system(np.zeros(9))


def test_rule_space_switching_rules_off(fis):
    space = RuleSpace(fis, allow_off=True)
    p = space.x0.copy()
    p[[0, 4]] = 0
    pruned = space.to_system(p)
    assert len(pruned.rules) == 7
    assert pruned.rules[0] == fis.rules[1]
    assert not space.feasible(np.zeros((1, 9)))[0]  # at least one rule stays on
    partial = RuleSpace(fis, rules=[0, 1], allow_off=True)
    assert partial.feasible(np.zeros((1, 2)))[0]    # the other rules are still on


def test_rule_space_refuses_negated_consequents_and_bad_indices(fis):
    negated = dataclasses.replace(fis.rules[0], consequent=(-3,))
    with pytest.raises(ValueError, match="negated"):
        RuleSpace(dataclasses.replace(fis, rules=(negated,) + fis.rules[1:]))
    with pytest.raises(ValueError, match="0..8"):
        RuleSpace(fis, rules=[9])


# --------------------------------------------------------------------------- objective
@pytest.mark.parametrize("metric, reference", [("rmse", _rmse), ("mae", _mae)])
def test_objective_agrees_with_evaluate_for_terms(fis, data, metric, reference):
    X, y = data
    space = TermSpace(fis)
    objective = Objective(space, X, y, metric)
    P = _moved(space, np.random.default_rng(1), 6, 0.03)
    values = objective(P)
    expected = [reference(space.to_system(p), X, y) for p in P]
    np.testing.assert_allclose(values, expected, rtol=1e-12)
    assert objective.nfev == 6


def _with_gap(fis):
    """``fis`` with iou "low" shrunk to [0, 0.15]: for iou in (0.15, 0.25) no rule fires."""
    low = dataclasses.replace(fis.inputs[0].terms[0], params=(0.0, 0.05, 0.1, 0.15))
    iou = dataclasses.replace(fis.inputs[0], terms=(low,) + fis.inputs[0].terms[1:])
    return dataclasses.replace(fis, inputs=(iou, fis.inputs[1]))


@pytest.mark.parametrize("gap", [False, True])
def test_objective_agrees_with_evaluate_for_rules(fis, data, gap):
    X, y = data
    fis = _with_gap(fis) if gap else fis
    space = RuleSpace(fis, allow_off=True)
    P = np.random.default_rng(2).integers(0, 4, (12, 9)).astype(float)
    P[0] = 0  # every rule off: infeasible
    expected = [np.inf] + [_rmse(space.to_system(p), X, y) for p in P[1:]]
    direct = Objective(space, X, y)
    np.testing.assert_allclose(direct(P), expected, rtol=1e-12)
    tables = Objective(space, X, y, expected_evaluations=10_000)
    np.testing.assert_allclose(tables(P), expected, rtol=1e-12)
    assert tables.uses_tables and not direct.uses_tables  # the exact lookup tables were used, and only there


def test_objective_with_a_base_point_is_the_full_evaluation_bit_for_bit(fis, data):
    X, y = data
    space = TermSpace(fis)
    objective = Objective(space, X, y)
    steps = np.concatenate([np.diag(space.scale), -np.diag(space.scale)])
    for mesh in (0.2, 0.01):
        poll = space.x0 + mesh * steps
        np.testing.assert_array_equal(objective(poll, base=space.x0), objective(poll))
    base = _moved(space, np.random.default_rng(3), 1, 0.02)[0]
    P = _moved(space, np.random.default_rng(4), 5, 0.02)  # many parameters moved at once
    np.testing.assert_array_equal(objective(P, base=base), objective(P))
    rules = RuleSpace(fis)
    objective = Objective(rules, X, y)
    P = np.random.default_rng(5).integers(1, 4, (8, 9)).astype(float)
    np.testing.assert_array_equal(objective(P, base=rules.x0), objective(P))


@given(st.lists(st.integers(0, 2), min_size=9, max_size=9), st.integers(1, 5))
def test_objective_batch_equals_one_by_one(fis, data, consequents, n):
    X, y = data
    space = RuleSpace(fis)
    P = np.tile(np.array(consequents, dtype=float) + 1, (n, 1))
    P[:, 0] = np.arange(n) % 3 + 1
    objective = Objective(space, X, y)
    np.testing.assert_array_equal(objective(P), [objective(p[None])[0] for p in P])


def test_objective_marks_unscorable_candidates_inf(fis, data):
    X, y = data
    space = TermSpace(fis, ["iou"])
    gap = space.x0.copy()
    gap[:4] = [0.0, 0.05, 0.1, 0.15]  # "low" shrinks: nothing fires for iou in (0.15, 0.25)
    P = np.array([space.x0, gap])
    # by default the fallback answers where nothing fires, as fis.evaluate does
    plain = Objective(space, X, y)(P)
    np.testing.assert_allclose(plain, [_rmse(fis, X, y), _rmse(_with_gap(fis), X, y)], rtol=1e-12)
    # require_firing: a candidate leaving samples to the fallback cannot be scored
    strict = Objective(space, X, y, require_firing=True)(P)
    assert strict[0] == plain[0] and strict[1] == np.inf
    # and so is a system whose fallback is NaN
    nan_policy = TermSpace(dataclasses.replace(fis, no_rule_fired="nan"), ["iou"])
    np.testing.assert_array_equal(Objective(nan_policy, X, y)(P), strict)
    assert np.isnan(nan_policy.to_system(gap).evaluate(X)).any()


def test_objective_refuses_wrong_shapes(fis, data):
    X, y = data
    objective = Objective(TermSpace(fis), X, y)
    with pytest.raises(ValueError, match=r"expected \(n_candidates, 33\)"):
        objective(np.zeros((2, 5)))
    with pytest.raises(ValueError, match="metric 'r2'"):
        Objective(TermSpace(fis), X, y, "r2")


def test_firing_strengths_match_explain(fis, data):
    X, _ = data
    F = firing_strengths(fis, X[55:70])
    for row, x in zip(F, X[55:70]):
        np.testing.assert_array_equal(row, fis.explain(*x).strengths)
