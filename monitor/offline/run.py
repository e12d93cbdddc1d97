"""A dataset run of the monitor: scenes split into chunks of frames, each chunk processed alone.

The work of ``fuzzrisk monitor`` (and of ``eval`` and ``features`` with ``--workers`` or
``--ray``) in three picklable pieces, so that the same code runs in this process, in a
process pool or on Ray actors (:mod:`monitor.offline.parallel`):

- :class:`ScenePlan`: one scene's frames, as :class:`~monitor.datasets.frames.FrameRecord`
  (nuScenes, recording folders, scene folders) or as a synthetic scene to generate;
  :meth:`ScenePlan.chunks` cuts it into :class:`Chunk` s of consecutive frames;
- :class:`RunSpec`: what every worker builds once: the rule base, prior, camera,
  configuration and, for camera images, the depth network (:class:`~monitor.depth.images.DepthModel`);
- :class:`ChunkProcessor` (built from a spec, once per worker): a chunk in, one
  :class:`FrameResult` per frame out: the :class:`~monitor.offline.evaluation.Observation`
  (the monitor's report and the ground-truth score) or, for a frame that could not be
  processed (a depth map of the wrong size, an unreadable image, ...), the error message.

Frames are independent: the monitor keeps no state between frames (the shield, which does,
runs afterwards over the results in order, :mod:`monitor.offline.run_output`), so any split
gives the same results.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Iterator

import numpy as np

import fuzzcore
from monitor.config import MonitorConfig
from monitor.datasets.frames import FrameRecord
from monitor.depth.files import load_depth
from monitor.depth.images import DepthModel, ImageDepth
from monitor.geometry.camera import Camera
from monitor.offline.evaluation import Observation, observe
from monitor.risk_monitor import RiskMonitor
from monitor.offline.parallel import ordered_map
from monitor.walkers import walker_positions

#: frames per chunk of a scene read from files (synthetic scenes are one chunk: they are
#: generated from their start)
CHUNK_FRAMES = 8


@dataclass(frozen=True)
class Chunk:
    """Consecutive frames ``start .. stop - 1`` of one scene.

    Either ``records`` (frames whose depth is read from a file or estimated from an image)
    or ``source``: a scene read or generated frame by frame from its start (an object with
    ``frames``, an iterator of :class:`~monitor.datasets.frames.Frame`: a synthetic
    :class:`~monitor.synthetic.suite.SceneSource` or a scene folder); frames before ``start``
    are read and dropped.
    """

    scene: str
    condition: str
    start: int
    stop: int
    records: tuple[FrameRecord, ...] = ()
    source: object = None

    def frame_records(self) -> Iterator[FrameRecord]:
        """The chunk's records in order (frames of a ``source`` with their depth in memory)."""
        if self.source is None:
            yield from self.records
            return
        for frame in self.source.frames:
            if frame.index >= self.stop:
                return
            if frame.index >= self.start:
                yield FrameRecord.of_frame(frame, self.scene)


@dataclass(frozen=True)
class ScenePlan:
    """One scene of a run: its name, condition, split and frames.

    Attributes
    ----------
    name, condition, split : str
    n_frames : int
    records : tuple of FrameRecord
        The frames (empty for a scene read from a ``source``).
    source : object or None
        A scene read or generated frame by frame (see :class:`Chunk`).
    """

    name: str
    condition: str
    split: str
    n_frames: int
    records: tuple[FrameRecord, ...] = ()
    source: object = None

    @classmethod
    def of_records(cls, name: str, condition: str, records, split: str = "test") -> "ScenePlan":
        records = tuple(records)
        return cls(name, condition, split, len(records), records=records)

    @classmethod
    def of_source(cls, source, n_frames: int) -> "ScenePlan":
        """A scene with ``name``, ``condition``, ``split`` and ``frames`` (:class:`Chunk`)."""
        return cls(source.name, source.condition, source.split, n_frames, source=source)

    def keys(self) -> list[str]:
        """Frame keys in order (frames of a ``source``: the zero-padded index)."""
        if self.source is not None:
            return [f"{i:06d}" for i in range(self.n_frames)]
        return [r.key for r in self.records]

    def chunks(self, start: int = 0, size: int = CHUNK_FRAMES) -> list[Chunk]:
        """The frames from ``start`` on, in chunks of ``size`` (a ``source``: one chunk)."""
        if start >= self.n_frames:
            return []
        if self.source is not None:
            return [Chunk(self.name, self.condition, start, self.n_frames, source=self.source)]
        return [Chunk(self.name, self.condition, a, min(a + size, self.n_frames),
                      records=self.records[a:min(a + size, self.n_frames)])
                for a in range(start, self.n_frames, size)]


@dataclass(frozen=True, eq=False)
class FrameResult:
    """What became of one frame: an observation, or the error that stopped it.

    Attributes
    ----------
    scene, condition, key : str
    index : int
    timestamp : float
        Seconds from the start of the scene.
    ego_speed : float
        The ego's speed, m/s (for a path-gated shield).
    token : str or None
        The source's id of the frame (nuScenes sample token).
    has_ground_truth : bool
    observation : Observation or None
        None when the frame could not be processed.
    error : str
        Why not ("" when it was).
    walkers : ndarray of shape (k, 2) or None
        ``x, y`` (ego frame, metres) of the walkers the detector reports in the frame, for
        the shield's walker gate (:func:`monitor.walkers.walker_positions` at the monitor's
        ``detections.min_score``); None when the frame could not be processed.
    """

    scene: str
    condition: str
    key: str
    index: int
    timestamp: float
    ego_speed: float
    token: str | None
    has_ground_truth: bool
    observation: Observation | None = None
    error: str = ""
    walkers: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class RunSpec:
    """What each worker builds once: the monitor and, for images, the depth network.

    Attributes
    ----------
    rules : Path
        Rule base file (inputs ``iou`` and ``rdd``).
    prior : ndarray of shape (H, W), float32
    camera : Camera
    config : MonitorConfig
    explain : bool
        Record the rules that fired.
    depth_model : DepthModel or None
        For frames whose depth comes from camera images.
    """

    rules: Path
    prior: np.ndarray
    camera: Camera
    config: MonitorConfig
    explain: bool = True
    depth_model: DepthModel | None = None

    def build(self) -> "ChunkProcessor":
        monitor = RiskMonitor(fuzzcore.load(self.rules), self.prior, self.camera, self.config,
                              explain=self.explain)
        return ChunkProcessor(monitor, None if self.depth_model is None else self.depth_model.build())


def resolve_depths(records: list[FrameRecord], image_depth: ImageDepth | None
                   ) -> list[tuple[np.ndarray | None, str]]:
    """Each record's depth map: from memory, its file or its image (through ``image_depth``).

    Returns
    -------
    list of (depth, source) or (None, message)
        ``source`` names where the depth came from; a frame whose depth cannot be had
        (a damaged file, an unreadable image) gets the reason instead.
    """
    out: list[tuple[np.ndarray | None, str] | None] = [None] * len(records)
    images = []
    for k, record in enumerate(records):
        if record.depth is not None:
            out[k] = (record.depth, "memory")
        elif record.depth_path is not None:
            try:
                out[k] = (load_depth(record.depth_path, png_scale=record.png_scale), str(record.depth_path))
            except (ValueError, OSError) as exc:
                out[k] = (None, f"{record.name}: {exc}")
        elif record.image_path is not None and image_depth is not None:
            images.append(k)
        else:
            out[k] = (None, f"{record.name}: no depth map and no depth network for its image "
                            f"{record.image_path}")
    if images:
        estimated = image_depth([(records[k].key, records[k].image_path) for k in images])
        for k, depth in zip(images, estimated):
            out[k] = ((depth, str(records[k].image_path)) if isinstance(depth, np.ndarray)
                      else (None, f"{records[k].name}: {depth}"))
    return out


def _result(record: FrameRecord, condition: str, **outcome) -> FrameResult:
    return FrameResult(record.scene, condition, record.key, record.index, record.timestamp, record.ego_speed,
                       record.token, record.has_ground_truth, **outcome)


class ChunkProcessor:
    """The monitor (and depth network) of one worker, applied chunk by chunk.

    The two stages are apart so that Ray can run them on different actors:
    :meth:`depths` (depth from files, memory or images) and :meth:`observe`.
    """

    def __init__(self, monitor: RiskMonitor, image_depth: ImageDepth | None):
        self.monitor = monitor
        self.image_depth = image_depth

    def __call__(self, chunk: Chunk) -> list[FrameResult]:
        records = list(chunk.frame_records())
        return self.observe(records, self.depths(records), chunk.condition)

    def depths(self, records: list[FrameRecord]) -> list[tuple[np.ndarray | None, str]]:
        """Per record ``(depth, source)``, or ``(None, error message)`` (:func:`resolve_depths`)."""
        return resolve_depths(records, self.image_depth)

    def observe(self, records: list[FrameRecord], depths: list[tuple[np.ndarray | None, str]],
                condition: str) -> list[FrameResult]:
        """Run the monitor on each record with its depth map."""
        results = []
        for record, (depth, source) in zip(records, depths):
            if depth is None:
                results.append(_result(record, condition, error=source))
                continue
            try:
                frame = record.to_frame(depth, source)
            except ValueError as exc:
                results.append(_result(record, condition, error=str(exc)))
                continue
            walkers = walker_positions(frame.det_boxes3d, frame.det_classes, frame.det_scores,
                                       self.monitor.config.detections.min_score)
            results.append(_result(record, condition, walkers=walkers,
                                   observation=observe(self.monitor, frame, record.scene, condition)))
        return results


def process_chunks(spec: RunSpec, chunks: list[Chunk], *, workers: int = 1, ray: str | None = None,
                   depth_actors: int | None = None) -> Iterator[list[FrameResult]]:
    """The results of every chunk, in order: in this process, ``workers`` processes or on Ray.

    On Ray (:func:`monitor.offline.ray_backend.ray_run`) frames go one by one through a depth
    stage on GPU actors when the cluster has GPUs (``depth_actors`` of them, default one per
    GPU) and a monitor stage on ``workers`` CPU actors; results come back in the same order.
    """
    if ray is not None:
        from monitor.offline.ray_backend import ray_run  # Ray is optional: imported only when asked for
        yield from ray_run(spec, chunks, address=ray, actors=workers, depth_actors=depth_actors)
        return
    yield from ordered_map(spec, chunks, workers=workers)


def observe_plans(spec: RunSpec, plans: list[ScenePlan], *, workers: int = 1, ray: str | None = None,
                  progress=None) -> list[Observation]:
    """The observations of every frame of ``plans`` in order (``fuzzrisk eval`` and ``features``).

    A frame that cannot be processed is an error (ValueError with its message) here:
    evaluations need every frame. ``progress`` is called once per frame. No shield runs here,
    so the workers' views keep no blocks for one (``shield.confirm_emerged``; the reports'
    risks are the same, their ``unseen_points`` empty and ``road_depth`` None).
    """
    shield = replace(spec.config.shield, confirm_emerged=None)
    spec = replace(spec, config=replace(spec.config, shield=shield))
    out = []
    chunks = [chunk for plan in plans for chunk in plan.chunks()]
    for results in process_chunks(spec, chunks, workers=workers, ray=ray):
        for result in results:
            if result.observation is None:
                raise ValueError(result.error)
            out.append(result.observation)
            if progress is not None:
                progress()
    return out
