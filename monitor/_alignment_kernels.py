"""Numba kernel behind :mod:`monitor.alignment`.

Private: :func:`monitor.alignment.align` validates its input and then calls this kernel,
which never validates and never raises. The pair measures are the box kernels' own scalar
IoU and RDD (:mod:`monitor.geometry._box_kernels`), one definition of each measure: a
Numba kernel can only call kernels, so kernel modules may use another package's kernels;
Python modules use only public names.
"""
from __future__ import annotations

import numpy as np

from fuzzcore.jit import kernel
from monitor.geometry._box_kernels import intersection_areas, iou_one, rdd_one


@kernel
def score_pairs(s, p, partner, alpha, beta, pair_iou, pair_rdd, matched):
    """Fill the per-S alignment table (M,) given each S's partner row in P (-1: none).

    An S without a partner gets IoU 0, RDD 1, not matched; a pair is matched when
    IoU > alpha and |RDD| < beta.
    """
    for i in range(partner.shape[0]):
        j = partner[i]
        if j < 0:
            pair_iou[i] = 0.0
            pair_rdd[i] = 1.0
            matched[i] = False
        else:
            pair_iou[i] = iou_one(s[i], p[j])
            pair_rdd[i] = rdd_one(p[j, 4], s[i, 4])
            matched[i] = pair_iou[i] > alpha and abs(pair_rdd[i]) < beta


@kernel
def _union_area(x0, x1, y0, y1, n):
    """Area of the union of the first n rectangles [x0, x1) x [y0, y1) (exact: the plane is
    cut at every edge and each elementary cell is counted once)."""
    xs = np.sort(np.concatenate((x0[:n], x1[:n])))
    ys = np.sort(np.concatenate((y0[:n], y1[:n])))
    area = 0.0
    for a in range(2 * n - 1):
        w = xs[a + 1] - xs[a]
        if w <= 0.0:
            continue
        xm = 0.5 * (xs[a] + xs[a + 1])
        for b in range(2 * n - 1):
            h = ys[b + 1] - ys[b]
            if h <= 0.0:
                continue
            ym = 0.5 * (ys[b] + ys[b + 1])
            for k in range(n):
                if x0[k] <= xm < x1[k] and y0[k] <= ym < y1[k]:
                    area += w * h
                    break
    return area


@kernel
def score_coverage(s, p, alpha, beta, partner, pair_cov, pair_rdd, matched):
    """Fill the per-S coverage table (M,): which share of each S the detections cover.

    A P takes part for S when its RDD ``min(1, (d_P - d_S) / d_S) < beta`` (one-sided: a
    detection nearer than S is cautious, as USC's DR treats it). ``pair_cov`` is the area
    of S inside the union of those P over the area of S (0 for an S of zero area);
    ``partner`` the one with the largest intersection (-1: none overlaps), ``pair_rdd`` its
    RDD (1 without one); ``matched`` is ``pair_cov > alpha`` with a partner.
    """
    n = p.shape[0]
    x0 = np.empty(n)
    x1 = np.empty(n)
    y0 = np.empty(n)
    y1 = np.empty(n)
    for i in range(s.shape[0]):
        sx0, sx1 = s[i, 0] - 0.5 * s[i, 2], s[i, 0] + 0.5 * s[i, 2]
        sy0, sy1 = s[i, 1] - 0.5 * s[i, 3], s[i, 1] + 0.5 * s[i, 3]
        area = (sx1 - sx0) * (sy1 - sy0)
        best, best_inter, k = -1, 0.0, 0
        for j in range(n):
            if not rdd_one(p[j, 4], s[i, 4]) < beta:
                continue
            inter, _, _ = intersection_areas(s[i], p[j])
            if inter <= 0.0:
                continue
            if inter > best_inter:
                best, best_inter = j, inter
            x0[k] = max(sx0, p[j, 0] - 0.5 * p[j, 2])  # the part of P inside S
            x1[k] = min(sx1, p[j, 0] + 0.5 * p[j, 2])
            y0[k] = max(sy0, p[j, 1] - 0.5 * p[j, 3])
            y1[k] = min(sy1, p[j, 1] + 0.5 * p[j, 3])
            k += 1
        partner[i] = best
        pair_cov[i] = min(1.0, _union_area(x0, x1, y0, y1, k) / area) if (k > 0 and area > 0.0) else 0.0
        pair_rdd[i] = rdd_one(p[best, 4], s[i, 4]) if best >= 0 else 1.0
        matched[i] = best >= 0 and pair_cov[i] > alpha
