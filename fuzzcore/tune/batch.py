"""Front door of the objective kernels: candidate rows of a parameter space, scored on samples.

Every function takes the packed arrays of the system the candidates modify (``packed``:
``(fblob, iblob)``, normally ``space.system.packed[:2]``), :class:`Samples` (built from
data validated by :func:`fuzzcore.tune.data.check_data`) and candidate rows that are
feasible for the space; the loss code is
:data:`~fuzzcore.tune._objective_kernels.LOSS_SQUARED` or ``LOSS_ABSOLUTE``. A batch of
several candidates is cut into one block per thread (``numba.get_num_threads()``); a
candidate's number does not depend on the cut.
"""
from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba
import numpy as np

from . import _objective_kernels as KO


@dataclass(frozen=True)
class Samples:
    """Tuning data with its distinct input rows (the kernels evaluate each row once).

    Attributes
    ----------
    X : ndarray (n, n_inputs);  Y : ndarray (n, n_outputs)
    unique : ndarray (m, n_inputs), the distinct rows of X (sorted)
    inverse : ndarray (n,), int64: ``X[i] == unique[inverse[i]]``
    """

    X: np.ndarray
    Y: np.ndarray
    unique: np.ndarray
    inverse: np.ndarray

    @classmethod
    def of(cls, X: np.ndarray, Y: np.ndarray) -> "Samples":
        unique, inverse = np.unique(X, axis=0, return_inverse=True)
        return cls(X, Y, np.ascontiguousarray(unique), inverse.ravel().astype(np.int64))

    def take(self, index: np.ndarray) -> "Samples":
        """The samples ``index`` (in that order)."""
        return Samples.of(np.ascontiguousarray(self.X[index]), np.ascontiguousarray(self.Y[index]))


def _blobs(space, packed, P: np.ndarray):
    fblob, iblob = packed
    f_val, i_val = space.blob_values(P)
    return fblob, iblob, space.f_positions, f_val, space.i_positions, i_val, space.refresh


def _in_blocks(n_candidates: int, work) -> None:
    """Run ``work(lo, hi)`` over candidate blocks, one per thread (in this thread for one block)."""
    n_blocks = min(n_candidates, numba.get_num_threads())
    if n_blocks <= 1:
        work(0, n_candidates)
        return
    edges = np.linspace(0, n_candidates, n_blocks + 1).astype(int)
    with ThreadPoolExecutor(n_blocks) as pool:
        for future in [pool.submit(work, lo, hi) for lo, hi in zip(edges[:-1], edges[1:])]:
            future.result()


def full_sums(space, packed, data: Samples, P: np.ndarray, loss: int) -> np.ndarray:
    """Summed loss over every sample and output of each candidate row of ``P`` (n_candidates, n_params).

    Returns ndarray (n_candidates,); NaN where some prediction is NaN.
    """
    fblob, iblob, f_pos, f_val, i_pos, i_val, refresh = _blobs(space, packed, P)
    sums = np.empty(P.shape[0])

    def work(lo, hi):
        KO.full_sums(data.unique, data.inverse, data.Y, fblob, iblob, f_pos, f_val[lo:hi], i_pos, i_val[lo:hi],
                     refresh, loss, sums[lo:hi])

    _in_blocks(P.shape[0], work)
    return sums


def predictions(space, packed, data: Samples, p: np.ndarray) -> np.ndarray:
    """Outputs of candidate ``p`` (n_params,) at every distinct row: ndarray (m, n_outputs)."""
    out = np.empty((data.unique.shape[0], data.Y.shape[1]))
    KO.predictions(data.unique, *_blobs(space, packed, p[None]), out)
    return out


def subset_sums(space, packed, data: Samples, P: np.ndarray, loss: int, base_pred: np.ndarray,
                rows: list[np.ndarray]) -> np.ndarray:
    """As :func:`full_sums`, re-evaluating only the distinct rows ``rows[c]`` for candidate c.

    Every other row keeps its prediction in ``base_pred`` (m, n_outputs); when those
    predictions are the same under candidate c, the result equals :func:`full_sums` bit
    for bit.
    """
    fblob, iblob, f_pos, f_val, i_pos, i_val, refresh = _blobs(space, packed, P)
    sizes = np.array([r.shape[0] for r in rows], dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    flat = np.concatenate(rows).astype(np.int64)
    sums = np.empty(P.shape[0])

    def work(lo, hi):
        KO.subset_sums(data.unique, data.inverse, data.Y, fblob, iblob, f_pos, f_val[lo:hi], i_pos, i_val[lo:hi],
                       refresh, loss, base_pred, flat, start[lo:hi + 1], sums[lo:hi])

    _in_blocks(P.shape[0], work)
    return sums
