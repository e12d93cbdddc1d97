"""Camera calibration files: a small YAML file describing one :class:`~monitor.geometry.camera.Camera`.

.. code-block:: yaml

    # camera.yaml
    width: 1600                 # pixels
    height: 900
    intrinsics:                 # 3 x 3, pixels
      - [1266.417, 0.0, 816.267]
      - [0.0, 1266.417, 491.507]
      - [0.0, 0.0, 1.0]
    # the mounting, either as a 4 x 4 camera -> ego transform ...
    cam_to_ego:
      - [0.0, 0.0, 1.0, 1.70]
      - [-1.0, 0.0, 0.0, 0.016]
      - [0.0, -1.0, 0.0, 1.51]
      - [0.0, 0.0, 0.0, 1.0]
    # ... or nuScenes-style (calibrated_sensor): camera -> ego rotation and position
    # rotation: [0.4998, -0.5030, 0.4998, -0.4974]   # quaternion w, x, y, z
    # translation: [1.70, 0.016, 1.51]               # metres
    near: 0.1                   # optional, metres (default 0.1)

Unknown, missing, repeated or malformed fields are errors naming the file and the field;
the file is read as strict safe YAML (:func:`fuzzcore.strict_yaml.load`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fuzzcore import strict_yaml
from monitor.geometry.camera import Camera
from monitor.geometry.poses import as_pose, pose_matrix

#: field -> what it must hold, for messages
FIELDS = {
    "width": "a positive integer (pixels)",
    "height": "a positive integer (pixels)",
    "intrinsics": "a 3 x 3 list of numbers (pixels)",
    "cam_to_ego": "a 4 x 4 list of numbers (camera -> ego rigid transform)",
    "rotation": "a list of 4 numbers (camera -> ego quaternion w, x, y, z)",
    "translation": "a list of 3 numbers (camera position in the ego frame, metres)",
    "near": "a number of metres >= 0.001",
}
_SHAPES = {"intrinsics": (3, 3), "cam_to_ego": (4, 4), "rotation": (4,), "translation": (3,)}


def _matrix(path: Path, data: dict, key: str) -> np.ndarray:
    value = data[key]
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        arr = None
    if arr is None or isinstance(value, (str, bytes)) or arr.shape != _SHAPES[key] \
            or not np.isfinite(arr).all():
        raise ValueError(f"{path}: {key} = {value!r}, expected {FIELDS[key]}")
    return arr


def load_camera(path: str | Path) -> Camera:
    """Read a camera calibration file (format in the module docstring).

    Returns
    -------
    Camera
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such camera file")
    try:
        data = strict_yaml.load(path.read_text(encoding="utf-8"))
    except (strict_yaml.YamlError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not a readable YAML file: {exc}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a mapping with fields {', '.join(FIELDS)}, "
                         f"got {type(data).__name__}")
    unknown = sorted(str(k) for k in set(data) - set(FIELDS))
    if unknown:
        raise ValueError(f"{path}: unknown field(s) {', '.join(unknown)}; expected {', '.join(FIELDS)}")
    missing = [k for k in ("width", "height", "intrinsics") if k not in data]
    if "cam_to_ego" in data:
        if "rotation" in data or "translation" in data:
            raise ValueError(f"{path}: give either cam_to_ego or rotation and translation, not both")
    else:
        missing += [k for k in ("rotation", "translation") if k not in data]
    if missing:
        raise ValueError(f"{path}: missing {', '.join(missing)}"
                         + ("" if "cam_to_ego" in data else
                            " (the mounting is cam_to_ego, or rotation and translation)"))
    for key in ("width", "height"):
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise ValueError(f"{path}: {key} = {value!r}, expected {FIELDS[key]}")
    near = data.get("near", 0.1)
    if isinstance(near, bool) or not isinstance(near, (int, float)) or not near >= 1e-3:
        raise ValueError(f"{path}: near = {near!r}, expected {FIELDS['near']}")
    K = _matrix(path, data, "intrinsics")
    if "cam_to_ego" in data:
        cam_to_ego = _matrix(path, data, "cam_to_ego")
        try:
            as_pose(cam_to_ego, "cam_to_ego")
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None
    else:
        rotation, translation = _matrix(path, data, "rotation"), _matrix(path, data, "translation")
        try:
            cam_to_ego = pose_matrix(rotation, translation)
        except ValueError as exc:  # not a unit quaternion
            raise ValueError(f"{path}: rotation: {exc}") from None
    try:
        return Camera(K, data["width"], data["height"], cam_to_ego, near=float(near))
    except ValueError as exc:  # the rest is checked above: what is left is K's form
        raise ValueError(f"{path}: intrinsics: {exc}") from None
