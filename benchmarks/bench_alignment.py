"""Alignment of one frame, 50 S against 50 P (target: <= 50 us per frame).

Run: ``python -m pytest benchmarks/bench_alignment.py --benchmark-only -q``

Peers in the same run, on the same frame, answers checked before timing:

- ``lsa_only``: ``scipy.optimize.linear_sum_assignment`` on a precomputed cost matrix, the
  floor no implementation of the paper's alignment can go under;
- ``reference_loop``: ``scipy.spatial.distance.cdist`` + the assignment + a Python loop
  over the pairs (the straightforward implementation);
- ``reference_numpy``: the same with the pair measures vectorised in NumPy;
- ``align_coverage``: coverage matching (each S's share inside the union of the
  detections' boxes, exact; ``monitor.alignment``), means over S, against the paper's pairs
  above;
- ``align_known``: the monitor's defaults, coverage with the means over the known objects
  (the S no detection covers and the detections within 20 m).
"""
import time

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from monitor import alignment

ALPHA, BETA = 0.3, 0.2


def _frame(seed=2025, n=50):
    """50 objects and 50 predictions: 40 predictions near an object, 10 elsewhere."""
    rng = np.random.default_rng(seed)
    S = np.column_stack([rng.uniform(0, 1600, n), rng.uniform(300, 900, n),
                         rng.uniform(20, 300, n), rng.uniform(20, 200, n),
                         rng.uniform(1, 20, n)])
    P = S * rng.uniform(0.9, 1.1, S.shape)
    P[:, :2] = S[:, :2] + rng.normal(0, 8, (n, 2))
    P[40:] = np.column_stack([rng.uniform(0, 1600, 10), rng.uniform(300, 900, 10),
                              rng.uniform(20, 300, 10), rng.uniform(20, 200, 10),
                              rng.uniform(1, 30, 10)])
    return S, P[rng.permutation(n)]


S, P = _frame()


def reference_loop(S, P, alpha=ALPHA, beta=BETA):
    iou = np.zeros(len(S))
    rdd = np.ones(len(S))
    rows, cols = linear_sum_assignment(cdist(S[:, :2], P[:, :2]))
    for i, j in zip(rows, cols):
        s, p = S[i], P[j]
        iw = max(0.0, min(s[0] + s[2] / 2, p[0] + p[2] / 2) - max(s[0] - s[2] / 2, p[0] - p[2] / 2))
        ih = max(0.0, min(s[1] + s[3] / 2, p[1] + p[3] / 2) - max(s[1] - s[3] / 2, p[1] - p[3] / 2))
        v = iw * ih / (s[2] * s[3] + p[2] * p[3] - iw * ih)
        r = min(1.0, (p[4] - s[4]) / s[4])
        if v > alpha and abs(r) < beta:
            iou[i], rdd[i] = v, r
    return iou.mean(), rdd.mean()


def reference_numpy(S, P, alpha=ALPHA, beta=BETA):
    rows, cols = linear_sum_assignment(cdist(S[:, :2], P[:, :2]))
    s, p = S[rows], P[cols]
    iw = np.clip(np.minimum(s[:, 0] + s[:, 2] / 2, p[:, 0] + p[:, 2] / 2)
                 - np.maximum(s[:, 0] - s[:, 2] / 2, p[:, 0] - p[:, 2] / 2), 0, None)
    ih = np.clip(np.minimum(s[:, 1] + s[:, 3] / 2, p[:, 1] + p[:, 3] / 2)
                 - np.maximum(s[:, 1] - s[:, 3] / 2, p[:, 1] - p[:, 3] / 2), 0, None)
    v = iw * ih / (s[:, 2] * s[:, 3] + p[:, 2] * p[:, 3] - iw * ih)
    r = np.minimum(1.0, (p[:, 4] - s[:, 4]) / s[:, 4])
    keep = (v > alpha) & (np.abs(r) < beta)
    iou = np.zeros(len(S))
    rdd = np.ones(len(S))
    iou[rows[keep]], rdd[rows[keep]] = v[keep], r[keep]
    return iou.mean(), rdd.mean()


def ours(S, P):
    a = alignment.align(S, P, ALPHA, BETA)
    return a.iou_mean, a.rdd_mean


@pytest.fixture(scope="module")
def warm_up_seconds():
    start = time.perf_counter()
    alignment.warmup()  # compiles the kernels, or loads them from numba's cache
    return time.perf_counter() - start


def _check_answers():
    """Every implementation gives the same IoU~ and RDD~ on the benchmark frame."""
    expected = reference_loop(S, P)
    assert 10 < alignment.align(S, P, ALPHA, BETA).matched.sum() < 50  # both kinds of pair
    np.testing.assert_allclose(ours(S, P), expected, rtol=1e-12)
    np.testing.assert_allclose(reference_numpy(S, P), expected, rtol=1e-12)


@pytest.mark.benchmark(group="align 50 S x 50 P", warmup=True)
def test_align(benchmark, warm_up_seconds):
    benchmark.extra_info["warm_up_s"] = warm_up_seconds
    _check_answers()
    benchmark(ours, S, P)


@pytest.mark.benchmark(group="align 50 S x 50 P", warmup=True)
def test_align_coverage(benchmark, warm_up_seconds):
    a = alignment.align(S, P, ALPHA, 1.0, matching="coverage")
    # 40 predictions lie on their objects: those objects are mostly covered
    assert 30 < a.matched.sum() <= 50 and np.all((a.pair_iou >= 0) & (a.pair_iou <= 1))
    benchmark(alignment.align, S, P, ALPHA, 1.0, "mean", "coverage")


@pytest.mark.benchmark(group="align 50 S x 50 P", warmup=True)
def test_align_known(benchmark, warm_up_seconds):
    a = alignment.align(S, P, ALPHA, 1.0, matching="coverage", objects="known", max_range=20.0)
    # the detections within 20 m, and those beyond partnering a counted S, are terms
    partners = np.zeros(len(P), bool)
    partners[a.partner[a.matched & (a.partner >= 0)]] = True
    np.testing.assert_array_equal(a.det_counted, (P[:, 4] <= 20.0) | partners)
    assert 0 < (P[:, 4] > 20.0).sum() and a.n_terms == (~a.matched).sum() + a.det_counted.sum()
    benchmark(alignment.align, S, P, ALPHA, 1.0, "mean", "coverage", "known", 20.0)


@pytest.mark.benchmark(group="align 50 S x 50 P", warmup=True)
def test_reference_loop(benchmark):
    _check_answers()
    benchmark(reference_loop, S, P)


@pytest.mark.benchmark(group="align 50 S x 50 P", warmup=True)
def test_reference_numpy(benchmark):
    _check_answers()
    benchmark(reference_numpy, S, P)


@pytest.mark.benchmark(group="align 50 S x 50 P", warmup=True)
def test_lsa_only(benchmark):
    cost = cdist(S[:, :2], P[:, :2])
    rows, cols = linear_sum_assignment(cost)
    np.testing.assert_array_equal(alignment.align(S, P).partner[rows], cols)
    benchmark(linear_sum_assignment, cost)
