"""Recording folders: the format for users' own drives (``fuzzrisk monitor --recording DIR``).

One folder is one scene, named after the folder::

    RECORDING/
      camera.yaml        the camera calibration (format: monitor.datasets.calibration)
      frames.jsonl       one line per frame, in time order (below)
      depth/             depth maps named by frame key: 000000.npy (float metres) or
                         000000.png (16-bit, metres * 256); see monitor.depth.files
      images/            camera images named by frame key (000000.jpg, .png, ...): the input
                         of a depth network (--depth-model); needed only without depth/
      detections.jsonl   the detector's boxes in the ego frame, one line per frame, or
      detections.json    the nuScenes detection-results format, frame keys as sample tokens,
                         boxes in the global frame (then every frame needs an ego_pose)
      ground_truth.jsonl optional: annotated boxes in the ego frame, one line per frame

``frames.jsonl``, one object per line::

    {"frame": "000000", "timestamp": 0.0, "ego_speed": 8.3,
     "ego_pose": {"translation": [x, y, z], "rotation": [w, x, y, z]}}

``frame`` is the key that names the frame's files (sorted like the lines: zero-pad
numbers), ``timestamp`` seconds (increasing), ``ego_speed`` m/s and ``ego_pose`` the
ego -> global pose (metres, unit quaternion). Each frame needs ``ego_speed`` or an
``ego_pose`` (the speed is then the distance to the previous frame's pose over the time
between them; the first frame uses the next one, as for nuScenes).

``detections.jsonl``, one object per frame, every frame listed (``[]`` when nothing was
detected)::

    {"frame": "000000", "detections": [{"translation": [x, y, z], "size": [w, l, h],
      "yaw": 0.1, "detection_name": "car", "detection_score": 0.7}, ...]}

with the ego frame of :mod:`monitor.geometry.boxes3d` (x forward, y left, z up; metres,
``size`` as nuScenes' ``[w, l, h]``, yaw radians about z). ``ground_truth.jsonl`` has the
same lines with ``"annotations"`` holding ``translation``, ``size``, ``yaw``,
``category_name``, ``instance_id`` (an integer stable across the recording) and optionally
``visibility`` (the visible fraction in [0, 1]; default 1 for a box the camera sees and 0
for one it does not). Without ``ground_truth.jsonl`` the reports carry no target.

Every problem is an error naming the file, the line and the field; a frame missing from
the detections, or a line for a frame not in ``frames.jsonl``, is an error too.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from monitor.datasets.calibration import load_camera
from monitor.datasets.fields import JsonFields
from monitor.datasets.frames import FrameRecord
from monitor.datasets.nuscenes import read_detection_results
from monitor.depth.files import DepthFolder
from monitor.geometry.boxes3d import transform_boxes
from monitor.geometry.camera import project_boxes
from monitor.geometry.poses import invert_pose, pose_matrix

CAMERA_FILE = "camera.yaml"
FRAMES_FILE = "frames.jsonl"
DEPTH_DIR = "depth"
IMAGES_DIR = "images"
DETECTION_LINES = "detections.jsonl"
DETECTION_RESULTS = "detections.json"
GROUND_TRUTH = "ground_truth.jsonl"
#: image file extensions looked for in images/ (OpenCV reads them)
IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp")
#: the condition label of every recording
CONDITION = "recorded"


def _json_lines(path: Path, key: str) -> dict[str, JsonFields]:
    """``{frame key: line}`` of a JSON-lines file whose objects name their frame in ``key``."""
    out: dict[str, JsonFields] = {}
    with open(path, encoding="utf-8") as f:
        for n, text in enumerate(f, start=1):
            if not text.strip():
                continue
            try:
                obj = json.loads(text)
            except json.JSONDecodeError as exc:
                raise ValueError(f"{path}: line {n}: not valid JSON ({exc})") from None
            line = JsonFields(obj, f"line {n}", path)
            frame = line.string(key)
            if frame in out:
                raise line.error(key, f"frame {frame!r} appears twice")
            line.where = f"line {n} (frame {frame})"
            out[frame] = line
    return out


def _ego_boxes(records: list[JsonFields]) -> np.ndarray:
    rows = []
    for r in records:
        size = r.numbers("size", 3)
        if min(size) <= 0.0:
            raise r.error("size", f"{size!r}: sizes [w, l, h] must be > 0 metres")
        rows.append(r.numbers("translation", 3) + size + [r.number("yaw")])
    return np.array(rows, dtype=np.float64).reshape(len(rows), 7)


def _unit(record: JsonFields, key: str) -> float:
    value = record.number(key)
    if not 0.0 <= value <= 1.0:
        raise record.error(key, f"{value!r}, must be in [0, 1]")
    return value


class RecordingReader:
    """One recording folder (format in the module docstring) as frame records.

    Parameters
    ----------
    directory : str or Path
    need_images : bool, default False
        The depth is to be estimated from ``images/`` (a depth network); otherwise it is
        read from ``depth/``.
    png_scale : float, default 256
        Stored value per metre of 16-bit PNG depth maps.

    Attributes
    ----------
    name : str
        The folder's name, the scene's name.
    condition : str
        :data:`CONDITION`.
    camera : Camera
    has_ground_truth : bool

    Raises
    ------
    FileNotFoundError
        A missing folder, calibration, frame list, detections, depth map or image.
    ValueError
        Malformed content; the message names the file, line and field.
    """

    split = "test"
    condition = CONDITION

    def __init__(self, directory: str | Path, *, need_images: bool = False, png_scale: float = 256.0):
        self.directory = Path(directory)
        if not self.directory.is_dir():
            raise FileNotFoundError(f"recording folder {self.directory} does not exist or is not a directory")
        self.name = self.directory.resolve().name
        self.camera = load_camera(self._file(CAMERA_FILE, "camera calibration"))
        frames_path = self._file(FRAMES_FILE, "frame list")
        self._frames = _json_lines(frames_path, "frame")
        if not self._frames:
            raise ValueError(f"{frames_path}: lists no frames")
        keys = list(self._frames)
        times = [self._frames[k].number("timestamp") for k in keys]
        for k in range(1, len(keys)):
            if not times[k] > times[k - 1]:
                raise self._frames[keys[k]].error("timestamp", f"{times[k]!r}, not after the previous "
                                                               f"frame's {times[k - 1]!r} (lines in time order)")
        if keys != sorted(keys):
            raise ValueError(f"{frames_path}: frame keys are not in sorted order (first out of order: "
                             f"{next(b for a, b in zip(keys, keys[1:]) if b < a)!r}); zero-pad numbered keys")
        self._times = times
        self._poses = {k: self._pose(line) for k, line in self._frames.items()}
        self._speeds = [self._speed(i) for i in range(len(keys))]
        self._detections = self._read_detections()
        gt_path = self.directory / GROUND_TRUTH
        self.has_ground_truth = gt_path.is_file()
        self._truth = self._per_frame(gt_path, "annotations") if self.has_ground_truth else None
        self._depth_dir, self._images = None, None
        if need_images:
            self._images = self._image_files()
        else:
            depth_dir = self.directory / DEPTH_DIR
            if not depth_dir.is_dir():
                raise FileNotFoundError(
                    f"recording {self.directory}: no {DEPTH_DIR}/ folder of depth maps; give one, or "
                    f"camera images in {IMAGES_DIR}/ and a depth network (--depth-model)")
            self._depth_dir = DepthFolder(depth_dir, png_scale=png_scale)
            missing = [k for k in keys if k not in self._depth_dir]
            if missing:
                raise FileNotFoundError(f"depth folder {depth_dir} has no map for frame {missing[0]!r} "
                                        f"({len(missing)} of {len(keys)} frames missing)")

    def _file(self, name: str, what: str) -> Path:
        path = self.directory / name
        if not path.is_file():
            raise FileNotFoundError(f"recording {self.directory}: {what} {name} is missing")
        return path

    def _pose(self, line: JsonFields) -> np.ndarray | None:
        if "ego_pose" not in line.obj:
            return None
        pose = JsonFields(line.get("ego_pose"), f"{line.where}.ego_pose", line.file)
        try:
            return pose_matrix(pose.numbers("rotation", 4), pose.numbers("translation", 3))
        except ValueError as exc:
            if str(exc).startswith(str(line.file)):
                raise
            raise pose.error("rotation", str(exc)) from None

    def _speed(self, i: int) -> float:
        keys = list(self._frames)
        line = self._frames[keys[i]]
        if "ego_speed" in line.obj:
            speed = line.number("ego_speed")
            if speed < 0:
                raise line.error("ego_speed", f"{speed!r}, must be >= 0 m/s")
            return speed
        j = i - 1 if i > 0 else i + 1
        if j >= len(keys) or self._poses[keys[i]] is None or self._poses[keys[j]] is None:
            raise line.error("ego_speed", "missing, and no ego_pose here and at the neighbouring frame "
                                          "to measure it from; give ego_speed (m/s) or ego_pose")
        distance = np.linalg.norm(self._poses[keys[i]][:3, 3] - self._poses[keys[j]][:3, 3])
        return float(distance / abs(self._times[i] - self._times[j]))

    def _per_frame(self, path: Path, field: str) -> dict[str, list[JsonFields]]:
        lines = _json_lines(path, "frame")
        unknown = [k for k in lines if k not in self._frames]
        if unknown:
            raise ValueError(f"{path}: {lines[unknown[0]].where}: frame {unknown[0]!r} is not in {FRAMES_FILE}")
        missing = [k for k in self._frames if k not in lines]
        if missing:
            raise ValueError(f"{path}: no line for frame {missing[0]!r} ({len(missing)} frames missing; "
                             f"list every frame, with [] when it has no boxes)")
        return {k: lines[k].objects(field) for k in self._frames}

    def _read_detections(self) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        lines_path, results_path = self.directory / DETECTION_LINES, self.directory / DETECTION_RESULTS
        if lines_path.is_file() == results_path.is_file():
            raise FileNotFoundError(
                f"recording {self.directory}: needs exactly one of {DETECTION_LINES} (ego-frame boxes) and "
                f"{DETECTION_RESULTS} (nuScenes results format); found "
                f"{'both' if lines_path.is_file() else 'neither'}")
        out = {}
        if lines_path.is_file():
            for key, records in self._per_frame(lines_path, "detections").items():
                for r in records:
                    r.string("detection_name")
                    _unit(r, "detection_score")
                out[key] = (_ego_boxes(records),
                            np.array([r.string("detection_name") for r in records], dtype=str),
                            np.array([r.number("detection_score") for r in records], dtype=np.float64))
            return out
        results = read_detection_results(results_path, self._frames,
                                         tokens_file=f"{self.directory / FRAMES_FILE} (the frame keys)")
        for key, line in self._frames.items():
            if key not in results.boxes:
                raise ValueError(f"{results_path}: results has no entry for frame {key!r} (every frame must "
                                 "be listed, with [] when nothing was detected)")
            pose = self._poses[key]
            if pose is None:
                raise line.error("ego_pose", f"missing: the detections in {DETECTION_RESULTS} are in the global "
                                             "frame and need the ego pose of every frame")
            out[key] = (transform_boxes(results.boxes[key], invert_pose(pose)), results.classes[key],
                        results.scores[key])
        return out

    def _image_files(self) -> dict[str, Path]:
        folder = self.directory / IMAGES_DIR
        if not folder.is_dir():
            raise FileNotFoundError(f"recording {self.directory}: no {IMAGES_DIR}/ folder of camera images "
                                    "for the depth network")
        found: dict[str, Path] = {}
        for path in folder.iterdir():
            if path.suffix.lower() in IMAGE_SUFFIXES and path.stem in self._frames:
                if path.stem in found:
                    raise ValueError(f"images folder {folder}: frame {path.stem!r} has two images "
                                     f"({found[path.stem].name}, {path.name}); keep one")
                found[path.stem] = path
        missing = [k for k in self._frames if k not in found]
        if missing:
            raise FileNotFoundError(f"images folder {folder} has no image of frame {missing[0]!r} "
                                    f"({len(missing)} of {len(self._frames)} missing; looked for "
                                    f"{', '.join(IMAGE_SUFFIXES)})")
        return found

    def __len__(self) -> int:
        return len(self._frames)

    def _truth_of(self, key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        if self._truth is None:
            return np.zeros((0, 7)), np.zeros(0, dtype=str), np.zeros(0, dtype=np.int64), np.zeros(0)
        records = self._truth[key]
        boxes = _ego_boxes(records)
        _, seen = project_boxes(boxes, self.camera)
        in_view = np.zeros(len(records), dtype=bool)
        in_view[seen] = True
        visibility = np.array([_unit(r, "visibility") if "visibility" in r.obj else float(in_view[k])
                               for k, r in enumerate(records)], dtype=np.float64)
        return (boxes, np.array([r.string("category_name") for r in records], dtype=str),
                np.array([r.integer("instance_id") for r in records], dtype=np.int64), visibility)

    def record(self, i: int) -> FrameRecord:
        """Frame ``i`` (the ``i``-th line of ``frames.jsonl``) before its depth is read."""
        key = list(self._frames)[i]
        boxes, classes, scores = self._detections[key]
        gt, gt_classes, gt_ids, visibility = self._truth_of(key)
        return FrameRecord(
            scene=self.name, key=key, index=i, timestamp=self._times[i], ego_speed=self._speeds[i],
            camera=self.camera, det_boxes3d=boxes, det_classes=classes, det_scores=scores,
            gt_boxes3d=gt, gt_classes=gt_classes, gt_ids=gt_ids, gt_visibility=visibility,
            has_ground_truth=self.has_ground_truth,
            depth_path=None if self._depth_dir is None else self._depth_dir.path(key),
            png_scale=256.0 if self._depth_dir is None else self._depth_dir.png_scale,
            image_path=None if self._images is None else self._images[key])

    def records(self) -> list[FrameRecord]:
        """Every frame's record, in time order."""
        return [self.record(i) for i in range(len(self))]

    def __repr__(self) -> str:
        return f"RecordingReader({str(self.directory)!r}, {len(self)} frames)"

