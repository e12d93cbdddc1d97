"""The run-time risk monitor: one camera frame in, one collision risk out (paper, Fig. 1).

Per frame (:meth:`RiskMonitor.step`):

1. depth view: safety-critical objects S from the depth map (:mod:`monitor.depth.retrieval`);
2. detector view: the 3D detections projected into the image, P (:func:`monitor.geometry.camera.project_boxes`);
3. alignment of S to P: IoU~ and RDD~ (:func:`monitor.alignment.align`);
4. risk = FIS(IoU~, RDD~) (:mod:`fuzzcore`).

``step`` never raises for a bad frame: a depth map of the wrong shape or mostly invalid,
detections with NaN or of the wrong shape, give a report with status ``invalid-input``, the
reason, and the configured fail-safe risk (1.0 by default). A frame whose depth view finds
nothing in range gives status ``no-objects`` and the configured ``no_objects`` risk.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

import fuzzcore
from monitor.alignment import Alignment, align
from monitor.geometry.boxes3d import as_boxes3d
from monitor.geometry.camera import Camera, project_boxes
from monitor.config import MonitorConfig
from monitor.depth.prior import check_prior
from monitor.depth.retrieval import Retriever

OK = "ok"
NO_OBJECTS = "no-objects"
INVALID_INPUT = "invalid-input"

_EMPTY = np.zeros((0, 5))


@dataclass(frozen=True, eq=False)
class RiskReport:
    """What the monitor concluded about one frame.

    Attributes
    ----------
    risk : float
        In [0, 1]. For ``invalid-input`` the fail-safe risk, for ``no-objects`` the
        configured no-objects risk; never NaN.
    status : {"ok", "no-objects", "invalid-input"}
    reason : str
        Why the frame is not ``ok`` ("" when it is).
    iou, rdd : float
        The frame features IoU~ and RDD~ (NaN unless ``ok``).
    S, P : ndarray of shape (m, 5) / (n, 5)
        Depth-view objects and projected detections, rows ``cx, cy, w, h, d``.
    alignment : Alignment or None
        Which S matched which P, with IoU and RDD per object.
    fired : list of (rule index, rule text, strength)
        Rules that fired, strongest first (empty unless ``ok``).
    timings : dict of str to float
        Seconds spent per stage: ``retrieval``, ``projection``, ``alignment``, ``inference``.
    """

    risk: float
    status: str
    reason: str = ""
    iou: float = float("nan")
    rdd: float = float("nan")
    S: np.ndarray = field(default_factory=lambda: _EMPTY)
    P: np.ndarray = field(default_factory=lambda: _EMPTY)
    alignment: Alignment | None = None
    fired: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """A JSON-ready summary (boxes as lists)."""
        return {
            "risk": self.risk, "status": self.status, "reason": self.reason,
            "iou": None if np.isnan(self.iou) else self.iou,
            "rdd": None if np.isnan(self.rdd) else self.rdd,
            "S": self.S.tolist(), "P": self.P.tolist(),
            "matched": [] if self.alignment is None else self.alignment.partner.tolist(),
            "fired": [{"rule": r + 1, "text": t, "strength": s} for r, t, s in self.fired],
            "timings_ms": {k: 1e3 * v for k, v in self.timings.items()},
        }


class RiskMonitor:
    """Collision-risk monitor for one camera.

    Parameters
    ----------
    fis : fuzzcore.FuzzySystem
        Two inputs named ``iou`` and ``rdd`` (any order) and one output in [0, 1].
    prior : ndarray of shape (H, W)
        Mean inverse depth of training frames, 1/m (:mod:`monitor.depth.prior`).
    camera : Camera
        The camera the depth maps and projections refer to; its size must match ``prior``.
    config : MonitorConfig, optional
        Defaults: :func:`monitor.config.load_config` with no file.
    explain : bool
        Record the rules that fired in each report (costs a few microseconds per frame).
    """

    def __init__(self, fis: fuzzcore.FuzzySystem, prior: np.ndarray, camera: Camera,
                 config: MonitorConfig | None = None, *, explain: bool = True):
        if sorted(fis.input_names) != ["iou", "rdd"] or len(fis.outputs) != 1:
            raise ValueError(f"fis {fis.name!r} has inputs {list(fis.input_names)} and outputs "
                             f"{list(fis.output_names)}; the monitor needs inputs iou and rdd and one output")
        lo, hi = fis.outputs[0].range
        if lo < 0 or hi > 1:
            raise ValueError(f"fis output range [{lo}, {hi}] must lie within [0, 1] (a risk)")
        if not isinstance(camera, Camera):
            raise ValueError(f"camera is a {type(camera).__name__}, expected a monitor.geometry.camera.Camera")
        prior = check_prior(prior)
        if prior.shape != (camera.height, camera.width):
            raise ValueError(f"prior has shape {prior.shape}, the camera's image is "
                             f"({camera.height}, {camera.width})")
        self.fis = fis.warmup()
        self.camera = camera
        self.config = config if config is not None else MonitorConfig()
        self.explain = explain
        self._retriever = Retriever(prior, self.config.retrieval)
        self._iou_first = fis.input_names[0] == "iou"

    def _invalid(self, reason: str, timings: dict, **parts) -> RiskReport:
        return RiskReport(risk=self.config.fail_safe_risk, status=INVALID_INPUT, reason=reason,
                          timings=timings, **parts)

    def project(self, detections, scores=None) -> np.ndarray:
        """P: detections (n, 7) ``x, y, z, w, l, h, yaw`` in the ego frame -> (m, 5) image boxes.

        Detections scoring below ``config.min_score`` are dropped first (all are kept when
        ``scores`` is None). Raises ValueError for malformed input.
        """
        boxes = as_boxes3d(detections, "detections")
        if scores is not None:
            scores = np.asarray(scores, dtype=np.float64)
            if scores.shape != (boxes.shape[0],) or not np.all(np.isfinite(scores)):
                raise ValueError(f"scores must be {boxes.shape[0]} finite numbers, one per detection; "
                                 f"got shape {scores.shape}")
            boxes = boxes[scores >= self.config.min_score]
        P, _ = project_boxes(boxes, self.camera, self.config.distance)
        return P

    def step(self, depth, detections, scores=None) -> RiskReport:
        """Assess one frame.

        Parameters
        ----------
        depth : ndarray of shape (H, W)
            Metric depth map, metres, floating point (worked on as float32); invalid pixels
            are NaN, inf or <= 0.
        detections : array_like of shape (n, 7)
            The AV's 3D detections in the ego frame: ``x, y, z, w, l, h, yaw``.
        scores : array_like of shape (n,), optional
            Detection scores; those below ``config.min_score`` are ignored.

        Returns
        -------
        RiskReport
        """
        timings: dict[str, float] = {}
        t0 = time.perf_counter()
        depth = np.asarray(depth)
        if depth.shape != (self.camera.height, self.camera.width):
            return self._invalid(f"depth has shape {depth.shape}, expected "
                                 f"({self.camera.height}, {self.camera.width})", timings)
        if depth.dtype.kind != "f":
            return self._invalid(f"depth has dtype {depth.dtype}, expected floating-point metres", timings)
        try:
            S = self._retriever(depth.astype(np.float32, copy=False))
        except ValueError as exc:  # InvalidDepthError (mostly invalid) among them
            return self._invalid(str(exc), timings)
        t1 = time.perf_counter()
        timings["retrieval"] = t1 - t0
        try:
            P = self.project(detections, scores)
        except ValueError as exc:
            return self._invalid(str(exc), timings, S=S)
        t2 = time.perf_counter()
        timings["projection"] = t2 - t1
        alignment = align(S, P, self.config.alpha, self.config.beta)
        t3 = time.perf_counter()
        timings["alignment"] = t3 - t2
        if alignment.n_objects == 0:
            return RiskReport(risk=self.config.no_objects_risk, status=NO_OBJECTS,
                              reason=f"no safety-critical object within {self.config.max_range:g} m",
                              S=S, P=P, alignment=alignment, timings=timings)
        iou, rdd = alignment.iou_mean, alignment.rdd_mean
        args = (iou, rdd) if self._iou_first else (rdd, iou)
        if self.explain:  # one inference either way: the explanation carries the output
            explanation = self.fis.explain(*args)
            risk, fired = explanation.outputs[self.fis.output_names[0]], explanation.fired()
        else:
            risk, fired = self.fis.infer(*args), []
        timings["inference"] = time.perf_counter() - t3
        if not np.isfinite(risk):
            return self._invalid(f"the rule base gave {risk} for IoU~ = {iou}, RDD~ = {rdd}", timings,
                                 S=S, P=P, alignment=alignment)
        return RiskReport(risk=float(risk), status=OK, iou=iou, rdd=rdd, S=S, P=P,
                          alignment=alignment, fired=fired, timings=timings)
