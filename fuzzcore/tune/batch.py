"""Front door of the objective kernels: candidate rows of a parameter space, scored on a data set.

Every function takes data validated by :func:`fuzzcore.tune.data.check_data` (float64,
C-contiguous, finite) and candidate rows that are feasible for the space; the loss code
is :data:`~fuzzcore.tune._objective_kernels.LOSS_SQUARED` or ``LOSS_ABSOLUTE``.
"""
from __future__ import annotations

import numpy as np

from . import _objective_kernels as KO


def _blobs(space, P: np.ndarray):
    fblob, iblob, _ = space.system.packed
    f_val, i_val = space.blob_values(P)
    return fblob, iblob, space.f_positions, f_val, space.i_positions, i_val, space.refresh


def full_sums(space, X: np.ndarray, Y: np.ndarray, P: np.ndarray, loss: int) -> np.ndarray:
    """Summed loss over every sample and output of each candidate row of ``P`` (n_candidates, n_params).

    Returns ndarray (n_candidates,); NaN where some prediction is NaN.
    """
    sums = np.empty(P.shape[0])
    KO.full_sums(X, Y, *_blobs(space, P), loss, sums)
    return sums


def sample_losses(space, X: np.ndarray, Y: np.ndarray, p: np.ndarray, loss: int) -> np.ndarray:
    """Loss of candidate ``p`` (n_params,) at every sample and output: ndarray (n_samples, n_outputs)."""
    out = np.empty(Y.shape)
    KO.sample_losses(X, Y, *_blobs(space, p[None]), loss, out)
    return out


def subset_sums(space, X: np.ndarray, Y: np.ndarray, P: np.ndarray, loss: int, base_loss: np.ndarray,
                subsets: list[np.ndarray]) -> np.ndarray:
    """As :func:`full_sums`, re-evaluating only ``subsets[c]`` (sorted sample indices) for candidate c.

    Every other sample contributes ``base_loss`` (n_samples, n_outputs); when those
    samples' predictions are the same under candidate c as under the base, the result
    equals :func:`full_sums` bit for bit.
    """
    sizes = np.array([s.shape[0] for s in subsets], dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    subset = np.concatenate(subsets).astype(np.int64) if subsets else np.empty(0, dtype=np.int64)
    task_cand = np.repeat(np.arange(len(subsets)), (sizes + KO.CHUNK - 1) // KO.CHUNK).astype(np.int64)
    task_lo = np.concatenate([np.arange(start[c], start[c + 1], KO.CHUNK) for c in range(len(subsets))]
                             + [np.empty(0)]).astype(np.int64)
    sums = np.empty(P.shape[0])
    KO.subset_sums(X, Y, *_blobs(space, P), loss, base_loss, subset, start, task_cand, task_lo, sums)
    return sums
