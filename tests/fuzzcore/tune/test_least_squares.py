"""fuzzcore.tune.LeastSquares: Sugeno consequents by (constrained) least squares."""
import dataclasses

import numpy as np
import pytest
from scipy.optimize import LinearConstraint, lsq_linear, minimize

import fuzzcore
from fuzzcore.rules import Rule
from fuzzcore.tune import LeastSquares
from fuzzcore.tune.base import CALLBACK_STOP, CONVERGED
from fuzzcore.variables import Term, Variable

RULES = "rules/fuzzrisk.yaml"


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load(RULES)


def _trap(x, a, b, c, d):
    """MATLAB's trapmf, written out here apart from the engine."""
    with np.errstate(divide="ignore", invalid="ignore"):
        up = np.where(b > a, (x - a) / (b - a), 1.0)
        down = np.where(d > c, (d - x) / (d - c), 1.0)
    return np.clip(np.minimum(np.minimum(up, down), 1.0), 0.0, 1.0)


def _shares(fis, X):
    """Each rule's share of the firing strength (min AND) of rules/fuzzrisk.yaml, by hand."""
    def mu(variable, k, x):
        kind, *p = [fis.inputs[variable].terms[k].kind, *fis.inputs[variable].terms[k].params]
        return _trap(x, *(p if kind == "trapmf" else [p[0], p[1], p[1], p[2]]))
    w = np.column_stack([np.minimum(*[mu(v, abs(a) - 1, X[:, v]) if a else np.ones(len(X))
                                      for v, a in enumerate(rule.antecedent)]) for rule in fis.rules])
    return w / w.sum(axis=1, keepdims=True)


def _design(fis, X):
    """The first-order design matrix by hand: per rule, its share times ``iou, rdd, 1``."""
    share = _shares(fis, X)
    return np.hstack([share[:, [k]] * np.column_stack([X, np.ones(len(X))]) for k in range(len(fis.rules))])


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(3)
    X = np.column_stack([rng.uniform(0, 1, 800), rng.uniform(-1, 1, 800)])
    y = np.clip(0.3 + 0.5 * np.clip(X[:, 1], 0, 1) + 0.3 * (1 - X[:, 0]) + rng.normal(0, 0.05, 800), 0, 1)
    return X, y


def _grid(n=101):
    i, d = np.meshgrid(np.linspace(0, 1, n), np.linspace(-1, 1, n), indexing="ij")
    return np.column_stack([i.ravel(), d.ravel()])


def test_a_free_fit_is_the_least_squares_solution_on_the_rules_shares(fis, data):
    X, y = data
    tuner = LeastSquares(fis, bounded=False).fit(X, y)
    design = _design(fis, X)
    expected = np.linalg.lstsq(design, y, rcond=None)[0]
    np.testing.assert_allclose(tuner.result_.x, expected, atol=1e-9)
    np.testing.assert_allclose(tuner.system_.evaluate(X)[:, 0], design @ expected, atol=1e-12)
    assert tuner.result_.fun == pytest.approx(np.sqrt(np.mean((design @ expected - y) ** 2)), rel=1e-12)
    system = tuner.system_
    assert system.type == "sugeno" and system.defuzzifier == "wtaver"
    assert [r.antecedent for r in system.rules] == [r.antecedent for r in fis.rules]
    assert [t.kind for t in system.outputs[0].terms] == ["linear"] * len(fis.rules)


def test_a_first_order_system_is_recovered_exactly(fis):
    rng = np.random.default_rng(0)
    params = [(float(a), float(b), float(c)) for a, b, c in rng.uniform(-0.2, 0.2, (len(fis.rules), 3)) + [0, 0, 0.5]]
    terms = tuple(Term(f"t{k}", "linear", p) for k, p in enumerate(params))
    known = dataclasses.replace(
        fis, type="sugeno", defuzzifier="wtaver", outputs=(Variable("risk", (0.0, 1.0), terms),),
        rules=tuple(Rule(r.antecedent, (k + 1,), r.weight, r.connective) for k, r in enumerate(fis.rules)))
    X = _grid(41)
    assert (known.evaluate(X) >= 0).all() and (known.evaluate(X) <= 1).all()
    tuner = LeastSquares(fis).fit(X, known.evaluate(X)[:, 0])  # bounded: the truth lies inside the bounds
    np.testing.assert_allclose(tuner.result_.x, np.ravel(params), atol=1e-6)
    assert tuner.result_.fun < 1e-7 and tuner.result_.status == CONVERGED


def test_bounded_order_0_is_bounded_variable_least_squares(fis, data):
    X, _ = data
    y = np.clip(1.4 * (1 - X[:, 0]) * (X[:, 1] > 0) - 0.2, 0, 1)  # a free fit overshoots [0, 1]
    free = LeastSquares(fis, order=0, bounded=False).fit(X, y).result_.x
    assert free.min() < 0 or free.max() > 1
    tuner = LeastSquares(fis, order=0).fit(X, y)
    bvls = lsq_linear(_shares(fis, X), y, bounds=(0, 1), method="bvls").x
    np.testing.assert_allclose(tuner.result_.x, bvls, atol=1e-6)
    assert [t.kind for t in tuner.system_.outputs[0].terms] == ["constant"] * len(fis.rules)


def test_a_bounded_first_order_fit_stays_in_range_everywhere(fis, data):
    X, _ = data
    y = np.clip(2.0 * (1 - X[:, 0]) * np.clip(X[:, 1], 0, 1), 0, 1)
    free = LeastSquares(fis, bounded=False).fit(X, y)
    grid = _grid()
    assert free.system_.evaluate(grid).max() > 1.001  # the free fit leaves the range
    tuner = LeastSquares(fis).fit(X, y)
    out = tuner.system_.evaluate(grid)
    assert out.min() >= -1e-9 and out.max() <= 1 + 1e-9
    # every rule's own plane stays in range at the corners of the input box
    for term in tuner.system_.outputs[0].terms:
        a, b, c = term.params
        corners = [a * i + b * d + c for i in (0, 1) for d in (-1, 1)]
        assert min(corners) >= -1e-9 and max(corners) <= 1 + 1e-9
    # the optimum of another formulation (each plane bounded at the 4 corners of the box, the
    # slopes not split), solved by another method (trust-constr on the hand-computed shares)
    design = _design(fis, X)
    corners = np.array([np.concatenate([np.zeros(3 * k), (i, d, 1.0), np.zeros(3 * (len(fis.rules) - k - 1))])
                        for k in range(len(fis.rules)) for i in (0, 1) for d in (-1, 1)])
    reference = minimize(lambda p: np.mean((design @ p - y) ** 2), np.tile([0.0, 0.0, 0.5], len(fis.rules)),
                         jac=lambda p: 2 * design.T @ (design @ p - y) / len(y), method="trust-constr",
                         constraints=[LinearConstraint(corners, 0.0, 1.0)],
                         options={"gtol": 1e-12, "xtol": 1e-14, "maxiter": 5000})
    assert free.result_.fun <= tuner.result_.fun <= np.sqrt(reference.fun) + 1e-7


def test_monotone_constraints_hold_where_the_free_fit_breaks_them(fis, data):
    X, _ = data
    rng = np.random.default_rng(5)
    y = np.clip(0.5 + 0.4 * np.sin(6 * X[:, 0]) + rng.normal(0, 0.02, len(X)), 0, 1)  # rises, then falls in iou
    free = LeastSquares(fis).fit(X, y).system_
    assert not fuzzcore.verify(free, {"iou": -1}).ok
    tuner = LeastSquares(fis, monotone={"iou": -1}, grid=21).fit(X, y)
    assert "constraints added where fuzzcore.verify found the grid's fit non-monotone" in tuner.result_.message
    report = fuzzcore.verify(tuner.system_, {"iou": -1})
    assert report.ok, str(report)
    surface = tuner.system_.evaluate(_grid()).reshape(101, 101)
    assert np.diff(surface, axis=0).max() <= 1e-9
    assert tuner.system_.metadata["tuning"]["settings"]["monotone"] == {"iou": -1}


def test_a_rule_no_sample_fires_keeps_the_middle_of_the_range(fis):
    X = np.column_stack([np.linspace(0.8, 1.0, 50), np.linspace(0.6, 1.0, 50)])  # iou high, rdd high only
    tuner = LeastSquares(fis, order=0).fit(X, np.full(50, 0.9))
    fired = [k for k, r in enumerate(fis.rules) if r.antecedent == (3, 3)]  # iou high and rdd high
    assert len(fired) == 1
    idle = [k + 1 for k in range(len(fis.rules)) if k not in fired]
    assert f"rules {', '.join(map(str, idle))} fire on no training sample" in tuner.result_.message
    terms = tuner.system_.outputs[0].terms
    assert terms[fired[0]].params == pytest.approx((0.9,))
    assert all(terms[k - 1].params == (0.5,) for k in idle)


def test_saved_system_loads_back_with_its_provenance(fis, data, tmp_path):
    X, y = data
    tuner = LeastSquares(fis, monotone={"iou": -1}, grid=21).fit(X, y)
    path = tmp_path / "lse.yaml"
    tuner.system_.save(path)
    back = fuzzcore.load(path)
    np.testing.assert_array_equal(back.evaluate(X), tuner.system_.evaluate(X))
    tuning = back.metadata["tuning"]
    assert tuning["method"] == "lse" and tuning["seed"] is None and tuning["metric"] == "rmse"
    assert tuning["settings"] == {"order": 1, "bounded": True, "monotone": {"iou": -1}, "grid": 21, "max_iter": 10_000}
    assert tuning["score"]["final"] == pytest.approx(np.sqrt(np.mean((back.evaluate(X)[:, 0] - y) ** 2)))


def test_callback_sees_iterations_and_stops_the_run(fis, data):
    X, y = data
    seen = []

    def stop(info):
        seen.append(info.nit)
        if info.nit == 3:
            raise StopIteration

    tuner = LeastSquares(fis, callback=stop).fit(X, y)
    assert seen == [1, 2, 3] and tuner.result_.status == CALLBACK_STOP
    # it ends at a point that keeps the range, no better than the finished fit
    out = tuner.system_.evaluate(_grid())
    assert out.min() >= -1e-9 and out.max() <= 1 + 1e-9
    assert tuner.result_.fun >= LeastSquares(fis).fit(X, y).result_.fun - 1e-12


@pytest.mark.parametrize("kwargs, words", [
    ({"order": 2}, "order = 2: expected 0"),
    ({"bounded": "yes"}, "bounded = 'yes'"),
    ({"monotone": {"speed": 1}}, "'speed' is not an input of 'fuzzrisk'"),
    ({"monotone": {"iou": 0}}, "monotone['iou'] = 0"),
    ({"grid": 1}, "grid = 1, must be >= 2"),
    # 1000 points per input and the 3 breakpoints of its terms inside the range: 1003^2
    ({"monotone": {"iou": -1}, "grid": 1000}, "would take 1,006,009 grid points"),
])
def test_bad_settings_are_refused_at_fit(fis, data, kwargs, words):
    with pytest.raises(ValueError) as err:
        LeastSquares(fis, **kwargs).fit(*data)
    assert words in str(err.value)


def test_uncovered_samples_and_negated_outputs_are_refused(fis, data):
    narrow = dataclasses.replace(fis, rules=fis.rules[:1])  # rdd high and iou low only
    with pytest.raises(ValueError) as err:
        LeastSquares(narrow).fit(*data)
    assert "fire no rule of output 'risk' (the first: iou = " in str(err.value)
    negated = dataclasses.replace(fis, rules=(Rule((1, 3), (-3,)),) + fis.rules[1:])
    with pytest.raises(ValueError, match="rule 1 .* negates its output term"):
        LeastSquares(negated).fit(*data)
