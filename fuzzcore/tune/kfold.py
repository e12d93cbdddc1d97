"""k-fold cross-validation as the tuners use it: folds by group, and early stopping on the held-out fold.

How cross-validation enters tuning (MATLAB's ``tunefis`` with ``KFoldValue = k``, which
the paper used): the data are split into k folds; fold j's run tunes on the other k - 1
folds, starting from where run j - 1 ended, and watches the cost on fold j after every
iteration that moved the incumbent. The run stops early when that validation cost rises
by more than ``validation_tol`` (relative) above the smallest of the previous
``validation_window`` validation costs (overfitting), and hands on the point with the
lowest validation cost it saw (not the last one: restoring the best is what makes the
stop safe). The result of run k is the tuned system; the k validation costs are its
cross-validation scores (optimistic: each fold also chose its stopping point).

Folds never split a group: when the data have groups (the scenes of a driving data set),
whole groups are dealt to folds (shuffled, then each to the fold with the fewest samples
so far), because frames of one scene are near-copies of each other and would leak
between training and validation. Without groups, samples are shuffled and cut into k
near-equal folds.
"""
from __future__ import annotations

import math

import numpy as np


def fold_labels(n_samples: int, n_folds: int, rng: np.random.Generator,
                groups: np.ndarray | None = None) -> np.ndarray:
    """Fold index (0..n_folds-1) of every sample.

    Parameters
    ----------
    n_samples : int
    n_folds : int >= 2
    rng : numpy Generator
    groups : ndarray (n_samples,), optional
        Group labels; a group's samples all land in one fold.

    Returns
    -------
    ndarray (n_samples,), int64
    """
    if groups is None:
        if n_samples < n_folds:
            raise ValueError(f"n_folds = {n_folds} but there are only {n_samples} samples; "
                             "expected at least one sample per fold")
        labels = np.empty(n_samples, dtype=np.int64)
        labels[rng.permutation(n_samples)] = np.arange(n_samples) % n_folds
        return labels
    names, inverse, counts = np.unique(groups, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    if names.shape[0] < n_folds:
        raise ValueError(f"n_folds = {n_folds} but the data have only {names.shape[0]} groups "
                         f"({', '.join(map(str, names[:5]))}{', ...' if names.shape[0] > 5 else ''}); "
                         "folds never split a group, so expected at least one group per fold")
    filled = np.zeros(n_folds, dtype=np.int64)
    group_fold = np.empty(names.shape[0], dtype=np.int64)
    for g in rng.permutation(names.shape[0]):
        f = int(np.argmin(filled))  # the first of the lightest folds
        group_fold[g] = f
        filled[f] += counts[g]
    return group_fold[inverse]


class EarlyStopping:
    """Validation-cost watch of one cross-validation run (rule: module docstring).

    Parameters
    ----------
    objective : callable
        ``(n, n_params) -> (n,)`` cost on the held-out fold.
    tol : float >= 0
        Largest allowed relative rise of the validation cost.
    window : int >= 1
        How many previous validation costs the rise is measured against (their minimum).

    Attributes
    ----------
    best_x : ndarray
        The point with the lowest validation cost so far.
    best_value : float
    values : list of float
        Every validation cost, in order.
    """

    def __init__(self, objective, tol: float, window: int):
        self.objective = objective
        self.tol = tol
        self.window = window
        self.values: list[float] = []
        self.best_x = None
        self.best_value = math.inf

    def update(self, x: np.ndarray) -> bool:
        """Score ``x`` on the held-out fold; return True when the run should stop."""
        value = float(self.objective(x[None])[0])
        recent = self.values[-self.window:]
        self.values.append(value)
        if value < self.best_value:
            self.best_value = value
            self.best_x = x.copy()
        return bool(recent) and value > (1.0 + self.tol) * min(recent)
