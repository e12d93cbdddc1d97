"""Scene folders: the on-disk format of a :class:`~monitor.datasets.frames.Scene`.

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
from pathlib import Path
from typing import Iterator

import numpy as np

from fuzzcore.outputs import write_text
from monitor.datasets.fields import JsonFields, load_json
from monitor.datasets.frames import MAPS, Frame, Scene
from monitor.geometry.camera import Camera
from monitor.userfiles import read_npy, write_npy

FORMAT = "fuzzrisk-scene"
VERSION = 1
SCENE_FILE = "scene.json"


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
        if not frame.camera.same_as(self._camera):
            raise ValueError(f"frame {frame.index} has another camera than the scene")
        record = {"index": frame.index, "timestamp": frame.timestamp, "ego_speed": frame.ego_speed}
        for name in MAPS:
            array = getattr(frame, name)
            if array is None:
                record[name] = None
                continue
            relative = f"{name}/{len(self._frames):06d}.npy"
            (self.directory / name).mkdir(exist_ok=True)
            write_npy(self.directory / relative, array)
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
        write_text(path, json.dumps({**self._header, "frames": self._frames}, allow_nan=False))
        return path

    def __enter__(self) -> "SceneWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()


def write_scene(scene: Scene, directory: str | Path, *, overwrite: bool = False) -> Path:
    """Write a whole :class:`Scene` to a folder; return the path of ``scene.json``."""
    with SceneWriter(directory, scene.name, scene.camera, scene.condition, scene.seed,
                     scene.synthetic, overwrite=overwrite) as writer:
        for frame in scene.frames:
            writer.add(frame)
    return writer.directory / SCENE_FILE


def _boxes_from(records: list[JsonFields]) -> np.ndarray:
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
        data = load_json(path, "scene file")
        self._path = path
        top = JsonFields(data, "scene", path)
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
        cam = JsonFields(top.get("camera"), "scene.camera", path)
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

    def _load_map(self, record: JsonFields, name: str) -> np.ndarray | None:
        relative = record.string(name, optional=name != "depth_est")
        if relative is None:
            return None
        path = self.directory / relative
        if not path.is_file():
            raise FileNotFoundError(
                f"{self._path}: {record.where}.{name}: file {path} does not exist")
        array = read_npy(path, f"{name} map")
        if array.dtype != MAPS[name]:
            raise ValueError(f"{path}: holds {array.dtype}, expected a {np.dtype(MAPS[name])} {name} map")
        return array


def read_scene(directory: str | Path) -> Scene:
    """Read a whole scene folder into memory (see :class:`SceneReader` for the errors)."""
    reader = SceneReader(directory)
    return Scene(name=reader.name, camera=reader.camera, condition=reader.condition,
                 seed=reader.seed, synthetic=reader.synthetic, frames=tuple(reader))

