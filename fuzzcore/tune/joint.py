"""Joint tuning of terms and rules (the paper's future work): block coordinate descent.

Membership functions and rule consequents are two blocks of one problem with one
objective (the metric on the training data). :class:`JointTuner` minimises it block by
block, each block with the tuner made for it
(:class:`~fuzzcore.tune.patternsearch.PatternSearch` for the terms,
:class:`~fuzzcore.tune.particleswarm.ParticleSwarm` for the rules), in two chains:

- chain 1 starts with the terms, chain 2 with the rules; each chain's first step runs
  from the starting system with the joint tuner's own seed, i.e. it *is* that
  single-block tuner run alone;
- a chain then alternates blocks, each step starting from the chain's current system
  (seeds drawn from the joint seed); a step's result is kept only if it lowers the
  objective by more than ``tol * max(1, f)``;
- a chain ends when two steps in a row (one per block) fail to improve it, a block
  coordinate minimum as far as the block tuners can tell, or after ``max_steps`` steps.

The better chain end is the result. Kept steps only lower the objective, and the chains
start with the single-block tuners, so the result is never worse on the training data
than either tuner alone with the same seed and options. Two orders because they end in
different places: the rule step searches globally and can leave the terms' local
minimum, the term step refines locally around whatever rules it gets.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.optimize import OptimizeResult

from .base import CALLBACK_STOP, CONVERGED, MAX_ITER, STATUS, Tuner, check_number
from .data import check_data
from .particleswarm import ParticleSwarm
from .patternsearch import PatternSearch
from .rule_space import RuleSpace
from .term_space import TermSpace

#: block name -> tuner class
BLOCKS = {"terms": PatternSearch, "rules": ParticleSwarm}
#: options the joint tuner sets itself on every block tuner
_OWN = ("system", "metric", "seed", "callback")


class JointTuner(Tuner):
    """Tune membership functions and rule consequents together (module docstring).

    Parameters
    ----------
    system : FuzzySystem
    pattern_search : dict, optional
        Keyword options of :class:`~fuzzcore.tune.patternsearch.PatternSearch` for the
        terms block (not ``system``, ``metric``, ``seed``, ``callback``).
    particle_swarm : dict, optional
        Keyword options of :class:`~fuzzcore.tune.particleswarm.ParticleSwarm` for the
        rules block.
    max_steps : int >= 1
        Block steps per chain at most.
    tol : float >= 0
        Smallest relative improvement that keeps a step.
    metric : {"rmse", "mae"}
    seed : int or None
        The first step of each chain runs with it (as the single tuner would); later
        steps get seeds drawn from a Generator made from it.
    callback : callable, optional
        Passed to every block tuner (its ``nit`` counts that step's iterations);
        ``intermediate_result`` also has ``chain`` (1 or 2), ``step`` (1-based over the
        whole run) and ``block`` (``"terms"``/``"rules"``). ``StopIteration`` ends the
        joint run, with the best system so far.

    Attributes
    ----------
    system_ : FuzzySystem
    result_ : OptimizeResult
        ``x`` = the final term parameters then consequents (``names`` says which);
        ``steps``: one record per block step (chain, block, seed, fun, kept); ``chain``:
        the chain whose end is the result.
    """

    method = "joint"

    def __init__(self, system, *, pattern_search=None, particle_swarm=None, max_steps=6, tol=1e-6,
                 metric="rmse", seed=None, callback=None):
        self.system = system
        self.pattern_search = pattern_search
        self.particle_swarm = particle_swarm
        self.max_steps = max_steps
        self.tol = tol
        self.metric = metric
        self.seed = seed
        self.callback = callback

    def _options(self) -> dict:
        options = {"terms": self.pattern_search, "rules": self.particle_swarm}
        for block, given in options.items():
            given = {} if given is None else given
            if not isinstance(given, dict):
                raise ValueError(f"{'pattern_search' if block == 'terms' else 'particle_swarm'} = {given!r}: "
                                 "expected a dict of keyword options or None")
            clash = sorted(set(given) & set(_OWN))
            if clash:
                raise ValueError(f"options for the {block} block may not set {', '.join(clash)}: the joint tuner "
                                 "sets them")
            options[block] = given
        return options

    def fit(self, X, y, groups=None):
        """Tune on ``X``, ``y`` (and ``groups``, used by the blocks' cross-validation); returns ``self``."""
        self._check_common()
        check_number("max_steps", self.max_steps, 1, integer=True)
        check_number("tol", self.tol, 0.0)
        options = self._options()
        X, Y, groups = check_data(self.system, X, y, groups)
        rng = np.random.default_rng(self.seed)
        steps, counts = [], {"nit": 0, "nfev": 0}

        def run(block, system, seed, chain):
            """One block step: tune ``block`` of ``system``; record it; return the tuner."""
            def forward(info):
                info.chain, info.step, info.block = chain, len(steps) + 1, block
                self.callback(info)

            tuner = BLOCKS[block](system, metric=self.metric, seed=seed,
                                  callback=None if self.callback is None else forward, **options[block])
            tuner.fit(X, Y, groups)
            counts["nit"] += tuner.result_.nit
            counts["nfev"] += tuner.result_.nfev
            return tuner

        ends = []  # (fun, system, status) at the end of each chain
        for chain, first in enumerate(("terms", "rules"), start=1):
            current, fun, block, seed = self.system, None, first, self.seed
            failures, status = 0, MAX_ITER
            for _ in range(self.max_steps):
                tuner = run(block, current, seed, chain)
                if fun is None:  # the starting system's score
                    fun = initial_fun = tuner.result_.initial_fun
                kept = bool(tuner.result_.fun < fun - self.tol * max(1.0, abs(fun)))
                steps.append({"chain": chain, "block": block, "seed": seed, "fun": tuner.result_.fun,
                              "kept": kept})
                if kept:
                    current, fun, failures = tuner.system_, tuner.result_.fun, 0
                else:
                    failures += 1
                if tuner.result_.status == CALLBACK_STOP:
                    status = CALLBACK_STOP
                    break
                if failures == 2:
                    status = CONVERGED
                    break
                block = "rules" if block == "terms" else "terms"
                seed = int(rng.integers(2**32))
            ends.append((fun, current, status))
            if status == CALLBACK_STOP:
                break
        best = min(range(len(ends)), key=lambda c: ends[c][0])  # chain 1 on a tie
        fun, current, _ = ends[best]
        status = max(end[2] for end in ends)  # CALLBACK_STOP > MAX_ITER > CONVERGED
        reason = {CONVERGED: f"in both chains neither block improves the other's result; chain {best + 1} kept",
                  MAX_ITER: f"max_steps = {self.max_steps} block steps in a chain; chain {best + 1} kept",
                  CALLBACK_STOP: f"during step {len(steps)}"}[status]
        terms, rules = TermSpace(current), RuleSpace(current)
        groups_n = None if groups is None else int(np.unique(groups).shape[0])
        self.result_ = OptimizeResult(
            x=np.concatenate([terms.x0, rules.x0]), fun=fun, nit=counts["nit"], nfev=counts["nfev"],
            success=status == CONVERGED, status=status, message=f"{STATUS[status]}: {reason}",
            initial_fun=initial_fun, cv_scores=np.empty(0), cv_score=math.nan, fold_nit=[],
            names=terms.names + rules.names, metric=self.metric, n_samples=X.shape[0], n_groups=groups_n,
            steps=steps, chain=best + 1,
        )
        system = dataclasses.replace(current, metadata={k: v for k, v in current.metadata.items() if k != "tuning"})
        self.system_ = self._provenance(system, self.result_, steps=steps, chain=best + 1)
        return self
