"""The on-disk scene format: exact round trip, lazy reading, clear errors."""
import json
from dataclasses import replace

import numpy as np
import pytest

from monitor.geometry.camera import Camera
from monitor.datasets.frames import Frame, Scene
from monitor.datasets.scene_folder import (SCENE_FILE, SceneReader, SceneWriter, read_scene, write_scene)
from monitor.synthetic import generate_scene

FIELDS = ("index", "timestamp", "ego_speed", "depth_est", "depth_true", "labels",
          "gt_boxes3d", "gt_classes", "gt_ids", "gt_visibility", "det_boxes3d",
          "det_classes", "det_scores")


def small_camera() -> Camera:
    front = Camera.nuscenes_front()
    return Camera(np.diag([0.05, 0.05, 1.0]) @ front.K, 80, 45, front.cam_to_ego)


@pytest.fixture(scope="module")
def scene() -> Scene:
    return generate_scene("rare", seed=8, n_frames=3, camera=small_camera())


def assert_frames_identical(a: Frame, b: Frame) -> None:
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.shape == y.shape, name
            np.testing.assert_array_equal(x, y, err_msg=name)
        else:
            assert type(x) is type(y) and x == y, name


def assert_cameras_identical(a: Camera, b: Camera) -> None:
    assert (a.width, a.height, a.near) == (b.width, b.height, b.near)
    np.testing.assert_array_equal(a.K, b.K)
    np.testing.assert_array_equal(a.cam_to_ego, b.cam_to_ego)


def test_round_trip_is_exact(tmp_path, scene):
    path = write_scene(scene, tmp_path / "s")
    assert path == tmp_path / "s" / SCENE_FILE
    back = read_scene(tmp_path / "s")
    assert (back.name, back.condition, back.seed, back.synthetic) == (
        scene.name, "rare", 8, True)
    assert_cameras_identical(back.camera, scene.camera)
    assert len(back.frames) == len(scene.frames) == 3
    for a, b in zip(scene.frames, back.frames):
        assert_frames_identical(a, b)
        assert b.camera is back.camera
    assert any(f.det_scores.size for f in scene.frames)  # the check compared something


def test_json_uses_nuscenes_vocabulary(tmp_path, scene):
    write_scene(scene, tmp_path)
    data = json.loads((tmp_path / SCENE_FILE).read_text())
    assert data["synthetic"] is True and data["coordinate_frame"] == "ego"
    frame = data["frames"][0]
    annotation, detection = frame["annotations"][0], frame["detections"][0]
    assert set(annotation) == {"instance_id", "category_name", "translation", "size", "yaw",
                               "visibility"}
    assert set(detection) == {"detection_name", "detection_score", "translation", "size", "yaw"}
    assert detection["detection_score"] == scene.frames[0].det_scores[0]
    assert frame["depth_est"] == "depth_est/000000.npy"
    assert data["camera"]["camera_intrinsic"] == scene.camera.K.tolist()


def test_optional_maps_and_empty_frames(tmp_path):
    camera = small_camera()
    frame = Frame(
        index=0, timestamp=1.25, ego_speed=0.0, camera=camera,
        depth_est=np.full((45, 80), 7.5, dtype=np.float32), depth_true=None, labels=None,
        gt_boxes3d=np.zeros((0, 7)), gt_classes=np.zeros(0, dtype=str),
        gt_ids=np.zeros(0, dtype=np.int64), gt_visibility=np.zeros(0),
        det_boxes3d=np.zeros((0, 7)), det_classes=np.zeros(0, dtype=str), det_scores=np.zeros(0),
    )
    real = Scene("real", camera, "clear", None, False, (frame,))
    write_scene(real, tmp_path)
    back = read_scene(tmp_path)
    assert back.seed is None and back.synthetic is False
    assert back.frames[0].depth_true is None and back.frames[0].labels is None
    assert back.frames[0].det_boxes3d.shape == (0, 7)
    assert back.frames[0].gt_classes.shape == (0,)
    assert_frames_identical(frame, back.frames[0])


def test_reader_is_lazy_and_writer_streams(tmp_path, scene):
    with SceneWriter(tmp_path, scene.name, scene.camera, scene.condition, scene.seed, True) as w:
        for frame in scene.frames:
            w.add(frame)
    reader = SceneReader(tmp_path)
    assert len(reader) == 3
    (tmp_path / "depth_est" / "000002.npy").unlink()
    assert_frames_identical(reader.frame(1), scene.frames[1])
    with pytest.raises(FileNotFoundError, match=r"frames\[2\]\.depth_est: file .*000002\.npy"):
        reader.frame(2)


def test_writer_refuses_to_overwrite_and_foreign_cameras(tmp_path, scene):
    write_scene(scene, tmp_path)
    with pytest.raises(FileExistsError, match="overwrite=True"):
        write_scene(scene, tmp_path)
    write_scene(scene, tmp_path, overwrite=True)
    front = Camera.nuscenes_front()
    writer = SceneWriter(tmp_path / "other", "x", front, "nominal", 0, True)
    with pytest.raises(ValueError, match="another camera"):
        writer.add(scene.frames[0])


def _write_and_edit(tmp_path, scene, edit):
    write_scene(scene, tmp_path)
    path = tmp_path / SCENE_FILE
    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize("edit, message", [
    (lambda d: d["frames"][0]["annotations"][1].update(size=[1.0, 2.0]),
     r"frames\[0\]\.annotations\[1\]\.size: \[1\.0, 2\.0\] is not a list of 3 finite numbers"),
    (lambda d: d["frames"][1]["detections"][0].update(detection_score=1.5),
     r"frames\[1\]: det_scores\[0\] = 1\.5, must be in \[0, 1\]"),
    (lambda d: d["frames"][0]["annotations"][0].pop("category_name"),
     r"frames\[0\]\.annotations\[0\]: field 'category_name' is missing"),
    (lambda d: d["frames"][0]["annotations"][0].update(size=[0.0, 1.0, 1.0]),
     r"frames\[0\]: gt_boxes3d\[0, 3\] \(w\) = 0\.0: box sizes must be > 0"),
    (lambda d: d["frames"][0].update(timestamp="soon"),
     r"frames\[0\]\.timestamp: 'soon' is not a finite number"),
    (lambda d: d["frames"][0]["annotations"][1].update(
        instance_id=d["frames"][0]["annotations"][0]["instance_id"]),
     r"frames\[0\]: gt_ids has repeated instance ids"),
    (lambda d: d["camera"].update(width=0), r"scene\.camera: width = 0"),
    (lambda d: d.update(synthetic="yes"), r"scene\.synthetic: 'yes' is not true or false"),
    (lambda d: d.update(version=2), r"format 'fuzzrisk-scene' version 2, expected"),
])
def test_reader_names_file_and_field(tmp_path, scene, edit, message):
    path = _write_and_edit(tmp_path, scene, edit)
    with pytest.raises(ValueError, match=message) as info:
        list(SceneReader(tmp_path))
    assert str(path) in str(info.value)


def test_reader_checks_map_files(tmp_path, scene):
    write_scene(scene, tmp_path)
    np.save(tmp_path / "depth_est" / "000001.npy", np.ones((45, 80), dtype=np.float64))
    with pytest.raises(ValueError,
                       match=r"000001\.npy: holds float64, expected a float32 depth_est"):
        read_scene(tmp_path)
    np.save(tmp_path / "depth_est" / "000001.npy", np.ones((40, 80), dtype=np.float32))
    with pytest.raises(ValueError, match=r"frames\[1\]: depth_est is .*\(45, 80\)"):
        read_scene(tmp_path)
    with pytest.raises(FileNotFoundError, match="scene file"):
        read_scene(tmp_path / "nowhere")
    (tmp_path / SCENE_FILE).write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        read_scene(tmp_path)


def test_frame_validation(scene):
    frame = scene.frames[0]
    with pytest.raises(ValueError, match="gt_classes has shape"):
        replace(frame, gt_classes=frame.gt_classes[:-1])
    with pytest.raises(ValueError, match="depth_est is"):
        replace(frame, depth_est=frame.depth_est.astype(np.float64))
    with pytest.raises(ValueError, match="ego_speed = -1.0"):
        replace(frame, ego_speed=-1.0)
    with pytest.raises(ValueError, match="timestamp = nan"):
        replace(frame, timestamp=float("nan"))
    with pytest.raises(ValueError, match=r"det_boxes3d has shape \(3, 5\)"):
        replace(frame, det_boxes3d=np.zeros((3, 5)))
