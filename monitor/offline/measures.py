"""Quality measures of the monitor as a safety engineer reads them: the risk against the truth.

The paper's Tables I-III (:mod:`monitor.offline.evaluation`) say how well the two views
agree; the measures here say whether the risk the monitor reports carries the information
it exists to carry. Every frame counts, with the risk the monitor reported (a
``no-objects`` or ``invalid-input`` frame with its configured risk), so the numbers are
what a car would see.

Per frame (:func:`frame_truth`, independent of the rule base):

- the target ``1 - USC~`` (NaN when no ground truth is within range);
- *hazard*: some ground truth G within range is covered by no detection P, where P covers
  G when ``IoG(P, G) > min_iog`` and ``DR(d_P, d_G) = min(1, d_G / d_P) > min_dr``
  (:class:`HazardCriterion`, defaults 0.5 and 0.8: the detector missed it, or placed it
  more than 25 % too far);
- the depth view against the ground truth within range. Recall: a G is *found* when some
  S has ``IoG(S, G) > min_iog`` and a depth within the band, ``min(d_S, d_G) / max(d_S,
  d_G) > min_dr`` (too near is as wrong as too far for a depth view). Precision: an S is
  *on* a G when ``area(S & G) / area(S) > min_iog`` (intersection over S, so a box that is
  mostly wall, pole or road is not on a G however much of the G it covers) with a depth in
  the same band;
- *hazard in view*: some G that no detection covers is found by the depth view. Only then
  does the frame hold evidence of what the detector missed; in the other hazard frames an
  alarm rests on something else the frame holds;
- the monitor's status.

Over frames (:func:`risk_quality` for one predictor's risks, :func:`depth_view_quality`):

- Pearson and Spearman r(risk, target), RMSE and skill ``1 - RMSE / RMSE_0``, where
  ``RMSE_0`` is the RMSE of the constant predictor that always says the *training*
  targets' mean (frames with a target only);
- AUROC (the Mann-Whitney U statistic, ties counted 1/2, as scipy and scikit-learn do) and
  AUPRC (average precision, scikit-learn's step-wise sum) of the risk for hazard frames;
- hit rate and false-alarm rate at the shield threshold (an alarm is ``risk > threshold``),
  the hit rate and the AUROC on the hazard frames in view alone against the hazard-free
  ones (what the risk makes of the evidence it has: the AUROC over all hazard frames is
  the in-view share times the AUROC in view plus the rest times the AUROC out of view), and
  the false-positive rates at 80 % and 95 % true-positive rate (the lowest FPR of any
  threshold reaching that TPR: at 80 %, the false alarms at an 80 % hit rate, whatever the
  shield's threshold);
- the share of frames per status; the depth view's recall and precision; the share of
  hazard frames in view, the highest hit rate that evidence of the missed objects allows.

A measure that is undefined on the frames given (no hazard frame, no non-hazard frame,
fewer than three targets, a constant risk for a correlation) is NaN, and the result's
``notes`` say why: never a plausible 0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.stats import rankdata

from monitor.geometry import boxes
from monitor.offline.evaluation import Observation
from monitor.risk_monitor import INVALID_INPUT, OK, STATUSES


@dataclass(frozen=True)
class HazardCriterion:
    """When a box covers a ground truth (see the module docstring).

    Attributes
    ----------
    min_iog : float in [0, 1)
        Coverage needed: ``IoG > min_iog`` (intersection over S for the depth view's
        precision).
    min_dr : float in [0, 1)
        Depth agreement needed: ``DR > min_dr`` for detections, the symmetric ratio
        ``min / max > min_dr`` for the depth view.
    """

    min_iog: float = 0.5
    min_dr: float = 0.8

    def __post_init__(self):
        for name in ("min_iog", "min_dr"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value < 1.0:
                raise ValueError(f"{name} = {value!r}, must be a number in [0, 1)")


@dataclass(frozen=True)
class FrameTruth:
    """What the ground truth says about one frame (the same for every rule base).

    Attributes
    ----------
    condition : str
    status : str
        The monitor's status of the frame.
    target : float
        ``1 - USC~``; NaN when no ground truth is within range.
    hazard : bool
        A ground truth within range that no detection covers.
    gts : int
        Ground truths within range.
    found : int
        Of those, how many the depth view finds.
    objects : int
        Depth-view objects S (0 for an invalid frame: there was no depth view).
    on_truth : int
        Of those, how many lie on a ground truth.
    hazard_in_view : bool
        A ground truth within range that no detection covers is found by the depth view.
    """

    condition: str
    status: str
    target: float
    hazard: bool
    gts: int
    found: int
    objects: int
    on_truth: int
    hazard_in_view: bool


def _pairwise(kernel, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(len(a), len(b)) ``kernel(a_i, b_j)`` over box rows."""
    if len(a) == 0 or len(b) == 0:
        return np.zeros((len(a), len(b)))
    return np.asarray(kernel(a[:, None, :], b[None, :, :])).reshape(len(a), len(b))


def _depth_band(d_a: np.ndarray, d_b: np.ndarray) -> np.ndarray:
    """(len(a), len(b)) symmetric depth ratio ``min / max`` (1 for two zeros)."""
    lo = np.minimum(d_a[:, None], d_b[None, :])
    hi = np.maximum(d_a[:, None], d_b[None, :])
    return np.divide(lo, hi, out=np.ones_like(hi), where=hi > 0)


def coverage(P: np.ndarray, S: np.ndarray, G: np.ndarray, criterion: HazardCriterion
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which ground truths the detections cover, which the depth view finds, which S are on one.

    Parameters
    ----------
    P, S, G : ndarray of shape (n, 5), (m, 5), (k, 5)
        Detections, depth-view objects and ground truths within range, rows
        ``cx, cy, w, h, d`` (pixels, metres); G with positive areas.
    criterion : HazardCriterion

    Returns
    -------
    covered : ndarray of shape (k,), bool
        Some P covers the G (IoG and DR).
    found : ndarray of shape (k,), bool
        Some S covers the G (IoG and the symmetric depth band).
    on_truth : ndarray of shape (m,), bool
        The S lies on some G (intersection over S and the depth band); an S of zero
        area lies on nothing.
    """
    P = boxes.as_boxes(P, "P")
    S = boxes.as_boxes(S, "S")
    G = boxes.as_boxes(G, "G", positive_area=True)
    dr = (np.asarray(boxes.depth_ratio(P[:, None, 4], G[None, :, 4])).reshape(len(P), len(G))
          if len(P) and len(G) else np.zeros((len(P), len(G))))
    covered = ((_pairwise(boxes.iog, P, G) > criterion.min_iog) & (dr > criterion.min_dr)).any(axis=0)
    band = _depth_band(S[:, 4], G[:, 4]) > criterion.min_dr
    found = ((_pairwise(boxes.iog, S, G) > criterion.min_iog) & band).any(axis=0)
    area = S[:, 2] * S[:, 3] > 0
    on_truth = np.zeros(len(S), dtype=bool)
    if area.any() and len(G):
        ios = _pairwise(boxes.iog, G, S[area]).T  # area(G & S) / area(S)
        on_truth[area] = ((ios > criterion.min_iog) & band[area]).any(axis=1)
    return covered, found, on_truth


def frame_truth(ob: Observation, criterion: HazardCriterion = HazardCriterion()) -> FrameTruth:
    """The ground truth's view of one observed frame (see :class:`FrameTruth`)."""
    G = ob.G[ob.truth.g_index]  # within range
    S = ob.report.S if ob.report.status != INVALID_INPUT else np.zeros((0, 5))
    covered, found, on_truth = coverage(ob.P, S, G, criterion)
    return FrameTruth(ob.condition, ob.report.status, ob.target, bool((~covered).any()), len(G),
                      int(found.sum()), len(S), int(on_truth.sum()), bool((~covered & found).any()))


def rule_base_risk(observations: Sequence[Observation], fis, fail_safe_risk: float) -> np.ndarray:
    """The risk a monitor running ``fis`` would report on each observed frame.

    ``ok`` frames get ``fis`` at their features; other frames keep the risk the monitor
    reported (the configured no-objects or fail-safe risk: no rule base is consulted). A
    rule base that gives NaN makes the frame invalid, hence ``fail_safe_risk``, as the
    monitor does.

    Returns
    -------
    ndarray of shape (n_frames,), float64
    """
    risk = np.array([ob.report.risk for ob in observations], dtype=np.float64)
    ok = np.array([ob.report.status == OK for ob in observations], dtype=bool)
    if ok.any():
        feats = {k: np.array([getattr(ob.report, k) for ob, o in zip(observations, ok) if o])
                 for k in ("iou", "rdd")}
        risk[ok] = np.asarray(fis.infer(**feats), dtype=np.float64)
    return np.where(np.isfinite(risk), risk, fail_safe_risk)


# --- measures on arrays ------------------------------------------------------------------

def pearson(x, y) -> float:
    """Pearson r of two equally long 1-D arrays; NaN for fewer than 3 values or a constant."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if x.size < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return float("nan")
    x, y = x - x.mean(), y - y.mean()
    return float(np.sum(x * y) / math.sqrt(np.sum(x * x) * np.sum(y * y)))


def spearman(x, y) -> float:
    """Spearman's rho: Pearson r of the ranks, ties given their average rank (as scipy)."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if x.size < 3:
        return float("nan")
    return pearson(rankdata(x), rankdata(y))


def rmse(pred, target) -> float:
    """Root mean squared error; NaN for no values."""
    err = np.asarray(pred, dtype=np.float64) - np.asarray(target, dtype=np.float64)
    return float(np.sqrt(np.mean(err ** 2))) if err.size else float("nan")


def skill(pred, target, reference: float) -> float:
    """``1 - RMSE(pred) / RMSE(constant reference)``: 0 for the constant, 1 for perfect.

    NaN when there are no values or the constant is already exact.
    """
    base = rmse(np.full(np.shape(target), reference), target)
    if not base > 0:
        return float("nan")
    return 1.0 - rmse(pred, target) / base


def _two_classes(scores, labels) -> tuple[np.ndarray, np.ndarray]:
    scores = np.asarray(scores, dtype=np.float64)
    labels = np.asarray(labels, dtype=bool)
    if scores.shape != labels.shape or scores.ndim != 1:
        raise ValueError(f"scores and labels have shapes {scores.shape} and {labels.shape}; "
                         "expected two 1-D arrays of the same length")
    if not np.all(np.isfinite(scores)):
        raise ValueError("scores must be finite")
    return scores, labels


def auroc(scores, labels) -> float:
    """Area under the ROC curve: ``U / (n_pos n_neg)``, U the Mann-Whitney statistic with
    ties counted 1/2. NaN when a class is missing."""
    scores, labels = _two_classes(scores, labels)
    n_pos = int(labels.sum())
    n_neg = labels.size - n_pos
    if n_pos == 0 or n_neg == 0:
        return float("nan")
    ranks = rankdata(scores)
    u = ranks[labels].sum() - n_pos * (n_pos + 1) / 2
    return float(u / (n_pos * n_neg))


def roc_curve(scores, labels) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """False- and true-positive rates of ``score >= t`` for every distinct score t.

    Returns
    -------
    fpr, tpr : ndarray of shape (k + 1,)
        From (0, 0) (threshold above every score) to (1, 1); NaN when a class is missing.
    thresholds : ndarray of shape (k + 1,)
        Decreasing; the first is ``inf``.
    """
    scores, labels = _two_classes(scores, labels)
    order = np.argsort(-scores, kind="stable")
    s, y = scores[order], labels[order]
    last = np.r_[np.flatnonzero(np.diff(s)), s.size - 1]  # last index of each distinct score
    tp = np.r_[0, np.cumsum(y)[last]]
    fp = np.r_[0, np.cumsum(~y)[last]]
    n_pos, n_neg = tp[-1], fp[-1]
    with np.errstate(invalid="ignore", divide="ignore"):
        return (fp / n_neg if n_neg else np.full(fp.shape, np.nan),
                tp / n_pos if n_pos else np.full(tp.shape, np.nan), np.r_[np.inf, s[last]])


def auprc(scores, labels) -> float:
    """Average precision, ``sum_k (R_k - R_(k-1)) P_k`` over the distinct scores in
    decreasing order (scikit-learn's ``average_precision_score``). NaN without positives."""
    scores, labels = _two_classes(scores, labels)
    if not labels.any():
        return float("nan")
    order = np.argsort(-scores, kind="stable")
    s, y = scores[order], labels[order]
    last = np.r_[np.flatnonzero(np.diff(s)), s.size - 1]
    tp = np.cumsum(y)[last]
    precision = tp / (last + 1)
    recall = tp / tp[-1]
    return float(np.sum(np.diff(np.r_[0.0, recall]) * precision))


def fpr_at_tpr(scores, labels, tpr: float = 0.95) -> float:
    """The lowest false-positive rate of a threshold whose true-positive rate is >= ``tpr``."""
    fpr_, tpr_, _ = roc_curve(scores, labels)
    if not np.isfinite(fpr_).all() or not np.isfinite(tpr_).all():
        return float("nan")
    return float(fpr_[tpr_ >= tpr - 1e-12].min())


def alarm_rates(scores, labels, threshold: float) -> tuple[float, float]:
    """(hit rate, false-alarm rate) of ``score > threshold``; NaN for a missing class."""
    scores, labels = _two_classes(scores, labels)
    alarm = scores > threshold
    hit = float(alarm[labels].mean()) if labels.any() else float("nan")
    false = float(alarm[~labels].mean()) if (~labels).any() else float("nan")
    return hit, false


def core_measures(risk: np.ndarray, target: np.ndarray, hazard: np.ndarray, reference: float,
                  threshold: float) -> dict:
    """``pearson, rmse, skill`` of the risk against the target on the frames with one, and
    ``auroc, hit_rate, false_alarm_rate, fpr80`` for the hazard frames on all
    (:func:`risk_quality` adds the rest; :mod:`monitor.offline.bootstrap` resamples these)."""
    has = np.isfinite(target)
    hit, false = alarm_rates(risk, hazard, threshold)
    return {"pearson": pearson(risk[has], target[has]), "rmse": rmse(risk[has], target[has]),
            "skill": skill(risk[has], target[has], reference), "auroc": auroc(risk, hazard),
            "hit_rate": hit, "false_alarm_rate": false,
            "fpr80": fpr_at_tpr(risk, hazard, 0.80) if risk.size else float("nan")}


# --- tables ------------------------------------------------------------------------------

def risk_quality(risk, truth: Sequence[FrameTruth], reference: float, threshold: float) -> dict:
    """Every risk measure of one predictor on some frames.

    Parameters
    ----------
    risk : array_like of shape (n,)
        The predictor's risk per frame, finite.
    truth : sequence of n FrameTruth
    reference : float
        The constant predictor's value: the training targets' mean.
    threshold : float
        The shield's threshold; an alarm is ``risk > threshold``.

    Returns
    -------
    dict
        ``frames, targets, hazards, pearson, spearman, rmse, skill, auroc, auroc_in_view``
        (the hazard frames in view against the hazard-free ones), ``auprc, hit_rate,
        hit_in_view`` (the hit rate on the hazard frames in view), ``false_alarm_rate,
        fpr80, fpr95, alarm_rate`` and ``notes`` (why a measure is NaN; "" when none is).
    """
    risk = np.asarray(risk, dtype=np.float64)
    if risk.shape != (len(truth),):
        raise ValueError(f"risk has shape {risk.shape}, expected ({len(truth)},): one per frame")
    target = np.array([t.target for t in truth], dtype=np.float64)
    hazard = np.array([t.hazard for t in truth], dtype=bool)
    in_view = np.array([t.hazard_in_view for t in truth], dtype=bool)
    has = np.isfinite(target)
    notes = []
    if has.sum() < 3:
        notes.append(f"{int(has.sum())} frames with a target: no correlation")
    elif np.ptp(risk[has]) == 0:
        notes.append("constant risk: no correlation")
    if not hazard.any():
        notes.append("no hazard frame: no AUROC, AUPRC, hit rate or FPR at a TPR")
    elif not in_view.any():
        notes.append("no hazard frame in view: no hit rate or AUROC in view")
    if hazard.all():
        notes.append("only hazard frames: no AUROC (nor in view), false-alarm rate or FPR at a TPR")
    core = core_measures(risk, target, hazard, reference, threshold)
    return {
        "frames": int(risk.size), "targets": int(has.sum()), "hazards": int(hazard.sum()),
        "pearson": core["pearson"], "spearman": spearman(risk[has], target[has]),
        "rmse": core["rmse"], "skill": core["skill"], "auroc": core["auroc"],
        "auroc_in_view": auroc(risk[in_view | ~hazard], in_view[in_view | ~hazard]),
        "auprc": auprc(risk, hazard) if risk.size else float("nan"),
        "hit_rate": core["hit_rate"],
        "hit_in_view": float(np.mean(risk[in_view] > threshold)) if in_view.any() else float("nan"),
        "false_alarm_rate": core["false_alarm_rate"],
        "fpr80": core["fpr80"],
        "fpr95": fpr_at_tpr(risk, hazard) if risk.size else float("nan"),
        "alarm_rate": float(np.mean(risk > threshold)) if risk.size else float("nan"),
        "notes": "; ".join(notes),
    }


def depth_view_quality(truth: Sequence[FrameTruth]) -> dict:
    """The depth view's recall and precision of ground truth within range, the share of
    hazard frames in view (``hazards_in_view``, NaN without a hazard frame) and the share
    of frames per status (each of :data:`monitor.risk_monitor.STATUSES`)."""
    gts = sum(t.gts for t in truth)
    objects = sum(t.objects for t in truth)
    hazards = sum(t.hazard for t in truth)
    n = len(truth)
    out = {"frames": n, "gts": gts, "objects": objects,
           "recall": sum(t.found for t in truth) / gts if gts else float("nan"),
           "precision": sum(t.on_truth for t in truth) / objects if objects else float("nan"),
           "hazards_in_view": sum(t.hazard_in_view for t in truth) / hazards if hazards else float("nan")}
    for status in STATUSES:
        out[status] = sum(t.status == status for t in truth) / n if n else float("nan")
    return out


def training_mean(train: Sequence[FrameTruth], test: Sequence[FrameTruth]) -> tuple[float, str]:
    """The constant predictor's value, and a sentence saying where it comes from.

    The mean target of the training frames; when there are none with a target (scenes on
    disk have no split), the test frames' own mean, which the sentence says (it flatters
    the constant, so skill is harder to earn).
    """
    values = np.array([t.target for t in train], dtype=np.float64)
    values = values[np.isfinite(values)]
    if values.size:
        return float(values.mean()), f"the mean target of {values.size} training frames"
    values = np.array([t.target for t in test], dtype=np.float64)
    values = values[np.isfinite(values)]
    if values.size:
        return float(values.mean()), (f"no training frames: the mean target of the {values.size} "
                                      "evaluated frames themselves (flatters the constant)")
    return float("nan"), "no frame has a target"


def quality_tables(observations: Sequence[Observation], truth: Sequence[FrameTruth], systems: dict,
                   reference: float, threshold: float, fail_safe_risk: float
                   ) -> tuple[list[dict], list[dict], dict]:
    """The headline tables, per condition (in order of appearance) and over all frames.

    Parameters
    ----------
    observations : sequence of Observation
    truth : sequence of FrameTruth
        :func:`frame_truth` of each observation.
    systems : dict of str -> FuzzySystem
        Rule bases to measure (inputs ``iou`` and ``rdd``).
    reference : float
        The constant predictor's value (:func:`training_mean`).
    threshold, fail_safe_risk : float
        The shield threshold; the risk of a frame a rule base gives NaN.

    Returns
    -------
    risk_rows : list of dict
        :func:`risk_quality` with ``condition`` and ``predictor``, the constant predictor
        first in each condition (left out when ``reference`` is NaN).
    depth_rows : list of dict
        :func:`depth_view_quality` with ``condition``.
    risks : dict of str -> ndarray of shape (n_frames,)
        Each predictor's risk per observation.
    """
    if len(observations) != len(truth):
        raise ValueError(f"{len(observations)} observations but {len(truth)} FrameTruth; expected one each")
    risks = {}
    if np.isfinite(reference):
        risks[f"constant {reference:.3f}"] = np.full(len(observations), reference)
    risks.update({name: rule_base_risk(observations, fis, fail_safe_risk) for name, fis in systems.items()})
    conditions = list(dict.fromkeys(ob.condition for ob in observations))
    groups = [(c, np.array([ob.condition == c for ob in observations], dtype=bool)) for c in conditions]
    groups.append(("all", np.ones(len(observations), dtype=bool)))
    risk_rows, depth_rows = [], []
    for condition, mask in groups:
        frames = [t for t, m in zip(truth, mask) if m]
        depth_rows.append({"condition": condition, **depth_view_quality(frames)})
        for name, r in risks.items():
            risk_rows.append({"condition": condition, "predictor": name,
                              **risk_quality(r[mask], frames, reference, threshold)})
    return risk_rows, depth_rows, risks


def frame_rows(observations: Sequence[Observation], truth: Sequence[FrameTruth], risks: dict,
               test_scenes) -> list[dict]:
    """One JSON-ready row per observed frame: what each measure above is computed from.

    Parameters
    ----------
    observations : sequence of Observation
    truth : sequence of FrameTruth
        :func:`frame_truth` of each observation.
    risks : dict of str -> ndarray of shape (n_frames,)
        Each rule base's risk per observation (:func:`rule_base_risk`).
    test_scenes : collection of str
        The held-out scenes (their rows say ``"split": "test"``, the others ``"train"``).

    Returns
    -------
    list of dict
        ``scene, condition, split, frame, time, status``; the features ``iou, rdd`` (null
        unless the rule base ran); ``objects`` (S), ``unseen`` (of those, how many no
        detection covers; null for a frame without a view), ``detections`` (P); ``target``
        (1 - USC~, null without ground truth in range), ``hazard``, ``hazard_in_view``,
        ``gts``, ``found``, ``on_truth`` (:class:`FrameTruth`); ``risk``, rule base name ->
        risk.
    """
    lengths = {len(observations), len(truth), *(len(r) for r in risks.values())}
    if len(lengths) > 1:
        raise ValueError(f"{len(observations)} observations, {len(truth)} FrameTruth and risks of "
                         f"{[len(r) for r in risks.values()]} frames; expected one each")
    rows = []
    for k, (ob, t) in enumerate(zip(observations, truth)):
        report = ob.report
        rows.append({
            "scene": ob.scene, "condition": ob.condition,
            "split": "test" if ob.scene in test_scenes else "train", "frame": ob.index,
            "time": ob.timestamp, "status": report.status,
            "iou": None if math.isnan(report.iou) else report.iou,
            "rdd": None if math.isnan(report.rdd) else report.rdd,
            "objects": t.objects, "unseen": None if report.unseen is None else len(report.unseen),
            "detections": len(ob.P), "target": None if math.isnan(t.target) else t.target,
            "hazard": t.hazard, "hazard_in_view": t.hazard_in_view, "gts": t.gts, "found": t.found,
            "on_truth": t.on_truth,
            "risk": {name: float(r[k]) for name, r in risks.items()}})
    return rows
