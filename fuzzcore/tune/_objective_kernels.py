"""Numba kernels of the batched tuning objective. Private: callers go through
:class:`fuzzcore.tune.objective.Objective`, which validates everything first.

One call scores many candidate systems on one data set: each candidate gets its own copy
of the packed arrays with its parameters written in, then (candidate, chunk of samples)
tasks run in parallel through the engine's :func:`fuzzcore._kernels.evaluate_serial`, so
a batch of one candidate still uses every core.

Sums have one canonical order, whatever the thread count and whichever kernel computes
them: per block of :data:`CHUNK` consecutive samples, the losses of each sample's outputs
in order; then the block sums in block order. :func:`subset_sums`, which re-evaluates only
some samples of each candidate and takes the others' losses from a base point, therefore
returns bit for bit what :func:`full_sums` returns when those other samples' predictions
are unchanged.

Note: Numba's cache does not notice changes to the engine kernels this module calls;
after editing :mod:`fuzzcore._kernels`, delete this package's ``__pycache__``.
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from .. import _kernels as K

#: loss codes: squared error (RMSE), absolute error (MAE)
LOSS_SQUARED, LOSS_ABSOLUTE = 0, 1

#: samples per parallel task and per block of the canonical sum
CHUNK = 512


@njit(cache=True, nogil=True)
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


@njit(parallel=True, cache=True, nogil=True)
def _candidates(fblob, iblob, f_pos, f_val, i_pos, i_val, refresh):
    n_cand = max(f_val.shape[0], i_val.shape[0])
    fbs = np.empty((n_cand, fblob.shape[0]))
    ibs = np.empty((n_cand, iblob.shape[0]), dtype=np.int64)
    for c in prange(n_cand):
        _write_candidate(fblob, iblob, f_pos, f_val[c], i_pos, i_val[c], refresh, fbs[c], ibs[c])
    return fbs, ibs


@njit(inline="always", cache=True, nogil=True)
def _loss(pred, target, loss):
    d = pred - target
    return d * d if loss == LOSS_SQUARED else abs(d)


@njit(parallel=True, cache=True, nogil=True)
def full_sums(X, Y, fblob, iblob, f_pos, f_val, i_pos, i_val, refresh, loss, sums):
    """``sums[c]`` = summed loss of candidate ``c`` over every sample and output.

    Parameters
    ----------
    X : (n, n_in) float64;  Y : (n, n_out) float64 targets
    fblob, iblob : the base system's packed arrays
    f_pos (nf,), f_val (n_cand, nf) : fblob positions and each candidate's values
    i_pos (ni,), i_val (n_cand, ni) : iblob positions and values (one of nf, ni may be 0,
        with ``(n_cand, 0)`` values)
    refresh : bool, recompute output tables (output terms changed)
    loss : LOSS_SQUARED or LOSS_ABSOLUTE
    sums : (n_cand,) output; NaN where some prediction is NaN
    """
    fbs, ibs = _candidates(fblob, iblob, f_pos, f_val, i_pos, i_val, refresh)
    n_cand = sums.shape[0]
    n, n_out = Y.shape
    n_chunks = (n + CHUNK - 1) // CHUNK
    partial = np.empty((n_cand, n_chunks))
    for task in prange(n_cand * n_chunks):
        c, k = task // n_chunks, task % n_chunks
        a = k * CHUNK
        b = min(n, a + CHUNK)
        pred = np.empty((b - a, n_out))
        K.evaluate_serial(X[a:b], fbs[c], ibs[c], pred)
        s = 0.0
        for i in range(b - a):
            for o in range(n_out):
                s += _loss(pred[i, o], Y[a + i, o], loss)
        partial[c, k] = s
    for c in range(n_cand):
        s = 0.0
        for k in range(n_chunks):
            s += partial[c, k]
        sums[c] = s


@njit(parallel=True, cache=True, nogil=True)
def sample_losses(X, Y, fblob, iblob, f_pos, f_val, i_pos, i_val, refresh, loss, out):
    """``out[i, o]`` = loss of one candidate (``f_val``/``i_val`` of shape (1, .)) at sample i, output o."""
    fbs, ibs = _candidates(fblob, iblob, f_pos, f_val, i_pos, i_val, refresh)
    n, n_out = Y.shape
    n_chunks = (n + CHUNK - 1) // CHUNK
    for k in prange(n_chunks):
        a = k * CHUNK
        b = min(n, a + CHUNK)
        pred = np.empty((b - a, n_out))
        K.evaluate_serial(X[a:b], fbs[0], ibs[0], pred)
        for i in range(b - a):
            for o in range(n_out):
                out[a + i, o] = _loss(pred[i, o], Y[a + i, o], loss)


@njit(parallel=True, cache=True, nogil=True)
def subset_sums(X, Y, fblob, iblob, f_pos, f_val, i_pos, i_val, refresh, loss, base_loss, subset, start,
                task_cand, task_lo, sums):
    """Summed loss of each candidate, re-evaluating only its subset of samples.

    Candidate ``c`` re-evaluates the samples ``subset[start[c]:start[c + 1]]`` (sorted,
    distinct); every other sample contributes ``base_loss`` (n, n_out). Tasks are
    ``(task_cand[t], subset positions task_lo[t] .. min(task_lo[t] + CHUNK, start[c + 1]))``.
    ``sums`` (n_cand,) is filled in the canonical order (module docstring).
    """
    fbs, ibs = _candidates(fblob, iblob, f_pos, f_val, i_pos, i_val, refresh)
    n_cand = sums.shape[0]
    n, n_out = Y.shape
    fresh = np.empty((subset.shape[0], n_out))
    for t in prange(task_cand.shape[0]):
        c = task_cand[t]
        a = task_lo[t]
        b = min(a + CHUNK, start[c + 1])
        Xs = np.empty((b - a, X.shape[1]))
        for i in range(b - a):
            Xs[i] = X[subset[a + i]]
        pred = np.empty((b - a, n_out))
        K.evaluate_serial(Xs, fbs[c], ibs[c], pred)
        for i in range(b - a):
            for o in range(n_out):
                fresh[a + i, o] = _loss(pred[i, o], Y[subset[a + i], o], loss)
    for c in prange(n_cand):
        j, end = start[c], start[c + 1]
        total = 0.0
        for a in range(0, n, CHUNK):
            s = 0.0
            for i in range(a, min(n, a + CHUNK)):
                if j < end and subset[j] == i:
                    for o in range(n_out):
                        s += fresh[j, o]
                    j += 1
                else:
                    for o in range(n_out):
                        s += base_loss[i, o]
            total += s
        sums[c] = total
