"""Membership-function tuning by generalised pattern search (the paper's tuned variant).

The algorithm is MATLAB's ``patternsearch`` as ``tunefis`` runs it (classic GPS):

- the pattern is the maximal positive basis ``[e_1 .. e_N, -e_1 .. -e_N]``
  (``GPSPositiveBasis2N``); a poll tries ``x + mesh * scale_k * (+-e_k)`` in that order,
  where ``scale_k`` converts the mesh into the parameter's units (its variable's range
  for a vertex: :mod:`fuzzcore.tune.term_space`);
- the poll is opportunistic (MATLAB's default): the first poll point in that order that
  lowers the objective is taken; with ``complete_poll=True`` every point is scored and
  the best taken;
- after a successful poll the mesh doubles (``MeshExpansionFactor`` 2), after an
  unsuccessful one it halves (``MeshContractionFactor`` 0.5);
- constraints (ordered vertices, points inside the range, positive widths) are an
  extreme barrier: an invalid poll point is skipped without being scored;
- a poll point differs from the incumbent in one parameter, so it is scored with the
  incumbent as base (:class:`~fuzzcore.tune.objective.Objective`): only the samples that
  parameter can affect are re-evaluated, with the same result as a full evaluation.

The search stops when the mesh falls below ``mesh_tol`` (MATLAB's ``MeshTolerance``),
when the objective improved by at most ``f_tol`` relative (``f_old - f <= f_tol *
max(1, |f|)``) over the last ``stall_iter`` iterations (the stall test of MATLAB's
``particleswarm``), after ``max_iter`` iterations (per fold), or early on the
validation fold (:mod:`fuzzcore.tune.kfold`). The stall test is there so a run does not
spend thousands of polls refining a mesh that no longer pays. On feature tables of the
synthetic benchmark (two benchmark seeds, 2,200-2,300 frames), ``f_tol = 1e-5`` (the
default) needed 2x and 7x fewer evaluations than ``1e-6``; the tuned system was the same
on one table and 0.25 % worse in held-out RMSE on the other (each fold's best point on
its validation fold tends to come long before the training objective stalls).
"""
from __future__ import annotations

import numpy as np

from .base import CALLBACK_STOP, CONVERGED, MAX_ITER, Tuner, check_number, stalled, stop_reason
from .term_space import TermSpace

EXPANSION, CONTRACTION = 2.0, 0.5


class PatternSearch(Tuner):
    """Tune membership functions by pattern search, with k-fold cross-validation.

    Parameters
    ----------
    system : FuzzySystem
        The starting system; its rules are kept.
    variables : sequence of str, optional
        Variables whose terms are tuned (default: every input and output).
    keep_order : bool
        Keep each variable's terms in their starting order, so "low" stays left of
        "medium" (:mod:`fuzzcore.tune.term_space`).
    partition : bool
        Keep each variable's piecewise-linear terms a readable partition of its range:
        ordered, covering it, bounded overlap and width
        (:mod:`fuzzcore.tune.term_space`). On by default: without it a search fits the data
        with terms that read as nonsense and leave parts of the input box where no rule fires.
    require_firing : bool
        Never choose a candidate under which some training sample fires no rule
        (:mod:`fuzzcore.tune.base`).
    metric : {"rmse", "mae"}
    n_folds : int
        Cross-validation folds (1: tune on all the data, no validation). Paper: 5.
    max_iter : int
        Iterations per fold. Paper: 1000.
    initial_mesh : float
        Starting mesh size, in units of ``scale`` (1 = a whole variable range).
    mesh_tol, f_tol : float
        Stop tests (module docstring).
    stall_iter : int
        Window of the ``f_tol`` test, in iterations.
    complete_poll : bool
        Score every poll point and take the best (default: the first improving one).
    validation_tol : float
        Largest relative rise of the validation cost before a fold stops (MATLAB's
        ``ValidationTolerance``).
    validation_window : int
        Previous validation costs the rise is measured against (``ValidationWindowSize``).
    seed : int, SeedSequence or None
        Seeds the fold assignment (the search itself is deterministic).
    callback : callable, optional
        ``callback(intermediate_result)``; raise ``StopIteration`` to stop
        (:mod:`fuzzcore.tune.base`). ``intermediate_result.mesh`` is the mesh size.

    Attributes
    ----------
    system_ : FuzzySystem
    result_ : OptimizeResult
        See :mod:`fuzzcore.tune.base`; ``x`` is the tuned parameter vector, in the order
        of :class:`~fuzzcore.tune.term_space.TermSpace` (``result_.names``).

    Examples
    --------
    >>> tuner = PatternSearch(fis, n_folds=5, seed=0).fit(X, y, groups=scenes)
    >>> tuner.system_.save("tuned.yaml")
    """

    method = "patternsearch"

    def __init__(self, system, *, variables=None, keep_order=True, partition=True, require_firing=True,
                 metric="rmse", n_folds=5, max_iter=1000, initial_mesh=1.0, mesh_tol=1e-6, f_tol=1e-5, stall_iter=20,
                 complete_poll=False, validation_tol=0.1, validation_window=5, seed=None, callback=None):
        self.system = system
        self.variables = variables
        self.keep_order = keep_order
        self.partition = partition
        self.require_firing = require_firing
        self.metric = metric
        self.n_folds = n_folds
        self.max_iter = max_iter
        self.initial_mesh = initial_mesh
        self.mesh_tol = mesh_tol
        self.f_tol = f_tol
        self.stall_iter = stall_iter
        self.complete_poll = complete_poll
        self.validation_tol = validation_tol
        self.validation_window = validation_window
        self.seed = seed
        self.callback = callback

    def _check_params(self) -> None:
        check_number("max_iter", self.max_iter, 1, integer=True)
        check_number("initial_mesh", self.initial_mesh, 0.0, low_open=True)
        check_number("mesh_tol", self.mesh_tol, 0.0, low_open=True)
        check_number("f_tol", self.f_tol, 0.0)
        check_number("stall_iter", self.stall_iter, 1, integer=True)
        for name in ("complete_poll", "keep_order", "partition"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} = {getattr(self, name)!r}: expected True or False")

    def _space(self, system) -> TermSpace:
        return TermSpace(system, self.variables, self.keep_order, self.partition)

    def _expected_evaluations(self):
        return None

    def _search(self, objective, x0, rng, stopping, reporter):
        space = objective.space
        x = x0.copy()
        f = float(objective(x[None])[0])
        steps = np.concatenate([np.diag(space.scale), -np.diag(space.scale)])  # (2N, N), poll order
        mesh = float(self.initial_mesh)
        history = [f]
        for it in range(self.max_iter):
            poll = x + mesh * steps
            valid = np.flatnonzero(space.feasible(poll))
            moved = False
            if self.complete_poll:
                if valid.size:
                    values = objective(poll[valid], base=x)
                    best = int(np.argmin(values))
                    if values[best] < f:
                        x, f, moved = poll[valid[best]].copy(), float(values[best]), True
            else:
                for k in valid:
                    value = float(objective(poll[k][None], base=x)[0])
                    if value < f:
                        x, f, moved = poll[k].copy(), value, True
                        break
            mesh *= EXPANSION if moved else CONTRACTION
            history.append(f)
            if reporter.iteration(x, f, mesh=mesh):
                return x, CALLBACK_STOP, f"after {it + 1} iterations"
            if moved and stopping is not None and stopping.update(x):
                return x, CONVERGED, stop_reason("validation", self, it + 1)
            if mesh < self.mesh_tol:
                return x, CONVERGED, f"mesh size {mesh:.3g} below mesh_tol after {it + 1} iterations"
            if stalled(history, self.stall_iter, self.f_tol):
                return x, CONVERGED, stop_reason("stall", self, it + 1)
        return x, MAX_ITER, f"max_iter = {self.max_iter} iterations"
