"""Rule learning by global particle swarm optimisation (the paper's learned variant).

The swarm is MATLAB's ``particleswarm`` (Kennedy and Eberhart, with the adaptive
inertia and neighbourhood of its documentation), run on the rule consequents of a
:class:`~fuzzcore.tune.rule_space.RuleSpace`:

- positions are continuous, in ``[lower - 0.5, upper + 0.5]`` per slot, and a particle
  is scored at its rounded position (:meth:`RuleSpace.round`: nearest integer, each
  consequent owning a cell of width 1), so the swarm's dynamics stay MATLAB's while
  every scored candidate is a valid rule base;
- particle 1 starts at the starting system's consequents, the others uniformly in the
  bounds; velocities start uniform in ``[-range, range]``;
- each iteration, every particle draws ``neighbours`` other particles at random and is
  pulled towards its own best position and the best of theirs:
  ``v = W v + c1 u1 (p - x) + c2 u2 (g - x)``, ``x = x + v``, clamped to the bounds
  (the velocity component pushing out is zeroed);
- after an iteration that improved the global best, the stall counter ``c`` drops by
  one, the neighbourhood shrinks to its minimum, and the inertia doubles if ``c < 2``
  or halves if ``c > 5`` (kept within ``inertia_range``); otherwise ``c`` grows and the
  neighbourhood grows by its minimum size.

The paper's budget is the default: a swarm of 100 for 20 iterations (2,100 scored
candidates with the initial swarm). The search stops after ``max_iter`` iterations, or
when the best objective improved by less than ``f_tol`` relative over the last
``stall_iter`` iterations (MATLAB's ``MaxStallIterations``/``FunctionTolerance``).
Scoring uses the exact rule tables of :mod:`fuzzcore.tune.rule_tables` when they are
cheaper than the budget.
"""
from __future__ import annotations

import math

import numpy as np

from .base import CALLBACK_STOP, CONVERGED, MAX_ITER, Tuner, check_number, stalled, stop_reason
from .rule_space import RuleSpace

#: largest swarm: each iteration draws an S x S matrix of neighbour keys and partitions it
#: (16 S^2 bytes: 256 MiB at this size)
MAX_SWARM = 4096


class ParticleSwarm(Tuner):
    """Learn rule consequents by particle swarm optimisation.

    Parameters
    ----------
    system : FuzzySystem
        The starting system; its terms and antecedents are kept.
    rules : sequence of int, optional
        0-based indices of the rules whose consequents are learned (default all).
    allow_off : bool
        Whether a rule may be switched off (consequent 0, removed from the result).
    require_firing : bool
        Never choose a candidate under which some training sample fires no rule
        (:mod:`fuzzcore.tune.base`).
    metric : {"rmse", "mae"}
    swarm_size : int
        Particles (MATLAB's ``SwarmSize``), 3 .. :data:`MAX_SWARM`. Paper: 100.
    max_iter : int
        Iterations after the initial swarm. Paper: 20.
    inertia_range : (float, float)
        Bounds of the adaptive inertia ``W`` (MATLAB: (0.1, 1.1)); ``W`` starts at the upper.
    self_weight, social_weight : float
        ``c1``, ``c2`` (MATLAB: 1.49 each).
    min_neighbors_fraction : float in (0, 1]
        Smallest neighbourhood, as a fraction of the swarm (MATLAB: 0.25; at least 2).
    f_tol : float
    stall_iter : int
    n_folds, validation_tol, validation_window :
        Cross-validation, as in :class:`~fuzzcore.tune.patternsearch.PatternSearch`
        (default 1: no folds, as in the paper).
    seed : int, SeedSequence or None
    callback : callable, optional

    Attributes
    ----------
    system_ : FuzzySystem
    result_ : OptimizeResult
        ``x`` holds the learned consequents (1-based term indices, 0 = off), in the order
        of ``result_.names``.
    """

    method = "particleswarm"

    def __init__(self, system, *, rules=None, allow_off=False, require_firing=True, metric="rmse", swarm_size=100,
                 max_iter=20, inertia_range=(0.1, 1.1), self_weight=1.49, social_weight=1.49,
                 min_neighbors_fraction=0.25, f_tol=1e-6, stall_iter=20, n_folds=1, validation_tol=0.1,
                 validation_window=5, seed=None, callback=None):
        self.system = system
        self.rules = rules
        self.allow_off = allow_off
        self.require_firing = require_firing
        self.metric = metric
        self.swarm_size = swarm_size
        self.max_iter = max_iter
        self.inertia_range = inertia_range
        self.self_weight = self_weight
        self.social_weight = social_weight
        self.min_neighbors_fraction = min_neighbors_fraction
        self.f_tol = f_tol
        self.stall_iter = stall_iter
        self.n_folds = n_folds
        self.validation_tol = validation_tol
        self.validation_window = validation_window
        self.seed = seed
        self.callback = callback

    def _check_params(self) -> None:
        check_number("swarm_size", self.swarm_size, 3, integer=True)
        if self.swarm_size > MAX_SWARM:
            size = 16 * self.swarm_size**2 / 2**30
            raise ValueError(f"swarm_size = {self.swarm_size!r}, must be <= {MAX_SWARM}: each iteration draws an "
                             f"S x S matrix of neighbour choices, {size:,.3g} GiB for this swarm")
        check_number("max_iter", self.max_iter, 1, integer=True)
        if not (isinstance(self.inertia_range, (tuple, list)) and len(self.inertia_range) == 2):
            raise ValueError(f"inertia_range = {self.inertia_range!r}: expected (low, high)")
        for k, w in enumerate(self.inertia_range):
            check_number(f"inertia_range[{k}]", w, 0.0, low_open=True)
        if self.inertia_range[0] > self.inertia_range[1]:
            raise ValueError(f"inertia_range = {self.inertia_range!r}: expected low <= high")
        check_number("self_weight", self.self_weight, 0.0)
        check_number("social_weight", self.social_weight, 0.0)
        check_number("min_neighbors_fraction", self.min_neighbors_fraction, 0.0, 1.0, low_open=True)
        check_number("f_tol", self.f_tol, 0.0)
        check_number("stall_iter", self.stall_iter, 1, integer=True)
        if not isinstance(self.allow_off, bool):
            raise ValueError(f"allow_off = {self.allow_off!r}: expected True or False")

    def _space(self, system) -> RuleSpace:
        return RuleSpace(system, self.rules, self.allow_off)

    def _expected_evaluations(self):
        return self.swarm_size * (self.max_iter + 1)

    def _search(self, objective, x0, rng, stopping, reporter):
        space = objective.space
        S, N = self.swarm_size, space.n_params
        lb, ub = space.lower - 0.5, space.upper + 0.5
        X = rng.uniform(lb, ub, (S, N))
        X[0] = x0
        V = rng.uniform(-(ub - lb), ub - lb, (S, N))
        F = objective(space.round(X))
        P, PF = X.copy(), F.copy()
        k = int(np.argmin(PF))
        best_x, best_f = P[k].copy(), float(PF[k])
        min_nb = max(2, math.floor(S * self.min_neighbors_fraction))
        nb = min(min_nb, S - 1)
        w_lo, w_hi = self.inertia_range
        W, stall = float(w_hi), 0
        history = [best_f]
        for it in range(self.max_iter):
            keys = rng.random((S, S))
            np.fill_diagonal(keys, np.inf)  # a particle is not its own neighbour
            hood = np.argpartition(keys, nb - 1, axis=1)[:, :nb]
            G = P[hood[np.arange(S), np.argmin(PF[hood], axis=1)]]
            U1, U2 = rng.random((S, N)), rng.random((S, N))
            V = W * V + self.self_weight * U1 * (P - X) + self.social_weight * U2 * (G - X)
            X = X + V
            low, high = X < lb, X > ub
            X = np.clip(X, lb, ub)
            V[(low & (V < 0)) | (high & (V > 0))] = 0.0
            F = objective(space.round(X))
            better = F < PF
            P[better], PF[better] = X[better], F[better]
            k = int(np.argmin(F))
            improved = F[k] < best_f
            if improved:
                best_x, best_f = X[k].copy(), float(F[k])
                stall = max(0, stall - 1)
                nb = min(min_nb, S - 1)
                if stall < 2:
                    W *= 2.0
                if stall > 5:
                    W /= 2.0
                W = min(max(W, w_lo), w_hi)
            else:
                stall += 1
                nb = min(nb + min_nb, S - 1)
            history.append(best_f)
            x = space.round(best_x[None])[0]
            if reporter.iteration(x, best_f, inertia=W, neighbours=nb):
                return x, CALLBACK_STOP, f"after {it + 1} iterations"
            if improved and stopping is not None and stopping.update(x):
                return x, CONVERGED, stop_reason("validation", self, it + 1)
            if stalled(history, self.stall_iter, self.f_tol):
                return x, CONVERGED, stop_reason("stall", self, it + 1)
        return space.round(best_x[None])[0], MAX_ITER, f"max_iter = {self.max_iter} iterations"
