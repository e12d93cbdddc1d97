"""Hostile inputs to the engine: what ``fis.infer`` / ``evaluate`` / ``explain`` take, and NaN honesty.

Documented outcomes (``FuzzySystem.infer``, :mod:`fuzzcore.inputs`, :mod:`fuzzcore._kernels`):
a real number of any Python or NumPy type gives the same result as its ``float()``; what is
not a real number raises ``TypeError`` naming the input; a number too large for a float64
raises ``ValueError`` naming it; the ``no_rule_fired`` policy answers only for an empty
output set, every other NaN propagates.
"""
import math

import numpy as np
import pytest
from hypothesis import given, strategies as st

import fuzzcore
from fuzzcore import FuzzySystem, Rule, RuleBaseError, Term, Variable
from fuzzcore import _kernels as K
from fuzzcore.compiled import MAX_WORK

RULES = "rules/fuzzrisk.yaml"


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load(RULES)


# --------------------------------------------------------------------------- item 7: what is a number
BAD_INPUTS = [
    (None, TypeError, "is None"),
    ("0.4", TypeError, "is text"),
    (b"0.4", TypeError, "is text"),
    (True, TypeError, "boolean"),
    (np.bool_(False), TypeError, "boolean"),
    (np.datetime64("2024-01-01"), TypeError, "datetime64"),
    (np.timedelta64(5, "s"), TypeError, "timedelta64"),
    (0.4 + 0.5j, TypeError, "complex"),
    (np.complex128(0.4), TypeError, "complex"),
    (np.ma.masked_array([0.4, 0.5], mask=[False, True]), TypeError, "masked array"),
    (np.array([0.4, None], dtype=object), TypeError, "holds None"),
    ([0.5, 10**400], ValueError, "too large for a float64"),
    (["0.4"], TypeError, "is text"),
    (10**400, ValueError, "too large for a float64"),
    (-(10**400), ValueError, "too large for a float64"),
]


@pytest.mark.parametrize("value, error, words", BAD_INPUTS, ids=lambda v: type(v).__name__)
def test_infer_refuses_what_is_not_a_real_number_naming_the_input(fis, value, error, words):
    with pytest.raises(error, match=words) as caught:
        fis.infer(value, 0.3)
    assert "input 'iou'" in str(caught.value)
    with pytest.raises(error, match=words) as caught:
        fis.infer(iou=0.4, rdd=value)
    assert "input 'rdd'" in str(caught.value)
    with pytest.raises(error, match=words):
        fis.explain(0.4, value)


def test_a_long_double_too_large_for_float64_is_named(fis):
    big = np.longdouble(10) ** 400
    if np.isinf(big):
        pytest.skip("this platform's long double is float64: no such value exists")
    with pytest.raises(ValueError, match="input 'iou' holds .* too large for a float64"):
        fis.infer(big, 0.3)


def test_evaluate_refuses_complex_and_masked_X(fis):
    with pytest.raises(TypeError, match="X is complex"):
        fis.evaluate(np.array([[0.4, 0.3]], dtype=complex))
    with pytest.raises(TypeError, match="X is a masked array"):
        fis.evaluate(np.ma.masked_array([[0.4, 0.3]], mask=[[False, True]]))


SCALAR_TYPES = [int, float, np.float64, np.float32, np.float16, np.int8, np.int16, np.int32, np.int64,
                np.uint8, np.uint16, np.uint32, np.uint64]


@pytest.mark.parametrize("kind", SCALAR_TYPES, ids=lambda k: k.__name__)
def test_every_real_scalar_type_gives_the_float_result(fis, kind):
    # 0 and 1 exist in every type; rdd = 0 is "medium" (two rules fire at iou 1 / 0)
    for iou in (0, 1):
        want = fis.infer(float(iou), 0.0)
        assert fis.infer(kind(iou), kind(0)) == want
        assert fis.infer(iou=kind(iou), rdd=kind(0)) == want
    x = fis.infer(np.float32(0.4), 0.3)
    assert x == fis.infer(float(np.float32(0.4)), 0.3)


@given(st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-(10**320), 10**320)))
def test_random_numbers_give_their_float_result_or_a_named_overflow(value):
    fis = _fis_cache()
    try:
        expected = float(value)
    except OverflowError:
        with pytest.raises(ValueError, match="input 'rdd'"):
            fis.infer(0.5, value)
        return
    got, want = fis.infer(0.5, value), fis.infer(0.5, expected)
    batch = fis.evaluate([[0.5, value]])[0, 0]
    for v in (got, batch):
        assert v == want or (math.isnan(v) and math.isnan(want))


_FIS = []


def _fis_cache():
    if not _FIS:
        _FIS.append(fuzzcore.load(RULES))
    return _FIS[0]


def test_arrays_of_numpy_integers_and_lists_work(fis):
    got = fis.infer(np.array([0, 1], dtype=np.int16), [0, 0])
    np.testing.assert_array_equal(got, [fis.infer(0.0, 0.0), fis.infer(1.0, 0.0)])


# --------------------------------------------------------------------------- item 3: only an empty set takes the policy
def _sugeno_sum(no_rule_fired="midpoint", defuzzifier="wtaver"):
    """z = 1*a + 0*b on [0, 10]; one rule, firing where a is 'any' (a trapezoid over [0, 10])."""
    a = Variable("a", (0.0, 10.0), (Term("any", "trapmf", (0.0, 0.0, 10.0, 10.0)),))
    b = Variable("b", (0.0, 10.0), (Term("any", "trapmf", (0.0, 0.0, 10.0, 10.0)),))
    z = Variable("z", (0.0, 10.0), (Term("sum", "linear", (1.0, 0.0, 0.0)),))
    return FuzzySystem("s", (a, b), (z,), (Rule((1, 0), (1,)),), type="sugeno", defuzzifier=defuzzifier,
                       no_rule_fired=no_rule_fired)


@pytest.mark.parametrize("defuzzifier", ["wtaver", "wtsum"])
def test_a_nan_sugeno_output_propagates_instead_of_the_midpoint(defuzzifier):
    fis = _sugeno_sum(defuzzifier=defuzzifier)
    # the rule fires with strength 1 at a = 2 (inside the trapezoid's top); z = 1*2 + 0*b
    assert fis.infer(2.0, 3.0) == 2.0
    # b = inf: 0 * inf = NaN, so z is NaN; the midpoint 5.0 would be a confident wrong number
    assert math.isnan(fis.infer(2.0, math.inf))
    assert np.isnan(fis.evaluate(np.tile([2.0, math.inf], (600, 1)))[:, 0]).all()  # the batch path too
    # nothing fires at a = 20 (outside the trapezoid): the policy answers
    assert fis.infer(20.0, 3.0) == 5.0


def test_an_empty_mamdani_set_still_takes_the_policy():
    # the rule fires (strength 1 at x = 0.5) but its output term lies between two grid
    # points (grid of 11 on [0, 1]: 0.0, 0.1, ...; the triangle 0.12..0.18 covers none): the
    # aggregated set is empty on the grid, which is "no output" -> the declared 0.75
    x = Variable("x", (0.0, 1.0), (Term("mid", "trimf", (0.0, 0.5, 1.0)),))
    y = Variable("y", (0.0, 1.0), (Term("thin", "trimf", (0.12, 0.15, 0.18)),))
    fis = FuzzySystem("m", (x,), (y,), (Rule((1,), (1,)),), resolution=11, no_rule_fired=0.75)
    assert fis.infer(0.5) == 0.75
    assert fis.evaluate(np.full((40, 1), 0.5))[:, 0].tolist() == [0.75] * 40


# --------------------------------------------------------------------------- item 4: NaN memberships
def _strength_nan_case(and_method):
    """The paper's rule base with the 'low' IoU term's parameters replaced, in the packed
    arrays, by a degenerate Gaussian (sigma 1e-200: 2 sigma^2 = 0, so mu(c) = exp(-0/0) = NaN)
    -- the state a loader now refuses, reached the way a tuner writes candidates."""
    fis = fuzzcore.load(RULES)
    fis = FuzzySystem(**{**{f: getattr(fis, f) for f in ("name", "inputs", "outputs", "rules")},
                         "and_method": and_method})
    fblob, iblob, layout = fis.packed
    t = 0  # flat input-term index of iou.low
    iblob[iblob[K.I_IN_KIND] + t] = 2  # gaussmf
    fblob[layout.in_params.start + 4 * t: layout.in_params.start + 4 * t + 4] = [1e-200, 0.2, 0.0, 0.0]
    return fblob, iblob


@pytest.mark.parametrize("and_method", ["min", "prod"])
def test_a_nan_membership_gives_a_nan_strength_and_a_nan_output(and_method):
    fblob, iblob = _strength_nan_case(and_method)
    X = np.array([[0.2, 0.0]])  # iou exactly at the degenerate centre; rdd = 0 is fully 'medium'
    out = np.empty((1, 1))
    K.evaluate_serial(X, fblob, iblob, out)
    # min(NaN, 1.0) ignoring the NaN would fire "iou is low and rdd is medium" at 1.0
    assert math.isnan(out[0, 0])
    mu, fire, agg, y = np.empty(6), np.empty(9), np.zeros((1, 101)), np.empty((1, 1))
    K.explain_one(X, fblob, iblob, mu, fire, agg, y)
    assert math.isnan(mu[0]) and math.isnan(y[0, 0])
    assert np.isnan(fire).sum() >= 1


# --------------------------------------------------------------------------- item 16: scratch by need
def _many_rules(n_rules, **settings):
    n_terms = 100
    x = Variable("x", (0.0, 1.0), tuple(Term(f"t{k}", "trimf", (k / n_terms, (k + 0.5) / n_terms, (k + 1) / n_terms))
                                        for k in range(n_terms)))
    z = Variable("z", (0.0, 1.0), tuple(Term(f"t{k}", "trimf", (k / 10, (k + 0.5) / 10, (k + 1) / 10))
                                        for k in range(10)))
    v = Variable("v", (0.0, 1.0), (Term("any", "trapmf", (0.0, 0.0, 1.0, 1.0)),) * 1)
    rules = tuple(Rule((r % n_terms + 1, 1), (r % 10 + 1,)) for r in range(n_rules))
    return FuzzySystem("big", (x, v), (z,), rules, **settings)


def test_scratch_is_sized_by_what_the_defuzzifier_needs():
    fis = _many_rules(12_000)  # centroid, max aggregation: 2K = 20 sets, no exact-centroid lists
    tail = int(fis.packed[1][K.N_TAIL])
    assert tail == 4 * 20 + 101  # the set lists and one aggregated row (compiled.py layout)
    # a 12,000-rule sum-aggregated centroid_exact would keep 12000 * 11999 / 2 = 72 million
    # crossing points (576 MB) per call: refused, naming the cause
    with pytest.raises(RuleBaseError, match=r"centroid_exact with sum aggregation over 12,000 rules") as caught:
        _many_rules(12_000, aggregation="sum", defuzzifier="centroid_exact")
    assert f"{MAX_WORK:,}" in str(caught.value) and caught.value.place == "defuzzifier"
    # the same with max aggregation merges sets per output term: fine, and correct
    exact = _many_rules(12_000, defuzzifier="centroid_exact")
    assert exact.packed[1][K.N_TAIL] < 10_000
    y = exact.infer(0.333, 0.5)
    assert 0.0 < y < 1.0


def test_a_large_fis_loads_and_runs_without_a_huge_scratch(tmp_path):
    n = 20_000
    lines = ["[System]", "Name='big'", "NumInputs=1", "NumOutputs=1", f"NumRules={n}", "",
             "[Input1]", "Name='x'", "Range=[0 1]", "NumMFs=2", "MF1='a':'trimf',[0 0 1]", "MF2='b':'trimf',[0 1 1]",
             "", "[Output1]", "Name='y'", "Range=[0 1]", "NumMFs=2", "MF1='a':'trimf',[0 0 1]",
             "MF2='b':'trimf',[0 1 1]", "", "[Rules]"] + [f"{r % 2 + 1}, {r % 2 + 1} (1) : 1" for r in range(n)]
    path = tmp_path / "big.fis"
    path.write_text("\n".join(lines) + "\n")
    fis = fuzzcore.load(path)
    assert fis.packed[1][K.N_TAIL] == 4 * 4 + 101
    # at x = 0.25: 'a' 0.75, 'b' 0.25, thousands of copies of the same two rules (max merges them)
    small = FuzzySystem("small", fis.inputs, fis.outputs, fis.rules[:2])
    assert fis.infer(0.25) == small.infer(0.25)


# --------------------------------------------------------------------------- item 17: messages
def test_a_sugeno_defuzzifier_on_a_mamdani_system_is_said_once():
    x = Variable("x", (0.0, 1.0), (Term("a", "trimf", (0.0, 0.5, 1.0)),))
    with pytest.raises(RuleBaseError) as caught:
        FuzzySystem("m", (x,), (Variable("y", (0.0, 1.0), x.terms),), (Rule((1,), (1,)),), defuzzifier="wtaver")
    message = str(caught.value)
    assert message.count("wtaver") == 1 and message.count("defuzzifier (") == 0
    assert message == ("defuzzifier: 'wtaver': expected one of centroid, bisector, mom, som, lom, centroid_exact "
                       "(the defuzzifiers of a mamdani system)")
