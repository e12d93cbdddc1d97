"""Numba kernels of the depth-based retrieval (private; see :mod:`monitor.depth.retrieval`).

The kernels trust their inputs (the public functions validate them: C-contiguous arrays of
the stated dtypes and shapes) and never raise. A depth is valid when it is finite and > 0;
a prior (per pixel, or per block at ``downsample = 2``) is known when it is finite. NaN and
inf are tested with plain comparisons.

Compiled with :mod:`fuzzcore.jit`'s options, whose ``error_model="numpy"`` makes a float division follow IEEE rules instead of testing for
zero (that test would both raise and keep LLVM from vectorising the loops); the kernels
only use the quotient of a positive depth anyway. No fastmath: the per-pixel passes are
bound by memory bandwidth (fastmath flags changed nothing measurable), and without them the
float32 arithmetic is exactly NumPy's, so the tests compare against NumPy bit for bit.
The pixel loops run along contiguous rows with no branch on data; a loop that walks down
columns or sums a variable number of pixels per output ran 5-20 times slower.
"""
from __future__ import annotations

import numpy as np

from fuzzcore.jit import kernel

_INF = np.float32(np.inf)


@kernel(inline=True)
def _pixel(d, p):
    """``(1/d - p, 1)`` for a valid pixel, ``(0, 0)`` for an invalid one (float32, int32)."""
    zero = np.float32(0.0)
    valid = (d > zero) & (d < _INF) & (abs(p) < _INF)
    value = np.float32(1.0) / d - p
    return (value if valid else zero), np.int32(valid)


@kernel(inline=True)
def _block_value(total, count, prior, known):
    """``total / count - prior`` clipped at 0, or -1 (the invalid marker) when
    ``count == 0`` or the prior is not ``known``."""
    zero = np.float32(0.0)
    value = total / np.float32(max(count, 1)) - prior
    value = value if value > zero else zero
    return value if (count > 0) & known else np.float32(-1.0)


@kernel
def foreground_pixels(depth, prior, values):
    """Pass 1 at full resolution: ``values = max(1/D - prior, 0)``, -1 on invalid pixels.

    ``depth``, ``prior`` and ``values`` are float32 (H, W). Returns the number of invalid
    pixels.
    """
    height, width = depth.shape
    zero = np.float32(0.0)
    n_invalid = 0
    for i in range(height):
        for j in range(width):
            value, valid = _pixel(depth[i, j], prior[i, j])
            values[i, j] = _block_value(value, valid, zero, True)
            n_invalid += 1 - valid
    return n_invalid


@kernel(inline=True)
def _inverse(d):
    """``(1/d, 1, d)`` for a valid depth (finite, > 0), ``(0, 0, inf)`` otherwise."""
    zero = np.float32(0.0)
    valid = (d > zero) & (d < _INF)
    inverse = np.float32(1.0) / d
    return (inverse if valid else zero), np.int32(valid), (d if valid else _INF)


@kernel(inline=True)
def _quantise(v, scale):
    """``floor(v * scale + 0.5)`` capped at 255 as uint8; 0 for ``v <= 0`` (and invalid)."""
    q = v * scale + np.float32(0.5)
    q = q if q < np.float32(255.0) else np.float32(255.0)
    q = q if v > np.float32(0.0) else np.float32(0.0)
    return np.uint8(q)


@kernel
def foreground_pairs(depth, block_prior, values, nearest):
    """Pass 1 on 2 x 2 blocks: ``mean(1/D) - prior`` per block, clipped at 0, and each
    block's smallest valid depth.

    The mean is over the block's valid depths; ``block_prior`` is the prior averaged over
    the block (computed once per prior). A block without a valid depth, or whose prior is
    NaN, gets -1 (invalid) in ``values``; ``nearest`` is +inf for a block without a valid
    depth.

    ``depth`` is float32 (H, W); ``block_prior``, ``values`` and ``nearest`` are float32
    (ceil(H / 2), ceil(W / 2)), the last row and column of blocks being partial when H or W
    is odd. Returns the number of invalid pixels: invalid depths, plus the valid ones in
    blocks without a prior. Reading the prior at block resolution saves a quarter of the
    pass's memory traffic. (Quantising in this pass as well, when the full scale is fixed,
    measured slower than the separate pass 2: the per-block stores do not vectorise.)
    """
    height, width = depth.shape
    n_cols = values.shape[1]
    sums = np.empty(width, dtype=np.float32)
    counts = np.empty(width, dtype=np.int32)
    mins = np.empty(width, dtype=np.float32)
    n_invalid = 0
    for bi in range(values.shape[0]):
        top = depth[2 * bi]
        if 2 * bi + 1 < height:
            bottom = depth[2 * bi + 1]
            for j in range(width):
                v0, c0, d0 = _inverse(top[j])
                v1, c1, d1 = _inverse(bottom[j])
                sums[j] = v0 + v1
                counts[j] = c0 + c1
                mins[j] = min(d0, d1)
            rows = 2
        else:
            for j in range(width):
                sums[j], counts[j], mins[j] = _inverse(top[j])
            rows = 1
        for bj in range(width // 2):
            count = counts[2 * bj] + counts[2 * bj + 1]
            prior = block_prior[bi, bj]
            known = abs(prior) < _INF
            values[bi, bj] = _block_value(sums[2 * bj] + sums[2 * bj + 1], count, prior, known)
            nearest[bi, bj] = min(mins[2 * bj], mins[2 * bj + 1])
            n_invalid += 2 * rows - (count if known else 0)
        if width % 2:
            last = n_cols - 1
            count = counts[width - 1]
            prior = block_prior[bi, last]
            known = abs(prior) < _INF
            values[bi, last] = _block_value(sums[width - 1], count, prior, known)
            nearest[bi, last] = mins[width - 1]
            n_invalid += rows - (count if known else 0)
    return n_invalid


@kernel
def foreground_u8(values, scale, image, row_any, col_any, invalid, with_invalid):
    """Pass 2: quantise pass 1's values to uint8 and find the non-zero rows and columns.

    ``image = floor(values * scale + 0.5)`` capped at 255, and 0 where ``values <= 0``
    (-1 marks an invalid block). ``row_any[i]`` / ``col_any[j]`` become non-zero if row i /
    column j of ``image`` holds a non-zero pixel. If ``with_invalid``, ``invalid`` gets 1
    where ``values < 0`` and 0 elsewhere; otherwise it is not touched.
    """
    height, width = values.shape
    col_any[:] = 0
    for i in range(height):
        row = np.uint8(0)
        for j in range(width):
            v = values[i, j]
            u = _quantise(v, scale)
            image[i, j] = u
            col_any[j] |= u
            row |= u
            if with_invalid:
                invalid[i, j] = np.uint8(v < np.float32(0.0))
        row_any[i] = row


@kernel
def rect_min_depth(depth, rects):
    """Smallest valid depth inside each rectangle (NaN if it holds no valid pixel).

    ``depth`` is float32 (H, W): a depth map, or the per-block minima of
    :func:`foreground_pairs` (+inf marks an empty block). ``rects`` is int64 (n, 4) rows
    ``x, y, w, h`` in its pixels (rows y..y+h-1, columns x..x+w-1), inside it. Returns
    float64 (n,).
    """
    n = rects.shape[0]
    out = np.full(n, np.nan)
    for k in range(n):
        x, y, w, h = rects[k, 0], rects[k, 1], rects[k, 2], rects[k, 3]
        best = _INF
        for i in range(y, y + h):
            for j in range(x, x + w):
                d = depth[i, j]
                if d > 0 and d < best:
                    best = d
        if best < _INF:
            out[k] = best
    return out


@kernel(inline=True)
def _known(p):
    """``(p, 1)`` as float64 for a finite prior value, ``(0, 0)`` otherwise."""
    known = abs(p) < _INF
    return (np.float64(p) if known else 0.0), np.int32(known)


@kernel
def block_means(prior, out):
    """Mean of the finite values of each 2 x 2 block of ``prior``, NaN for a block without one.

    ``prior`` is float32 (H, W); ``out`` is float32 (ceil(H / 2), ceil(W / 2)), the last row
    and column of blocks being partial when H or W is odd. The sum runs in float64 in the
    block's row-major order (top-left, top-right, bottom-left, bottom-right), then the mean
    is rounded to float32 once. Rows are read contiguously and without branches on data,
    as in :func:`foreground_pairs`.
    """
    height, width = prior.shape
    n_cols = out.shape[1]
    nan = np.float32(np.nan)
    for bi in range(out.shape[0]):
        top = prior[2 * bi]
        bottom = prior[min(2 * bi + 1, height - 1)]
        has_bottom = 2 * bi + 1 < height
        for bj in range(width // 2):
            v0, c0 = _known(top[2 * bj])
            v1, c1 = _known(top[2 * bj + 1])
            v2, c2 = _known(bottom[2 * bj])
            v3, c3 = _known(bottom[2 * bj + 1])
            if not has_bottom:
                v2, c2, v3, c3 = 0.0, np.int32(0), 0.0, np.int32(0)
            count = c0 + c1 + c2 + c3
            mean = np.float32((((v0 + v1) + v2) + v3) / max(count, 1))
            out[bi, bj] = mean if count > 0 else nan
        if width % 2:
            v0, c0 = _known(top[width - 1])
            v2, c2 = _known(bottom[width - 1])
            if not has_bottom:
                v2, c2 = 0.0, np.int32(0)
            count = c0 + c2
            mean = np.float32((v0 + v2) / max(count, 1))
            out[bi, n_cols - 1] = mean if count > 0 else nan
