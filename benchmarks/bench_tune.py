"""Tuning speed: the paper's budgets on 10,000 frames (targets: rule learning <= 2 s, pattern
search with 1000 iterations per fold and 5 folds <= 60 s).

Run: ``python -m pytest benchmarks/bench_tune.py --benchmark-only -q -s``

The data: 10,000 frames in 500 scenes of 20, shaped like the synthetic benchmark's
feature table (``fuzzrisk features``): 56 % of frames have nothing matched (IoU~ = 0,
RDD~ = 1, targets around 0.7), the others IoU~ ~ Beta(2, 4.5) and RDD~ ~ N(0.45, 0.3)
clipped to [-1, 1], targets 0.55 - 0.15 IoU~ + 0.1 RDD~ + N(0, 0.17) clipped to [0, 1].
``continuous`` repeats the runs with no repeated rows (every frame matched), the worst
case for the objective's one-evaluation-per-distinct-row shortcut.

Peers in the same run, answers checked before timing:

- ``naive``: the objective the obvious way, one FuzzySystem per candidate and
  ``fis.evaluate`` (what the batched objective avoids);
- ``direct``: the batched objective without its exact shortcuts (rule tables for rule
  learning; the base point for pattern-search polls).

Each timed function also records its CPU time (``extra_info["cpu_s"]``): the machine's
cores are shared, so wall time is noisy.
"""
import time

import numpy as np
import pytest

import fuzzcore
from fuzzcore.tune import Objective, ParticleSwarm, PatternSearch, RuleSpace, TermSpace

N_FRAMES = 10_000


def frames(seed=2025, unmatched=0.56):
    rng = np.random.default_rng(seed)
    n = N_FRAMES
    iou = rng.beta(2, 4.5, n)
    rdd = np.clip(rng.normal(0.45, 0.3, n), -1, 1)
    y = 0.55 - 0.15 * iou + 0.1 * rdd + rng.normal(0, 0.17, n)
    none = rng.random(n) < unmatched
    iou[none], rdd[none] = 0.0, 1.0
    y[none] = rng.normal(0.7, 0.19, none.sum())
    scenes = np.repeat(np.arange(n // 20), 20)
    return np.column_stack([iou, rdd]), np.clip(y, 0, 1), scenes


DATA = {"typical": frames(), "continuous": frames(unmatched=0.0)}


@pytest.fixture(scope="module")
def fis():
    system = fuzzcore.load("rules/fuzzrisk.yaml")
    X, y, _ = DATA["typical"]
    Objective(TermSpace(system), X[:100], y[:100])(TermSpace(system).x0)  # compile / load kernels
    ParticleSwarm(system, swarm_size=5, max_iter=1).fit(X[:100], y[:100])
    PatternSearch(system, n_folds=1, max_iter=2).fit(X[:100], y[:100])
    return system


def _timed(benchmark, run):
    """Time ``run`` once (a long run: one round), recording its CPU time."""
    box = {}

    def target():
        start = time.process_time()
        box["out"] = run()
        box["cpu"] = time.process_time() - start
        return box["out"]

    out = benchmark.pedantic(target, rounds=1, iterations=1)
    benchmark.extra_info["cpu_s"] = round(box["cpu"], 3)
    return out


def _rmse(system, X, y):
    return float(np.sqrt(np.mean((system.evaluate(X)[:, 0] - y) ** 2)))


# --------------------------------------------------------------------------- objective
def _poll(space):
    steps = np.concatenate([np.diag(space.scale), -np.diag(space.scale)])
    poll = space.x0 + 0.05 * steps
    return poll[space.feasible(poll)]


@pytest.mark.parametrize("data", DATA)
def test_objective_poll_batched(benchmark, fis, data):
    X, y, _ = DATA[data]
    space = TermSpace(fis)
    objective, poll = Objective(space, X, y), _poll(space)
    expected = [_rmse(space.to_system(p), X, y) for p in poll[:3]]
    np.testing.assert_allclose(objective(poll[:3]), expected, rtol=1e-12)
    benchmark.extra_info["candidates"] = len(poll)
    benchmark(objective, poll)


@pytest.mark.parametrize("data", DATA)
def test_objective_poll_from_base(benchmark, fis, data):
    X, y, _ = DATA[data]
    space = TermSpace(fis)
    objective, poll = Objective(space, X, y), _poll(space)
    np.testing.assert_array_equal(objective(poll, base=space.x0), objective(poll))
    benchmark.extra_info["candidates"] = len(poll)
    benchmark(objective, poll, base=space.x0)


@pytest.mark.parametrize("data", DATA)
def test_objective_poll_naive(benchmark, fis, data):
    X, y, _ = DATA[data]
    space = TermSpace(fis)
    poll = _poll(space)
    benchmark.extra_info["candidates"] = len(poll)
    benchmark.pedantic(lambda: [_rmse(space.to_system(p), X, y) for p in poll], rounds=3, iterations=1)


# --------------------------------------------------------------------------- rule learning
@pytest.mark.parametrize("data", DATA)
def test_particle_swarm_paper_budget(benchmark, fis, data):
    X, y, _ = DATA[data]
    tuner = _timed(benchmark, lambda: ParticleSwarm(fis, seed=0).fit(X, y))  # swarm 100, 20 iterations
    assert tuner.result_.nfev == 100 * 21 + 2
    assert tuner.result_.fun <= tuner.result_.initial_fun
    assert tuner.result_.fun == pytest.approx(_rmse(tuner.system_, X, y), rel=1e-12)
    benchmark.extra_info["rmse"] = [round(tuner.result_.initial_fun, 5), round(tuner.result_.fun, 5)]


def test_particle_swarm_direct_200_candidates(benchmark, fis):
    """The swarm's candidates scored without the rule tables: 200 of its 2,100."""
    X, y, _ = DATA["typical"]
    space = RuleSpace(fis)
    P = np.random.default_rng(0).integers(1, 4, (200, space.n_params)).astype(float)
    direct, tables = Objective(space, X, y), Objective(space, X, y, expected_evaluations=2100)
    np.testing.assert_allclose(direct(P), tables(P), rtol=1e-12)
    _timed(benchmark, lambda: direct(P))


# --------------------------------------------------------------------------- pattern search
@pytest.mark.parametrize("data", DATA)
def test_pattern_search_paper_settings(benchmark, fis, data):
    X, y, scenes = DATA[data]
    tuner = _timed(benchmark, lambda: PatternSearch(fis, n_folds=5, max_iter=1000, seed=0).fit(X, y, scenes))
    result = tuner.result_
    assert result.fun < result.initial_fun
    assert result.fun == pytest.approx(_rmse(tuner.system_, X, y), rel=1e-12)
    benchmark.extra_info.update(nit=result.nit, fold_nit=result.fold_nit, nfev=result.nfev,
                                rmse=[round(result.initial_fun, 5), round(result.fun, 5)],
                                message=result.message)
