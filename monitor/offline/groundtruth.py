"""Ground-truth score of one frame: USC~ and the training target 1 - USC~.

FuzzRisk, Sec. III-B: ``USC(P, G) = IoG(P, G) * DR(d_P, d_G)``; the frame score USC~ is
the mean over the ground truths G within the range limit (20 m by default), a G without
a prediction scoring 0; the FIS is trained towards ``1 - USC~``.

Pairing (the paper does not say how each G finds its P): one prediction per ground truth,
the one-to-one assignment of the G within range to the P that maximises the summed USC
(the Hungarian algorithm on USC itself). A G that none of the predictions left for it
covers scores 0. P is not range-filtered, so a prediction placed too far away still covers its object, at
the price DR puts on its distance. There are no matching thresholds: a poor partner already
scores low through IoG and DR.

An assignment on box-centre distance instead (the paper's pairing of S and P) minimises the
summed distance over every G, the uncovered ones too, so a G that no prediction covers can
take a well-placed prediction from the G it lies on when that shortens the sum. In the
held-out frames of ``fuzzrisk eval``'s default benchmark it gave 227 of the 6,265 ground
truths (3.6 %) a USC of 0 although a detection covers them with a USC above 0.8, and it
moved 9 % of them by more than 0.1 (docs/risk-quality.md).

A frame without any G within range has no target: status :data:`NO_TARGETS` and NaN
``usc_mean`` / ``target``, never a risk of 0.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from monitor.geometry import boxes
from monitor.geometry.boxes import DEFAULT_RANGE_M, as_boxes, range_mask

#: :attr:`GroundTruthScore.status` of a frame with at least one G within range.
OK = "ok"
#: :attr:`GroundTruthScore.status` of a frame with no G within range: no target.
NO_TARGETS = "no-targets"


@dataclass(frozen=True, eq=False)
class GroundTruthScore:
    """USC of every ground truth within range in one frame, and the frame's target.

    Attributes
    ----------
    g_index : ndarray of shape (K,), int64
        Rows of G within range (``d <= max_range``), in order.
    partner : ndarray of shape (K,), int64
        Row of P paired with each of them, -1 where none covers it (USC 0 with every P
        the assignment left for it).
    iog : ndarray of shape (K,), float64
        IoG of the partner (0 where ``partner == -1``).
    depth_ratio : ndarray of shape (K,), float64
        DR ``min(1, d_G / d_P)`` of the partner (0 where ``partner == -1``).
    usc : ndarray of shape (K,), float64
        ``iog * depth_ratio``.
    usc_mean : float
        USC~, the mean of :attr:`usc`; NaN when K = 0.
    max_range : float
        The range limit used, metres.
    """

    g_index: np.ndarray
    partner: np.ndarray
    iog: np.ndarray
    depth_ratio: np.ndarray
    usc: np.ndarray
    usc_mean: float
    max_range: float

    @property
    def n_targets(self) -> int:
        """K, the number of ground truths within range."""
        return self.g_index.shape[0]

    @property
    def status(self) -> str:
        """:data:`OK`, or :data:`NO_TARGETS` when no G is within range (then NaN scores)."""
        return OK if self.n_targets else NO_TARGETS

    @property
    def target(self) -> float:
        """The training target ``1 - USC~``; NaN when no G is within range."""
        return 1.0 - self.usc_mean


def score(P, G, max_range: float = DEFAULT_RANGE_M) -> GroundTruthScore:
    """Score the predictions of one frame against its ground truths.

    Parameters
    ----------
    P : array_like of shape (N, 5)
        Predictions, rows ``cx, cy, w, h, d`` (pixels, metres).
    G : array_like of shape (L, 5)
        Ground truths, same rows; each with ``w > 0`` and ``h > 0`` (IoG divides by the
        area).
    max_range : float
        Only G with ``d <= max_range`` metres count (:func:`monitor.geometry.boxes.range_mask`).

    Returns
    -------
    GroundTruthScore

    Raises
    ------
    ValueError
        Invalid boxes (message names ``P`` or ``G``) or range.
    """
    P = as_boxes(P, "P")
    G = as_boxes(G, "G", positive_area=True)
    g_index = np.flatnonzero(range_mask(G, max_range))
    G = G[g_index]
    k = G.shape[0]
    partner = np.full(k, -1, dtype=np.int64)
    iog = np.zeros(k)
    dr = np.zeros(k)
    if k and P.shape[0]:
        pair_iog = boxes.iog(P[None, :, :], G[:, None, :])  # (K, N)
        pair_dr = boxes.depth_ratio(P[None, :, 4], G[:, None, 4])
        rows, cols = linear_sum_assignment(pair_iog * pair_dr, maximize=True)
        covers = pair_iog[rows, cols] * pair_dr[rows, cols] > 0.0
        rows, cols = rows[covers], cols[covers]
        partner[rows], iog[rows], dr[rows] = cols, pair_iog[rows, cols], pair_dr[rows, cols]
    usc = iog * dr
    usc_mean = float(usc.mean()) if usc.size else float("nan")
    return GroundTruthScore(g_index, partner, iog, dr, usc, usc_mean, float(max_range))
