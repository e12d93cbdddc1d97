"""Alignment of one frame: safety-critical objects S against the detector's predictions P.

FuzzRisk, Sec. III-A ("Measuring alignment with object detector predictions"): the
Hungarian algorithm pairs S with P on the distance between box centres; each pair gets
IoU and RDD; a pair counts only when ``IoU > alpha`` and ``|RDD| < beta``; an S without a
counted pair scores IoU = 0 and RDD = 1; the frame's features are the means over S,
IoU~ and RDD~. This is ``matching="hungarian"``.

``matching="coverage"`` asks of each S what USC asks of each ground truth: how much of it
the detections cover. The P that take part for an S are those not placed much farther
than it, ``RDD < beta`` (one-sided: a detection nearer than S is cautious, as USC's depth
ratio ``min(1, d_G / d_P)`` treats it); the S's overlap term is the share of its box inside
the union of their boxes (its IoG by the detections), its RDD that of the one overlapping
it most; it counts when that share is ``> alpha``. Unlike one-to-one pairs on box centres,
this is not thrown by a depth view that merges two neighbours into one object (each half
covered by its own detection) or splits one object into parts (each part inside the same
detection), which a view on an estimated depth map does all the time.

``weighting="inverse_distance"`` makes the features means weighted by ``1 / d`` of each S
(an object at 5 m counts four times one at 20 m: the nearer matters more to a car about
to reach it); ``"mean"`` is the paper's plain mean.

Which objects the means run over is ``objects``. ``"depth"`` is the paper's: the
safety-critical objects S. ``"known"`` takes every object either view knows of within
range, as the target 1 - USC~ takes every ground truth within range: each S no detection
covers (IoU 0, RDD 1, as in the paper) and each detection within ``max_range`` (or
partnering a counted S). A detection that counted S have as their partner is scored by
them (the largest of their IoU, the largest of their RDD: the depth view's word on it); one
that no counted S has, which the depth view did not see or saw outside its corridor, scores
IoU 1 and RDD 0, the detector's own word. The counted S themselves are not terms: their detections
stand for them. So a frame in which the detector sees nine cars and the depth view finds
one object it misses reads one unseen object in ten, where the paper's mean over S reads
one in one: the detector's objects, which the depth view only partly finds, say how many
objects the frame holds.

A frame without any object to average over (empty S; with ``"known"``, also no detection
within range) has no features: its means are NaN (:attr:`Alignment.n_terms` is 0). The
caller must check; the NaN is there so that forgetting to cannot produce a confident
number. (What the monitor reports for such a frame is its status ``no-objects``, see
:mod:`monitor.risk_monitor`.)
"""
from __future__ import annotations

import numbers
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from monitor import _alignment_kernels as _k
from monitor.geometry.boxes import DEFAULT_RANGE_M, as_boxes, centre_distances, check_range

#: The paper's matching thresholds (Table I, second row).
DEFAULT_ALPHA = 0.3
DEFAULT_BETA = 0.2
#: How the per-object terms become the frame's features: the paper's plain mean over S, or
#: the mean weighted by 1 / d (metres) of each S.
WEIGHTINGS = ("mean", "inverse_distance")
#: How S meets P: the paper's one-to-one pairs, or each S's coverage by the detections.
MATCHINGS = ("hungarian", "coverage")
#: Which objects IoU~ and RDD~ average over: the paper's S, or every object either view knows.
OBJECTS = ("depth", "known")


@dataclass(frozen=True, eq=False)
class Alignment:
    """The alignment of one frame: a per-S table and the frame features.

    Attributes
    ----------
    partner : ndarray of shape (M,), int64
        Row of P the Hungarian assignment gave to each row of S; -1 when it gave none
        (only when S has more rows than P). Coverage matching: the taking-part P that
        overlaps the S most, -1 when none overlaps it.
    pair_iou : ndarray of shape (M,), float64
        IoU of each S with its partner (0 where ``partner == -1``). Coverage matching: the
        share of the S's box inside the union of the taking-part detections (its IoG).
    pair_rdd : ndarray of shape (M,), float64
        RDD of each S with its partner, ``min(1, (d_P - d_S) / d_S)`` (1 where
        ``partner == -1``).
    matched : ndarray of shape (M,), bool
        The partner counts: ``pair_iou > alpha`` and ``|pair_rdd| < beta`` (coverage
        matching: ``pair_iou > alpha``, the depth test having chosen the P).
    iou_mean : float
        IoU~, the mean of the per-object terms (``objects``); NaN when there are none.
    rdd_mean : float
        RDD~, likewise.
    alpha, beta : float
        The thresholds used.
    matching : str
        One of :data:`MATCHINGS`.
    objects : str
        One of :data:`OBJECTS`: what the means run over.
    det_iou, det_rdd : ndarray of shape (N,), float64
        With ``objects="known"``, each detection's terms: the largest IoU and the largest
        RDD of the counted S partnering it, IoU 1 and RDD 0 where none does. Empty (0,)
        with ``"depth"``.
    det_counted : ndarray of shape (N,), bool
        With ``"known"``, the detections that are terms: within range, or partnering a
        counted S. Empty (0,) with ``"depth"``.
    """

    partner: np.ndarray
    pair_iou: np.ndarray
    pair_rdd: np.ndarray
    matched: np.ndarray
    iou_mean: float
    rdd_mean: float
    alpha: float
    beta: float
    matching: str = "hungarian"
    objects: str = "depth"
    det_iou: np.ndarray = field(default_factory=lambda: np.zeros(0))
    det_rdd: np.ndarray = field(default_factory=lambda: np.zeros(0))
    det_counted: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    @property
    def n_objects(self) -> int:
        """M, the number of safety-critical objects."""
        return self.partner.shape[0]

    @property
    def n_terms(self) -> int:
        """How many per-object terms IoU~ and RDD~ average: M with ``objects="depth"``;
        the S no detection covers plus the counted detections with ``"known"``."""
        if self.objects == "depth":
            return self.n_objects
        return int((~self.matched).sum() + self.det_counted.sum())

    @property
    def iou(self) -> np.ndarray:
        """(M,) per-S IoU score: ``pair_iou`` where matched, else 0."""
        return np.where(self.matched, self.pair_iou, 0.0)

    @property
    def rdd(self) -> np.ndarray:
        """(M,) per-S RDD score: ``pair_rdd`` where matched, else 1."""
        return np.where(self.matched, self.pair_rdd, 1.0)


def _assign(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    partner = np.full(a.shape[0], -1, dtype=np.int64)
    rows, cols = linear_sum_assignment(centre_distances(a, b))
    partner[rows] = cols
    return partner


def assign_by_centre(a, b) -> np.ndarray:
    """Hungarian assignment of the rows of ``a`` to the rows of ``b`` on centre distance.

    Minimises the summed Euclidean distance between paired box centres
    (``scipy.optimize.linear_sum_assignment``); ``min(n, m)`` pairs are formed.

    Parameters
    ----------
    a : array_like of shape (n, 5)
    b : array_like of shape (m, 5)
        Box arrays, rows ``cx, cy, w, h, d``.

    Returns
    -------
    ndarray of shape (n,), int64
        The row of ``b`` paired with each row of ``a``, -1 for a row left without one.
    """
    return _assign(as_boxes(a, "a"), as_boxes(b, "b"))


def check_thresholds(alpha, beta) -> tuple[float, float]:
    """Validate the matching thresholds (the one rule for them, also the configuration's).

    Parameters
    ----------
    alpha : real number in [0, 1]
        A pair counts only when its IoU is ``> alpha`` (1: no pair counts).
    beta : real number, finite and > 0
        A pair counts only when ``|RDD| < beta`` (RDD lies in [-1, 1], so beta > 1 drops
        the depth test).

    Returns
    -------
    (float, float)

    Raises
    ------
    ValueError
        Naming the threshold, its value and the rule (strings and booleans are refused).
    """
    for name, value in (("alpha", alpha), ("beta", beta)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ValueError(f"{name} = {value!r}, must be a number")
    alpha, beta = float(alpha), float(beta)
    if not 0.0 <= alpha <= 1.0:
        raise ValueError(f"alpha = {alpha!r}, expected an IoU threshold in [0, 1]")
    if not 0.0 < beta < np.inf:
        raise ValueError(f"beta = {beta!r}, expected a finite |RDD| threshold > 0")
    return alpha, beta


def check_weighting(weighting) -> str:
    """Validate the features' weighting (the one rule for it, also the configuration's)."""
    if weighting not in WEIGHTINGS:
        raise ValueError(f"weighting = {weighting!r}, must be one of {', '.join(WEIGHTINGS)}")
    return weighting


def check_matching(matching) -> str:
    """Validate how S meets P (the one rule for it, also the configuration's)."""
    if matching not in MATCHINGS:
        raise ValueError(f"matching = {matching!r}, must be one of {', '.join(MATCHINGS)}")
    return matching


def check_objects(objects, weighting) -> str:
    """Validate what the features average over (the one rule for it, also the
    configuration's). ``"known"`` takes the plain mean only: a detection's distance may be
    0 (a box around the ego origin), which has no inverse."""
    if objects not in OBJECTS:
        raise ValueError(f"objects = {objects!r}, must be one of {', '.join(OBJECTS)}")
    if objects == "known" and weighting != "mean":
        raise ValueError(f"objects = 'known' with weighting = {weighting!r}: the known objects "
                         "take the plain mean only (weighting: mean)")
    return objects


def align(S, P, alpha: float = DEFAULT_ALPHA, beta: float = DEFAULT_BETA,
          weighting: str = "mean", matching: str = "hungarian", objects: str = "depth",
          max_range: float = DEFAULT_RANGE_M) -> Alignment:
    """Align the safety-critical objects of one frame with the predictions.

    Parameters
    ----------
    S : array_like of shape (M, 5)
        Safety-critical objects, rows ``cx, cy, w, h, d``; ``d > 0`` metres (RDD divides
        by it).
    P : array_like of shape (N, 5)
        Predictions, rows ``cx, cy, w, h, d``; ``d >= 0`` metres.
    alpha : float
        A pair counts only when its IoU (coverage matching: the S's covered share) is
        ``> alpha``; in ``[0, 1]``.
    beta : float
        A pair counts only when ``|RDD| < beta`` (coverage matching: a P takes part only
        when ``RDD < beta``); ``> 0``.
    weighting : str
        One of :data:`WEIGHTINGS`: ``"mean"`` (the paper) or ``"inverse_distance"`` (each S
        weighted by ``1 / d``).
    matching : str
        One of :data:`MATCHINGS`: ``"hungarian"`` (the paper) or ``"coverage"`` (see the
        module docstring).
    objects : str
        One of :data:`OBJECTS`: ``"depth"`` (the paper: the means run over S) or
        ``"known"`` (over the S no detection covers and the detections within
        ``max_range``; see the module docstring). ``"known"`` needs ``weighting="mean"``.
    max_range : float
        Metres, > 0: with ``"known"``, the detections with ``d <= max_range`` are terms
        (:func:`monitor.geometry.boxes.check_range`).

    Returns
    -------
    Alignment
        ``iou_mean`` and ``rdd_mean`` are IoU~ and RDD~, NaN when there is no term (empty S;
        with ``"known"``, and no detection in range); empty P gives every S IoU 0 and RDD 1.

    Raises
    ------
    ValueError
        Invalid boxes (message names ``S`` or ``P``, the row and column), thresholds,
        weighting, matching, objects or range.
    """
    alpha, beta = check_thresholds(alpha, beta)
    weighting = check_weighting(weighting)
    matching = check_matching(matching)
    objects = check_objects(objects, weighting)
    max_range = check_range(max_range)
    S = as_boxes(S, "S", positive_depth=True)
    P = as_boxes(P, "P")
    m = S.shape[0]
    pair_iou = np.empty(m)
    pair_rdd = np.empty(m)
    matched = np.empty(m, dtype=np.bool_)
    if matching == "coverage":
        partner = np.empty(m, dtype=np.int64)
        _k.score_coverage(S, P, alpha, beta, partner, pair_iou, pair_rdd, matched)
    else:
        partner = _assign(S, P)
        _k.score_pairs(S, P, partner, alpha, beta, pair_iou, pair_rdd, matched)
    if objects == "known":
        det_iou, det_rdd, det_counted = _detection_terms(P, partner, pair_iou, pair_rdd,
                                                         matched, max_range)
        unseen = ~matched
        n = int(unseen.sum() + det_counted.sum())
        iou_mean = float(det_iou[det_counted].sum()) / n if n else float("nan")
        rdd_mean = float(unseen.sum() + det_rdd[det_counted].sum()) / n if n else float("nan")
        return Alignment(partner, pair_iou, pair_rdd, matched, iou_mean, rdd_mean, alpha, beta,
                         matching, objects, det_iou, det_rdd, det_counted)
    scored_iou, scored_rdd = np.where(matched, pair_iou, 0.0), np.where(matched, pair_rdd, 1.0)
    if m == 0:
        iou_mean = rdd_mean = float("nan")
    elif weighting == "inverse_distance":
        w = 1.0 / S[:, 4]
        iou_mean, rdd_mean = float(w @ scored_iou / w.sum()), float(w @ scored_rdd / w.sum())
    else:
        iou_mean, rdd_mean = float(scored_iou.mean()), float(scored_rdd.mean())
    return Alignment(partner, pair_iou, pair_rdd, matched, iou_mean, rdd_mean, alpha, beta, matching)


def _detection_terms(P: np.ndarray, partner: np.ndarray, pair_iou: np.ndarray,
                     pair_rdd: np.ndarray, matched: np.ndarray, max_range: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each detection's IoU and RDD terms and whether it is one (``objects="known"``):
    (N,) float64, (N,) float64, (N,) bool; see :attr:`Alignment.det_iou`."""
    n = P.shape[0]
    counted_pairs = matched & (partner >= 0)
    rows = partner[counted_pairs]
    seen = np.zeros(n, dtype=bool)
    seen[rows] = True
    det_iou = np.full(n, -np.inf)
    det_rdd = np.full(n, -np.inf)
    np.maximum.at(det_iou, rows, pair_iou[counted_pairs])
    np.maximum.at(det_rdd, rows, pair_rdd[counted_pairs])
    det_iou[~seen], det_rdd[~seen] = 1.0, 0.0
    return det_iou, det_rdd, (P[:, 4] <= max_range) | seen


def warmup() -> None:
    """Compile (or load from the cache) every kernel :func:`align` uses.

    Call once before a real-time loop so that its first frame does not pay the compile.
    """
    S = np.array([[10.0, 10.0, 4.0, 4.0, 5.0], [30.0, 10.0, 4.0, 4.0, 8.0]])
    for matching in MATCHINGS:
        align(S, S[:1], matching=matching)
