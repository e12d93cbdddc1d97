"""The tuning objective: RMSE or MAE of many candidate systems on a data set, in one call.

Candidates are rows of a parameter matrix of a :class:`~fuzzcore.tune.term_space.TermSpace`
or :class:`~fuzzcore.tune.rule_space.RuleSpace`; each row is written into a copy of the
packed system and evaluated by the engine's own kernel, in parallel
(:mod:`fuzzcore.tune._objective_kernels`). No Python object is built per candidate.

Two exact shortcuts give the same numbers with fewer inferences:

- **Distinct rows**: each distinct input row is evaluated once (feature tables repeat
  rows: every frame where nothing matched has IoU~ = 0, RDD~ = 1).
- **Base point** (``objective(P, base=x)``): a candidate that differs from ``x`` in a few
  parameters can change only some rows' predictions: those whose input falls where a
  moved membership function changed, or whose firing rules conclude a moved output term
  or a changed consequent (:meth:`TermSpace.changes`, :meth:`RuleSpace.changes`). Only
  those rows are re-evaluated; the others keep ``x``'s predictions, and the sum runs in
  the kernels' canonical order, so the value is bit for bit the full evaluation's.
  Pattern search polls (one parameter moved at a time) use it.
- **Rule tables** (rule spaces): a sample's output depends only on the consequents of the
  rules that fire for it, so each group of samples with the same firing rules is scored
  once per combination of their consequents (:mod:`fuzzcore.tune.rule_tables`), and a
  candidate costs a lookup per group. :class:`Objective` builds the tables when they
  cost fewer inferences than the caller plans to spend (``expected_evaluations``).
"""
from __future__ import annotations

import numpy as np

from .. import _kernels as K
from . import _objective_kernels as KO
from .batch import Samples, full_sums, predictions, subset_sums
from .data import check_data
from .rule_space import RuleSpace
from .rule_tables import RuleTables, firing_strengths, group_by_firing

METRICS = {"rmse": KO.LOSS_SQUARED, "mae": KO.LOSS_ABSOLUTE}
#: slot of the no-rule-fired policy in the header of ``iblob`` (:mod:`fuzzcore.compiled`)
POLICY = 6


class Objective:
    """The metric of candidate systems on ``(X, y)``, vectorised over candidates.

    Parameters
    ----------
    space : TermSpace or RuleSpace
        What a candidate row means (and the system it modifies).
    X : array_like (n_samples, n_inputs)
    y : array_like (n_samples,) or (n_samples, n_outputs)
        Checked by :func:`fuzzcore.tune.data.check_data`.
    metric : {"rmse", "mae"}
        Over every sample and output.
    expected_evaluations : int, optional
        How many candidates the caller expects to score. For a rule space, the exact
        lookup tables are built (at the first call) when they cost fewer inferences
        than that many direct evaluations.
    require_firing : bool
        Score a candidate ``inf`` if, for some sample, no rule fires (the candidate's
        ``no_rule_fired`` fallback would answer instead of its rules). Tuners set it so
        that no search wins by moving terms away from the data and letting the fallback
        (MATLAB's midpoint of the output range) predict.

    Attributes
    ----------
    data : Samples
        The data, with its distinct input rows.
    nfev : int
        Candidates scored so far (feasible or not).
    uses_tables : bool
        Whether candidates are scored from the exact lookup tables (built at the first
        call), as ``expected_evaluations`` decided.

    Notes
    -----
    ``objective(P)`` with ``P`` of shape (n_candidates, n_params) returns shape
    (n_candidates,): the metric, or ``inf`` for a candidate that violates the space's
    constraints or whose system gives NaN for some sample (no rule fired under
    ``no_rule_fired: nan``, or under ``require_firing``). ``inf`` is never better than
    anything, so no tuner can choose such a candidate.
    """

    def __init__(self, space, X, y, metric: str = "rmse", expected_evaluations: int | None = None,
                 require_firing: bool = False):
        if metric not in METRICS:
            raise ValueError(f"metric {metric!r}: expected one of {', '.join(METRICS)}")
        self.space = space
        fblob, iblob, _ = space.system.packed
        if require_firing:
            iblob[POLICY] = K.P_NAN
        self._packed = (fblob, iblob)
        X, Y, _ = check_data(space.system, X, y)
        self.data = Samples.of(X, Y)
        self.metric = metric
        self.nfev = 0
        self._loss = METRICS[metric]
        self._tables = None
        self._want_tables = False
        if isinstance(space, RuleSpace) and expected_evaluations is not None:
            cost = group_by_firing(space, self.data).cost
            self._want_tables = cost is not None and cost < expected_evaluations * self.data.unique.shape[0]
        U = self.data.unique
        self._order = np.argsort(U, axis=0, kind="stable")  # distinct rows sorted, per input
        self._sorted = np.take_along_axis(U, self._order, axis=0)
        self._base = None        # the base point whose predictions are cached
        self._base_pred = None
        self._fires = None       # (m, n_rules) bool: which rules fire at each distinct row, at the base
        self._users = {}         # {("rule", r) or ("output_term", o, k): rows}, at the base

    @property
    def uses_tables(self) -> bool:
        return self._want_tables

    def __call__(self, P, base=None) -> np.ndarray:
        """Score candidate rows ``P`` (n_candidates, n_params) -> (n_candidates,).

        ``base`` (n_params,), optional: a feasible point (typically the incumbent) whose
        per-sample results are reused (module docstring); same values, fewer inferences
        when candidates differ from it in few parameters.
        """
        P = np.asarray(P, dtype=np.float64)
        if P.ndim == 1:
            P = P[None]
        if P.ndim != 2 or P.shape[1] != self.space.n_params:
            raise ValueError(f"candidates have shape {np.shape(P)}, expected (n_candidates, "
                             f"{self.space.n_params})")
        self.nfev += P.shape[0]
        out = np.full(P.shape[0], np.inf)
        ok = np.flatnonzero(self.space.feasible(P))
        if ok.size == 0:
            return out
        good = np.ascontiguousarray(P[ok])
        if self._want_tables and self._tables is None:
            self._tables = RuleTables(self.space, self._packed, self.data, self._loss)
        if self._tables is not None:
            sums = self._tables.sums(good)
        elif base is not None:
            self._use_base(np.asarray(base, dtype=np.float64))
            rows = [self._affected(p) for p in good]
            sums = subset_sums(self.space, self._packed, self.data, good, self._loss, self._base_pred, rows)
        else:
            sums = full_sums(self.space, self._packed, self.data, good, self._loss)
        value = sums / self.data.Y.size
        if self.metric == "rmse":
            value = np.sqrt(value)
        out[ok] = np.where(np.isfinite(value), value, np.inf)
        return out

    # ------------------------------------------------------------------ base point
    def _use_base(self, base: np.ndarray) -> None:
        if self._base is not None and np.array_equal(base, self._base):
            return
        if base.shape != (self.space.n_params,) or not self.space.feasible(base[None])[0]:
            raise ValueError(f"base must be a feasible point of shape ({self.space.n_params},)")
        self._base = base.copy()
        self._base_pred = predictions(self.space, self._packed, self.data, base)
        self._fires = None
        self._users = {}

    def _rows_using(self, key: tuple) -> np.ndarray:
        """Distinct rows where ``key``'s rule, or a rule concluding ``key``'s output term, fires at the base."""
        if key not in self._users:
            if self._fires is None:  # firing depends on the input terms only: the base's, for a term space
                system = self.space.system if isinstance(self.space, RuleSpace) else self.space.to_system(self._base)
                self._fires = firing_strengths(system, self.data.unique) > 0.0
            if key[0] == "rule":
                rules = [key[1]]
            else:
                _, o, k = key
                rules = [r for r, rule in enumerate(self.space.system.rules) if abs(rule.consequent[o]) == k + 1]
            self._users[key] = np.flatnonzero(self._fires[:, rules].any(axis=1))
        return self._users[key]

    def _affected(self, p: np.ndarray) -> np.ndarray:
        """Distinct rows (sorted) whose prediction can differ between the base and ``p``."""
        parts = []
        for change in self.space.changes(self._base, p):
            if change[0] == "input":
                return np.arange(self.data.unique.shape[0])
            if change[0] == "interval":
                _, v, lo, hi = change
                column = self._sorted[:, v]
                a, b = np.searchsorted(column, lo, "left"), np.searchsorted(column, hi, "right")
                parts.append(self._order[a:b, v])
            else:
                parts.append(self._rows_using(change))
        if not parts:
            return np.empty(0, dtype=np.int64)
        if len(parts) == 1:
            return np.sort(parts[0])
        return np.unique(np.concatenate(parts))
