"""Frames of a driving scene in memory and on disk.

In memory
---------
A :class:`Frame` is what the monitor needs from one camera frame: the estimated depth
map, the 3D detector's boxes, and for evaluation the ground-truth boxes (and, from the
synthetic generator, the true depth and a label map). A :class:`Scene` is a sequence of
frames from one camera. 3D boxes are float64 ``(n, 7)`` rows ``x, y, z, w, l, h, yaw``
in the ego frame (see :mod:`monitor.camera`). Class names are numpy string arrays.

The label map (int16, ``(H, W)``) says what each pixel of the true depth shows:
:data:`LABEL_SKY`, :data:`LABEL_ROAD`, :data:`LABEL_MARKING`, :data:`LABEL_SIDEWALK`, or
``k + 1`` for ground-truth box ``k`` of the frame.

On disk
-------
A scene is a folder::

    scene.json                 everything but the maps
    depth_est/000000.npy       float32 (H, W) estimated depth, metres, one per frame
    depth_true/000000.npy      float32 (H, W) true depth (optional)
    labels/000000.npy          int16 (H, W) label map (optional)

``scene.json`` mirrors nuScenes' vocabulary where it is natural::

    {"format": "fuzzrisk-scene", "version": 1, "name": "...", "synthetic": true,
     "condition": "nominal", "seed": 7, "coordinate_frame": "ego",
     "camera": {"camera_intrinsic": [[...3x3...]], "width": 1600, "height": 900,
                "cam_to_ego": [[...4x4...]], "near": 0.1},
     "frames": [{"index": 0, "timestamp": 0.0, "ego_speed": 5.1,
                 "depth_est": "depth_est/000000.npy", "depth_true": ..., "labels": ...,
                 "annotations": [{"instance_id": 3, "category_name": "car",
                                  "translation": [x, y, z], "size": [w, l, h],
                                  "yaw": 0.1, "visibility": 0.8}, ...],
                 "detections": [{"detection_name": "car", "detection_score": 0.7,
                                 "translation": [x, y, z], "size": [w, l, h],
                                 "yaw": 0.1}, ...]}, ...]}

Unlike nuScenes, translations are in the ego frame (``coordinate_frame``), rotations are a
yaw angle (radians about z; a quaternion would not round-trip exactly), timestamps are
seconds, and ``"synthetic": true`` marks generated data. Numbers round-trip exactly: JSON
floats are written with Python's shortest exact ``repr`` and maps as ``.npy``.
:class:`SceneReader` validates everything and names the file and field of any problem.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from monitor.camera import Camera, as_boxes3d

#: label-map codes (ground-truth box k is k + 1)
LABEL_SKY = -1
LABEL_ROAD = 0
LABEL_MARKING = -2
LABEL_SIDEWALK = -3

FORMAT = "fuzzrisk-scene"
VERSION = 1
SCENE_FILE = "scene.json"
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


def _json_boxes(boxes: np.ndarray) -> Iterator[dict]:
    for row in boxes.tolist():
        yield {"translation": row[0:3], "size": row[3:6], "yaw": row[6]}


class SceneWriter:
    """Write a scene folder one frame at a time (``scene.json`` is written on :meth:`close`).

    Parameters
    ----------
    directory : str or Path
        The scene folder; created if missing. It must not hold a ``scene.json`` unless
        ``overwrite``.
    name, camera, condition, seed, synthetic
        As in :class:`Scene`.
    overwrite : bool, default False

    Examples
    --------
    >>> with SceneWriter("out/scene-0", "s0", camera, "nominal", 0, True) as w:  # doctest: +SKIP
    ...     for frame in frames:
    ...         w.add(frame)
    """

    def __init__(self, directory: str | Path, name: str, camera: Camera, condition: str,
                 seed: int | None, synthetic: bool, *, overwrite: bool = False):
        self.directory = Path(directory)
        if (self.directory / SCENE_FILE).exists() and not overwrite:
            raise FileExistsError(
                f"{self.directory / SCENE_FILE} exists; choose another folder or pass "
                "overwrite=True"
            )
        if seed is not None and (not isinstance(seed, int) or isinstance(seed, bool)):
            raise ValueError(f"seed = {seed!r}, must be an integer or None")
        self.directory.mkdir(parents=True, exist_ok=True)
        self._header = {
            "format": FORMAT, "version": VERSION, "name": str(name), "synthetic": bool(synthetic),
            "condition": str(condition), "seed": seed, "coordinate_frame": "ego",
            "camera": {
                "camera_intrinsic": camera.K.tolist(), "width": camera.width,
                "height": camera.height, "cam_to_ego": camera.cam_to_ego.tolist(),
                "near": camera.near,
            },
        }
        self._camera = camera
        self._frames: list[dict] = []

    def add(self, frame: Frame) -> None:
        """Write one frame's maps and keep its record for ``scene.json``."""
        if not isinstance(frame, Frame):
            raise ValueError(f"frame is a {type(frame).__name__}, expected a Frame")
        if not _same_camera(frame.camera, self._camera):
            raise ValueError(f"frame {frame.index} has another camera than the scene")
        record = {"index": frame.index, "timestamp": frame.timestamp, "ego_speed": frame.ego_speed}
        for name in MAPS:
            array = getattr(frame, name)
            if array is None:
                record[name] = None
                continue
            relative = f"{name}/{len(self._frames):06d}.npy"
            (self.directory / name).mkdir(exist_ok=True)
            np.save(self.directory / relative, array, allow_pickle=False)
            record[name] = relative
        record["annotations"] = [
            {"instance_id": int(i), "category_name": str(c), **box, "visibility": float(v)}
            for i, c, box, v in zip(frame.gt_ids.tolist(), frame.gt_classes.tolist(),
                                    _json_boxes(frame.gt_boxes3d), frame.gt_visibility.tolist())
        ]
        record["detections"] = [
            {"detection_name": str(c), "detection_score": float(s), **box}
            for c, s, box in zip(frame.det_classes.tolist(), frame.det_scores.tolist(),
                                 _json_boxes(frame.det_boxes3d))
        ]
        self._frames.append(record)

    def close(self) -> Path:
        """Write ``scene.json`` (via a temporary file and a rename); return its path."""
        path = self.directory / SCENE_FILE
        tmp = path.with_suffix(".json.tmp")
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump({**self._header, "frames": self._frames}, f, allow_nan=False)
        os.replace(tmp, path)
        return path

    def __enter__(self) -> "SceneWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()


def _same_camera(a: Camera, b: Camera) -> bool:
    return (a.width == b.width and a.height == b.height and a.near == b.near
            and np.array_equal(a.K, b.K) and np.array_equal(a.cam_to_ego, b.cam_to_ego))


def write_scene(scene: Scene, directory: str | Path, *, overwrite: bool = False) -> Path:
    """Write a whole :class:`Scene` to a folder; return the path of ``scene.json``."""
    with SceneWriter(directory, scene.name, scene.camera, scene.condition, scene.seed,
                     scene.synthetic, overwrite=overwrite) as writer:
        for frame in scene.frames:
            writer.add(frame)
    return writer.directory / SCENE_FILE


class _Fields:
    """Typed access to one JSON object; errors name the file and the field path."""

    def __init__(self, obj, where: str, file: Path):
        if not isinstance(obj, dict):
            raise ValueError(f"{file}: {where} is a {type(obj).__name__}, expected an object")
        self.obj, self.where, self.file = obj, where, file

    def error(self, key: str, message: str) -> ValueError:
        return ValueError(f"{self.file}: {self.where}.{key}: {message}")

    def get(self, key: str):
        if key not in self.obj:
            raise ValueError(f"{self.file}: {self.where}: field {key!r} is missing")
        return self.obj[key]

    def number(self, key: str) -> float:
        value = self.get(key)
        if (isinstance(value, bool) or not isinstance(value, (int, float))
                or not math.isfinite(value)):
            raise self.error(key, f"{value!r} is not a finite number")
        return float(value)

    def integer(self, key: str, *, optional: bool = False) -> int | None:
        value = self.get(key)
        if value is None and optional:
            return None
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"{value!r} is not an integer")
        return value

    def string(self, key: str, *, optional: bool = False) -> str | None:
        value = self.get(key)
        if value is None and optional:
            return None
        if not isinstance(value, str):
            raise self.error(key, f"{value!r} is not a string")
        return value

    def numbers(self, key: str, n: int) -> list[float]:
        value = self.get(key)
        if (not isinstance(value, list) or len(value) != n
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
            raise self.error(key, f"{value!r} is not a list of {n} numbers")
        return [float(v) for v in value]

    def matrix(self, key: str, rows: int, cols: int) -> np.ndarray:
        value = self.get(key)
        ok = isinstance(value, list) and len(value) == rows and all(
            isinstance(r, list) and len(r) == cols
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in r)
            for r in value)
        if not ok:
            raise self.error(key, f"expected a {rows}x{cols} list of lists of numbers")
        return np.array(value, dtype=np.float64)

    def objects(self, key: str) -> list["_Fields"]:
        value = self.get(key)
        if not isinstance(value, list):
            raise self.error(key, f"is a {type(value).__name__}, expected a list")
        return [_Fields(v, f"{self.where}.{key}[{i}]", self.file) for i, v in enumerate(value)]


def _boxes_from(records: list[_Fields]) -> np.ndarray:
    rows = [r.numbers("translation", 3) + r.numbers("size", 3) + [r.number("yaw")] for r in records]
    return np.array(rows, dtype=np.float64).reshape(len(rows), 7)


class SceneReader:
    """Read a scene folder lazily: the header now, each frame's maps when asked.

    Parameters
    ----------
    directory : str or Path
        A folder written by :class:`SceneWriter` (or in the same format).

    Attributes
    ----------
    directory : Path
    name, camera, condition, seed, synthetic
        As in :class:`Scene`.

    Raises
    ------
    FileNotFoundError
        No folder or no ``scene.json`` (and, from :meth:`frame`, a missing map file).
    ValueError
        Malformed JSON or a field of the wrong type, shape or value; the message names the
        file and the field (``scene.json: frames[3].annotations[2].size: ...``).
    """

    def __init__(self, directory: str | Path):
        self.directory = Path(directory)
        path = self.directory / SCENE_FILE
        if not path.is_file():
            raise FileNotFoundError(f"scene file {path} does not exist")
        try:
            with open(path, encoding="utf-8") as f:
                data = json.load(f)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}: not valid JSON ({exc})") from exc
        self._path = path
        top = _Fields(data, "scene", path)
        if top.get("format") != FORMAT or top.get("version") != VERSION:
            raise ValueError(
                f"{path}: format {top.get('format')!r} version {top.get('version')!r}, "
                f"expected {FORMAT!r} version {VERSION}"
            )
        if top.get("coordinate_frame") != "ego":
            raise top.error("coordinate_frame", f"{top.get('coordinate_frame')!r}, expected 'ego'")
        self.name = top.string("name")
        self.condition = top.string("condition")
        self.seed = top.integer("seed", optional=True)
        self.synthetic = top.get("synthetic")
        if not isinstance(self.synthetic, bool):
            raise top.error("synthetic", f"{self.synthetic!r} is not true or false")
        cam = _Fields(top.get("camera"), "scene.camera", path)
        try:
            self.camera = Camera(
                K=cam.matrix("camera_intrinsic", 3, 3), width=cam.integer("width"),
                height=cam.integer("height"), cam_to_ego=cam.matrix("cam_to_ego", 4, 4),
                near=cam.number("near"),
            )
        except (ValueError, TypeError) as exc:
            raise ValueError(f"{path}: scene.camera: {exc}") from exc
        self._records = top.objects("frames")

    def __len__(self) -> int:
        return len(self._records)

    def __iter__(self) -> Iterator[Frame]:
        return (self.frame(i) for i in range(len(self)))

    def frame(self, i: int) -> Frame:
        """Load and validate frame ``i`` (its position in ``scene.json``)."""
        record = self._records[i]
        maps = {name: self._load_map(record, name) for name in MAPS}
        annotations = record.objects("annotations")
        detections = record.objects("detections")
        try:
            return Frame(
                index=record.integer("index"), timestamp=record.number("timestamp"),
                ego_speed=record.number("ego_speed"), camera=self.camera, **maps,
                gt_boxes3d=_boxes_from(annotations),
                gt_classes=np.array([a.string("category_name") for a in annotations], dtype=str),
                gt_ids=np.array([a.integer("instance_id") for a in annotations], dtype=np.int64),
                gt_visibility=np.array([a.number("visibility") for a in annotations],
                                       dtype=np.float64),
                det_boxes3d=_boxes_from(detections),
                det_classes=np.array([d.string("detection_name") for d in detections], dtype=str),
                det_scores=np.array([d.number("detection_score") for d in detections],
                                    dtype=np.float64),
            )
        except ValueError as exc:
            if str(exc).startswith(str(self._path)):
                raise
            raise ValueError(f"{self._path}: {record.where}: {exc}") from exc

    def _load_map(self, record: _Fields, name: str) -> np.ndarray | None:
        relative = record.string(name, optional=name != "depth_est")
        if relative is None:
            return None
        path = self.directory / relative
        if not path.is_file():
            raise FileNotFoundError(
                f"{self._path}: {record.where}.{name}: file {path} does not exist")
        try:
            array = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise ValueError(f"{path}: not a readable .npy array ({exc})") from exc
        if not isinstance(array, np.ndarray) or array.dtype != MAPS[name]:
            got = array.dtype if isinstance(array, np.ndarray) else "an archive"
            raise ValueError(f"{path}: holds {got}, expected a {np.dtype(MAPS[name])} {name} map")
        return array


def read_scene(directory: str | Path) -> Scene:
    """Read a whole scene folder into memory (see :class:`SceneReader` for the errors)."""
    reader = SceneReader(directory)
    return Scene(name=reader.name, camera=reader.camera, condition=reader.condition,
                 seed=reader.seed, synthetic=reader.synthetic, frames=tuple(reader))

