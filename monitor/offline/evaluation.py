"""Offline evaluation with ground truth: the measurements behind the paper's Tables I-III.

:func:`observe` runs the monitor on one :class:`~monitor.datasets.frames.Frame` and keeps, beside its
report, the ground truth G projected like the detections (visible boxes within range) and
the frame's USC score. The table functions then aggregate observations:

- :func:`correlation_table` (Table I): Pearson correlation, over frames, between the
  features measured against the depth view S (what the monitor sees at run time) and the
  same features measured against the ground truth G, for several (alpha, beta);
- :func:`recall_table` (Table II): the share of G recovered by S and by P;
- :func:`detection_analysis` (Table III): of the detector's true positives, how many the
  depth view approves; of its false negatives, how many the depth view identifies;
- :func:`rmse_table`: each rule base's RMSE against the target 1 - USC~.

"Recovered" follows the paper's matching: G and X are paired by the Hungarian assignment
on centre distance and a pair counts when IoU > alpha and |RDD| < beta.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from monitor.alignment import align
from monitor.geometry.boxes import within_range
from monitor.geometry.camera import project_boxes
from monitor.datasets.frames import Frame
from monitor.offline.groundtruth import GroundTruthScore, score
from monitor.risk_monitor import INVALID_INPUT, OK, RiskMonitor, RiskReport

#: the two matching settings of the paper's Tables I and II
PAPER_THRESHOLDS = ((0.5, 0.1), (0.3, 0.2))


@dataclass(frozen=True, eq=False)
class Observation:
    """One frame: where it comes from, the monitor's report, and the ground truth.

    ``G`` holds the ground-truth boxes that are visible (visibility > 0), projected like the
    detections and within the range limit, rows ``cx, cy, w, h, d``; ``P`` the detections the
    ground truth was scored against (the report's, or for an invalid frame the detections
    projected all the same).
    """

    scene: str
    condition: str
    index: int
    timestamp: float
    report: RiskReport
    G: np.ndarray
    P: np.ndarray
    truth: GroundTruthScore

    @property
    def target(self) -> float:
        """1 - USC~, NaN when no ground truth is in range (no target, not zero risk)."""
        return self.truth.target


def observe(monitor: RiskMonitor, frame: Frame, scene: str, condition: str) -> Observation:
    """Run ``monitor`` on ``frame`` and measure the frame against its ground truth."""
    report = monitor.step(frame.depth_est, frame.det_boxes3d, frame.det_scores)
    visible = frame.gt_boxes3d[frame.gt_visibility > 0]
    G, _ = project_boxes(visible, monitor.camera, monitor.config.detections.distance)
    G = within_range(G, monitor.config.max_range)
    P = report.P
    if report.status == INVALID_INPUT:  # the depth failed: score the detections all the same
        try:
            P = monitor.project(frame.det_boxes3d, frame.det_scores)
        except ValueError:  # the detections themselves are unusable: nothing was detected
            P = np.zeros((0, 5))
    return Observation(scene, condition, frame.index, frame.timestamp, report, G, P,
                       score(P, G, monitor.config.max_range))


def _pearson(a: np.ndarray, b: np.ndarray) -> float:
    keep = np.isfinite(a) & np.isfinite(b)
    a, b = a[keep], b[keep]
    if a.size < 3 or a.std() == 0 or b.std() == 0:
        return float("nan")
    return float(np.corrcoef(a, b)[0, 1])


def correlation_table(observations: Sequence[Observation],
                      thresholds: Sequence[tuple[float, float]] = PAPER_THRESHOLDS) -> list[dict]:
    """Table I: Pearson r between S-based and G-based IoU~ and RDD~, per (alpha, beta).

    Frames where either S or G is empty have no features and are left out; ``frames`` says
    how many remained.
    """
    rows = []
    for alpha, beta in thresholds:
        feats = []
        for ob in observations:
            if ob.report.status == INVALID_INPUT or len(ob.G) == 0 or len(ob.report.S) == 0:
                continue
            s = align(ob.report.S, ob.report.P, alpha, beta)
            g = align(ob.G, ob.report.P, alpha, beta)
            feats.append((s.iou_mean, s.rdd_mean, g.iou_mean, g.rdd_mean))
        f = np.array(feats).reshape(-1, 4)
        rows.append({"alpha": alpha, "beta": beta, "frames": len(f),
                     "iou_r": _pearson(f[:, 0], f[:, 2]), "rdd_r": _pearson(f[:, 1], f[:, 3])})
    return rows


def _recovered(G: np.ndarray, X: np.ndarray, alpha: float, beta: float) -> np.ndarray:
    """(len(G),) bool: which ground-truth boxes X recovers."""
    if len(G) == 0:
        return np.zeros(0, dtype=bool)
    return align(G, X, alpha, beta).matched


def recall_table(observations: Sequence[Observation], alpha: float, beta: float) -> dict:
    """Table II for one condition's observations: recall of G by S and by P."""
    n = by_s = by_p = 0
    for ob in observations:
        if ob.report.status == INVALID_INPUT:
            continue
        n += len(ob.G)
        by_s += int(_recovered(ob.G, ob.report.S, alpha, beta).sum())
        by_p += int(_recovered(ob.G, ob.report.P, alpha, beta).sum())
    return {"gts": n, "recall_s": by_s / n if n else float("nan"), "recall_p": by_p / n if n else float("nan")}


def detection_analysis(observations: Sequence[Observation], alpha: float, beta: float) -> dict:
    """Table III for one condition: approved TPs and identified FNs.

    A ground truth recovered by P is a true positive of the detector, otherwise a false
    negative; the depth view approves a TP / identifies an FN when S recovers it too.
    """
    tp = approved = fn = identified = 0
    for ob in observations:
        if ob.report.status == INVALID_INPUT or len(ob.G) == 0:
            continue
        by_p = _recovered(ob.G, ob.report.P, alpha, beta)
        by_s = _recovered(ob.G, ob.report.S, alpha, beta)
        tp += int(by_p.sum())
        approved += int((by_p & by_s).sum())
        fn += int((~by_p).sum())
        identified += int((~by_p & by_s).sum())
    return {"tps": tp, "approved_tps": approved, "fns": fn, "identified_fns": identified}


def feature_rows(observations: Sequence[Observation]) -> list[dict]:
    """(scene, frame, condition, iou, rdd, target) of every frame with features (status ok)."""
    return [{"scene": ob.scene, "frame": ob.index, "condition": ob.condition,
             "iou": ob.report.iou, "rdd": ob.report.rdd, "target": ob.target}
            for ob in observations if ob.report.status == OK]


def rmse_table(observations: Sequence[Observation], systems: dict) -> list[dict]:
    """RMSE and MAE of each rule base (name -> FuzzySystem with inputs iou, rdd) against
    1 - USC~, over the frames that have both features (status ok) and a target."""
    rows = [r for r in feature_rows(observations) if np.isfinite(r["target"])]
    target = np.array([r["target"] for r in rows])
    out = []
    for name, fis in systems.items():
        if not rows:
            out.append({"rules": name, "frames": 0, "rmse": float("nan"), "mae": float("nan")})
            continue
        pred = fis.infer(**{k: np.array([r[k] for r in rows]) for k in ("iou", "rdd")})
        err = pred - target
        out.append({"rules": name, "frames": len(rows), "rmse": float(np.sqrt(np.mean(err ** 2))),
                    "mae": float(np.mean(np.abs(err)))})
    return out
