"""The public contract of a fuzzy system: infer, evaluate, explain, policies, exact centroid."""
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, strategies as st

import fuzzcore
from fuzzcore import FuzzySystem, Rule, RuleBaseError, Term, Variable

import reference
from strategies import PIECEWISE, mamdani_systems, samples


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load("rules/fuzzrisk.yaml").warmup()


def test_scalar_positional_and_named_agree_and_are_floats(fis):
    a = fis.infer(0.4, 0.3)
    assert type(a) is float
    assert fis.infer(iou=0.4, rdd=0.3) == a == fis.infer(rdd=0.3, iou=0.4)
    assert fis.infer(np.float64(0.4), 0.3) == a and fis.infer(0.4, np.float32(0.3)) == pytest.approx(a)
    assert fis.infer(1, 0) == fis.infer(1.0, 0.0)


def test_value_by_hand(fis):
    # iou = 0.4: low 0.4, medium 0.6; rdd = 0.3: medium 0.4, high 0.6. Fired (min): high <- 0.6
    # (rdd high & iou medium), low <- 0.4, medium <- 0.4. The aggregated set on the 101-point
    # grid, by hand: max(min(0.4, low(y)), min(0.4, medium(y)), min(0.6, high(y))).
    y = np.linspace(0, 1, 101)
    low = np.clip((0.5 - y) / 0.25, 0, 1)
    medium = np.clip(np.minimum((y - 0.25) / 0.25, (0.75 - y) / 0.25), 0, 1)
    high = np.clip((y - 0.5) / 0.25, 0, 1)
    agg = np.maximum.reduce([np.minimum(0.4, low), np.minimum(0.4, medium), np.minimum(0.6, high)])
    assert fis.infer(0.4, 0.3) == pytest.approx((y * agg).sum() / agg.sum(), abs=1e-14)


def test_arrays_broadcast(fis):
    iou = np.linspace(0, 1, 5)[:, None]
    rdd = np.linspace(-1, 1, 7)[None, :]
    out = fis.infer(iou, rdd)
    assert out.shape == (5, 7)
    assert out[2, 3] == fis.infer(float(iou[2, 0]), float(rdd[0, 3]))
    assert fis.infer([0.1, 0.2], 0.5).shape == (2,)
    assert fis.infer(np.empty(0), np.empty(0)).shape == (0,)


def test_evaluate_shape_and_errors(fis):
    X = np.array([[0.4, 0.3], [0.9, -0.2]])
    out = fis.evaluate(X)
    assert out.shape == (2, 1) and out[0, 0] == fis.infer(0.4, 0.3)
    with pytest.raises(ValueError, match=r"X has shape \(2, 3\), expected \(n_samples, 2\) with columns iou, rdd"):
        fis.evaluate(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="expected"):
        fis.evaluate(np.zeros(2))


def test_bad_calls_name_the_problem(fis):
    with pytest.raises(TypeError, match="takes 2 inputs \\(iou, rdd\\), got 1"):
        fis.infer(0.4)
    with pytest.raises(TypeError, match="unknown: speed; missing: rdd"):
        fis.infer(iou=0.4, speed=1.0)
    with pytest.raises(TypeError, match="input 'rdd' is text"):
        fis.infer(0.4, "high")
    with pytest.raises(ValueError, match="do not broadcast"):
        fis.infer([0.1, 0.2], [0.1, 0.2, 0.3])


def test_explain_lists_fired_rules_with_strengths(fis):
    ex = fis.explain(0.4, 0.3)
    assert ex.outputs["risk"] == fis.infer(0.4, 0.3)
    assert ex.memberships["iou"] == pytest.approx({"low": 0.4, "medium": 0.6, "high": 0.0})
    fired = ex.fired()
    assert [round(s, 12) for _, _, s in fired] == [0.6, 0.4, 0.4, 0.4]
    assert fired[0][1] == "if iou is medium and rdd is high then risk is high"
    assert ex.aggregated.shape == (1, 101) and ex.aggregated.max() == pytest.approx(0.6)
    assert "rules fired: 4 of 9" in str(ex)


def _one_rule_system(**kw):
    x = Variable("x", (0, 1), (Term("low", "trimf", (0, 0, 0.5)),))
    y = Variable("y", (0, 2), (Term("a", "trimf", (0, 1, 2)),))
    return FuzzySystem("one", (x,), (y,), (Rule((1,), (1,)),), **kw)


@pytest.mark.parametrize("policy, expected", [("midpoint", 1.0), ("nan", None), (0.25, 0.25)])
def test_no_rule_fired_policy(policy, expected):
    fis = _one_rule_system(no_rule_fired=policy)
    out = fis.infer(0.9)  # low(0.9) = 0: no rule fires
    assert np.isnan(out) if expected is None else out == expected
    assert fis.infer(0.1) == pytest.approx(1.0)  # a symmetric triangle's centroid, clipped or not


def test_policy_value_outside_the_output_range_is_refused():
    with pytest.raises(RuleBaseError, match="no_rule_fired 5.0 lies outside the range of y"):
        _one_rule_system(no_rule_fired=5.0)


def test_exact_centroid_by_hand():
    # a right triangle trimf [0, 0, 1] on [0, 1], clipped at h = 0.5 (x = 0.75 fires low at 0.5):
    # f = 0.5 on [0, 0.5], 1 - y on [0.5, 1]; area 0.375, moment 7/48: centroid 7/18
    x = Variable("x", (0, 1), (Term("low", "trimf", (0.5, 1, 1)),))
    y = Variable("y", (0, 1), (Term("a", "trimf", (0, 0, 1)),))
    fis = FuzzySystem("exact", (x,), (y,), (Rule((1,), (1,)),), defuzzifier="centroid_exact")
    assert fis.infer(0.75) == pytest.approx(7 / 18, abs=1e-15)
    assert fis.infer(1.0) == pytest.approx(1 / 3, abs=1e-15)  # unclipped: the triangle's 1/3
    discrete = replace(fis, defuzzifier="centroid")
    assert abs(discrete.infer(1.0) - 1 / 3) > 1e-3  # MATLAB's 101 points are not exact


@given(st.data())
def test_exact_centroid_matches_a_fine_integral(data):
    system = data.draw(mamdani_systems(output_kinds=PIECEWISE, aggregations=("max", "sum"),
                                       defuzzifiers=("centroid_exact",), max_outputs=1))
    fine = replace(system, defuzzifier="centroid", resolution=200_001)
    rows = samples(system, 4, data.draw)
    got = system.evaluate(rows)[:, 0]
    lo, hi = system.outputs[0].range
    for row, value in zip(rows, got):
        y, mu = reference.aggregated_set(fine, row, 0)
        area = np.trapezoid(mu, y)
        if np.isnan(row).any() or area < 1e-4 * (hi - lo):
            continue  # an empty or zero-width set (a spike): the exact area is 0, the policy applies
        # a vertical edge costs the trapezoid rule O(grid step) = 1e-5 of the range
        assert value == pytest.approx(np.trapezoid(y * mu, y) / area, abs=2e-5 * (hi - lo))


def test_exact_centroid_needs_piecewise_linear_outputs():
    x = Variable("x", (0, 1), (Term("low", "trimf", (0, 0, 1)),))
    y = Variable("y", (0, 1), (Term("g", "gaussmf", (0.2, 0.5)),))
    with pytest.raises(RuleBaseError, match="gaussmf is not piecewise linear"):
        FuzzySystem("e", (x,), (y,), (Rule((1,), (1,)),), defuzzifier="centroid_exact")


def _ruspini(knots):
    n = len(knots)
    return tuple(Term(f"t{i}", "trimf", (knots[max(i - 1, 0)], knots[i], knots[min(i + 1, n - 1)]))
                 for i in range(n))


_OUTPUT_TERMS = tuple(Term(f"o{k}", "trimf", (max(k - 1, 0) / 4, k / 4, min(k + 1, 4) / 4)) for k in range(5))


@given(st.lists(st.floats(0.05, 1.0), min_size=2, max_size=5), st.data())
def test_monotone_rule_base_gives_monotone_output(gaps, data):
    # A Ruspini partition of triangles on x, consequents a non-decreasing map onto ordered
    # output triangles, prod implication and sum aggregation: between two knots the output
    # is ((1-t) A_a c_a + t A_b c_b) / ((1-t) A_a + t A_b) with c_a <= c_b (A: areas, c:
    # centroids of the output terms on the grid), non-decreasing in t.
    knots = np.concatenate([[0.0], np.cumsum(gaps)])
    knots /= knots[-1]
    cons = sorted(data.draw(st.lists(st.integers(1, 5), min_size=len(knots), max_size=len(knots))))
    fis = FuzzySystem("mono", (Variable("x", (0, 1), _ruspini(knots)),), (Variable("y", (0, 1), _OUTPUT_TERMS),),
                      tuple(Rule((i + 1,), (c,)) for i, c in enumerate(cons)),
                      implication="prod", aggregation="sum")
    out = fis.infer(np.linspace(0, 1, 401))
    assert np.all(np.diff(out) >= -1e-12)


def test_min_max_clipping_is_not_monotone_preserving():
    # Why the property above uses prod/sum: with min implication and max aggregation, rules
    # that all conclude the same term still move the output, because the clip height (the
    # larger of two neighbouring memberships) dips to 0.5 between knots. MATLAB does the same.
    fis = FuzzySystem("clip", (Variable("x", (0, 1), _ruspini([0.0, 0.5, 1.0])),),
                      (Variable("y", (0, 1), _OUTPUT_TERMS),), tuple(Rule((i + 1,), (1,)) for i in range(3)))
    at_knot, between = fis.infer(0.0), fis.infer(0.25)
    # o0 = trimf [0 0 0.25] clipped at 1 vs at 0.5 (on the 101-point grid): different centroids
    assert at_knot != pytest.approx(between, abs=1e-6)


def test_explain_reports_the_kernels_grid_and_describes_rules_without_inputs():
    # a MATLAB file may hold a rule with every input "don't care" (it always fires fully)
    x = Variable("x", (0, 1), (Term("low", "trimf", (0, 0, 1)),))
    y = Variable("y", (0, 3), (Term("a", "trimf", (0, 1, 2)),))
    fis = FuzzySystem("always", (x,), (y,), (Rule((0,), (1,)),), resolution=7)
    ex = fis.explain(0.3)
    assert ex.rules == ("always then y is a",) and ex.strengths[0] == 1.0
    # MATLAB's linspace: lo + (j * (hi - lo)) / (n - 1), as the kernels sampled it
    np.testing.assert_array_equal(ex.grid[0], [0 + (j * 3.0) / 6 for j in range(7)])
    assert ex.outputs["y"] == pytest.approx(1.0)
