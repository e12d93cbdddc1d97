"""Numba kernel behind :mod:`monitor.alignment`.

Private: :func:`monitor.alignment.align` validates its input and then calls this kernel,
which never validates and never raises. The pair measures are the box kernels' own scalar
IoU and RDD (:mod:`monitor.geometry._box_kernels`), one definition of each measure: a
Numba kernel can only call kernels, so kernel modules may use another package's kernels;
Python modules use only public names.
"""
from __future__ import annotations

from fuzzcore.jit import kernel
from monitor.geometry._box_kernels import iou_one, rdd_one


@kernel
def score_pairs(s, p, partner, alpha, beta, pair_iou, pair_rdd, matched):
    """Fill the per-S alignment table (M,) given each S's partner row in P (-1: none).

    An S without a partner gets IoU 0, RDD 1, not matched; a pair is matched when
    IoU > alpha and |RDD| < beta. Returns the sums over S of the scores (IoU where
    matched else 0, RDD where matched else 1).
    """
    iou_sum = 0.0
    rdd_sum = 0.0
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
        if matched[i]:
            iou_sum += pair_iou[i]
            rdd_sum += pair_rdd[i]
        else:
            rdd_sum += 1.0
    return iou_sum, rdd_sum
