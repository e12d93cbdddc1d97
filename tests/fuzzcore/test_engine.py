"""The Numba engine against the NumPy reference evaluator, on random systems and inputs."""
import math

import numpy as np
from hypothesis import given, settings, strategies as st

from fuzzcore import FuzzySystem, Rule, Term, Variable

import reference
from strategies import PIECEWISE, mamdani_systems, samples, sugeno_systems


def _check(system, rows):
    got = system.evaluate(rows)
    want = reference.evaluate(system, rows)
    scale = max(v.range[1] - v.range[0] for v in system.outputs)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * scale, equal_nan=True)
    return got


@settings(max_examples=150)
@given(st.data())
def test_mamdani_matches_reference(data):
    system = data.draw(mamdani_systems())
    _check(system, samples(system, 12, data.draw))


def test_mom_of_a_probor_tie_follows_each_bit_of_exp():
    # found by test_mamdani_matches_reference (shrunk): NOT linzmf(0, 0) is 1 on (0, 1], and
    # probor with gaussmf(1, 0) gives 1 + g - 1*g there, which is exactly 1.0 or not depending
    # on g's last bit; mom averages the grid points equal to the maximum, so one ulp of exp
    # moves the answer by ~1e-3. The engine's exp (the C library's, correctly rounded here)
    # gave 0.510617..., the reference's numpy exp (SIMD, 1 ulp low at y = 0.15, 0.3, 0.5,
    # 0.96 on an AVX-512 CPU) gave 0.509615...
    y0 = Variable("y0", (0.0, 1.0), (Term("g", "gaussmf", (1.0, 0.0)), Term("z", "linzmf", (0.0, 0.0))))
    x0 = Variable("x0", (0.0, 1.0), (Term("t0", "trimf", (0.0, 0.5, 1.0)),))
    system = FuzzySystem(name="tie", inputs=(x0,), outputs=(y0,),
                         rules=(Rule((0,), (-2,), 1.0, "and"), Rule((0,), (1,), 1.0, "and")),
                         aggregation="probor", defuzzifier="mom", resolution=101)
    # by hand: both rules fire at 1 (no antecedent), min implication leaves the sets as they are
    y = np.arange(101) / 100  # MATLAB's linspace(0, 1, 101): j * (1 - 0) / 100
    agg = np.zeros(101)
    for j, yj in enumerate(y):
        a = 1.0 if yj > 0 else 0.0  # NOT linzmf(0, 0)
        g = math.exp(-(yj * yj) / 2.0)  # gaussmf(1, 0), the C library's exp
        agg[j] = a + g - a * g  # probor of rule 1 (onto 0, exact) then rule 2
    at_max = y[agg == agg.max()]
    assert 0 < len(at_max) < 101  # a genuine tie: some points round to the maximum, some not
    want = sum(at_max.tolist()) / len(at_max)
    np.testing.assert_allclose(system.evaluate([[0.5]]), [[want]], rtol=0, atol=1e-12)
    _check(system, [[0.5]])


@given(st.data())
def test_sugeno_matches_reference(data):
    system = data.draw(sugeno_systems())
    _check(system, samples(system, 12, data.draw))


@given(st.data())
def test_batch_equals_one_by_one(data):
    system = data.draw(mamdani_systems(max_outputs=1))
    rows = np.array(samples(system, 20, data.draw))
    batch = system.evaluate(rows)[:, 0]
    single = np.array([system.infer(*map(float, row)) for row in rows])
    np.testing.assert_array_equal(batch, single)


@settings(max_examples=20)
@given(st.data())
def test_batch_with_a_partial_block_equals_one_by_one(data):
    # the batch kernel works on blocks of 128 samples; 133 rows end in a block of 5
    system = data.draw(mamdani_systems(max_outputs=1))
    rows = np.array(samples(system, 133, data.draw))
    single = np.array([system.infer(*map(float, row)) for row in rows])
    np.testing.assert_array_equal(system.evaluate(rows)[:, 0], single)


@given(st.data())
def test_parallel_path_equals_serial(data):
    # large batches run on the parallel kernel; the same rows one chunk at a time run serially
    system = data.draw(mamdani_systems(max_outputs=1))
    rows = np.array(samples(system, 8, data.draw) * 300)  # 2400 rows: over the parallel threshold
    np.testing.assert_array_equal(system.evaluate(rows), system.evaluate(rows[:8]).repeat(1, 0).tolist() * 300)


@given(st.data())
def test_output_inside_range(data):
    system = data.draw(mamdani_systems(defuzzifiers=("centroid", "bisector", "mom", "som", "lom",
                                                     "centroid_exact"),
                                       output_kinds=PIECEWISE, aggregations=("max", "sum")))
    out = system.evaluate(samples(system, 10, data.draw))
    for o, var in enumerate(system.outputs):
        col = out[:, o]
        col = col[~np.isnan(col)]
        assert np.all((col >= var.range[0] - 1e-12) & (col <= var.range[1] + 1e-12))


def _shuffled(system, data):
    from dataclasses import replace

    order = data.draw(st.permutations(range(len(system.rules))))
    return replace(system, rules=tuple(system.rules[i] for i in order))


@given(st.data())
def test_rule_order_does_not_matter_max_aggregation(data):
    # max and min are exact, so with max aggregation the order cannot change a single bit
    system = data.draw(mamdani_systems(aggregations=("max",)))
    rows = samples(system, 10, data.draw)
    np.testing.assert_array_equal(system.evaluate(rows), _shuffled(system, data).evaluate(rows))


@given(st.data())
def test_rule_order_does_not_matter_sum_aggregation(data):
    # sums are reordered, so only up to rounding; mom/som/lom/bisector compare for exact ties
    # or thresholds and may flip on a rounding difference, hence the centroid here
    system = data.draw(mamdani_systems(aggregations=("sum", "probor"), defuzzifiers=("centroid",)))
    rows = samples(system, 10, data.draw)
    np.testing.assert_allclose(system.evaluate(rows), _shuffled(system, data).evaluate(rows),
                               rtol=0, atol=1e-12, equal_nan=True)


def test_nan_input_gives_nan_not_a_number():
    from fuzzcore import load

    fis = load("rules/fuzzrisk.yaml")
    assert np.isnan(fis.infer(float("nan"), 0.1))
    out = fis.evaluate([[0.5, np.nan], [0.5, 0.1], [np.nan, np.nan]])
    assert np.isnan(out[0, 0]) and not np.isnan(out[1, 0]) and np.isnan(out[2, 0])
