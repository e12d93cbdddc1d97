"""Membership functions: hand-computed edge tables, and the kernel against MATLAB's formulas."""
import math

import numpy as np
import pytest
from hypothesis import given, strategies as st

from fuzzcore import Term
from fuzzcore._kernels import mf_array
from fuzzcore.membership import resolve_kind

from reference import membership
from strategies import INPUT_KINDS, term_params

INF = math.inf


def kernel(kind, params, xs):
    p = np.zeros(4)
    p[:len(params)] = params
    x = np.asarray(xs, dtype=float)
    out = np.empty_like(x)
    mf_array(resolve_kind(kind).code, p, x, out)
    return out


# (kind, params, x, expected) -- each expected value worked out by hand from the formula
EDGES = [
    # trimf [0 1 3]: feet, peak, slopes (x - a)/(b - a), (c - x)/(c - b), outside
    ("trimf", [0, 1, 3], 0.0, 0.0), ("trimf", [0, 1, 3], 1.0, 1.0), ("trimf", [0, 1, 3], 3.0, 0.0),
    ("trimf", [0, 1, 3], 0.25, 0.25), ("trimf", [0, 1, 3], 2.5, 0.25), ("trimf", [0, 1, 3], -5.0, 0.0),
    ("trimf", [0, 1, 3], INF, 0.0), ("trimf", [0, 1, 3], -INF, 0.0),
    ("trimf", [0, 0, 1], 0.0, 1.0),   # left shoulder: x == b wins, as in MATLAB's trimf.m
    ("trimf", [0, 1, 1], 1.0, 1.0), ("trimf", [2, 2, 2], 2.0, 1.0), ("trimf", [2, 2, 2], 2.1, 0.0),
    # trapmf [0 1 2 4]
    ("trapmf", [0, 1, 2, 4], 0.0, 0.0), ("trapmf", [0, 1, 2, 4], 0.5, 0.5), ("trapmf", [0, 1, 2, 4], 1.0, 1.0),
    ("trapmf", [0, 1, 2, 4], 2.0, 1.0), ("trapmf", [0, 1, 2, 4], 3.0, 0.5), ("trapmf", [0, 1, 2, 4], 4.0, 0.0),
    ("trapmf", [0, 0, 1, 3], 0.0, 1.0), ("trapmf", [0, 0, 1, 3], -0.1, 0.0), ("trapmf", [0, 0, 1, 3], INF, 0.0),
    ("trapmf", [0, 1, 2, 2], 2.0, 1.0), ("trapmf", [0, 1, 2, 2], 2.0001, 0.0), ("trapmf", [0, 1, 2, 4], -INF, 0.0),
    # gaussmf [sigma=2, c=1]: exp(-(x-c)^2 / (2 sigma^2)); at x = 3: exp(-4/8)
    ("gaussmf", [2, 1], 1.0, 1.0), ("gaussmf", [2, 1], 3.0, math.exp(-0.5)), ("gaussmf", [2, 1], INF, 0.0),
    # gauss2mf [1 0 2 1]: 1 on [0, 1]; x = -1: exp(-1/2); x = 3: exp(-(2^2)/(2*4))
    ("gauss2mf", [1, 0, 2, 1], 0.5, 1.0), ("gauss2mf", [1, 0, 2, 1], -1.0, math.exp(-0.5)),
    ("gauss2mf", [1, 0, 2, 1], 3.0, math.exp(-0.5)), ("gauss2mf", [1, 0, 2, 1], -INF, 0.0),
    # gbellmf [a=2 b=1 c=0]: 1/(1 + (x/2)^2); x = 2: 1/2; x = 4: 1/5
    ("gbellmf", [2, 1, 0], 0.0, 1.0), ("gbellmf", [2, 1, 0], 2.0, 0.5), ("gbellmf", [2, 1, 0], -4.0, 0.2),
    ("gbellmf", [2, 1, 0], INF, 0.0),
    # sigmf [a=2 c=1]: 1/(1 + exp(-2(x - 1)))
    ("sigmf", [2, 1], 1.0, 0.5), ("sigmf", [2, 1], 2.0, 1 / (1 + math.exp(-2))), ("sigmf", [2, 1], INF, 1.0),
    ("sigmf", [2, 1], -INF, 0.0), ("sigmf", [-2, 1], INF, 0.0), ("sigmf", [0, 1], INF, 0.5),
    ("sigmf", [2, 1], -1000.0, 0.0),  # exp overflows to inf: 1/inf = 0, no warning, no NaN
    # dsigmf [5 2 5 7] at 4.5: |sig(5, 2) - sig(5, 7)| at the middle
    ("dsigmf", [5, 2, 5, 7], 4.5, abs(1 / (1 + math.exp(-12.5)) - 1 / (1 + math.exp(12.5)))),
    ("dsigmf", [5, 2, 5, 7], INF, 0.0),
    ("psigmf", [2, 3, -5, 8], 5.5, (1 / (1 + math.exp(-5))) * (1 / (1 + math.exp(-12.5)))),
    ("psigmf", [2, 3, -5, 8], INF, 0.0),
    # smf [1 3]: midpoint 2; x = 1.5: 2((0.5)/2)^2 = 0.125; x = 2.5: 1 - 2(0.5/2)^2 = 0.875
    ("smf", [1, 3], 1.0, 0.0), ("smf", [1, 3], 1.5, 0.125), ("smf", [1, 3], 2.0, 0.5),
    ("smf", [1, 3], 2.5, 0.875), ("smf", [1, 3], 3.0, 1.0), ("smf", [1, 3], INF, 1.0),
    ("smf", [2, 2], 2.0, 1.0), ("smf", [2, 2], 1.9, 0.0),  # a == b: a step at (a + b)/2
    ("zmf", [1, 3], 1.5, 0.875), ("zmf", [1, 3], 2.5, 0.125), ("zmf", [1, 3], -INF, 1.0),
    ("pimf", [0, 2, 4, 6], 1.0, 0.5), ("pimf", [0, 2, 4, 6], 3.0, 1.0), ("pimf", [0, 2, 4, 6], 5.0, 0.5),
    ("linsmf", [1, 3], 2.0, 0.5), ("linsmf", [1, 3], 0.0, 0.0), ("linsmf", [1, 3], 3.0, 1.0),
    ("linzmf", [1, 3], 2.5, 0.25), ("linzmf", [1, 3], 1.0, 1.0), ("linzmf", [1, 3], INF, 0.0),
]


@pytest.mark.parametrize("kind, params, x, expected", EDGES)
def test_edge_table(kind, params, x, expected):
    assert kernel(kind, params, [x])[0] == pytest.approx(expected, abs=1e-15)


@pytest.mark.parametrize("kind", INPUT_KINDS)
def test_nan_stays_nan(kind):
    # each kind with plain valid parameters
    params = {"trimf": [0, 1, 2], "trapmf": [0, 1, 2, 3], "gaussmf": [1, 0], "gauss2mf": [1, 0, 1, 1],
              "gbellmf": [1, 2, 0], "sigmf": [1, 0], "dsigmf": [1, 0, 1, 1], "psigmf": [1, 0, -1, 1],
              "smf": [0, 1], "zmf": [0, 1], "pimf": [0, 1, 2, 3], "linsmf": [0, 1], "linzmf": [0, 1]}[kind]
    assert np.isnan(kernel(kind, params, [np.nan])[0])


@given(st.sampled_from(INPUT_KINDS).flatmap(lambda k: st.tuples(st.just(k), term_params(k))),
       st.lists(st.floats(-1.5, 1.5), min_size=1, max_size=30))
def test_kernel_matches_matlab_formulas(kind_params, xs):
    kind, params = kind_params
    got = kernel(kind, params, xs)
    want = membership(kind, params, xs)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert np.all((got >= 0) & (got <= 1))


@pytest.mark.parametrize("kind, params, message", [
    ("trimf", [0, 2, 1], "non-decreasing"),
    ("trapmf", [0, 1, 3, 2], "non-decreasing"),
    ("gaussmf", [0, 1], "must be > 0"),
    ("gaussmf", [-1, 1], "must be > 0"),
    ("gbellmf", [0, 1, 0], "!= 0"),
    ("trimf", [0, 1], "takes 3 parameters"),
    ("trimf", [0, math.nan, 1], "finite"),
    ("pimf", [0, 3, 2, 4], "non-decreasing"),
])
def test_invalid_parameters_named(kind, params, message):
    from fuzzcore import FuzzySystem, Rule, RuleBaseError, Variable

    good = Term("ok", "trimf", [0, 0.5, 1])
    bad_var = Variable("x", (0, 1), (Term("bad", kind, params),))
    out = Variable("y", (0, 1), (good,))
    with pytest.raises(RuleBaseError) as err:
        FuzzySystem("s", (bad_var,), (out,), (Rule((1,), (1,)),))
    assert message in str(err.value) and "'bad'" in str(err.value) and "inputs.x" in str(err.value)


def test_aliases_resolve_to_matlab_names():
    assert Term("a", "triangle", [0, 1, 2]).kind == "trimf"
    assert Term("a", "trapezoid", [0, 1, 2, 3]).kind == "trapmf"
    with pytest.raises(ValueError, match="unknown membership function 'triangel'"):
        Term("a", "triangel", [0, 1, 2])


# --------------------------------------------------------------------------- Term.membership
@given(st.sampled_from(INPUT_KINDS).flatmap(lambda k: st.tuples(st.just(k), term_params(k))),
       st.lists(st.floats(-1.5, 1.5), min_size=1, max_size=30))
def test_term_membership_matches_matlab_formulas(kind_params, xs):
    kind, params = kind_params
    term = Term("t", kind, params)
    got = term.membership(np.array(xs))
    assert isinstance(got, np.ndarray) and got.dtype == np.float64 and got.shape == (len(xs),)
    np.testing.assert_allclose(got, membership(kind, params, xs), rtol=0, atol=1e-12)
    # a scalar in gives a float out, the same number as in the array
    first = term.membership(xs[0])
    assert type(first) is float and first == got[0]


@pytest.mark.parametrize("kind, params, x, expected", EDGES)
def test_term_membership_edge_table(kind, params, x, expected):
    assert Term("t", kind, params).membership(x) == pytest.approx(expected, abs=1e-15)


def test_term_membership_shapes_and_nan():
    term = Term("mid", "trimf", [0.0, 1.0, 3.0])
    # (x - a)/(b - a) on the rise, (c - x)/(c - b) on the fall: 0.5 -> 0.5, 2.0 -> 0.5, 2.5 -> 0.25
    x = np.array([[0.5, 2.0], [2.5, np.nan]])
    got = term.membership(x)
    assert got.shape == (2, 2)
    np.testing.assert_array_equal(got[0], [0.5, 0.5])
    assert got[1, 0] == 0.25 and np.isnan(got[1, 1])
    assert math.isnan(term.membership(math.nan))
    assert term.membership(np.float32(1.0)) == 1.0 and term.membership(2) == 0.5  # ints and float32
    assert term.membership([0.5, 1.0]).tolist() == [0.5, 1.0]                   # lists
    assert term.membership(np.arange(6.0).reshape(2, 3)[:, ::2]).tolist() == [[0.0, 0.5], [0.0, 0.0]]
    assert term.membership(np.empty((0, 3))).shape == (0, 3)


@pytest.mark.parametrize("x", ["0.5", None, True, np.array([True]), np.array([1 + 1j]), {"x": 1}])
def test_term_membership_refuses_non_numbers(x):
    with pytest.raises(TypeError, match="term 'low': x must be a real number or an array of real"):
        Term("low", "trimf", [0, 0, 1]).membership(x)


def test_term_membership_refuses_invalid_terms():
    from fuzzcore import RuleBaseError

    with pytest.raises(RuleBaseError, match=r"term 'bad' \(trimf \[0.0, 2.0, 1.0\]\): .*non-decreasing"):
        Term("bad", "trimf", [0, 2, 1]).membership(0.5)
    with pytest.raises(RuleBaseError, match="term 'c' .*constant.* is a Sugeno output"):
        Term("c", "constant", [0.3]).membership(0.5)
