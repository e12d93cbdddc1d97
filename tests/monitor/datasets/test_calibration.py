"""Camera calibration files: both mounting forms give the camera, bad fields are named."""
import numpy as np
import pytest

from monitor.datasets.calibration import load_camera
from monitor.geometry.camera import Camera

FRONT = Camera.nuscenes_front()
K_ROWS = "[[1266.417203046554, 0.0, 816.2670197447984], [0.0, 1266.417203046554, 491.50706579294757], [0.0, 0.0, 1.0]]"
NUSCENES = f"""\
width: 1600
height: 900
intrinsics: {K_ROWS}
rotation: [0.4998015430569128, -0.5030316162024876, 0.4997798114386805, -0.49737083824542755]
translation: [1.70079118954, 0.0159456324149, 1.51095763913]
"""


def _write(tmp_path, text, name="camera.yaml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_nuscenes_style_file_is_the_front_camera(tmp_path):
    assert load_camera(_write(tmp_path, NUSCENES)).same_as(FRONT)


def test_cam_to_ego_file_is_the_same_camera(tmp_path):
    rows = np.array2string(FRONT.cam_to_ego, separator=", ", precision=17, max_line_width=10_000)
    text = f"width: 1600\nheight: 900\nintrinsics: {K_ROWS}\ncam_to_ego: {rows}\nnear: 0.1\n"
    camera = load_camera(_write(tmp_path, text))
    assert camera.same_as(FRONT)


@pytest.mark.parametrize("change, message", [
    (lambda t: t + "focal: 3\n", "unknown field(s) focal; expected width, height, intrinsics"),
    (lambda t: t.replace("width: 1600\n", ""), "missing width"),
    (lambda t: t.replace("width: 1600", "width: 1600.5"), "width = 1600.5, expected a positive integer"),
    (lambda t: t.replace(K_ROWS, "[[1, 0, 0], [0, 1, 0]]"), "intrinsics = [[1, 0, 0], [0, 1, 0]], expected a 3 x 3"),
    (lambda t: t.replace(K_ROWS, "[[1, 0, 0], [0, 1, 0], [0, 1, 1]]"), "intrinsics: K = "),
    (lambda t: t.replace("rotation: [0.4998015430569128", "rotation: [0.9"), "rotation: rotation_wxyz has norm"),
    (lambda t: t.replace("translation: [1.70079118954, ", "translation: ["), "translation = [0.0159"),
    (lambda t: t.replace("translation:", "#"), "missing translation (the mounting is cam_to_ego, or rotation"),
    (lambda t: t + "cam_to_ego: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n",
     "either cam_to_ego or rotation and translation, not both"),
    (lambda t: t + "near: 0\n", "near = 0, expected a number of metres >= 0.001"),
    (lambda t: "- just a list\n", "expected a mapping with fields width"),
    # width is line 1 of NUSCENES; the second one is line 6, after the five lines
    (lambda t: t + "width: 800\n", "not a readable YAML file: line 6: duplicate key 'width' (first at line 1)"),
    (lambda t: t + "near: !!python/object:os.system x\n", "not a readable YAML file: line 6: not valid safe YAML"),
])
def test_bad_fields_are_named_with_the_file(tmp_path, change, message):
    path = _write(tmp_path, change(NUSCENES))
    with pytest.raises(ValueError) as err:
        load_camera(path)
    assert str(err.value).startswith(str(path)) and message in str(err.value)


def test_a_cam_to_ego_that_is_not_rigid_is_named(tmp_path):
    text = f"width: 8\nheight: 8\nintrinsics: {K_ROWS}\ncam_to_ego: [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n"
    with pytest.raises(ValueError, match=r"camera.yaml: cam_to_ego\[:3, :3\] is not a rotation"):
        load_camera(_write(tmp_path, text))


def test_missing_file_is_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.yaml: no such camera file"):
        load_camera(tmp_path / "nope.yaml")
