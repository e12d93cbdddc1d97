"""Ground-truth score of one frame: USC~ and the training target 1 - USC~.

FuzzRisk, Sec. III-B: ``USC(P, G) = IoG(P, G) * DR(d_P, d_G)``; the frame score USC~ is
the mean over the ground truths G within the range limit (20 m by default), a G without
a prediction scoring 0; the FIS is trained towards ``1 - USC~``.

Pairing (the paper does not say how each G finds its P): the Hungarian assignment on
centre distance, as in :func:`monitor.alignment.align` (:func:`assign_by_centre`), of the
G within range against every P. P is not range-filtered, so a prediction placed too far
away still covers its object, at the price DR puts on its distance. There are no matching
thresholds: a poor partner already scores low through IoG and DR.

A frame without any G within range has no target: status :data:`NO_TARGETS` and NaN
``usc_mean`` / ``target``, never a risk of 0.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from monitor.geometry import boxes
from monitor.alignment import assign_by_centre
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
        Row of P paired with each of them, -1 for none (more G in range than P).
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
    partner = assign_by_centre(G, P)
    has = partner >= 0
    iog = np.zeros(G.shape[0])
    dr = np.zeros(G.shape[0])
    paired_p, paired_g = P[partner[has]], G[has]
    iog[has] = boxes.iog(paired_p, paired_g)
    dr[has] = boxes.depth_ratio(paired_p[:, 4], paired_g[:, 4])
    usc = iog * dr
    usc_mean = float(usc.mean()) if usc.size else float("nan")
    return GroundTruthScore(g_index, partner, iog, dr, usc, usc_mean, float(max_range))
