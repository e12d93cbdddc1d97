"""Frames of a driving scene in memory: :class:`Frame` and :class:`Scene`.

A :class:`Frame` is what the monitor needs from one camera frame: the estimated depth
map, the 3D detector's boxes, and for evaluation the ground-truth boxes (and, from the
synthetic generator, the true depth and a label map). A :class:`Scene` is a sequence of
frames from one camera. 3D boxes are float64 ``(n, 7)`` rows ``x, y, z, w, l, h, yaw``
in the ego frame (see :mod:`monitor.geometry.boxes3d`). Class names are numpy string arrays.

The label map (int16, ``(H, W)``) says what each pixel of the true depth shows:
:data:`LABEL_SKY`, :data:`LABEL_ROAD`, :data:`LABEL_MARKING`, :data:`LABEL_SIDEWALK` (with the
curbs), :data:`LABEL_STRUCTURE` (buildings, fences, poles, vegetation: not ground truth), or
``k + 1`` for ground-truth box ``k`` of the frame.
On disk they are scene folders (:mod:`monitor.datasets.scene_folder`). A :class:`FrameRecord` is a
frame before its depth map is read or estimated (what a dataset run hands to its workers).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from monitor.geometry.boxes3d import as_boxes3d
from monitor.geometry.camera import Camera

#: label-map codes (ground-truth box k is k + 1)
LABEL_SKY = -1
LABEL_ROAD = 0
LABEL_MARKING = -2
LABEL_SIDEWALK = -3
LABEL_STRUCTURE = -4

#: the per-frame maps: field name -> dtype on disk and in memory
MAPS = {"depth_est": np.float32, "depth_true": np.float32, "labels": np.int16}


def _check_boxes3d(boxes, name: str) -> np.ndarray:
    arr = np.asarray(boxes)
    if arr.dtype != np.float64 or arr.ndim != 2 or arr.shape[1] != 7:
        raise ValueError(
            f"{name} has shape {arr.shape} and dtype {arr.dtype}, expected float64 (n, 7) rows "
            "x, y, z, w, l, h, yaw (metres, radians; an empty frame is (0, 7))"
        )
    return as_boxes3d(arr, name)  # finite, sizes > 0


def _check_vector(values, name: str, n: int, kind: str) -> np.ndarray:
    arr = np.asarray(values)
    expected = {"str": "U", "int": "i", "float": "f"}[kind]
    if arr.ndim != 1 or arr.shape[0] != n or arr.dtype.kind != expected:
        raise ValueError(
            f"{name} has shape {arr.shape} and dtype {arr.dtype}, expected a 1-D {kind} array "
            f"of length {n} (one per box)"
        )
    return arr


def _check_unit_interval(arr: np.ndarray, name: str) -> None:
    bad = ~(np.isfinite(arr) & (arr >= 0.0) & (arr <= 1.0))
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"{name}[{i}] = {float(arr[i])!r}, must be in [0, 1]")


def _check_map(array, name: str, camera: Camera, dtype, optional: bool) -> None:
    if array is None:
        if not optional:
            raise ValueError(f"{name} is missing")
        return
    shape = (camera.height, camera.width)
    if not isinstance(array, np.ndarray) or array.shape != shape or array.dtype != dtype:
        got = (array.shape, array.dtype) if isinstance(array, np.ndarray) else type(array).__name__
        raise ValueError(
            f"{name} is {got}, expected a {np.dtype(dtype)} array of shape {shape} "
            "(the camera's height x width)"
        )


@dataclass(frozen=True, eq=False)
class Frame:
    """One camera frame of a scene.

    Attributes
    ----------
    index : int
        Position in the scene, from 0.
    timestamp : float
        Seconds from the start of the scene.
    ego_speed : float
        Metres per second, >= 0.
    camera : Camera
    depth_est : ndarray of shape (H, W), float32
        Estimated depth in metres (non-finite or <= 0 pixels are invalid).
    depth_true : ndarray of shape (H, W), float32, or None
        True camera-frame depth in metres, inf where the ray hits nothing.
    labels : ndarray of shape (H, W), int16, or None
        What each pixel of the true depth shows (the LABEL_* codes, or k + 1 for box k).
    gt_boxes3d : ndarray of shape (n, 7), float64
        Ground-truth boxes ``x, y, z, w, l, h, yaw`` in the ego frame.
    gt_classes : ndarray of shape (n,), str
    gt_ids : ndarray of shape (n,), int64
        Instance ids, unique within the frame, stable across the scene.
    gt_visibility : ndarray of shape (n,), float64
        Visible fraction of each box's silhouette in this image, in [0, 1] (0: not in view).
    det_boxes3d : ndarray of shape (m, 7), float64
        The 3D detector's boxes, same layout.
    det_classes : ndarray of shape (m,), str
        Detection names (nuScenes' detection vocabulary).
    det_scores : ndarray of shape (m,), float64
        Detection scores in [0, 1].
    """

    index: int
    timestamp: float
    ego_speed: float
    camera: Camera
    depth_est: np.ndarray
    depth_true: np.ndarray | None
    labels: np.ndarray | None
    gt_boxes3d: np.ndarray
    gt_classes: np.ndarray
    gt_ids: np.ndarray
    gt_visibility: np.ndarray
    det_boxes3d: np.ndarray
    det_classes: np.ndarray
    det_scores: np.ndarray

    def __post_init__(self):
        if not isinstance(self.index, int) or isinstance(self.index, bool) or self.index < 0:
            raise ValueError(f"index = {self.index!r}, must be an integer >= 0")
        for name in ("timestamp", "ego_speed"):
            value = getattr(self, name)
            if not isinstance(value, float) or not math.isfinite(value):
                raise ValueError(f"{name} = {value!r}, must be a finite float")
        if self.ego_speed < 0:
            raise ValueError(f"ego_speed = {self.ego_speed!r}, must be >= 0 m/s")
        if not isinstance(self.camera, Camera):
            raise ValueError(f"camera is a {type(self.camera).__name__}, expected a Camera")
        for name, dtype in MAPS.items():
            _check_map(getattr(self, name), name, self.camera, dtype, optional=name != "depth_est")
        n = _check_boxes3d(self.gt_boxes3d, "gt_boxes3d").shape[0]
        _check_vector(self.gt_classes, "gt_classes", n, "str")
        ids = _check_vector(self.gt_ids, "gt_ids", n, "int")
        if np.unique(ids).size != n:
            raise ValueError(f"gt_ids has repeated instance ids: {np.sort(ids).tolist()}")
        _check_unit_interval(_check_vector(self.gt_visibility, "gt_visibility", n, "float"),
                             "gt_visibility")
        m = _check_boxes3d(self.det_boxes3d, "det_boxes3d").shape[0]
        _check_vector(self.det_classes, "det_classes", m, "str")
        _check_unit_interval(_check_vector(self.det_scores, "det_scores", m, "float"),
                             "det_scores")
        if self.labels is not None and n + 1 > np.iinfo(np.int16).max:
            raise ValueError(f"{n} ground-truth boxes do not fit an int16 label map")


@dataclass(frozen=True, eq=False)
class Scene:
    """A sequence of frames from one camera.

    Attributes
    ----------
    name : str
    camera : Camera
    condition : str
        The condition (``"nominal"``, ``"night"``, ...); free text for real data.
    seed : int or None
        The generator's seed (None for real data).
    synthetic : bool
        True for generated data: every report on it must say so.
    frames : tuple of Frame
    """

    name: str
    camera: Camera
    condition: str
    seed: int | None
    synthetic: bool
    frames: tuple[Frame, ...]


@dataclass(frozen=True, eq=False)
class FrameRecord:
    """A frame before its depth map is read or estimated: what a run sends to its workers.

    Everything of a :class:`Frame` but the maps, and where the depth map comes from: a
    file (``depth_path``), a camera image for a depth network (``image_path``), or an
    array already in memory (``depth``, the synthetic scenes). Light and picklable, so a
    dataset's frames can be listed up front and processed in other processes.

    Attributes
    ----------
    scene : str
        Name of the scene the frame belongs to.
    key : str
        The frame's name within its source: the depth map's and image's file stem (nuScenes:
        the camera image's stem; the recording folder: the frame key).
    index, timestamp, ego_speed, camera
        As in :class:`Frame`.
    det_boxes3d, det_classes, det_scores
        As in :class:`Frame`.
    gt_boxes3d, gt_classes, gt_ids, gt_visibility
        As in :class:`Frame`; empty when the source has no ground truth.
    has_ground_truth : bool
        False when the source has no ground truth at all (reports then give no target),
        as opposed to ground truth with nothing in view.
    depth_path : Path or None
        A depth file (:func:`monitor.depth.files.load_depth`).
    png_scale : float
        Stored value per metre of a PNG ``depth_path``.
    image_path : Path or None
        The camera image (for a depth network).
    depth : ndarray of shape (H, W), float32, or None
        The depth map itself.
    token : str or None
        The source's own id of the frame (nuScenes: the sample token).
    """

    scene: str
    key: str
    index: int
    timestamp: float
    ego_speed: float
    camera: Camera
    det_boxes3d: np.ndarray
    det_classes: np.ndarray
    det_scores: np.ndarray
    gt_boxes3d: np.ndarray
    gt_classes: np.ndarray
    gt_ids: np.ndarray
    gt_visibility: np.ndarray
    has_ground_truth: bool
    depth_path: Path | None = None
    png_scale: float = 256.0
    image_path: Path | None = None
    depth: np.ndarray | None = None
    token: str | None = None

    @classmethod
    def of_frame(cls, frame: Frame, scene: str, *, has_ground_truth: bool = True) -> "FrameRecord":
        """The record of a frame in memory (its depth map carried along)."""
        return cls(scene=scene, key=f"{frame.index:06d}", index=frame.index, timestamp=frame.timestamp,
                   ego_speed=frame.ego_speed, camera=frame.camera, det_boxes3d=frame.det_boxes3d,
                   det_classes=frame.det_classes, det_scores=frame.det_scores,
                   gt_boxes3d=frame.gt_boxes3d, gt_classes=frame.gt_classes, gt_ids=frame.gt_ids,
                   gt_visibility=frame.gt_visibility, has_ground_truth=has_ground_truth,
                   depth=frame.depth_est)

    @property
    def name(self) -> str:
        """How messages name the frame: scene, index and key (and token when there is one)."""
        token = f", sample {self.token!r}" if self.token else ""
        return f"scene {self.scene!r} frame {self.index} ({self.key}{token})"

    def to_frame(self, depth: np.ndarray, source: str) -> Frame:
        """The :class:`Frame` with ``depth`` as its estimated depth map.

        ``source`` names where the depth came from (a file, an image) in the errors.

        Raises
        ------
        ValueError
            A depth map that is not float32 metres of the camera's size, or a malformed
            field; the message names the frame and ``source``.
        """
        try:
            return Frame(index=self.index, timestamp=self.timestamp, ego_speed=self.ego_speed,
                         camera=self.camera, depth_est=depth, depth_true=None, labels=None,
                         gt_boxes3d=self.gt_boxes3d, gt_classes=self.gt_classes, gt_ids=self.gt_ids,
                         gt_visibility=self.gt_visibility, det_boxes3d=self.det_boxes3d,
                         det_classes=self.det_classes, det_scores=self.det_scores)
        except ValueError as exc:
            raise ValueError(f"{self.name}, depth from {source}: {exc}") from exc
