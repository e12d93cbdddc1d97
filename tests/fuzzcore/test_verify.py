"""fuzzcore.verify: coverage (exact, against brute force), monotonicity, rules, partitions, the report."""
import dataclasses
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fuzzcore
from fuzzcore import FuzzySystem, Rule, Term, Variable
from fuzzcore.testing import PIECEWISE, systems
from fuzzcore.tune import PatternSearch, TermSpace
from reference import membership

PAPER = "rules/fuzzrisk.yaml"


def _system(x_terms, rules, y_terms=(("any", "trapmf", (0.0, 0.0, 1.0, 1.0)),), **options):
    """Inputs x, y on [0, 1]; output z on [0, 1] with low/high ramps; rules as (antecedent, consequent)."""
    x = Variable("x", (0.0, 1.0), tuple(Term(*t) for t in x_terms))
    y = Variable("y", (0.0, 1.0), tuple(Term(*t) for t in y_terms))
    z = Variable("z", (0.0, 1.0), (Term("low", "trimf", (0.0, 0.0, 1.0)), Term("high", "trimf", (0.0, 1.0, 1.0))))
    return FuzzySystem("sys", (x, y), (z,), tuple(Rule(a, c) for a, c in rules), **options)


def _hole_system():
    # x low is 0 from 0.4 on, x high is 0 up to 0.6: nothing fires for x in [0.4, 0.6], whatever y
    return _system([("low", "trimf", (0.0, 0.0, 0.4)), ("high", "trimf", (0.6, 1.0, 1.0))],
                   [((1, 1), (1,)), ((2, 1), (2,))])


def _clean_system():
    # a Ruspini partition of x, and z follows x: covered, monotone increasing, nothing redundant
    return _system([("low", "trimf", (0.0, 0.0, 1.0)), ("high", "trimf", (0.0, 1.0, 1.0))],
                   [((1, 1), (1,)), ((2, 1), (2,))], y_terms=(("any", "trapmf", (-1.0, 0.0, 1.0, 2.0)),))


# --------------------------------------------------------------------------- coverage
def test_a_known_hole_is_found_with_its_exact_extent():
    report = fuzzcore.verify(_hole_system())
    c = report.coverage
    assert not c.covered and not report.ok and c.exact
    assert c.uncovered_share == pytest.approx(0.2, abs=1e-15)  # (0.6 - 0.4) * 1 of the unit box
    (region,) = c.regions
    assert region.bounds == {"x": (0.4, 0.6, True, True), "y": (0.0, 1.0, True, True)}
    assert region.share == pytest.approx(0.2, abs=1e-15)
    fis = _hole_system()
    for x in (0.4, 0.5, 0.6):  # inside, on both closed ends: no rule fires (the midpoint answers)
        assert fis.explain(x, 0.3).fired() == []
    for x in (np.nextafter(0.4, 0), np.nextafter(0.6, 1)):  # one ulp outside: a rule fires
        assert fis.explain(x, 0.3).fired()


def test_terms_that_only_touch_leave_a_line_uncovered():
    # low ends at 0.5 where high starts: at x = 0.5 exactly both are 0 (a measure-zero hole)
    fis = _system([("low", "trimf", (0.0, 0.0, 0.5)), ("high", "trimf", (0.5, 1.0, 1.0))],
                  [((1, 0), (1,)), ((2, 0), (2,))])
    c = fuzzcore.verify(fis).coverage
    assert not c.covered and c.uncovered_share == 0.0
    (region,) = c.regions
    assert region.bounds["x"] == (0.5, 0.5, True, True) and region.dimension == 1


def test_smooth_terms_bound_a_hole_within_the_stated_tolerance():
    # zmf is 0 from 0.4 on, smf is 0 up to 0.6: the same hole, found by bisection
    fis = _system([("low", "zmf", (0.2, 0.4)), ("high", "smf", (0.6, 0.8))], [((1, 0), (1,)), ((2, 0), (2,))])
    c = fuzzcore.verify(fis, tol=1e-10).coverage
    assert not c.exact and "bisected" in c.method
    (region,) = c.regions
    lo, hi, *_ = region.bounds["x"]
    assert lo == pytest.approx(0.4, abs=1e-9) and hi == pytest.approx(0.6, abs=1e-9)


def _brute_strongest(fis, X):
    """The strongest weighted firing strength at each row of X, from the reference memberships."""
    best = np.zeros(X.shape[0])
    for rule in fis.rules:
        f = np.full(X.shape[0], 0.0 if rule.connective == "or" else 1.0)
        for i, (code, var) in enumerate(zip(rule.antecedent, fis.inputs)):
            if code == 0:
                continue
            term = var.terms[abs(code) - 1]
            m = membership(term.kind, term.params, X[:, i])
            m = 1 - m if code < 0 else m
            if rule.connective == "or":
                f = np.maximum(f, m) if fis.or_method == "max" else f + m - f * m
            else:
                f = np.minimum(f, m) if fis.and_method == "min" else f * m
        best = np.maximum(best, f * rule.weight)
    return best


def _inside(region, X, names):
    ok = np.ones(X.shape[0], dtype=bool)
    for i, name in enumerate(names):
        lo, hi, lc, hc = region.bounds[name]
        ok &= (X[:, i] >= lo) if lc else (X[:, i] > lo)
        ok &= (X[:, i] <= hi) if hc else (X[:, i] < hi)
    return ok


@settings(max_examples=25)
@given(systems(kinds=PIECEWISE, max_inputs=2, max_rules=5), st.sampled_from((0.0, 0.3)))
def test_piecewise_linear_coverage_agrees_with_a_dense_grid(fis, threshold):
    fis = dataclasses.replace(fis, and_method="min", or_method="max")  # threshold > 0 is exact for these
    report = fuzzcore.verify(fis, threshold=threshold, max_regions=10_000, budget=200)
    c = report.coverage
    assert c.exact and c.complete
    # a dense grid, plus every breakpoint of every axis (the closed/open ends must be right too)
    axes = []
    for var in fis.inputs:
        grid = np.linspace(*var.range, 301)
        points = [p for t in var.terms for p in t.params if var.range[0] <= p <= var.range[1]]
        axes.append(np.unique(np.concatenate([grid, points])))
    X = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)
    strongest = _brute_strongest(fis, X)
    uncovered = ~(strongest > 0) if threshold == 0 else ~(strongest >= threshold)
    claimed = np.zeros(X.shape[0], dtype=bool)
    for region in c.regions:
        claimed |= _inside(region, X, fis.input_names)
    np.testing.assert_array_equal(claimed, uncovered)
    # the share: the fraction of a midpoint grid uncovered, within the grid's resolution
    n = 400
    mids = [var.range[0] + (np.arange(n) + 0.5) / n * (var.range[1] - var.range[0]) for var in fis.inputs]
    M = np.stack([g.ravel() for g in np.meshgrid(*mids, indexing="ij")], axis=1)
    s = _brute_strongest(fis, M)
    share = np.mean(~(s > 0) if threshold == 0 else ~(s >= threshold))
    n_breaks = sum(len(t.params) for v in fis.inputs for t in v.terms) * (2 if threshold else 1)
    assert c.uncovered_share == pytest.approx(share, abs=2 * n_breaks / n)


def test_a_level_crossing_is_placed_where_the_computed_membership_crosses_it():
    # 1 - x / 1.1875 reaches 0.3 at x = 0.7 * 1.1875 = 0.83125, where the computed membership is
    # 0.3 exactly (covered at 0.3) and one float above it 0.2999999999999999; the level's
    # crossing computed from the side's ends is 0.8312499999999999, an ulp below. Every float
    # near it is claimed uncovered exactly when the reference says the rule falls short
    x = Variable("x", (0.0, 1.1875), (Term("down", "trimf", (0.0, 0.0, 1.1875)),))
    z = Variable("z", (0.0, 1.0), (Term("low", "trimf", (0.0, 0.0, 1.0)),))
    fis = FuzzySystem("edge", (x,), (z,), (Rule((1,), (1,)),))
    c = fuzzcore.verify(fis, threshold=0.3).coverage
    assert c.exact
    near = [0.83125]
    for _ in range(4):
        near = [np.nextafter(near[0], 0.0), *near, np.nextafter(near[-1], 2.0)]
    X = np.array(near)[:, None]
    claimed = np.zeros(X.shape[0], dtype=bool)
    for region in c.regions:
        claimed |= _inside(region, X, fis.input_names)
    assert claimed.tolist() == (~(_brute_strongest(fis, X) >= 0.3)).tolist() == [False] * 5 + [True] * 4


# --------------------------------------------------------------------------- monotonicity
def test_a_known_non_monotone_pair_is_found():
    # z is high where x is low and low where x is high: decreasing in x, declared increasing
    fis = _system([("low", "trimf", (0.0, 0.0, 1.0)), ("high", "trimf", (0.0, 1.0, 1.0))],
                  [((1, 0), (2,)), ((2, 0), (1,))], y_terms=(("any", "trapmf", (-1.0, 0.0, 1.0, 2.0)),))
    report = fuzzcore.verify(fis, monotone={"x": +1})
    (m,) = report.monotonicity
    assert not m.holds and not report.ok
    assert m.start["x"] < m.end["x"] and m.start["y"] == m.end["y"]
    # the drop is what the system says at the two points
    assert m.values == (fis.infer(m.start["x"], m.start["y"]), fis.infer(m.end["x"], m.end["y"]))
    assert m.drop == pytest.approx(m.values[0] - m.values[1], abs=1e-15)
    # and at least the worst drop on a dense brute-force grid
    x = np.linspace(0, 1, 20001)
    z = fis.infer(x, 0.5)
    brute = np.max(np.maximum.accumulate(z)[:-1] - z[1:])
    assert m.drop >= brute - 1e-12
    assert fuzzcore.verify(fis, monotone={"x": -1}).monotonicity[0].holds


def test_the_paper_system_is_not_monotone_in_rdd():
    # low RDD~ gives medium risk, medium RDD~ low risk: by design (DESIGN.md)
    fis = fuzzcore.load(PAPER)
    (m,) = fuzzcore.verify(fis, monotone={"rdd": +1}).monotonicity
    assert not m.holds and m.drop > 0.25
    assert m.values[0] - m.values[1] == pytest.approx(m.drop)
    assert fis.infer(m.start["iou"], m.start["rdd"]) == m.values[0]


# --------------------------------------------------------------------------- rules
def test_a_redundant_rule_and_duplicates_and_conflicts_are_reported():
    fis = fuzzcore.load(PAPER)
    half = Rule(fis.rules[0].antecedent, fis.rules[0].consequent, 0.5)  # dominated by rule 1
    clash = Rule(fis.rules[4].antecedent, (3,))  # rule 5 concludes low
    report = fuzzcore.verify(dataclasses.replace(fis, rules=fis.rules + (half, clash)))
    f = report.rules
    assert [r for r, _ in f.redundant] == [9]
    assert f.duplicates == ((0, 9),) and f.conflicting == ((4, 10),)
    assert report.ok  # advice, not failure


def test_clean_system_reports_nothing():
    report = fuzzcore.verify(_clean_system(), monotone={"x": +1})
    assert report.ok and report.failures == []
    assert report.coverage.covered and report.monotonicity[0].holds
    f = report.rules
    assert f.never_firing == f.redundant == f.conflicting == f.duplicates == f.unused_terms == ()
    x = report.partitions[0]
    assert x.sound and x.ruspini == 0.0 and x.min_cover == pytest.approx(0.5, abs=1e-15) and x.uncovered == ()
    assert x.similarity[0][2] == pytest.approx(1 / 3)  # int min = 1/4, int max = 3/4
    x = np.linspace(0, 1, 100001)  # the steepest slope of z along x, by brute force
    brute = np.max(np.abs(np.diff(_clean_system().infer(x, 0.5))) / np.diff(x))
    assert report.steepest[0].input == "x" and not report.steepest[0].jump
    assert report.steepest[0].slope == pytest.approx(brute, rel=0.01)
    r = report.output_range[0]
    assert r.low == pytest.approx(1 / 3, abs=0.01) and r.high == pytest.approx(2 / 3, abs=0.01)


def test_never_firing_rules_and_unused_terms():
    fis = _clean_system()
    extra = Variable("x", (0.0, 1.0), fis.inputs[0].terms + (Term("far", "trimf", (2.0, 3.0, 4.0)),))
    fis = dataclasses.replace(fis, inputs=(extra, fis.inputs[1]),
                              rules=fis.rules + (Rule((3, 0), (2,)), Rule((1, 1), (1,), 0.0)))
    f = fuzzcore.verify(fis).rules
    assert f.never_firing == (2, 3)  # a term outside the range; a weight of 0
    assert fuzzcore.verify(dataclasses.replace(fis, rules=fis.rules[:2])).rules.unused_terms == (("x", "far"),)


def test_a_rule_alone_in_a_region_is_not_redundant():
    # in the paper's system, rule 7 alone fires at low IoU~ and low RDD~; the no-rule
    # midpoint (0.5) equals its output there, yet removing it opens a hole
    assert fuzzcore.verify(fuzzcore.load(PAPER)).rules.redundant == ()


# --------------------------------------------------------------------------- partitions
def test_partitions_of_the_old_joint_terms():
    fis = fuzzcore.load(PAPER)
    rdd = Variable("rdd", (-1.0, 1.0), (Term("low", "trapmf", (-0.5, 0.0, 0.5, 0.5)),
                                         Term("medium", "trimf", (-0.5, 1.0, 1.0)),
                                         Term("high", "trapmf", (-0.25, 1.0, 1.0, 1.0))))
    report = fuzzcore.verify(dataclasses.replace(fis, inputs=(fis.inputs[0], rdd)))
    p = report.partitions[1]
    assert p.uncovered == ((-1.0, -0.5),) and p.min_cover == 0.0
    assert [(a, b) for a, b, _ in p.similar] == [("medium", "high")]
    assert not p.sound
    assert report.coverage.uncovered_share == pytest.approx(0.25)  # rdd in [-1, -0.5] of [-1, 1]


# --------------------------------------------------------------------------- report
def test_report_text_and_json():
    report = fuzzcore.verify(_hole_system(), monotone={"x": +1})
    text = str(report)
    assert "20 % of the input box fires no rule" in text and "x in [0.4, 0.6], y in [0, 1]" in text
    assert text.splitlines()[-1].startswith("result: FAIL")
    data = json.loads(json.dumps(report.to_dict(), allow_nan=False))
    assert data["ok"] is False and data["coverage"]["uncovered_share"] == pytest.approx(0.2)
    assert data["coverage"]["regions"][0]["bounds"]["x"] == {"lo": 0.4, "hi": 0.6, "lo_closed": True,
                                                             "hi_closed": True}


@pytest.mark.parametrize("kwargs, message", [
    ({"monotone": {"speed": 1}}, "'speed' is not an input"),
    ({"monotone": {"x": 2}}, "expected +1 (increasing) or -1"),
    ({"threshold": 1.5}, "threshold = 1.5: expected a number in [0, 1]"),
    ({"budget": 0}, "budget = 0: expected an integer >= 2"),
    ({"max_cells": 3}, "more than max_cells = 3"),
])
def test_bad_arguments_are_named(kwargs, message):
    with pytest.raises(ValueError, match=None) as info:
        fuzzcore.verify(_hole_system(), **kwargs)
    assert message in str(info.value)


# --------------------------------------------------------------------------- tuning keeps a partition
def test_pattern_search_keeps_a_covering_partition():
    fis = fuzzcore.load(PAPER)
    rng = np.random.default_rng(1)
    X = np.column_stack([rng.beta(2, 2, 400), np.clip(rng.normal(0.1, 0.4, 400), -1, 1)])
    X[:200] = [0.0, 1.0]  # half the frames unmatched, as in the benchmark data
    y = np.clip(0.6 * np.clip(X[:, 1], 0, 1) + 0.3 * (1 - X[:, 0]) + rng.normal(0, 0.05, 400), 0, 1)
    tuned = PatternSearch(fis, n_folds=1, max_iter=200, seed=0).fit(X, y).system_
    report = fuzzcore.verify(tuned)
    assert report.coverage.covered
    for p in report.partitions:
        assert p.ordered and p.uncovered == () and p.min_cover >= 0.5 - 1e-12
    space = TermSpace(tuned, partition=True)
    assert space.broken_constraints(space.x0) == []


def test_a_start_that_is_no_partition_is_refused_naming_the_constraint():
    fis = fuzzcore.load(PAPER)
    space = TermSpace(fis)
    p = space.x0.copy()
    p[space.names.index("iou.low[2]")] = 0.45  # low stays 1 until 0.45: it and medium cross above 0.75
    start = space.to_system(p)
    with pytest.raises(ValueError, match="iou.low and iou.medium cross at 0.75 or below"):
        TermSpace(start, partition=True)
    assert "iou.low and iou.medium cross at 0.75 or below" in TermSpace(fis, partition=True).broken_constraints(p)
    PatternSearch(start, partition=False, n_folds=1, max_iter=2).fit([[0.2, 0.1]] * 4, [0.5] * 4)
