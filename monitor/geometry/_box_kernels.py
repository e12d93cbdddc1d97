"""Numba kernels behind :mod:`monitor.geometry.boxes` (and the scalar measures behind
:mod:`monitor._alignment_kernels`).

Private: the public functions validate their input and then call these. Kernels never
validate and never raise. Box rows are ``cx, cy, w, h, d``; every measure is written once,
as a scalar function, and the row and frame kernels call it.

Box extents are taken from the corner coordinates (``x1 - x0``, not ``w``) both for the
intersection and for the areas, so that ``intersection <= area`` holds exactly in floating
point: IoU and IoG never exceed 1 by a rounding error, IoU never exceeds IoG, and the IoU
of a box with itself is exactly 1.
"""
from __future__ import annotations

import numpy as np

from fuzzcore.jit import kernel

# codes returned by invalid_entry, turned into messages by monitor.geometry.boxes
OK = 0
NOT_FINITE = 1
NEGATIVE_SIZE = 2
NEGATIVE_DEPTH = 3
NONPOSITIVE_DEPTH = 4
ZERO_AREA = 5
TOO_LARGE = 6

#: largest magnitude of a box entry (pixels or metres): beyond it centre distances and
#: areas could overflow to inf
MAX_MAGNITUDE = 1e15


@kernel
def _span(c, size):
    lo = c - 0.5 * size
    hi = c + 0.5 * size
    return lo, hi, hi - lo


@kernel
def intersection_areas(a, b):
    """Intersection area and the two box areas (all from corner coordinates)."""
    ax0, ax1, aw = _span(a[0], a[2])
    ay0, ay1, ah = _span(a[1], a[3])
    bx0, bx1, bw = _span(b[0], b[2])
    by0, by1, bh = _span(b[1], b[3])
    iw = min(ax1, bx1) - max(ax0, bx0)
    ih = min(ay1, by1) - max(ay0, by0)
    inter = iw * ih if (iw > 0.0 and ih > 0.0) else 0.0
    return inter, aw * ah, bw * bh


@kernel
def iou_one(a, b):
    """IoU of two boxes; 0 when the union has no area (both boxes degenerate)."""
    inter, area_a, area_b = intersection_areas(a, b)
    # inter <= min(area) exactly, so this union is >= max(area) exactly: IoU <= IoG
    union = max(area_a, area_b) + (min(area_a, area_b) - inter)
    return inter / union if union > 0.0 else 0.0


@kernel
def iog_one(p, g):
    """Intersection over the area of ``g``; the caller guarantees that area is > 0."""
    inter, _, area_g = intersection_areas(p, g)
    return inter / area_g


@kernel
def rdd_one(d_p, d_s):
    """min(1, (d_p - d_s) / d_s); the caller guarantees d_s > 0 and d_p >= 0."""
    return min(1.0, (d_p - d_s) / d_s)


@kernel
def depth_ratio_one(d_p, d_g):
    """min(1, d_g / d_p) written without the division when d_p <= d_g (so d_p = 0 gives 1)."""
    return 1.0 if d_p <= d_g else d_g / d_p


@kernel
def invalid_entry(a, positive_depth, positive_area):
    """First offending ``(row, column, code)`` of an (n, 5) array, or ``(-1, -1, OK)``.

    Checks: every entry finite and at most :data:`MAX_MAGNITUDE` in magnitude; ``w, h >= 0``;
    ``d >= 0`` (``> 0`` if ``positive_depth``);
    ``x1 - x0 > 0`` and ``y1 - y0 > 0`` (the extents the measures use) if ``positive_area``.
    """
    for i in range(a.shape[0]):
        for j in range(5):
            if not np.isfinite(a[i, j]):
                return i, j, NOT_FINITE
            if abs(a[i, j]) > MAX_MAGNITUDE:
                return i, j, TOO_LARGE
        for j in range(2, 4):
            if a[i, j] < 0.0:
                return i, j, NEGATIVE_SIZE
        if positive_depth and not a[i, 4] > 0.0:
            return i, 4, NONPOSITIVE_DEPTH
        if a[i, 4] < 0.0:
            return i, 4, NEGATIVE_DEPTH
        if positive_area:
            for j in range(2, 4):
                if not _span(a[i, j - 2], a[i, j])[2] > 0.0:
                    return i, j, ZERO_AREA
    return -1, -1, OK


@kernel
def iou_rows(a, b, out):
    for i in range(a.shape[0]):
        out[i] = iou_one(a[i], b[i])


@kernel
def iog_rows(p, g, out):
    for i in range(p.shape[0]):
        out[i] = iog_one(p[i], g[i])


@kernel
def rdd_rows(d_p, d_s, out):
    for i in range(d_p.shape[0]):
        out[i] = rdd_one(d_p[i], d_s[i])


@kernel
def depth_ratio_rows(d_p, d_g, out):
    for i in range(d_p.shape[0]):
        out[i] = depth_ratio_one(d_p[i], d_g[i])


@kernel
def centre_distances(a, b):
    """(n, m) Euclidean distances between the centres of the rows of ``a`` and ``b``."""
    bx = b[:, 0].copy()  # contiguous columns let the inner loop vectorise
    by = b[:, 1].copy()
    out = np.empty((a.shape[0], b.shape[0]))
    for i in range(a.shape[0]):
        ax = a[i, 0]
        ay = a[i, 1]
        for j in range(b.shape[0]):
            dx = ax - bx[j]
            dy = ay - by[j]
            out[i, j] = np.sqrt(dx * dx + dy * dy)
    return out

