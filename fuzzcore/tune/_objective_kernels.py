"""Numba kernels of the batched tuning objective. Private: callers go through
:class:`fuzzcore.tune.objective.Objective`, which validates everything first.

Each kernel scores candidate systems one after another on the calling thread: a
candidate's parameters are written into a copy of the packed arrays and the data run
through the engine's :func:`fuzzcore._kernels.evaluate_serial`. The kernels release the
GIL, so :mod:`fuzzcore.tune.batch` runs blocks of candidates on several threads. (Not
Numba's ``parallel``: on a machine shared with other work, its threads wait for each
other at every parallel region, which made single-candidate calls three times slower.)

Inputs are evaluated once per distinct row (``U``; ``inverse[i]`` is sample i's row):
identical inputs give identical outputs, and feature tables repeat rows (every frame in
which nothing was matched has IoU~ = 0, RDD~ = 1).

Sums have one canonical order, whichever kernel computes them: per block of
:data:`CHUNK` consecutive samples, the losses of each sample's outputs in order; then the
block sums in block order. :func:`subset_sums`, which re-evaluates only some rows for a
candidate and takes the others' predictions from a base point, therefore returns bit for
bit what :func:`full_sums` returns when those other rows' predictions are unchanged.

Note: Numba's cache does not notice changes to the engine kernels this module calls;
after editing :mod:`fuzzcore._kernels`, delete this package's ``__pycache__``.
"""
from __future__ import annotations

import numpy as np

from .. import _kernels as K
from ..jit import kernel

#: loss codes: squared error (RMSE), absolute error (MAE)
LOSS_SQUARED, LOSS_ABSOLUTE = 0, 1

#: samples per block of the canonical sum
CHUNK = 512


@kernel
def _write_candidate(fblob, iblob, f_pos, f_val, i_pos, i_val, refresh, fb, ib):
    """Copy the base arrays into ``fb``/``ib`` and write one candidate's values at the positions."""
    fb[:] = fblob
    ib[:] = iblob
    for j in range(f_pos.shape[0]):
        fb[f_pos[j]] = f_val[j]
    for j in range(i_pos.shape[0]):
        ib[i_pos[j]] = i_val[j]
    if refresh:
        K.refresh_tables(fb, ib)


@kernel
def _canonical_sum(inverse, Y, pred, fresh, position, loss):
    """Summed loss over samples (canonical order); sample i's prediction is ``fresh[position[u]]``
    where ``u = inverse[i]`` has ``position[u] >= 0``, else ``pred[u]``."""
    n, n_out = Y.shape
    total = 0.0
    for a in range(0, n, CHUNK):
        s = 0.0
        for i in range(a, min(n, a + CHUNK)):
            u = inverse[i]
            p = position[u]
            for o in range(n_out):
                d = (fresh[p, o] if p >= 0 else pred[u, o]) - Y[i, o]
                s += d * d if loss == LOSS_SQUARED else abs(d)
        total += s
    return total


@kernel
def full_sums(U, inverse, Y, fblob, iblob, f_pos, f_val, i_pos, i_val, refresh, loss, sums):
    """``sums[c]`` = summed loss of candidate ``c`` over every sample and output.

    Parameters
    ----------
    U : (m, n_in) float64, distinct input rows;  inverse : (n,) int64, row of each sample
    Y : (n, n_out) float64 targets
    fblob, iblob : the base system's packed arrays
    f_pos (nf,), f_val (n_cand, nf) : fblob positions and each candidate's values
    i_pos (ni,), i_val (n_cand, ni) : iblob positions and values (nf or ni may be 0)
    refresh : bool, recompute output tables (output terms changed)
    loss : LOSS_SQUARED or LOSS_ABSOLUTE
    sums : (n_cand,) output; NaN where some prediction is NaN
    """
    fb, ib = np.empty_like(fblob), np.empty_like(iblob)
    pred = np.empty((U.shape[0], Y.shape[1]))
    position = np.full(U.shape[0], -1, dtype=np.int64)
    for c in range(sums.shape[0]):
        _write_candidate(fblob, iblob, f_pos, f_val[c], i_pos, i_val[c], refresh, fb, ib)
        K.evaluate_serial(U, fb, ib, pred)
        sums[c] = _canonical_sum(inverse, Y, pred, pred, position, loss)


@kernel
def predictions(U, fblob, iblob, f_pos, f_val, i_pos, i_val, refresh, out):
    """``out`` (m, n_out) = outputs of one candidate (``f_val``/``i_val`` of shape (1, .)) at the rows U."""
    fb, ib = np.empty_like(fblob), np.empty_like(iblob)
    _write_candidate(fblob, iblob, f_pos, f_val[0], i_pos, i_val[0], refresh, fb, ib)
    K.evaluate_serial(U, fb, ib, out)


@kernel
def subset_sums(U, inverse, Y, fblob, iblob, f_pos, f_val, i_pos, i_val, refresh, loss, base_pred, rows, start,
                sums):
    """Summed loss of each candidate, re-evaluating only some rows.

    Candidate ``c`` re-evaluates the rows ``rows[start[c]:start[c + 1]]`` (distinct); every
    other row keeps its prediction in ``base_pred`` (m, n_out). ``sums`` (n_cand,) is
    filled in the canonical order (module docstring).
    """
    fb, ib = np.empty_like(fblob), np.empty_like(iblob)
    position = np.full(U.shape[0], -1, dtype=np.int64)
    for c in range(sums.shape[0]):
        _write_candidate(fblob, iblob, f_pos, f_val[c], i_pos, i_val[c], refresh, fb, ib)
        j0, m = start[c], start[c + 1] - start[c]
        Us = np.empty((m, U.shape[1]))
        for j in range(m):
            Us[j] = U[rows[j0 + j]]
            position[rows[j0 + j]] = j
        fresh = np.empty((m, Y.shape[1]))
        K.evaluate_serial(Us, fb, ib, fresh)
        sums[c] = _canonical_sum(inverse, Y, base_pred, fresh, position, loss)
        for j in range(m):
            position[rows[j0 + j]] = -1
