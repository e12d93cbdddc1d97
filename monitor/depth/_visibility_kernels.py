"""Numba kernel of the view check (private; see :mod:`monitor.depth.visibility`).

The kernel trusts its input (a C-contiguous float32 depth map and a uint8 mask of the rows
it reads, validated by the public function) and never raises. A depth is valid when it is
finite and > 0; NaN fails every comparison.
"""
from __future__ import annotations

import numpy as np

from fuzzcore.jit import kernel

_INF = np.float32(np.inf)


@kernel
def band_counts(depth, first_row, near, far, invalid, row_inverse, row_valid):
    """Count the pixels of rows ``first_row:`` of ``depth`` (float32 (H, W), metres).

    Writes ``invalid[r - first_row, c] = 1`` where the depth is invalid (0 elsewhere),
    ``row_inverse[r - first_row]`` the sum of 1/depth over the row's valid pixels (float64)
    and ``row_valid[r - first_row]`` their number, and returns ``(n_invalid, n_near,
    n_in_range)``: invalid pixels, valid pixels nearer than ``near`` and valid pixels at
    most ``far`` metres away.
    """
    zero = np.float32(0.0)
    n_invalid = 0
    n_near = 0
    n_in_range = 0
    for r in range(first_row, depth.shape[0]):
        row = depth[r]
        out = invalid[r - first_row]
        total = 0.0
        count = 0
        for c in range(depth.shape[1]):
            d = row[c]
            valid = (d > zero) & (d < _INF)
            out[c] = np.uint8(not valid)
            count += valid
            total += (1.0 / np.float64(d)) if valid else 0.0
            n_near += valid & (d < near)
            n_in_range += valid & (d <= far)
        row_inverse[r - first_row] = total
        row_valid[r - first_row] = count
        n_invalid += depth.shape[1] - count
    return n_invalid, n_near, n_in_range
