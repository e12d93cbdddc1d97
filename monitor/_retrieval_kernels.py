"""Numba kernels of the depth-based retrieval (private; see :mod:`monitor.retrieval`).

The kernels trust their inputs (the public functions validate them: C-contiguous arrays of
the stated dtypes and shapes) and never raise. A pixel is valid when its depth is finite
and > 0 and its prior is finite; NaN and inf are tested with plain comparisons.

``error_model="numpy"`` makes a float division follow IEEE rules instead of testing for
zero (that test would both raise and keep LLVM from vectorising the loops); the kernels
only use the quotient of a positive depth anyway. No fastmath: the per-pixel passes are
bound by memory bandwidth (fastmath flags changed nothing measurable), and without them the
float32 arithmetic is exactly NumPy's, so the tests compare against NumPy bit for bit.
The pixel loops run along contiguous rows with no branch on data; a loop that walks down
columns or sums a variable number of pixels per output ran 5-20 times slower.
"""
from __future__ import annotations

import numpy as np
from numba import njit

_INF = np.float32(np.inf)


@njit(cache=True, error_model="numpy", inline="always")
def _pixel(d, p):
    """``(1/d - p, 1)`` for a valid pixel, ``(0, 0)`` for an invalid one (float32, int32)."""
    zero = np.float32(0.0)
    valid = (d > zero) & (d < _INF) & (abs(p) < _INF)
    value = np.float32(1.0) / d - p
    return (value if valid else zero), np.int32(valid)


@njit(cache=True, error_model="numpy", inline="always")
def _block_value(total, count):
    """Mean ``total / count`` clipped at 0, or -1 (the invalid marker) when ``count == 0``."""
    zero = np.float32(0.0)
    mean = total / np.float32(max(count, 1))
    mean = mean if mean > zero else zero
    return mean if count > 0 else np.float32(-1.0)


@njit(cache=True, error_model="numpy")
def foreground_pixels(depth, prior, values):
    """Pass 1 at full resolution: ``values = max(1/D - prior, 0)``, -1 on invalid pixels.

    ``depth``, ``prior`` and ``values`` are float32 (H, W). Returns the number of invalid
    pixels.
    """
    height, width = depth.shape
    n_invalid = 0
    for i in range(height):
        for j in range(width):
            value, valid = _pixel(depth[i, j], prior[i, j])
            values[i, j] = _block_value(value, valid)
            n_invalid += 1 - valid
    return n_invalid


@njit(cache=True, error_model="numpy", inline="always")
def _depth_or_inf(d):
    """``d`` if it is a valid depth (finite, > 0), else +inf (float32)."""
    return d if (d > np.float32(0.0)) & (d < _INF) else _INF


@njit(cache=True, error_model="numpy")
def foreground_pairs(depth, prior, values, nearest):
    """Pass 1 on 2 x 2 blocks: the mean of ``1/D - prior`` over each block's valid pixels,
    clipped at 0 (-1 for a block without valid pixels), and each block's smallest valid
    depth (+inf if none).

    ``depth`` and ``prior`` are float32 (H, W); ``values`` and ``nearest`` are float32
    (ceil(H / 2), ceil(W / 2)), the last row and column of blocks being partial when H or W
    is odd. A depth counts for ``nearest`` when it is valid, whatever the prior. Returns
    the number of invalid pixels.
    """
    height, width = depth.shape
    n_rows = values.shape[0]
    sums = np.empty(width, dtype=np.float32)
    counts = np.empty(width, dtype=np.int32)
    mins = np.empty(width, dtype=np.float32)
    half = width // 2
    n_invalid = 0
    for bi in range(n_rows):
        top_depth = depth[2 * bi]
        top_prior = prior[2 * bi]
        if 2 * bi + 1 < height:
            bottom_depth = depth[2 * bi + 1]
            bottom_prior = prior[2 * bi + 1]
            for j in range(width):
                v0, c0 = _pixel(top_depth[j], top_prior[j])
                v1, c1 = _pixel(bottom_depth[j], bottom_prior[j])
                sums[j] = v0 + v1
                counts[j] = c0 + c1
                mins[j] = min(_depth_or_inf(top_depth[j]), _depth_or_inf(bottom_depth[j]))
            rows = 2
        else:
            for j in range(width):
                sums[j], counts[j] = _pixel(top_depth[j], top_prior[j])
                mins[j] = _depth_or_inf(top_depth[j])
            rows = 1
        for bj in range(half):
            count = counts[2 * bj] + counts[2 * bj + 1]
            values[bi, bj] = _block_value(sums[2 * bj] + sums[2 * bj + 1], count)
            nearest[bi, bj] = min(mins[2 * bj], mins[2 * bj + 1])
            n_invalid += 2 * rows - count
        if width % 2:
            values[bi, half] = _block_value(sums[width - 1], counts[width - 1])
            nearest[bi, half] = mins[width - 1]
            n_invalid += rows - counts[width - 1]
    return n_invalid


@njit(cache=True, error_model="numpy")
def foreground_u8(values, scale, image, row_any, col_any, invalid, with_invalid):
    """Pass 2: quantise pass 1's values to uint8 and find the non-zero rows and columns.

    ``image = floor(values * scale + 0.5)`` capped at 255, and 0 where ``values < 0``
    (invalid). ``row_any[i]`` / ``col_any[j]`` become non-zero if row i / column j of
    ``image`` holds a non-zero pixel. If ``with_invalid``, ``invalid`` gets 1 where
    ``values < 0`` and 0 elsewhere; otherwise it is not touched.
    """
    height, width = values.shape
    zero = np.float32(0.0)
    half = np.float32(0.5)
    top = np.float32(255.0)
    col_any[:] = 0
    for i in range(height):
        row = np.uint8(0)
        for j in range(width):
            v = values[i, j]
            q = v * scale + half
            q = q if q < top else top
            q = q if v > zero else zero
            u = np.uint8(q)
            image[i, j] = u
            col_any[j] |= u
            row |= u
            if with_invalid:
                invalid[i, j] = np.uint8(v < zero)
        row_any[i] = row


@njit(cache=True, error_model="numpy")
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
