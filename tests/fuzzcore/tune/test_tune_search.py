"""fuzzcore.tune tuners: recovery of known systems, seeds, callbacks, joint tuning, provenance."""
import numpy as np
import pytest

import fuzzcore
from fuzzcore.tune import JointTuner, ParticleSwarm, PatternSearch, RuleSpace, TermSpace
from fuzzcore.tune.base import CALLBACK_STOP, CONVERGED, MAX_ITER
from fuzzcore.tune.rule_tables import firing_strengths

RULES = "rules/fuzzrisk.yaml"


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load(RULES)


@pytest.fixture(scope="module")
def truth_data(fis):
    """Inputs over the whole input space and the known system's exact outputs."""
    rng = np.random.default_rng(0)
    X = np.column_stack([rng.uniform(0, 1, 600), rng.uniform(-1, 1, 600)])
    return X, fis.evaluate(X)[:, 0]


@pytest.fixture(scope="module")
def noisy_data(fis):
    """A target the rule base cannot match exactly, with 12 scenes of 40 frames."""
    rng = np.random.default_rng(1)
    X = np.column_stack([rng.beta(2, 2, 480), np.clip(rng.normal(0.1, 0.4, 480), -1, 1)])
    y = np.clip(0.6 * np.clip(X[:, 1], 0, 1) + 0.3 * (1 - X[:, 0]) + rng.normal(0, 0.05, 480), 0, 1)
    return X, y, np.repeat([f"scene-{k}" for k in range(12)], 40)


def _perturbed(fis, variables, moves):
    space = TermSpace(fis, variables)
    p = space.x0.copy()
    for name, delta in moves.items():
        p[space.names.index(name)] += delta
    return space, space.to_system(p)


# --------------------------------------------------------------------------- recovery
@pytest.mark.parametrize("variables, moves", [
    (["rdd"], {"rdd.low[2]": 0.08, "rdd.medium[1]": 0.08, "rdd.high[1]": -0.06, "rdd.medium[0]": -0.05}),
    (["iou", "risk"], {"iou.medium[1]": -0.06, "iou.high[0]": 0.05, "risk.medium[1]": 0.05}),
])
def test_pattern_search_recovers_perturbed_terms(fis, truth_data, variables, moves):
    X, y = truth_data
    space, start = _perturbed(fis, variables, moves)
    tuner = PatternSearch(start, variables=variables, partition=False, n_folds=1, max_iter=300, seed=0).fit(X, y)
    assert tuner.result_.initial_fun > 0.005
    assert tuner.result_.fun < 1e-4
    np.testing.assert_allclose(tuner.result_.x, space.x0, atol=0.01)
    assert tuner.result_.names == space.names
    # result_.x is what system_ holds, and fun is system_'s RMSE on the data
    np.testing.assert_array_equal(TermSpace(tuner.system_, variables).x0, tuner.result_.x)
    assert tuner.result_.fun == pytest.approx(np.sqrt(np.mean((tuner.system_.evaluate(X)[:, 0] - y) ** 2)),
                                              rel=1e-12)
    assert tuner.system_.rules == fis.rules


def test_particle_swarm_recovers_scrambled_consequents_exactly(fis, truth_data):
    X, y = truth_data
    space = RuleSpace(fis)
    scrambled = space.x0.copy()
    scrambled[[0, 3, 4, 8]] = [1, 3, 2, 3]
    tuner = ParticleSwarm(space.to_system(scrambled), swarm_size=30, max_iter=15, seed=0).fit(X, y)
    np.testing.assert_array_equal(tuner.result_.x, space.x0)
    assert tuner.result_.fun == 0.0
    assert tuner.system_.rules == fis.rules
    assert tuner.result_.nfev == 30 * 16 + 2  # the swarm, and the start and result scored on all data


def test_particle_swarm_can_switch_rules_off(fis, truth_data):
    X, _ = truth_data
    # the truth: the paper's system without its rule 5 (medium rdd, medium iou -> low)
    truth = RuleSpace(fis, allow_off=True)
    off = truth.x0.copy()
    off[4] = 0
    y = truth.to_system(off).evaluate(X)[:, 0]
    # 4^9 candidate rule bases; a stochastic search, deterministic for a given seed
    tuner = ParticleSwarm(fis, allow_off=True, swarm_size=40, max_iter=20, seed=0).fit(X, y)
    assert tuner.result_.fun == 0.0
    np.testing.assert_array_equal(tuner.result_.x, off)
    assert len(tuner.system_.rules) == 8


def test_tuners_keep_every_training_sample_firing(fis):
    """Targets that a system with no terms near the data, answering with the fallback (0.5),
    would fit best: the tuners may not get there."""
    rng = np.random.default_rng(3)
    X = np.column_stack([rng.uniform(0, 1, 300), rng.uniform(-1, 1, 300)])
    y = np.where(X[:, 1] < 0.4, 0.5, 0.9)
    strict = PatternSearch(fis, n_folds=1, max_iter=150, seed=0).fit(X, y)
    rules = ParticleSwarm(fis, allow_off=True, seed=0).fit(X, y)
    for tuner in (strict, rules):
        assert firing_strengths(tuner.system_, X).max(axis=1).min() > 0
    loose = PatternSearch(fis, n_folds=1, max_iter=150, seed=0, require_firing=False, partition=False).fit(X, y)
    assert firing_strengths(loose.system_, X).max(axis=1).min() == 0  # it did hand samples to the fallback
    # the partition constraints alone keep every point of the box firing too
    covering = PatternSearch(fis, n_folds=1, max_iter=150, seed=0, require_firing=False).fit(X, y)
    assert firing_strengths(covering.system_, X).max(axis=1).min() > 0


def test_a_start_that_leaves_samples_unfired_is_refused(fis, truth_data):
    X, y = truth_data
    space = TermSpace(fis, ["iou"])
    gap = space.x0.copy()
    gap[:4] = [0.0, 0.05, 0.1, 0.15]
    with pytest.raises(ValueError, match="for some sample no rule fires .require_firing is set."):
        PatternSearch(space.to_system(gap), n_folds=1, max_iter=2, partition=False).fit(X, y)
    PatternSearch(space.to_system(gap), n_folds=1, max_iter=2, require_firing=False, partition=False).fit(X, y)
    with pytest.raises(ValueError, match="iou.low and iou.medium cross at 0.5 or above"):
        PatternSearch(space.to_system(gap), n_folds=1, max_iter=2, require_firing=False).fit(X, y)


# --------------------------------------------------------------------------- cross-validation
def test_pattern_search_with_folds_reports_cv_and_keeps_scenes_apart(fis, noisy_data):
    X, y, scenes = noisy_data
    tuner = PatternSearch(fis, variables=["rdd"], n_folds=3, max_iter=15, seed=2).fit(X, y, scenes)
    result = tuner.result_
    assert result.cv_scores.shape == (3,) and np.isfinite(result.cv_scores).all()
    assert result.cv_score == pytest.approx(result.cv_scores.mean())
    assert len(result.fold_nit) == 3 and sum(result.fold_nit) == result.nit
    assert result.fun < result.initial_fun
    assert result.message.count("fold") == 3


# --------------------------------------------------------------------------- seeds
@pytest.mark.parametrize("make", [
    lambda fis, seed: PatternSearch(fis, variables=["rdd"], n_folds=3, max_iter=10, seed=seed),
    lambda fis, seed: ParticleSwarm(fis, swarm_size=20, max_iter=5, n_folds=2, seed=seed),
])
def test_same_seed_same_result(fis, noisy_data, make):
    X, y, scenes = noisy_data
    a, b, c = (make(fis, s).fit(X, y, scenes) for s in (5, 5, 6))
    for key in ("x", "fun", "nit", "nfev", "cv_scores"):
        np.testing.assert_array_equal(a.result_[key], b.result_[key])
    assert a.system_ == b.system_
    assert not np.array_equal(a.result_.cv_scores, c.result_.cv_scores)  # other folds


def test_particle_swarm_seed_changes_the_swarm(fis, noisy_data):
    X, y, _ = noisy_data
    paths = []
    for seed in (0, 0, 1):
        funs = []
        ParticleSwarm(fis, swarm_size=10, max_iter=6, seed=seed,
                      callback=lambda info: funs.append((info.fun, info.inertia))).fit(X, y)
        paths.append(funs)
    assert paths[0] == paths[1] and paths[0] != paths[2]


# --------------------------------------------------------------------------- callbacks
@pytest.mark.parametrize("make", [
    lambda fis, cb: PatternSearch(fis, n_folds=2, max_iter=50, seed=0, callback=cb),
    lambda fis, cb: ParticleSwarm(fis, swarm_size=10, max_iter=20, seed=0, callback=cb),
    lambda fis, cb: JointTuner(fis, pattern_search={"n_folds": 1, "max_iter": 50},
                               particle_swarm={"swarm_size": 10, "max_iter": 5}, seed=0, callback=cb),
])
def test_callback_sees_iterations_and_stops_the_run(fis, noisy_data, make):
    X, y, scenes = noisy_data
    seen = []

    def callback(info):
        seen.append((info.nit, info.fun, info.x.copy()))
        if len(seen) == 3:
            raise StopIteration

    tuner = make(fis, callback).fit(X, y, scenes)
    assert len(seen) == 3
    assert tuner.result_.status == CALLBACK_STOP and not tuner.result_.success
    assert "stopped by the callback" in tuner.result_.message
    assert [s[0] for s in seen] == [1, 2, 3]
    assert tuner.result_.fun <= tuner.result_.initial_fun  # the best point so far, a valid system
    assert tuner.system_.evaluate(X).shape == (X.shape[0], 1)


def test_status_of_budget_and_convergence(fis, noisy_data):
    X, y, _ = noisy_data
    short = PatternSearch(fis, variables=["rdd"], n_folds=1, max_iter=3).fit(X, y)
    assert short.result_.status == MAX_ITER and not short.result_.success and short.result_.nit == 3
    loose = PatternSearch(fis, variables=["rdd"], n_folds=1, max_iter=500, mesh_tol=0.01).fit(X, y)
    assert loose.result_.status == CONVERGED and loose.result_.success
    assert loose.result_.nit < 500


# --------------------------------------------------------------------------- joint
def test_joint_is_at_least_as_good_as_each_alone(fis, noisy_data):
    X, y, scenes = noisy_data
    ps = {"n_folds": 1, "max_iter": 40}
    pso = {"swarm_size": 20, "max_iter": 8}
    terms = PatternSearch(fis, seed=3, **ps).fit(X, y, scenes)
    rules = ParticleSwarm(fis, seed=3, **pso).fit(X, y, scenes)
    joint = JointTuner(fis, pattern_search=ps, particle_swarm=pso, max_steps=4, seed=3).fit(X, y, scenes)
    steps = joint.result_.steps
    chains = {c: [s for s in steps if s["chain"] == c] for c in (1, 2)}
    # each chain starts with one block tuner alone, then alternates
    assert chains[1][0]["fun"] == terms.result_.fun and chains[2][0]["fun"] == rules.result_.fun
    for c, first in ((1, "terms"), (2, "rules")):
        blocks = [s["block"] for s in chains[c]]
        assert blocks[0] == first and all(a != b for a, b in zip(blocks, blocks[1:]))
        kept = [s["fun"] for s in chains[c] if s["kept"]]
        assert kept == sorted(kept, reverse=True)  # kept steps only improve
    assert joint.result_.fun <= min(terms.result_.fun, rules.result_.fun)
    assert joint.result_.fun == min(min(s["fun"] for s in ch if s["kept"]) for ch in chains.values())
    rmse = np.sqrt(np.mean((joint.system_.evaluate(X)[:, 0] - y) ** 2))
    assert joint.result_.fun == pytest.approx(rmse, rel=1e-12)
    assert len(joint.result_.x) == len(joint.result_.names) == 33 + 9


def test_joint_refuses_options_it_sets_itself(fis, noisy_data):
    X, y, _ = noisy_data
    with pytest.raises(ValueError, match="may not set seed"):
        JointTuner(fis, pattern_search={"seed": 1}).fit(X, y)
    with pytest.raises(ValueError, match="max_steps = 0, must be >= 1"):
        JointTuner(fis, max_steps=0).fit(X, y)


# --------------------------------------------------------------------------- provenance
def test_tuned_system_saves_how_it_was_made(fis, noisy_data, tmp_path):
    X, y, scenes = noisy_data
    tuner = PatternSearch(fis, variables=["rdd"], n_folds=2, max_iter=5, seed=11).fit(X, y, scenes)
    path = tmp_path / "tuned.yaml"
    tuner.system_.save(path)
    loaded = fuzzcore.load(path)
    assert loaded == tuner.system_
    tuning = loaded.metadata["tuning"]
    assert tuning["method"] == "patternsearch" and tuning["seed"] == 11
    assert tuning["settings"]["n_folds"] == 2 and tuning["settings"]["variables"] == ["rdd"]
    assert tuning["data"] == {"n_samples": 480, "n_groups": 12}
    assert tuning["score"]["final"] == tuner.result_.fun
    assert tuning["score"]["cv_folds"] == tuner.result_.cv_scores.tolist()
    assert "patternsearch (seed 11) on 480 samples" in loaded.description


# --------------------------------------------------------------------------- parameter checks
@pytest.mark.parametrize("make, words", [
    (lambda fis: PatternSearch(fis, max_iter=0), "max_iter = 0, must be >= 1"),
    (lambda fis: PatternSearch(fis, initial_mesh=-1.0), "initial_mesh = -1.0, must be > 0"),
    (lambda fis: PatternSearch(fis, n_folds=2.5), "n_folds = 2.5: expected a finite integer"),
    (lambda fis: PatternSearch(fis, metric="r2"), "metric = 'r2'"),
    (lambda fis: PatternSearch(fis, seed="x"), "seed = 'x'"),
    (lambda fis: ParticleSwarm(fis, swarm_size=2), "swarm_size = 2, must be >= 3"),
    (lambda fis: ParticleSwarm(fis, inertia_range=(1.0, 0.5)), "expected low <= high"),
    (lambda fis: ParticleSwarm(fis, min_neighbors_fraction=0.0), "min_neighbors_fraction = 0.0, must be > 0"),
    (lambda fis: ParticleSwarm(fis, n_folds=50), "n_folds = 50 but the data have only 12 groups"),
])
def test_bad_parameters_are_refused_at_fit(fis, noisy_data, make, words):
    X, y, scenes = noisy_data
    tuner = make(fis)  # __init__ only stores
    with pytest.raises(ValueError) as info:
        tuner.fit(X, y, scenes)
    assert words in str(info.value)


def test_init_stores_arguments_only(fis):
    tuner = PatternSearch(fis, max_iter=-5, variables=["nope"])
    assert tuner.get_params()["max_iter"] == -5 and tuner.variables == ["nope"]
    assert not hasattr(tuner, "system_") and not hasattr(tuner, "result_")
