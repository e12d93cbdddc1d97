"""The run-time risk monitor: one camera frame in, one collision risk out (paper, Fig. 1).

Per frame (:meth:`RiskMonitor.step`):

1. depth view: safety-critical objects S from the depth map, by the method the configuration
   names (``retrieval.method``: the paper's :mod:`monitor.depth.retrieval` or the geometric
   :mod:`monitor.depth.geometric`);
2. detector view: the 3D detections projected into the image, P (:func:`monitor.geometry.camera.project_boxes`);
3. alignment of S to P: IoU~ and RDD~ (:func:`monitor.alignment.align`);
4. risk = FIS(IoU~, RDD~) (:mod:`fuzzcore`).

``step`` validates the frame once, where it enters, and never raises for a bad frame: a
depth map that is not a real floating (H, W) array (masked arrays included) or is mostly
invalid, detections that are not finite real (n, 7) boxes of sane size and place, scores
outside [0, 1], give a report with status ``invalid-input``, the reason, and the configured
fail-safe risk (1.0 by default); the stages behind the check trust their input, so a bug in
one of them raises instead of hiding in a report. A frame without any object for the
features to average over (the depth view finds nothing in range; with
``alignment.objects: known``, the default, and no detection within range either) gives
status ``no-objects`` and the configured ``risk.no_objects`` (a decision the
report states: its reason names the risk and where it comes from, its ``free_distance`` how
far the geometric view saw the corridor free), but only after a check that the view could
see anything: a frame the depth view cannot see through gives status ``no-view`` and
``risk.no_view`` (1.0 by default), whatever the view found. Each view has one check per
failure: the paper's view gets :mod:`monitor.depth.visibility` whole (its lower image
blocked by something near, no ground within range, a region of invalid pixels large enough
to hide an object); the geometric view calls its own blind frames
(:class:`~monitor.depth.geometric.BlindViewError`: too many invalid pixels, in the frame or
over the corridor's road, or a road seen under its plane) and reports a surface filling the
view as a near object, so of the visibility check it keeps only the hidden region. A frame whose
features no rule of the rule base covers gives status ``no-rule-fired`` and
``risk.no_rule_fired`` (1.0 by default) instead of the rule base's fallback output (MATLAB's
midpoint 0.5, which is exactly the paper's shield threshold).

The constructor calls :meth:`RiskMonitor.warmup`, which runs a synthetic frame through
every stage, so the first real frame costs what the others do. ``step`` may be called from
several threads at once (the retrieval keeps one set of scratch buffers per thread).
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

import fuzzcore
from monitor import alignment as alignment_stage
from monitor.alignment import Alignment, align
from monitor.config import MonitorConfig
from monitor.depth import geometric, retrieval, visibility
from monitor.depth.geometric import BlindViewError, GeometricRetriever
from monitor.depth.prior import check_prior
from monitor.depth.retrieval import InvalidDepthError, Retriever, as_depth_map
from monitor.depth.visibility import check_view
from monitor.geometry.arrays import finite_array
from monitor.geometry.boxes3d import as_boxes3d
from monitor.geometry.camera import Camera, project_boxes

#: :attr:`RiskReport.status` of an assessed frame: the risk comes from the rule base.
OK = "ok"
#: Status of a frame without objects to assess: the depth view found nothing in range (and,
#: with ``alignment.objects: known``, the detector nothing within range).
NO_OBJECTS = "no-objects"
#: Status of a frame the monitor could not assess: the risk is the fail-safe risk.
INVALID_INPUT = "invalid-input"
#: Status of a frame the depth view cannot see through: the risk is ``risk.no_view``.
NO_VIEW = "no-view"
#: Status of a frame whose features no rule covers: the risk is ``risk.no_rule_fired``.
NO_RULE_FIRED = "no-rule-fired"
#: Every status a report can have (the one definition; everything else imports these).
STATUSES = (OK, NO_OBJECTS, INVALID_INPUT, NO_VIEW, NO_RULE_FIRED)


class InvalidFrameError(ValueError):
    """A frame :meth:`RiskMonitor.step` cannot assess; ``step`` turns it into an
    ``invalid-input`` report whose reason is the message (naming the input, the value and
    what was expected). :meth:`RiskMonitor.check_frame` raises it."""

_EMPTY = np.zeros((0, 5))
#: how many frames before a report :meth:`RiskMonitor.emerged` compares it with
EMERGED_FRAMES = 2


@dataclass(frozen=True, eq=False)
class RiskReport:
    """What the monitor concluded about one frame.

    Attributes
    ----------
    risk : float
        In [0, 1]. For ``invalid-input`` the fail-safe risk, for ``no-objects``,
        ``no-view`` and ``no-rule-fired`` the configured ``risk.no_objects``,
        ``risk.no_view`` and ``risk.no_rule_fired``; never NaN.
    status : str
        One of :data:`STATUSES`: :data:`OK`, :data:`NO_OBJECTS`, :data:`INVALID_INPUT`,
        :data:`NO_VIEW`, :data:`NO_RULE_FIRED`.
    reason : str
        Why the frame is not ``ok`` ("" when it is).
    iou, rdd : float
        The frame features IoU~ and RDD~ (NaN unless ``ok`` or ``no-rule-fired``).
    S, P : ndarray of shape (m, 5) / (n, 5)
        Depth-view objects and projected detections, rows ``cx, cy, w, h, d``.
    alignment : Alignment or None
        Which S matched which P, with IoU and RDD per object.
    fired : list of (rule index, rule text, strength)
        Rules that fired, strongest first (empty unless ``ok``).
    free_distance : float
        The geometric view's free distance ahead in the corridor, metres from the ego
        origin: inf when nothing stands in it within range; NaN for the paper's view (which
        does not measure it) and for frames without a view (``invalid-input``, ``no-view``).
    unseen : ndarray of shape (k, 3) or None
        Where the depth-view objects no detection covers (``alignment.matched`` False)
        stand: per object ``x, y_min, y_max`` in the ego frame, metres (the geometric view's
        :attr:`~monitor.depth.geometric.GeometricView.extents`; for the paper's view
        :meth:`~monitor.geometry.camera.Camera.ground_extents`); (0, 3) when the view found
        nothing; None for frames without a view (``invalid-input``, ``no-view``). The
        path-gated shield reads it (:class:`monitor.shield.Shield`).
    unseen_contact : ndarray of shape (k,), float64, or None
        Per unseen object (rows as ``unseen``), the share of its columns in which it stands
        on the road or on something in front of it (the geometric view's
        :attr:`~monitor.depth.geometric.GeometricView.contact`); NaN where not measured (no
        valid depth beneath it, and every object of the paper's view); None with ``unseen``.
        The shield reads it (``shield.confirm_contact``).
    unseen_points : tuple of ndarray of shape (n_i, 3)
        Per unseen object (rows as ``unseen``), its blocks in the ego frame
        (:attr:`monitor.depth.geometric.GeometricView.points`); empty for the paper's view,
        frames without a view, and a monitor whose shield does not confirm what came out of
        the road (``shield.confirm_emerged`` None: the blocks are not kept).
        :meth:`RiskMonitor.emerged` reads them.
    road_depth : ndarray of shape (H / stride, W / stride), float16, or None
        How far the geometric view saw the road in each block of pixels (0 where it saw
        something else, NaN where nothing valid;
        :attr:`monitor.depth.geometric.GeometricView.road_depth`): a later frame's ``before``
        in :meth:`RiskMonitor.emerged`; None for the paper's view, frames without a view, and
        a monitor whose shield does not confirm what came out of the road.
    timings : dict of str to float
        Seconds spent per stage: ``retrieval`` (with the view check), ``projection``,
        ``alignment``, ``inference``.
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
    free_distance: float = float("nan")
    unseen: np.ndarray | None = None
    unseen_contact: np.ndarray | None = None
    unseen_points: tuple = ()
    road_depth: np.ndarray | None = None
    timings: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """A JSON-ready summary (boxes as lists) that strict JSON can hold: ``free_distance``
        is null where not measured (NaN) and the string ``"inf"`` where the corridor is free
        to the view's range (``float("inf")`` reads it back)."""
        return {
            "risk": self.risk, "status": self.status, "reason": self.reason,
            "iou": None if np.isnan(self.iou) else self.iou,
            "rdd": None if np.isnan(self.rdd) else self.rdd,
            "S": self.S.tolist(), "P": self.P.tolist(),
            "matched": [] if self.alignment is None else self.alignment.partner.tolist(),
            "fired": [{"rule": r + 1, "text": t, "strength": s} for r, t, s in self.fired],
            "free_distance": _json_distance(self.free_distance),
            "unseen": None if self.unseen is None else self.unseen.tolist(),
            "unseen_contact": None if self.unseen_contact is None else
            [None if np.isnan(c) else c for c in self.unseen_contact.tolist()],
            "timings_ms": {k: 1e3 * v for k, v in self.timings.items()},
        }


def _json_distance(value: float) -> float | str | None:
    """A distance as strict JSON holds it: null for NaN, ``"inf"`` for inf, else the number."""
    return None if math.isnan(value) else "inf" if math.isinf(value) else value


class _DepthView(NamedTuple):
    """What :meth:`RiskMonitor._depth_view` saw: S (m, 5); where each stands in the ego
    frame (m, 3) ``x, y_min, y_max`` (the geometric view measures it from its points, the
    paper's is back-projected from the box); how much of each stands on something (m,)
    (the geometric view's contact, NaN for the paper's); the free distance ahead (NaN for
    the paper's view); why the view cannot see through the frame ("" when it can); each S's
    blocks in the ego frame and the road it saw per block (the geometric view's rule 9;
    empty and None for the paper's)."""

    S: np.ndarray
    extents: np.ndarray
    contact: np.ndarray
    free: float
    blind: str
    points: tuple
    road_depth: np.ndarray | None


class RiskMonitor:
    """Collision-risk monitor for one camera.

    Parameters
    ----------
    fis : fuzzcore.FuzzySystem
        Two inputs named ``iou`` and ``rdd`` (any order) and one output in [0, 1]. The
        monitor evaluates it with ``no_rule_fired = "nan"`` whatever its file says, so that
        a frame no rule covers is reported as ``no-rule-fired`` (with
        ``config.risk.no_rule_fired``) and never as the rule base's fallback value.
    prior : ndarray of shape (H, W)
        Mean inverse depth of training frames, 1/m (:mod:`monitor.depth.prior`); the
        paper's view uses it, the geometric one does not (it is still checked).
    camera : Camera
        The camera the depth maps and projections refer to; its size must match ``prior``.
    config : MonitorConfig, optional
        Defaults: :func:`monitor.config.load_config` with no file.
    explain : bool
        Record the rules that fired in each report (costs a few microseconds per frame).
    warmup : bool
        Call :meth:`warmup` before returning (default), so that the first frame does not
        pay for compiling or loading kernels.
    """

    def __init__(self, fis: fuzzcore.FuzzySystem, prior: np.ndarray, camera: Camera,
                 config: MonitorConfig | None = None, *, explain: bool = True, warmup: bool = True):
        if sorted(fis.input_names) != ["iou", "rdd"] or len(fis.outputs) != 1:
            raise ValueError(f"fis {fis.name!r} has inputs {list(fis.input_names)} and outputs "
                             f"{list(fis.output_names)}; the monitor needs inputs iou and rdd and one output")
        lo, hi = fis.outputs[0].range
        if lo < 0 or hi > 1:
            raise ValueError(f"fis output range [{lo}, {hi}] must lie within [0, 1] (a risk)")
        if not isinstance(camera, Camera):
            raise ValueError(f"camera is a {type(camera).__name__}, expected a monitor.geometry.camera.Camera")
        if config is not None and not isinstance(config, MonitorConfig):
            raise ValueError(f"config is a {type(config).__name__}, expected a MonitorConfig "
                             "(monitor.config.load_config)")
        prior = check_prior(prior)
        if prior.shape != (camera.height, camera.width):
            raise ValueError(f"prior has shape {prior.shape}, the camera's image is "
                             f"({camera.height}, {camera.width})")
        self.fis = fis
        self._rules = dataclasses.replace(fis, no_rule_fired="nan") if fis.no_rule_fired != "nan" else fis
        self.camera = camera
        self.config = config if config is not None else MonitorConfig()
        self.explain = explain
        self._prior = prior
        chosen = self.config.retrieval
        if chosen.method == "geometric":
            self._retriever = GeometricRetriever(camera, chosen.geometric,
                                                 keep_blocks=self.config.shield.confirm_emerged is not None)
            # the view's own blind checks and near objects say what blocked and no-ground say
            self._visibility = dataclasses.replace(self.config.visibility, blocked_share=1.0,
                                                   min_in_range_share=0.0, min_ground_ratio=0.0)
        else:
            self._retriever = Retriever(prior, chosen.paper)
            self._visibility = self.config.visibility
        self._iou_first = fis.input_names[0] == "iou"
        if warmup:
            self.warmup()

    def warmup(self) -> "RiskMonitor":
        """Run one synthetic frame through every stage; returns ``self``.

        Compiles (or loads from Numba's cache) every kernel of the retrieval, the
        projection, the alignment and the rule base, and makes OpenCV and SciPy do their
        first-call set-up, so that the first real :meth:`step` costs what the others do.
        The frame: the road as the prior expects it (no foreground) with a near box at the
        image centre, and one detection where that box is.
        """
        (geometric if self.config.retrieval.method == "geometric" else retrieval).warmup()
        visibility.warmup()
        alignment_stage.warmup()
        self._rules.warmup()
        depth, detections = self._synthetic_frame()
        self.step(depth, detections, np.ones(len(detections)))
        self._rules.explain(*((0.5, 0.0) if self._iou_first else (0.0, 0.5)))
        return self

    def _synthetic_frame(self) -> tuple[np.ndarray, np.ndarray]:
        height, width = self.camera.height, self.camera.width
        prior = self._prior
        with np.errstate(divide="ignore"):
            depth = np.where(prior > 0, 1.0 / prior, 1e3).astype(np.float32)  # NaN prior stays NaN
        near = min(5.0, 0.5 * self.config.max_range)
        depth[height // 3: 2 * height // 3, width // 3: 2 * width // 3] = near
        # a 1 m cube on the optical axis at the same distance, in the ego frame
        centre = self.camera.camera_to_ego(np.array([[0.0, 0.0, near + 0.5]]))[0]
        return depth, np.array([[*centre, 1.0, 1.0, 1.0, 0.0]])

    def _depth_view(self, depth: np.ndarray) -> "_DepthView":
        """What the depth view saw in one depth map."""
        if isinstance(self._retriever, GeometricRetriever):
            try:
                view = self._retriever.view(depth)
            except BlindViewError as exc:
                return _DepthView(np.zeros((0, 5)), np.zeros((0, 3)), np.zeros(0), float("nan"), str(exc),
                                  (), None)
            return _DepthView(view.boxes, view.extents, view.contact, view.free_distance,
                              check_view(depth, self._visibility), view.points, view.road_depth)
        S = self._retriever(depth)
        return _DepthView(S, self.camera.ground_extents(S), np.full(len(S), np.nan), float("nan"),
                          check_view(depth, self._visibility), (), None)

    def emerged(self, report: RiskReport, earlier) -> np.ndarray | None:
        """Per unseen object of ``report``, the smallest share of its blocks behind whose
        place one of the frames before saw the road (the geometric view's rule 9,
        :meth:`monitor.depth.geometric.GeometricRetriever.emerged`): the shield's
        ``emerged`` (``confirm_emerged``). A patch of road that the depth reads too near in
        one frame stood where each frame before looked through to the road farther on; an
        obstacle that the network blended into the road in one of them stood out in another.

        Parameters
        ----------
        report : RiskReport
            This monitor's report of a frame.
        earlier : sequence of (RiskReport, float)
            This monitor's reports of the frames before it, the latest first, each with the
            metres the ego moved forward since that frame (its speed times the interval;
            negative when backing); the first :data:`EMERGED_FRAMES` are read. Empty for
            the first frame.

        Returns
        -------
        ndarray of shape (k,) or None
            One share per row of ``report.unseen``, NaN where no frame before can tell (a
            first frame, frames without a view, too little of the object in their images)
            and for every object of the paper's view, which does not see the road (not
            measured, so not asked). None where ``report.unseen`` is None, and for every
            report of a geometric view that keeps no blocks to measure it with (a monitor
            whose shield does not confirm what came out of the road, ``shield.confirm_emerged``
            None), which a shield that confirms it refuses.
        """
        if isinstance(self._retriever, GeometricRetriever):
            if not self._retriever.keep_blocks:
                _check_reports(report, earlier)
                return None
            return unseen_emerged(report, earlier, self._retriever)
        return unseen_emerged(report, earlier, None)

    def _invalid(self, reason: str, timings: dict) -> RiskReport:
        return RiskReport(risk=self.config.risk.fail_safe, status=INVALID_INPUT, reason=reason,
                          timings=timings)

    def check_frame(self, depth, detections, scores=None) -> tuple[np.ndarray, np.ndarray]:
        """Validate one frame: the depth map as float32 (H, W), and the detections to
        project (those scoring at least ``config.detections.min_score``) as (m, 7).

        Raises
        ------
        InvalidFrameError
            Naming the input (``depth``, ``detections[i, j]``, ``scores[i]``), the value and
            what was expected. See :meth:`step` for the rules.
        """
        try:
            return as_depth_map(depth, (self.camera.height, self.camera.width)), \
                self._kept_detections(detections, scores)
        except ValueError as exc:
            raise InvalidFrameError(str(exc)) from None

    def project(self, detections, scores=None) -> np.ndarray:
        """P: detections (n, 7) ``x, y, z, w, l, h, yaw`` in the ego frame -> (m, 5) image boxes.

        Detections scoring below ``config.detections.min_score`` are dropped first (all are
        kept when ``scores`` is None). Raises :class:`InvalidFrameError` for malformed input.
        """
        try:
            boxes = self._kept_detections(detections, scores)
        except ValueError as exc:
            raise InvalidFrameError(str(exc)) from None
        return self._project(boxes)

    def _kept_detections(self, detections, scores) -> np.ndarray:
        """The valid (m, 7) detections scoring at least ``min_score``; ValueError otherwise."""
        boxes = as_boxes3d(detections, "detections")
        if scores is None:
            return boxes
        n = boxes.shape[0]
        scores = finite_array(scores, "scores", f"({n},): one score per detection", ndim=1)
        if scores.shape != (n,):
            raise ValueError(f"scores has shape {scores.shape}, expected ({n},): one score per detection")
        outside = np.flatnonzero((scores < 0.0) | (scores > 1.0))
        if outside.size:
            i = int(outside[0])
            raise ValueError(f"scores[{i}] = {float(scores[i])!r}, expected a score in [0, 1]")
        return boxes[scores >= self.config.detections.min_score]

    def _project(self, boxes: np.ndarray) -> np.ndarray:
        P, _ = project_boxes(boxes, self.camera, self.config.detections.distance)
        return P

    def step(self, depth, detections, scores=None) -> RiskReport:
        """Assess one frame.

        Parameters
        ----------
        depth : ndarray of shape (H, W), real floating point
            Metric depth map, metres (worked on as float32); invalid pixels are NaN, inf
            or <= 0. Masked arrays are refused (mark invalid pixels NaN).
        detections : array_like of shape (n, 7)
            The AV's 3D detections in the ego frame: ``x, y, z, w, l, h, yaw``; finite real
            numbers, sizes in (0, 1000] m, centre coordinates within 100 km
            (:func:`monitor.geometry.boxes3d.as_boxes3d`). No detections is (0, 7).
        scores : array_like of shape (n,), optional
            Detection scores, real numbers in [0, 1]; those below
            ``config.detections.min_score`` are ignored.

        Returns
        -------
        RiskReport
            Status ``invalid-input`` (with the reason and the fail-safe risk) for a frame
            that fails these rules or whose depth map is more invalid than the depth view's
            ``max_invalid_fraction`` allows; ``no-view`` for a frame the depth view cannot see
            through (``config.visibility``, or the geometric view's own
            :class:`~monitor.depth.geometric.BlindViewError`), ``no-objects`` when the
            features have no object to average over, ``no-rule-fired`` when no rule covers
            the features.
        """
        timings: dict[str, float] = {}
        t0 = time.perf_counter()
        try:
            depth, boxes = self.check_frame(depth, detections, scores)
            seen = self._depth_view(depth)
        except (InvalidFrameError, InvalidDepthError) as exc:
            return self._invalid(str(exc), timings)
        t1 = time.perf_counter()
        timings["retrieval"] = t1 - t0
        S, P = seen.S, self._project(boxes)
        t2 = time.perf_counter()
        timings["projection"] = t2 - t1
        chosen = self.config.alignment
        alignment = align(S, P, chosen.alpha, chosen.beta, chosen.weighting, chosen.matching,
                          chosen.objects, self.config.max_range)
        unseen, unseen_contact = seen.extents[~alignment.matched], seen.contact[~alignment.matched]
        unseen_points = tuple(p for p, m in zip(seen.points, alignment.matched) if not m)
        t3 = time.perf_counter()
        timings["alignment"] = t3 - t2
        if seen.blind:
            return RiskReport(risk=self.config.risk.no_view, status=NO_VIEW, reason=seen.blind,
                              S=S, P=P, alignment=alignment, timings=timings)
        free = seen.free
        view = {"unseen": unseen, "unseen_contact": unseen_contact, "unseen_points": unseen_points,
                "road_depth": seen.road_depth}
        if alignment.n_terms == 0:
            free_note = "" if np.isnan(free) else " (the corridor is free to its end)"
            detected = " and no detection" if alignment.objects == "known" else ""
            return RiskReport(risk=self.config.risk.no_objects, status=NO_OBJECTS,
                              reason=f"no safety-critical object{detected} within "
                                     f"{self.config.max_range:g} m{free_note}: risk.no_objects = "
                                     f"{self.config.risk.no_objects:g}, the configured risk of an "
                                     "empty view (not a measured zero)",
                              S=S, P=P, alignment=alignment, free_distance=free, timings=timings, **view)
        iou, rdd = alignment.iou_mean, alignment.rdd_mean
        args = (iou, rdd) if self._iou_first else (rdd, iou)
        if self.explain:  # one inference either way: the explanation carries the output
            explanation = self._rules.explain(*args)
            risk, fired = explanation.outputs[self.fis.output_names[0]], explanation.fired()
        else:
            risk, fired = self._rules.infer(*args), []
        timings["inference"] = time.perf_counter() - t3
        if np.isnan(risk):  # the features are finite: only an empty rule output gives NaN
            return RiskReport(risk=self.config.risk.no_rule_fired, status=NO_RULE_FIRED,
                              reason=f"no rule of {self.fis.name!r} fired for IoU~ = {iou:.6g}, "
                                     f"RDD~ = {rdd:.6g}: the rule base has no answer there",
                              iou=iou, rdd=rdd, S=S, P=P, alignment=alignment, free_distance=free,
                              timings=timings, **view)
        return RiskReport(risk=float(risk), status=OK, iou=iou, rdd=rdd, S=S, P=P,
                          alignment=alignment, fired=fired, free_distance=free, timings=timings, **view)


def shift_earlier(earlier, report: RiskReport, moved: float) -> tuple[list, list]:
    """The frames before ``report`` as :meth:`RiskMonitor.emerged` reads them, and as the
    next frame will: the one bookkeeping of a frame loop (it returns new lists, so a
    simulation that branches may share them).

    Parameters
    ----------
    earlier : list of (RiskReport, float)
        The last frames' reports, the latest first, each with the metres the ego moved
        forward from it to the frame before ``report``; empty at the start of a drive.
    report : RiskReport
        This frame's report.
    moved : float
        Metres the ego moved forward from the frame before to this one (its speed times the
        interval; negative when backing).

    Returns
    -------
    before : list of (RiskReport, float)
        ``earlier`` with ``moved`` added to each: ``emerged``'s ``earlier`` for ``report``.
    kept : list of (RiskReport, float)
        ``report`` (0 m) then ``before``, the first :data:`EMERGED_FRAMES`: ``earlier`` for
        the next frame.
    """
    before = [(r, travel + moved) for r, travel in earlier]
    return before, [(report, 0.0), *before][:EMERGED_FRAMES]


def _check_reports(report, earlier) -> None:
    """Refuse a ``report`` that is not a RiskReport and ``earlier`` that is not a sequence of
    (RiskReport, travel) pairs (:meth:`RiskMonitor.emerged`'s arguments)."""
    if not isinstance(report, RiskReport):
        raise ValueError(f"report is a {type(report).__name__}, expected a RiskReport")
    for k, pair in enumerate(earlier):
        if not (isinstance(pair, tuple) and len(pair) == 2 and isinstance(pair[0], RiskReport)):
            raise ValueError(f"earlier[{k}] is a {type(pair).__name__}, expected a (RiskReport, travel in "
                             "metres) pair")


def unseen_emerged(report: RiskReport, earlier, retriever: GeometricRetriever | None) -> np.ndarray | None:
    """:meth:`RiskMonitor.emerged` with the geometric view's ``retriever``, for code that
    has the reports but not the monitor (the dataset run's output, which replays the shield
    in frame order). ``retriever`` None: the reports are the paper's view's, which does not
    see the road: NaN per unseen object (not measured); a report that carries the geometric
    view's road (``road_depth``) is refused then."""
    _check_reports(report, earlier)
    if report.unseen is None:
        return None
    if retriever is None:
        if report.road_depth is not None:
            raise ValueError("report carries the geometric view's road (road_depth): its emerged shares need "
                             "that view's retriever, not None")
        return np.full(len(report.unseen), np.nan)
    if len(report.unseen_points) != len(report.unseen):
        raise ValueError(f"report has {len(report.unseen)} unseen objects and the blocks of "
                         f"{len(report.unseen_points)}: its monitor keeps them only when its config sets "
                         "shield.confirm_emerged")
    shares = np.full(len(report.unseen), np.nan)
    for before, travel in list(earlier)[:EMERGED_FRAMES]:
        if before.road_depth is not None:
            shares = np.fmin(shares, retriever.emerged(report.unseen_points, before.road_depth, travel))
    return shares
