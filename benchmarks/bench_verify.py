"""Verification speed (issue 16 goals: the 9-rule paper system well under 1 s, a 5-input,
3-terms-each, 243-rule system under 1 min).

Run: ``python -m pytest benchmarks/bench_verify.py --benchmark-only -q -s``

Each run is the whole :func:`fuzzcore.verify` with a declared monotonicity (coverage on the
cell structure, line search with local refinement, steepest change, rule findings with
the redundancy check, partitions). The answer is checked before timing: full coverage,
exactly, and every rule firing somewhere. (The 243-rule system, output level = the inputs'
mean level rounded, is not monotone in ``a`` under the centroid: the verifier finds a drop
of about 0.034; it is timed with the search, not asserted monotone.)

Peer in the same run: ``grid``, a brute-force coverage estimate by the engine on a regular
grid of the same number of points as the verifier evaluates (what a user would otherwise
do, with no exact answer and no regions).
"""
import itertools
import time

import numpy as np
import pytest

import fuzzcore
from fuzzcore import FuzzySystem, Rule, Term, Variable


def _terms():
    return (Term("low", "trapmf", (0.0, 0.0, 0.25, 0.5)), Term("medium", "trimf", (0.25, 0.5, 0.75)),
            Term("high", "trapmf", (0.5, 0.75, 1.0, 1.0)))


def big_system() -> FuzzySystem:
    """5 inputs x 3 terms, all 243 rules: the output level is the inputs' mean level, rounded."""
    names = ["a", "b", "c", "d", "e"]
    rules = [Rule(levels, (int(round(sum(levels) / 5)),)) for levels in itertools.product((1, 2, 3), repeat=5)]
    return FuzzySystem("big", tuple(Variable(n, (0.0, 1.0), _terms()) for n in names),
                       (Variable("y", (0.0, 1.0), _terms()),), tuple(rules))


SYSTEMS = {"paper": (fuzzcore.load("rules/fuzzrisk.yaml"), {"iou": -1}),
           "big": (big_system(), {"a": +1})}


@pytest.fixture(scope="module", autouse=True)
def warm():
    for fis, monotone in SYSTEMS.values():
        fis.warmup()
        fuzzcore.verify(fis, monotone)  # compile / load the verifier's kernels


def _timed(benchmark, fn):
    cpu = time.process_time()
    result = benchmark.pedantic(fn, rounds=3, iterations=1)
    benchmark.extra_info["cpu_s"] = (time.process_time() - cpu) / 3
    return result


@pytest.mark.parametrize("name", SYSTEMS)
def test_verify(benchmark, name):
    fis, monotone = SYSTEMS[name]
    report = fuzzcore.verify(fis, monotone)
    assert report.coverage.covered and report.coverage.exact
    assert report.rules.never_firing == ()
    benchmark.extra_info["evaluations"] = report.n_evaluations
    benchmark.extra_info["cells"] = report.coverage.n_cells
    _timed(benchmark, lambda: fuzzcore.verify(fis, monotone))


@pytest.mark.parametrize("name", SYSTEMS)
def test_grid(benchmark, name):
    fis, monotone = SYSTEMS[name]
    n = fuzzcore.verify(fis, monotone).n_evaluations
    per_axis = max(2, int(round(n ** (1 / len(fis.inputs)))))
    axes = [np.linspace(*v.range, per_axis) for v in fis.inputs]
    X = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)

    def grid():
        return fis.evaluate(X)

    assert np.isfinite(grid()).all()
    _timed(benchmark, grid)
