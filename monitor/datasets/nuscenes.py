"""nuScenes tables and detection results, read into the monitor's frames.

What is read
------------
The tables of one version (``DATAROOT/VERSION/*.json``, e.g. ``v1.0-mini``) that a camera
frame needs: ``scene``, ``sample``, ``sample_data``, ``sensor``, ``calibrated_sensor``,
``ego_pose``, ``sample_annotation``, ``instance``, ``category`` and ``visibility``, in the
nuScenes schema (records with a ``token``; translations in metres, rotations as
quaternions ``[w, x, y, z]``, sizes ``[w, l, h]``, timestamps in microseconds). The
3D detector's boxes come from a results file in the format of the nuScenes detection
evaluation::

    {"meta": {...}, "results": {sample_token: [{"sample_token": ..., "translation": [x, y, z],
     "size": [w, l, h], "rotation": [w, x, y, z], "velocity": [vx, vy],
     "detection_name": "car", "detection_score": 0.7, "attribute_name": ...}, ...]}}

Depth maps (the depth network's output, not part of nuScenes) come from a
:class:`~monitor.depth.files.DepthFolder` keyed by the camera image's file stem (the
``sample_data`` file name without folder and extension, e.g.
``n008-2018-08-01-15-16-36-0400__CAM_FRONT__1533151603512404``).

What a frame holds
------------------
One :class:`~monitor.datasets.frames.Frame` per sample (key frame) of a scene, seen by one camera:

- the camera from that sample's ``calibrated_sensor`` record and image size;
- the ego frame (x forward, y left, z up) at the ego pose of the camera's ``sample_data``
  (the pose at the image's timestamp, as the devkit uses to project into an image); the
  annotations and detections, both in the global frame, are moved into it;
- ground truth: the annotations whose category maps to a detection class
  (:data:`DETECTION_MAPPING`, the devkit's ``category_to_detection_name``; others are not
  objects the detector is asked for and are left out), with instance ids numbered 0, 1, ...
  in order of first appearance in the scene, and a visibility: nuScenes' visibility level
  is the visible fraction of the object over *all six* cameras in bins 0-40, 40-60, 60-80,
  80-100 %; the upper bound of the bin / 100 is used (0.4, 0.6, 0.8, 1.0) for objects this
  camera sees, and 0 for objects it does not see at all (nothing of the box inside the
  camera's view), so an object behind the car never counts as ground truth of a front image;
- timestamp: seconds since the scene's first sample; ego speed: distance between the ego
  poses of this frame and the previous one (the next one for the first frame) over the time
  between them, m/s; ``depth_true`` and ``labels`` are None.

Decisions on incomplete input (each an error naming the file and token, never a guess):
a results entry for a sample token the tables do not have is an error (results from
another version or split); a selected scene with a sample the results file does not list
is an error (the nuScenes format lists every sample, with ``[]`` when nothing was
detected, so a missing one is not "no detections"). With ``scene_names=None`` the scenes
are those the results file covers, in ``scene.json`` order; scenes it does not cover at all
are listed in :attr:`NuScenesReader.uncovered_scenes`. A scene with a single sample has no
ego speed and is an error.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np

from monitor.geometry.boxes3d import boxes3d_from_quaternions, transform_boxes
from monitor.geometry.camera import Camera, project_boxes
from monitor.geometry.poses import invert_pose, pose_matrix
from monitor.depth.files import DepthFolder
from monitor.datasets.fields import JsonFields, load_json
from monitor.datasets.frames import Frame, FrameRecord

#: nuScenes category name -> detection class (the devkit's ``category_to_detection_name``);
#: categories not listed (animals, strollers, debris, ...) have no detection class.
DETECTION_MAPPING = {
    "movable_object.barrier": "barrier",
    "vehicle.bicycle": "bicycle",
    "vehicle.bus.bendy": "bus",
    "vehicle.bus.rigid": "bus",
    "vehicle.car": "car",
    "vehicle.construction": "construction_vehicle",
    "vehicle.motorcycle": "motorcycle",
    "human.pedestrian.adult": "pedestrian",
    "human.pedestrian.child": "pedestrian",
    "human.pedestrian.construction_worker": "pedestrian",
    "human.pedestrian.police_officer": "pedestrian",
    "movable_object.trafficcone": "traffic_cone",
    "vehicle.trailer": "trailer",
    "vehicle.truck": "truck",
}

#: the detection classes of the nuScenes detection task
DETECTION_NAMES = ("car", "truck", "bus", "trailer", "construction_vehicle", "pedestrian",
                   "motorcycle", "bicycle", "traffic_cone", "barrier")

#: the tables the reader loads
TABLES = ("scene", "sample", "sample_data", "sensor", "calibrated_sensor", "ego_pose",
          "sample_annotation", "instance", "category", "visibility")

_VISIBILITY_LEVEL = re.compile(r"^v(\d+)-(\d+)$")  # "v0-40" ... "v80-100"
_US = 1e-6  # seconds per nuScenes timestamp unit (microseconds)


def category_to_detection_name(category_name: str) -> str | None:
    """The detection class of a nuScenes category name, or None if it has none."""
    return DETECTION_MAPPING.get(category_name)


def _load_table(folder: Path, name: str) -> dict[str, JsonFields]:
    """A nuScenes table as ``{token: record}``; the file must be a list of objects."""
    path = folder / f"{name}.json"
    data = load_json(path, f"nuScenes table {name!r}:")
    if not isinstance(data, list):
        raise ValueError(f"{path}: holds a {type(data).__name__}, expected a list of records")
    table: dict[str, JsonFields] = {}
    for i, obj in enumerate(data):
        record = JsonFields(obj, f"{name}[{i}]", path)
        token = record.string("token")
        if token in table:
            raise ValueError(f"{path}: {name}[{i}]: token {token!r} appears twice")
        record.where = f"{name}[token={token}]"
        table[token] = record
    return table


def _lookup(table: dict[str, JsonFields], name: str, token: str, referrer: JsonFields,
            key: str) -> JsonFields:
    try:
        return table[token]
    except KeyError:
        raise referrer.error(key, f"{token!r} is not a token of table {name!r}") from None


def _quaternion(record: JsonFields, key: str) -> list[float]:
    q = record.numbers(key, 4)
    if abs(float(np.linalg.norm(q)) - 1.0) > 1e-3:
        raise record.error(key, f"{q!r} is not a unit quaternion [w, x, y, z]")
    return q


def _visibility_fractions(table: dict[str, JsonFields]) -> dict[str, float]:
    """visibility token -> upper bound of its level as a fraction (``"v40-60"`` -> 0.6)."""
    out = {}
    for token, record in table.items():
        level = record.string("level")
        match = _VISIBILITY_LEVEL.match(level)
        if match is None or not int(match[1]) < int(match[2]) <= 100:
            raise record.error("level", f"{level!r}, expected 'vA-B' with 0 <= A < B <= 100 "
                                        "(percent visible, e.g. 'v40-60')")
        out[token] = int(match[2]) / 100.0
    return out


@dataclass(frozen=True)
class DetectionResults:
    """A detection-results file: boxes per sample token, already parsed (global frame)."""

    path: Path
    boxes: dict[str, np.ndarray]   # (m, 7) global boxes x, y, z, w, l, h, yaw
    classes: dict[str, np.ndarray]
    scores: dict[str, np.ndarray]


def read_detection_results(path: Path, samples, *, tokens_file: str = "the tables' sample.json"
                           ) -> DetectionResults:
    """Read a results file in the nuScenes detection format (the module docstring).

    ``samples`` holds the known sample tokens (a token in the results that is not among
    them is an error that names ``tokens_file``, where the known tokens come from).
    """
    path = Path(path)
    data = load_json(path, "detection results file")
    top = JsonFields(data, "results file", path)
    top.get("meta")
    results = top.get("results")
    if not isinstance(results, dict):
        raise top.error("results", f"is a {type(results).__name__}, expected an object "
                                   "{sample_token: [box, ...]}")
    unknown = [t for t in results if t not in samples]
    if unknown:
        raise ValueError(f"{path}: results has {len(unknown)} sample tokens that are not in "
                         f"{tokens_file}, first {unknown[0]!r}: results from another "
                         "version or split?")
    boxes, classes, scores = {}, {}, {}
    for token, records in results.items():
        if not isinstance(records, list):
            raise ValueError(f"{path}: results[{token}] is a {type(records).__name__}, expected "
                             "a list of boxes ([] when nothing was detected)")
        entries = [JsonFields(r, f"results[{token}][{i}]", path) for i, r in enumerate(records)]
        for entry in entries:
            if entry.string("sample_token") != token:
                raise entry.error("sample_token", f"{entry.get('sample_token')!r}, expected "
                                                  f"{token!r} (the key it is listed under)")
            name = entry.string("detection_name")
            if name not in DETECTION_NAMES:
                raise entry.error("detection_name", f"{name!r}, expected one of {DETECTION_NAMES}")
            score = entry.number("detection_score")
            if not 0.0 <= score <= 1.0:
                raise entry.error("detection_score", f"{score!r}, must be in [0, 1]")
        boxes[token] = _global_boxes(entries, path)
        classes[token] = np.array([e.string("detection_name") for e in entries], dtype=str)
        scores[token] = np.array([e.number("detection_score") for e in entries], dtype=np.float64)
    return DetectionResults(path, boxes, classes, scores)


def _global_boxes(records: list[JsonFields], path: Path) -> np.ndarray:
    """(n, 7) boxes from records with translation, size ``[w, l, h]`` and rotation."""
    centres = [r.numbers("translation", 3) for r in records]
    sizes = []
    for r in records:
        size = r.numbers("size", 3)
        if min(size) <= 0.0:
            raise r.error("size", f"{size!r}: sizes [w, l, h] must be > 0 metres")
        sizes.append(size)
    rotations = [_quaternion(r, "rotation") for r in records]
    n = len(records)
    return boxes3d_from_quaternions(np.reshape(centres, (n, 3)), np.reshape(sizes, (n, 3)),
                                    np.reshape(rotations, (n, 4)))


class NuScenesScene:
    """One nuScenes scene seen by one camera; frames are built when ``frames`` is iterated.

    Attributes
    ----------
    name : str
        nuScenes' scene name (``"scene-0061"``).
    token : str
    condition : str
    split : str
        Always ``"test"``: the reader does not split scenes into training and test sets.
    camera : Camera
        The camera of the scene's first sample.
    samples : tuple of str
        Sample tokens in time order.
    """

    split = "test"

    def __init__(self, reader: "NuScenesReader", record: JsonFields, samples: tuple[str, ...],
                 condition: str):
        self._reader = reader
        self.name = record.string("name")
        self.token = record.string("token")
        self.condition = condition
        self.samples = samples
        self.camera = reader._camera(reader._camera_data(samples[0]))
        for sample in samples[1:]:
            reader._camera_data(sample)  # fail now, not halfway through an evaluation
        instances: dict[str, int] = {}
        for sample in samples:
            for ann in reader._annotations.get(sample, ()):
                instances.setdefault(ann.string("instance_token"), len(instances))
        self._instance_ids = instances

    def __len__(self) -> int:
        return len(self.samples)

    @property
    def frames(self) -> Iterator[Frame]:
        """The scene's frames in time order, read one at a time."""
        return (self.frame(i) for i in range(len(self.samples)))

    def frame(self, i: int) -> Frame:
        """Frame ``i`` (the scene's ``i``-th sample), its depth map read from the depth folder."""
        return self._reader._frame(self, i)

    def record(self, i: int) -> FrameRecord:
        """Frame ``i`` before its depth is read: the depth file (when the reader has a depth
        folder) and the camera image ``DATAROOT/filename``."""
        return self._reader._record(self, i)

    def records(self) -> list[FrameRecord]:
        """The records of every frame, in time order."""
        return [self.record(i) for i in range(len(self.samples))]

    def __repr__(self) -> str:
        return f"NuScenesScene({self.name!r}, {len(self)} samples)"


class NuScenesReader:
    """Read nuScenes scenes, a detection-results file and depth maps into frames.

    See the module docstring for what a frame holds and the decisions on missing data.

    Parameters
    ----------
    dataroot : str or Path
        The nuScenes root; the tables are in ``dataroot / version``.
    version : str, default "v1.0-trainval"
    detections : str or Path
        A detection-results JSON file (nuScenes detection-evaluation format).
    depth : DepthFolder, str, Path or None
        Depth maps keyed by the camera image's file stem; None when the depth is to be
        estimated from the camera images (then only :meth:`NuScenesScene.record` works).
    camera : str, default "CAM_FRONT"
        The camera channel (``sensor.channel``).
    condition : str, default "nuscenes"
        The condition label of every scene.
    scene_names : iterable of str, optional
        The scenes to read (default: the ones the results file covers).

    Attributes
    ----------
    uncovered_scenes : tuple of str
        With ``scene_names=None``: the scenes left out because the results file has none of
        their samples.

    Raises
    ------
    FileNotFoundError
        A missing table, results file or depth folder.
    ValueError
        Malformed JSON, a missing or mistyped field, a dangling token, a sample without the
        camera, results for unknown samples, a selected scene the results do not cover. The
        message names the file and the record (``sample_data[token=...].width: ...``).
    """

    def __init__(self, dataroot: str | Path, version: str = "v1.0-trainval", *,
                 detections: str | Path, depth: DepthFolder | str | Path,
                 camera: str = "CAM_FRONT", condition: str = "nuscenes",
                 scene_names: Iterable[str] | None = None):
        folder = Path(dataroot) / version
        if not folder.is_dir():
            raise FileNotFoundError(f"nuScenes tables folder {folder} (dataroot / version) "
                                    "does not exist")
        self.folder = folder
        self.dataroot = Path(dataroot)
        self.channel = camera
        self.depth = depth if depth is None or isinstance(depth, DepthFolder) else DepthFolder(depth)
        t = {name: _load_table(folder, name) for name in TABLES}
        self._t = t
        self._visibility = _visibility_fractions(t["visibility"])
        sensors = [tok for tok, r in t["sensor"].items() if r.string("channel") == camera]
        if not sensors:
            channels = sorted({r.string("channel") for r in t["sensor"].values()})
            raise ValueError(f"{folder / 'sensor.json'}: no sensor has channel {camera!r}; "
                             f"channels: {channels}")
        self._cam_data: dict[str, JsonFields] = {}
        for sd in t["sample_data"].values():
            cs = _lookup(t["calibrated_sensor"], "calibrated_sensor",
                         sd.string("calibrated_sensor_token"), sd, "calibrated_sensor_token")
            if cs.string("sensor_token") in sensors and sd.get("is_key_frame") is True:
                self._cam_data[sd.string("sample_token")] = sd
        self._annotations: dict[str, list[JsonFields]] = {}
        for ann in t["sample_annotation"].values():
            self._annotations.setdefault(ann.string("sample_token"), []).append(ann)
        self._detections = read_detection_results(Path(detections), t["sample"])
        self._cameras: dict[str, Camera] = {}
        self._scenes, uncovered = self._select(condition, scene_names)
        self.uncovered_scenes = tuple(uncovered)

    def scenes(self) -> list[NuScenesScene]:
        """The selected scenes, in ``scene.json`` order."""
        return list(self._scenes)

    def _select(self, condition: str, names: Iterable[str] | None
                ) -> tuple[list[NuScenesScene], list[str]]:
        scene_path = self.folder / "scene.json"
        by_name = {r.string("name"): r for r in self._t["scene"].values()}
        if names is not None:
            names = list(names)
            missing = [n for n in names if n not in by_name]
            if missing:
                raise ValueError(f"{scene_path}: no scene named {missing[0]!r} "
                                 f"({len(by_name)} scenes present)")
        scenes, uncovered = [], []
        for name, record in by_name.items():
            if names is not None and name not in names:
                continue
            samples = self._scene_samples(record)
            covered = [s in self._detections.boxes for s in samples]
            if names is None and not any(covered):
                uncovered.append(name)
                continue
            if not all(covered):
                raise ValueError(
                    f"{self._detections.path}: results has no entry for sample "
                    f"{samples[covered.index(False)]!r} of scene {name!r} (every sample of a "
                    "scene must be listed, with [] when nothing was detected)")
            if len(samples) < 2:
                raise record.error("first_sample_token", f"scene {name!r} has one sample; the "
                                                         "ego speed needs two")
            scenes.append(NuScenesScene(self, record, samples, condition))
        return scenes, uncovered

    def _scene_samples(self, scene: JsonFields) -> tuple[str, ...]:
        """The scene's sample tokens in time order, following ``next`` links."""
        samples, token = [], scene.string("first_sample_token")
        referrer, key = scene, "first_sample_token"
        while token:
            sample = _lookup(self._t["sample"], "sample", token, referrer, key)
            if sample.string("scene_token") != scene.string("token"):
                raise sample.error("scene_token", f"{sample.get('scene_token')!r}, but the sample "
                                                  f"is linked from scene {scene.string('name')!r}")
            if token in samples:
                raise referrer.error(key, f"{token!r} links back into the scene (a cycle)")
            samples.append(token)
            referrer, key, token = sample, "next", sample.string("next")
        return tuple(samples)

    def _camera_data(self, sample: str) -> JsonFields:
        try:
            return self._cam_data[sample]
        except KeyError:
            raise ValueError(f"{self.folder / 'sample_data.json'}: sample {sample!r} has no "
                             f"key-frame sample_data from camera {self.channel!r}") from None

    def _camera(self, sd: JsonFields) -> Camera:
        token = sd.string("calibrated_sensor_token")
        if token not in self._cameras:
            cs = self._t["calibrated_sensor"][token]
            width, height = sd.integer("width"), sd.integer("height")
            try:
                self._cameras[token] = Camera.from_nuscenes(
                    cs.matrix("camera_intrinsic", 3, 3), _quaternion(cs, "rotation"),
                    cs.numbers("translation", 3), width, height)
            except ValueError as exc:
                if str(exc).startswith(str(self.folder)):
                    raise
                raise ValueError(f"{self.folder}: {cs.where} with {sd.where} image size "
                                 f"{width} x {height}: {exc}") from exc
        return self._cameras[token]

    def _ego_pose(self, sd: JsonFields) -> tuple[np.ndarray, float]:
        """(4, 4) ego -> global transform at the image, and its timestamp in seconds."""
        pose = _lookup(self._t["ego_pose"], "ego_pose", sd.string("ego_pose_token"), sd,
                       "ego_pose_token")
        T = pose_matrix(_quaternion(pose, "rotation"), pose.numbers("translation", 3))
        return T, pose.integer("timestamp") * _US

    def _ego_speed(self, scene: NuScenesScene, i: int) -> float:
        j = i - 1 if i > 0 else i + 1
        (Ti, ti), (Tj, tj) = (self._ego_pose(self._camera_data(scene.samples[k])) for k in (i, j))
        if not abs(ti - tj) > 0.0:
            raise ValueError(f"{self.folder / 'ego_pose.json'}: scene {scene.name!r} samples "
                             f"{i} and {j}: the camera's ego poses have the same timestamp; "
                             "no speed can be measured")
        return float(np.linalg.norm(Ti[:3, 3] - Tj[:3, 3]) / abs(ti - tj))

    def _record(self, scene: NuScenesScene, i: int) -> FrameRecord:
        token = scene.samples[i]
        sd = self._camera_data(token)
        camera = self._camera(sd)
        ego_to_global, _ = self._ego_pose(sd)
        global_to_ego = invert_pose(ego_to_global)
        stem = Path(sd.string("filename")).stem
        depth_path = None
        if self.depth is not None:
            if stem not in self.depth:
                raise FileNotFoundError(
                    f"depth folder {self.depth.root} has no map {stem}.npy / {stem}.png for "
                    f"{sd.where} (sample {token!r} of scene {scene.name!r})")
            depth_path = self.depth.path(stem)
        gt, classes, ids, vis = self._ground_truth(scene, token, global_to_ego, camera)
        det = self._detections
        t0 = self._t["sample"][scene.samples[0]].integer("timestamp")
        return FrameRecord(
            scene=scene.name, key=stem, index=i,
            timestamp=(self._t["sample"][token].integer("timestamp") - t0) * _US,
            ego_speed=self._ego_speed(scene, i), camera=camera, gt_boxes3d=gt, gt_classes=classes,
            gt_ids=ids, gt_visibility=vis, has_ground_truth=True,
            det_boxes3d=transform_boxes(det.boxes[token], global_to_ego),
            det_classes=det.classes[token], det_scores=det.scores[token],
            depth_path=depth_path, png_scale=256.0 if self.depth is None else self.depth.png_scale,
            image_path=self.dataroot / sd.string("filename"), token=token)

    def _frame(self, scene: NuScenesScene, i: int) -> Frame:
        if self.depth is None:
            raise ValueError(f"NuScenesReader of {self.folder} has no depth folder: read frame records "
                             "(scene.record(i)) and estimate their depth from the images instead")
        record = self._record(scene, i)
        depth = self.depth[record.key]
        try:
            return record.to_frame(depth, str(record.depth_path))
        except ValueError as exc:
            raise ValueError(f"scene {scene.name!r} sample {record.token!r} (depth "
                             f"{record.depth_path}): {exc.__cause__}") from exc

    def _ground_truth(self, scene: NuScenesScene, sample: str, global_to_ego: np.ndarray,
                      camera: Camera) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        t = self._t
        kept, classes = [], []
        for ann in self._annotations.get(sample, ()):
            instance = _lookup(t["instance"], "instance", ann.string("instance_token"), ann,
                               "instance_token")
            category = _lookup(t["category"], "category", instance.string("category_token"),
                               instance, "category_token")
            name = category_to_detection_name(category.string("name"))
            if name is not None:
                kept.append(ann)
                classes.append(name)
        boxes = transform_boxes(_global_boxes(kept, self.folder / "sample_annotation.json"),
                                global_to_ego)
        visibility = np.zeros(len(kept))
        _, seen = project_boxes(boxes, camera)
        for k in seen:
            ann = kept[k]
            token = ann.string("visibility_token")
            if token not in self._visibility:
                raise ann.error("visibility_token", f"{token!r} is not a token of table "
                                                    "'visibility'")
            visibility[k] = self._visibility[token]
        ids = np.array([scene._instance_ids[a.string("instance_token")] for a in kept],
                       dtype=np.int64)
        return boxes, np.array(classes, dtype=str).reshape(len(kept)), ids, visibility
