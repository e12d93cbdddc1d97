"""Per-stage latency of :meth:`monitor.RiskMonitor.step` on synthetic frames of a given camera.

:func:`monitor_latency` generates frames with :mod:`monitor.synthetic` for the camera (its
image size and mounting; the traffic of the synthetic scenes, so a realistic number of
objects per frame, reported in the result), scenes of :data:`FRAMES_PER_SCENE` frames
taking the six conditions in turn. The inverse-depth prior is the mean inverse depth of
these same frames (for a latency measurement the prior matters only through how many
objects it lets through). Each frame is then stepped ``repeat`` times, the frames in
turn, after one untimed step; the stages are the ones :class:`~monitor.RiskMonitor`
reports in ``report.timings`` (retrieval, projection, alignment, inference: the last one
only on frames with objects), and ``step`` is the whole call timed from outside.
Percentiles are :mod:`fuzzcore.bench`'s (numpy's default definition).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

import fuzzcore
from fuzzcore.bench import Latency, Machine
from monitor.depth.prior import build_prior
from monitor.geometry.camera import Camera
from monitor.risk_monitor import RiskMonitor
from monitor.synthetic import CONDITIONS, generate_frames

#: the stages of ``report.timings``, then the whole ``step``: name -> description
STAGES = {
    "retrieval": "depth view: safety-critical objects S from the depth map",
    "projection": "detector view: 3D detections projected to P",
    "alignment": "alignment of S with P (coverage or Hungarian pairs), IoU~ and RDD~",
    "inference": "risk = FIS(IoU~, RDD~) (frames with objects only)",
    "step": "RiskMonitor.step, the whole call",
}

#: frames per synthetic scene; scenes take the conditions in turn
FRAMES_PER_SCENE = 4


@dataclass(frozen=True, eq=False)
class MonitorLatency:
    """What :func:`monitor_latency` measured.

    Attributes
    ----------
    width, height : int
        Image size, pixels.
    frames : int
        Distinct synthetic frames.
    repeat : int
        Timed steps per frame.
    hz : float
        Frame rate whose budget ``budget_share`` refers to.
    objects : dict of str to float
        Mean per frame of ``detections`` (3D), ``P`` (projected) and ``S`` (depth view).
    statuses : dict of str to int
        Frames per report status.
    stages : dict of str to Latency
        Keys of :data:`STAGES` (a stage no frame reached is absent).
    machine : Machine
    """

    width: int
    height: int
    frames: int
    repeat: int
    hz: float
    objects: dict
    statuses: dict
    stages: dict
    machine: Machine

    @property
    def frame_budget_ns(self) -> float:
        """One frame period at ``hz``, nanoseconds."""
        return 1e9 / self.hz

    def budget_share(self) -> dict[str, float]:
        """Each percentile of the whole ``step`` as a fraction of the frame period."""
        return {p: v / self.frame_budget_ns for p, v in self.stages["step"].percentiles_ns.items()}

    def to_dict(self, samples: bool = False) -> dict:
        """A JSON-ready dict; per-step samples only if ``samples``."""
        return {"schema": "fuzzrisk.bench-monitor/1", "width": self.width, "height": self.height,
                "frames": self.frames, "repeat": self.repeat, "hz": self.hz,
                "objects": dict(self.objects), "statuses": dict(self.statuses),
                "stages": {k: v.to_dict(samples) for k, v in self.stages.items()},
                "budget_share": self.budget_share(), "machine": self.machine.to_dict()}


def _count(value, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} = {value!r}, must be an integer >= 1")
    return int(value)


def monitor_latency(fis: fuzzcore.FuzzySystem, camera: Camera, *, frames: int = 24, repeat: int = 10,
                    hz: float = 12.0, seed: int = 0,
                    progress: Callable[[], None] | None = None) -> MonitorLatency:
    """Time :meth:`RiskMonitor.step` stage by stage on synthetic frames (see the module docstring).

    Parameters
    ----------
    fis : fuzzcore.FuzzySystem
        Inputs ``iou`` and ``rdd``, one output in [0, 1] (as :class:`RiskMonitor` needs).
    camera : Camera
        Image size and mounting of the frames.
    frames : int >= 1
        Distinct frames to generate (about 0.3 s each at 1600 x 900; 6 MB each is kept).
    repeat : int >= 1
        Timed steps per frame.
    hz : float > 0
        Frame rate for the budget share.
    seed : int >= 0
        Scene ``k`` has seed ``seed + k``.
    progress : callable, optional
        Called once per frame generated and once per timed pass over the frames.

    Returns
    -------
    MonitorLatency
    """
    if not isinstance(camera, Camera):
        raise ValueError(f"camera is a {type(camera).__name__}, expected a monitor.geometry.camera.Camera")
    frames, repeat = _count(frames, "frames"), _count(repeat, "repeat")
    if isinstance(hz, bool) or not isinstance(hz, (int, float)) or not (math.isfinite(hz) and hz > 0):
        raise ValueError(f"hz = {hz!r}, must be a finite frame rate > 0")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed = {seed!r}, must be an integer >= 0")
    conditions = list(CONDITIONS)
    depths, detections = [], []
    for k in range(math.ceil(frames / FRAMES_PER_SCENE)):
        n = min(FRAMES_PER_SCENE, frames - k * FRAMES_PER_SCENE)
        for frame in generate_frames(conditions[k % len(conditions)], int(seed) + k, n_frames=n,
                                     camera=camera):
            depths.append(frame.depth_est)
            detections.append((frame.det_boxes3d, frame.det_scores))
            if progress is not None:
                progress()
    prior = build_prior((f"frame {i}", d) for i, d in enumerate(depths)).mean()
    monitor = RiskMonitor(fis, prior, camera)
    monitor.step(depths[0], *detections[0])  # untimed: kernels compiled or loaded from the cache
    times: dict[str, list[float]] = {name: [] for name in STAGES}
    first = []  # the reports of the first pass: one per frame
    clock = time.perf_counter_ns
    for rep in range(repeat):
        for depth, (boxes, scores) in zip(depths, detections):
            t0 = clock()
            report = monitor.step(depth, boxes, scores)
            times["step"].append(clock() - t0)
            for stage, seconds in report.timings.items():
                times[stage].append(seconds * 1e9)
            if rep == 0:
                first.append(report)
        if progress is not None:
            progress()
    statuses: dict[str, int] = {}
    for report in first:
        statuses[report.status] = statuses.get(report.status, 0) + 1
    objects = {"detections": float(np.mean([len(b) for b, _ in detections])),
               "P": float(np.mean([len(r.P) for r in first])),
               "S": float(np.mean([len(r.S) for r in first]))}
    return MonitorLatency(width=camera.width, height=camera.height, frames=len(depths), repeat=repeat,
                          hz=float(hz), objects=objects, statuses=statuses,
                          stages={k: Latency.from_samples(k, STAGES[k], v) for k, v in times.items() if v},
                          machine=Machine.here())

