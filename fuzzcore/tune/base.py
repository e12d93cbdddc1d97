"""What every tuner shares: scikit-learn habits, the fit loop over folds, callbacks, results.

A tuner's ``__init__`` stores its arguments and nothing else; :meth:`Tuner.fit` checks
them, checks the data, draws everything random from one ``numpy.random.Generator`` made
from ``seed``, runs the search (over cross-validation folds when ``n_folds > 1``, see
:mod:`fuzzcore.tune.kfold`) and sets the learned attributes, which end in ``_``:

``system_``
    The tuned :class:`~fuzzcore.FuzzySystem`; its ``metadata["tuning"]`` says how it was
    made (method, settings, seed, data size, scores) and is saved with it.
``result_``
    A :class:`scipy.optimize.OptimizeResult`: ``x`` (the tuned parameter values, in the
    system's units), ``fun`` (the metric on all the data given to ``fit``), ``nit``,
    ``nfev`` (candidate systems scored, on any part of the data), ``success``,
    ``status`` (:data:`STATUS`), ``message``, ``initial_fun``, ``cv_scores`` (the
    validation metric of each fold's chosen point; empty without folds), ``cv_score``
    (their mean, NaN without folds), ``fold_nit``, ``names`` (one per parameter).

With ``require_firing`` (the default), a candidate that leaves some training sample with
no rule firing is never chosen (:class:`~fuzzcore.tune.objective.Objective`): otherwise
a search can win by moving every term away from awkward data and letting the
``no_rule_fired`` fallback (a constant) answer there, which leaves a rule base that no
longer says anything about those inputs.

``callback(intermediate_result)`` is called after every iteration with an
``OptimizeResult`` holding ``x``, ``fun`` (the best training metric so far), ``nit``,
``nfev``, ``fold`` (1-based; 0 without folds) and ``method``; raising ``StopIteration``
in it ends the run cleanly with the best point so far (scipy's convention).
"""
from __future__ import annotations

import dataclasses
import inspect
import math
import numbers

import numpy as np
from scipy.optimize import OptimizeResult

from ..system import FuzzySystem
from .data import check_data
from .kfold import EarlyStopping, fold_labels
from .objective import METRICS, Objective

#: ``result_.status`` codes
CONVERGED, MAX_ITER, CALLBACK_STOP = 0, 1, 2
STATUS = {CONVERGED: "converged", MAX_ITER: "iteration budget used up", CALLBACK_STOP: "stopped by the callback"}


def check_number(name: str, value, low: float | None = None, high: float | None = None,
                 integer: bool = False, low_open: bool = False) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``value`` is a (finite) number in the bounds."""
    kind = numbers.Integral if integer else numbers.Real
    if isinstance(value, bool) or not isinstance(value, kind) or not math.isfinite(value):
        raise ValueError(f"{name} = {value!r}: expected a finite {'integer' if integer else 'number'}")
    if low is not None and (value <= low if low_open else value < low):
        raise ValueError(f"{name} = {value!r}, must be {'>' if low_open else '>='} {low}")
    if high is not None and value > high:
        raise ValueError(f"{name} = {value!r}, must be <= {high}")


def plain(value):
    """``value`` with numpy scalars and arrays turned into Python numbers and lists (for YAML)."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def stalled(history: list[float], stall_iter: int, f_tol: float) -> bool:
    """The stall test: the best value improved by at most ``f_tol * max(1, |f|)`` over the
    last ``stall_iter`` iterations (``history``: best value after each iteration, start first)."""
    return len(history) > stall_iter and history[-1 - stall_iter] - history[-1] <= f_tol * max(1.0, abs(history[-1]))


def stop_reason(test: str, tuner, iterations: int) -> str:
    """Why a search ended, in words (``test``: "stall" or "validation")."""
    if test == "stall":
        return (f"relative improvement over the last {tuner.stall_iter} iterations below f_tol = {tuner.f_tol:g} "
                f"after {iterations} iterations")
    return (f"validation cost rose more than {tuner.validation_tol:g} above its recent minimum after "
            f"{iterations} iterations")


class Reporter:
    """Counts iterations across folds and forwards them to the user's callback."""

    def __init__(self, method: str, callback, objectives: list):
        self.method = method
        self.callback = callback
        self.objectives = objectives  # every Objective made, for nfev
        self.nit = 0
        self.fold = 0
        self.stopped = False

    @property
    def nfev(self) -> int:
        return sum(o.nfev for o in self.objectives)

    def iteration(self, x: np.ndarray, fun: float, **extra) -> bool:
        """Count one iteration; return True when the callback asked to stop."""
        self.nit += 1
        if self.callback is not None:
            info = OptimizeResult(x=x.copy(), fun=float(fun), nit=self.nit, nfev=self.nfev, fold=self.fold,
                                  method=self.method, **extra)
            try:
                self.callback(info)
            except StopIteration:
                self.stopped = True
        return self.stopped


class Tuner:
    """Base class of the tuners (see the module docstring). Subclasses define:

    ``method`` (str), ``_space(system)`` -> TermSpace/RuleSpace, ``_check_params()``,
    ``_expected_evaluations()`` (per objective, or None) and
    ``_search(objective, x0, rng, stopping, reporter) -> (x, status, reason)``: minimise
    ``objective`` from ``x0``; after each iteration call ``reporter.iteration`` and stop
    if it returns True (status :data:`CALLBACK_STOP`); with ``stopping`` (an
    :class:`~fuzzcore.tune.kfold.EarlyStopping`), call ``stopping.update(x)`` whenever
    the incumbent moves and stop (:data:`CONVERGED`) when it returns True. ``reason``
    says in words why the search ended.
    """

    method = ""

    def get_params(self) -> dict:
        """The constructor arguments (scikit-learn's ``get_params``, not deep)."""
        names = [p for p in inspect.signature(type(self).__init__).parameters if p != "self"]
        return {name: getattr(self, name) for name in names}

    def _check_common(self) -> None:
        if not isinstance(self.system, FuzzySystem):
            raise TypeError(f"system: expected a fuzzcore.FuzzySystem, got {type(self.system).__name__}")
        if self.metric not in METRICS:
            raise ValueError(f"metric = {self.metric!r}: expected one of {', '.join(METRICS)}")
        if self.seed is not None and not isinstance(self.seed, (numbers.Integral, np.random.SeedSequence)):
            raise ValueError(f"seed = {self.seed!r}: expected None, an integer or a numpy SeedSequence")
        if self.callback is not None and not callable(self.callback):
            raise TypeError(f"callback = {self.callback!r}: expected a callable or None")
        if not isinstance(getattr(self, "require_firing", False), bool):
            raise ValueError(f"require_firing = {self.require_firing!r}: expected True or False")

    def fit(self, X, y, groups=None):
        """Tune on ``X`` (n_samples, n_inputs) and ``y`` (n_samples,) or (n_samples, n_outputs).

        ``groups`` (n_samples,) labels samples that folds must keep together (scenes).
        Returns ``self``.
        """
        self._check_common()
        check_number("n_folds", self.n_folds, 1, integer=True)
        if self.n_folds > 1:
            check_number("validation_tol", self.validation_tol, 0.0)
            check_number("validation_window", self.validation_window, 1, integer=True)
        self._check_params()
        X, Y, groups = check_data(self.system, X, y, groups)
        rng = np.random.default_rng(self.seed)
        space = self._space(self.system)
        expected = self._expected_evaluations()
        # with folds, the whole data set only scores the start and the result
        firing = self.require_firing
        full = Objective(space, X, Y, self.metric, expected_evaluations=expected if self.n_folds == 1 else None,
                         require_firing=firing)
        reporter = Reporter(self.method, self.callback, [full])
        x = space.x0.copy()
        initial_fun = float(full(x[None])[0])
        if not math.isfinite(initial_fun):
            raise ValueError(f"the starting system {self.system.name!r} cannot be scored on the data: for some "
                             "sample no rule fires" + (" (require_firing is set)" if firing else
                                                       " and no_rule_fired is 'nan'")
                             + "; start from a system whose rules cover the data")
        cv_scores, fold_nit, statuses, reasons = [], [], [], []
        if self.n_folds == 1:
            x, status, reason = self._search(full, x, rng, None, reporter)
            statuses.append(status)
            reasons.append(reason)
            fold_nit.append(reporter.nit)
        else:
            labels = fold_labels(X.shape[0], self.n_folds, rng, groups)
            for fold in range(self.n_folds):
                reporter.fold = fold + 1
                held = labels == fold
                train = Objective(space, X[~held], Y[~held], self.metric, expected_evaluations=expected,
                                  require_firing=firing)
                stopping = EarlyStopping(Objective(space, X[held], Y[held], self.metric, require_firing=firing),
                                         self.validation_tol, self.validation_window)
                reporter.objectives += [train, stopping.objective]
                stopping.update(x)
                start = reporter.nit
                _, status, reason = self._search(train, x, rng, stopping, reporter)
                x = stopping.best_x
                cv_scores.append(stopping.best_value)
                fold_nit.append(reporter.nit - start)
                statuses.append(status)
                reasons.append(f"fold {fold + 1}: {reason}")
                if status == CALLBACK_STOP:
                    break
        status = max(statuses)  # CALLBACK_STOP > MAX_ITER > CONVERGED
        fun = float(full(x[None])[0])
        message = f"{STATUS[status]}: {'; '.join(reasons)}"
        self.result_ = OptimizeResult(
            x=x.copy(), fun=fun, nit=reporter.nit, nfev=reporter.nfev, success=status == CONVERGED,
            status=status, message=message, initial_fun=initial_fun, cv_scores=np.array(cv_scores),
            cv_score=float(np.mean(cv_scores)) if cv_scores else math.nan, fold_nit=fold_nit,
            names=space.names, metric=self.metric, n_samples=X.shape[0],
            n_groups=None if groups is None else int(np.unique(groups).shape[0]),
        )
        self.system_ = self._provenance(space.to_system(x), self.result_)
        return self

    def _settings(self) -> dict:
        return {k: v for k, v in self.get_params().items() if k not in ("system", "callback", "seed")}

    def _label(self) -> str:
        """How the description names this run: the method and its seed."""
        return f"{self.method} (seed {self.seed})"

    def _provenance(self, system, result: OptimizeResult, **extra):
        """``system`` with a description and ``metadata["tuning"]`` saying how it was made."""
        tuning = {
            "method": self.method,
            "started_from": self.system.name,
            "seed": self.seed if self.seed is None or isinstance(self.seed, numbers.Integral) else str(self.seed),
            "settings": self._settings(),
            "data": {"n_samples": result.n_samples, "n_groups": result.n_groups},
            "metric": result.metric,
            "score": {"initial": result.initial_fun, "final": result.fun, "cv_folds": result.cv_scores,
                      "cv_mean": None if math.isnan(result.cv_score) else result.cv_score},
            "nit": result.nit, "nfev": result.nfev, "message": result.message, **extra,
        }
        description = (f"{self.system.description + '; ' if self.system.description else ''}"
                       f"{self._label()} on {result.n_samples} samples: "
                       f"{result.metric} {result.initial_fun:.4g} -> {result.fun:.4g}")
        metadata = {**system.metadata, "tuning": plain(tuning)}
        return dataclasses.replace(system, description=description, metadata=metadata)
