"""fuzzcore.testing: the strategies draw only valid systems and inputs; the assertions fail when they must."""
import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fuzzcore
from fuzzcore import FuzzySystem, Rule, Term, Variable
from fuzzcore.testing import (PIECEWISE, assert_covered, assert_in_range, assert_matches_reference,
                              assert_monotone, assert_nan_propagates, inputs, systems)
from reference import evaluate

PAPER = fuzzcore.load("rules/fuzzrisk.yaml")


@settings(max_examples=40)
@given(systems())
def test_systems_are_valid_and_evaluate(fis):
    assert isinstance(fis, FuzzySystem)
    # valid: rebuilding from its parts passes every check, and it round-trips through its text form
    rebuilt = FuzzySystem(fis.name, fis.inputs, fis.outputs, fis.rules, and_method=fis.and_method,
                          or_method=fis.or_method, implication=fis.implication, aggregation=fis.aggregation)
    assert rebuilt == fis
    X = np.array([[0.5 * sum(v.range) for v in fis.inputs]])
    assert_in_range(fis, X)


@settings(max_examples=40)
@given(st.data(), systems(kinds=PIECEWISE, max_inputs=2))
def test_inputs_land_where_asked(data, fis):
    inside = data.draw(inputs(fis, "inside"))
    assert len(inside) == len(fis.inputs)
    assert all(v.range[0] <= x <= v.range[1] for x, v in zip(inside, fis.inputs))
    on = data.draw(inputs(fis, "breakpoints"))
    for x, v in zip(on, fis.inputs):
        corners = {v.range[0], v.range[1]} | {p for t in v.terms for p in t.params}
        near = corners | {float(np.nextafter(p, d)) for p in corners for d in (-np.inf, np.inf)}
        assert x in near and v.range[0] <= x <= v.range[1]
    odd = data.draw(inputs(fis, "nonfinite"))
    assert any(not math.isfinite(x) for x in odd)
    edge = data.draw(inputs(fis, "edges"))
    for x, v in zip(edge, fis.inputs):
        lo, hi = v.range
        assert x in (lo, hi, -1e300, 1e300) or lo - (hi - lo) <= x <= lo or hi <= x <= hi + (hi - lo)


@given(inputs(PAPER, "any"))
def test_the_paper_system_passes_its_own_properties(x):
    assert_in_range(PAPER, [x])
    if all(math.isfinite(v) for v in x):
        assert_nan_propagates(PAPER, x)


def test_inputs_refuses_unknown_places():
    with pytest.raises(ValueError, match="where = 'middle'"):
        inputs(PAPER, "middle")


def _one_input(rules):
    x = Variable("x", (0.0, 1.0), (Term("low", "trimf", (0.0, 0.0, 0.4)), Term("high", "trimf", (0.6, 1.0, 1.0))))
    z = Variable("z", (0.0, 1.0), (Term("low", "trimf", (0.0, 0.0, 1.0)), Term("high", "trimf", (0.0, 1.0, 1.0))))
    return FuzzySystem("one", (x,), (z,), tuple(Rule(a, c) for a, c in rules))


def test_assert_covered():
    assert_covered(PAPER)
    with pytest.raises(AssertionError, match=r"no rule fires on 20 % of the input box: x in \[0.4, 0.6\]"):
        assert_covered(_one_input([((1,), (1,)), ((2,), (2,))]))
    with pytest.raises(AssertionError, match="at 0.6"):  # the paper's terms cross at 0.5
        assert_covered(PAPER, threshold=0.6)


def test_assert_monotone():
    decreasing = _one_input([((1,), (2,)), ((2,), (1,)), ((-1,), (1,))])
    assert_monotone(decreasing, "x", -1)
    with pytest.raises(AssertionError, match="z drops by"):
        assert_monotone(decreasing, "x", +1)
    with pytest.raises(AssertionError, match="risk drops by"):
        assert_monotone(PAPER, "rdd", +1)


def test_assert_nan_propagates_catches_a_system_that_swallows_nan():
    assert_nan_propagates(PAPER, [0.4, 0.3])
    # an engine that answered NaN inputs with a number would fail: simulate with a wrapper
    class Swallowing:
        name, input_names, outputs = PAPER.name, PAPER.input_names, PAPER.outputs
        inputs = PAPER.inputs

        def evaluate(self, X):
            return np.nan_to_num(PAPER.evaluate(X), nan=0.5)

    with pytest.raises(AssertionError, match="expected NaN"):
        assert_nan_propagates(Swallowing(), [0.4, 0.3])


def test_assert_matches_reference():
    X = np.random.default_rng(0).uniform([0, -1], [1, 1], (200, 2))
    assert_matches_reference(PAPER, X, lambda X: evaluate(PAPER, X))
    moved = dataclasses.replace(PAPER, rules=PAPER.rules[1:])
    with pytest.raises(AssertionError, match="outputs differ from the reference"):
        assert_matches_reference(moved, X, evaluate(PAPER, X))
    with pytest.raises(ValueError, match="reference has shape"):
        assert_matches_reference(PAPER, X, np.zeros(3))
