"""The nuScenes reader on a tiny scene written in nuScenes' table and results formats.

The fixture: one scene, two samples 0.5 s apart, one camera (CAM_FRONT, 160 x 90 pixels)
plus a lidar that must be ignored. The ego vehicle stands at global (100, 50, 0) facing
global +y (yaw 90 degrees), then at (100, 55, 0): ego x = global +y, ego y (left) =
global -x, so a global point (X, Y, Z) is at ego (Y - Yego, -(X - Xego), Z), and a global
heading psi becomes psi - 90 degrees.
"""
import csv
import json
import math

import numpy as np
import pytest

import fuzzcore
from monitor.geometry.camera import Camera, project_boxes
from monitor.cli import main
from monitor.config import MonitorConfig, RetrievalConfig
from monitor.depth.files import DepthFolder
from monitor.datasets.nuscenes import NuScenesReader, category_to_detection_name
from monitor.depth.prior import save_prior
from monitor.depth.retrieval import RetrievalParams
from monitor.depth.visibility import VisibilityParams
from monitor.risk_monitor import OK, RiskMonitor
from monitor.shipped import shipped_rules

VERSION = "v1.0-mini"
W, H = 160, 90
K = [[100.0, 0.0, 80.0], [0.0, 100.0, 45.0], [0.0, 0.0, 1.0]]
# camera -> ego: camera z (forward) = ego x, camera x (right) = ego -y, camera y (down) = ego -z
CAM_ROTATION = [0.5, -0.5, 0.5, -0.5]
CAM_TRANSLATION = [1.5, 0.0, 1.5]
T0 = 1_533_151_603_512_404  # microseconds
FAR_M = 30.0


def yaw_q(degrees):
    """Quaternion [w, x, y, z] of a rotation by ``degrees`` about z."""
    h = math.radians(degrees) / 2
    return [math.cos(h), 0.0, 0.0, math.sin(h)]


def tables():
    """The tables of the fixture, as Python objects (mutated by the error tests)."""
    stems = ["n000__CAM_FRONT__0", "n000__CAM_FRONT__1"]
    return {
        "scene": [{"token": "sc0", "log_token": "log0", "nbr_samples": 2, "name": "scene-0001",
                   "description": "test", "first_sample_token": "s0", "last_sample_token": "s1"}],
        "sample": [
            {"token": "s0", "timestamp": T0, "prev": "", "next": "s1", "scene_token": "sc0"},
            {"token": "s1", "timestamp": T0 + 500_000, "prev": "s0", "next": "", "scene_token": "sc0"},
        ],
        "sensor": [{"token": "sen-cam", "channel": "CAM_FRONT", "modality": "camera"},
                   {"token": "sen-lid", "channel": "LIDAR_TOP", "modality": "lidar"}],
        "calibrated_sensor": [
            {"token": "cs-cam", "sensor_token": "sen-cam", "translation": CAM_TRANSLATION,
             "rotation": CAM_ROTATION, "camera_intrinsic": K},
            {"token": "cs-lid", "sensor_token": "sen-lid", "translation": [0.9, 0.0, 1.8],
             "rotation": [1.0, 0.0, 0.0, 0.0], "camera_intrinsic": []},
        ],
        "ego_pose": [
            {"token": "ep0", "timestamp": T0, "rotation": yaw_q(90), "translation": [100.0, 50.0, 0.0]},
            {"token": "ep1", "timestamp": T0 + 500_000, "rotation": yaw_q(90),
             "translation": [100.0, 55.0, 0.0]},
            {"token": "ep-l", "timestamp": T0 + 1000, "rotation": yaw_q(0), "translation": [0.0, 0.0, 0.0]},
            {"token": "ep-sweep", "timestamp": T0 + 80_000, "rotation": yaw_q(0),
             "translation": [0.0, 0.0, 0.0]},
        ],
        "sample_data": [
            {"token": f"sd{i}", "sample_token": f"s{i}", "ego_pose_token": f"ep{i}",
             "calibrated_sensor_token": "cs-cam", "timestamp": T0 + 500_000 * i, "fileformat": "jpg",
             "is_key_frame": True, "height": H, "width": W,
             "filename": f"samples/CAM_FRONT/{stems[i]}.jpg", "prev": "", "next": ""}
            for i in range(2)
        ] + [
            # a camera sweep between key frames and a lidar key frame: neither is the image
            {"token": "sd-sweep", "sample_token": "s0", "ego_pose_token": "ep-sweep",
             "calibrated_sensor_token": "cs-cam", "timestamp": T0 + 80_000, "fileformat": "jpg",
             "is_key_frame": False, "height": H, "width": W,
             "filename": "sweeps/CAM_FRONT/sweep.jpg", "prev": "sd0", "next": "sd1"},
            {"token": "sd-l", "sample_token": "s0", "ego_pose_token": "ep-l",
             "calibrated_sensor_token": "cs-lid", "timestamp": T0 + 1000, "fileformat": "pcd",
             "is_key_frame": True, "height": 0, "width": 0,
             "filename": "samples/LIDAR_TOP/l.pcd.bin", "prev": "", "next": ""},
        ],
        "category": [{"token": "c-car", "name": "vehicle.car", "description": ""},
                     {"token": "c-ped", "name": "human.pedestrian.adult", "description": ""},
                     {"token": "c-dog", "name": "animal", "description": ""}],
        "instance": [{"token": "i-car", "category_token": "c-car", "nbr_annotations": 2},
                     {"token": "i-ped", "category_token": "c-ped", "nbr_annotations": 1},
                     {"token": "i-dog", "category_token": "c-dog", "nbr_annotations": 1}],
        "visibility": [{"token": str(k + 1), "level": level, "description": ""}
                       for k, level in enumerate(["v0-40", "v40-60", "v60-80", "v80-100"])],
        "sample_annotation": [
            # the car: 10 m ahead, 2 m right, heading like the ego (global 90 degrees)
            {"token": "a0", "sample_token": "s0", "instance_token": "i-car", "visibility_token": "3",
             "attribute_tokens": [], "translation": [102.0, 60.0, 1.0], "size": [2.0, 4.0, 1.5],
             "rotation": yaw_q(90), "prev": "", "next": "a2", "num_lidar_pts": 5, "num_radar_pts": 0},
            # a pedestrian 10 m behind the ego, heading global +x: fully visible to the rear
            # cameras (level 4) but not to CAM_FRONT
            {"token": "a1", "sample_token": "s0", "instance_token": "i-ped", "visibility_token": "4",
             "attribute_tokens": [], "translation": [100.0, 40.0, 1.0], "size": [0.6, 0.7, 1.8],
             "rotation": yaw_q(0), "prev": "", "next": "", "num_lidar_pts": 5, "num_radar_pts": 0},
            # an animal: no detection class, left out
            {"token": "a-dog", "sample_token": "s0", "instance_token": "i-dog", "visibility_token": "4",
             "attribute_tokens": [], "translation": [101.0, 58.0, 0.3], "size": [0.3, 0.8, 0.5],
             "rotation": yaw_q(0), "prev": "", "next": "", "num_lidar_pts": 5, "num_radar_pts": 0},
            {"token": "a2", "sample_token": "s1", "instance_token": "i-car", "visibility_token": "2",
             "attribute_tokens": [], "translation": [102.0, 61.0, 1.0], "size": [2.0, 4.0, 1.5],
             "rotation": yaw_q(90), "prev": "a0", "next": "", "num_lidar_pts": 5, "num_radar_pts": 0},
        ],
    }


def results():
    def box(sample, translation, size, yaw_deg, name, score):
        return {"sample_token": sample, "translation": translation, "size": size,
                "rotation": yaw_q(yaw_deg), "velocity": [0.0, 0.0], "detection_name": name,
                "detection_score": score, "attribute_name": ""}
    return {"meta": {"use_camera": True, "use_lidar": False, "use_radar": False,
                     "use_map": False, "use_external": False},
            "results": {"s0": [box("s0", [101.5, 60.0, 1.0], [2.0, 4.0, 1.5], 180, "car", 0.9)],
                        "s1": [box("s1", [99.0, 65.0, 0.9], [0.6, 0.7, 1.8], 0, "pedestrian", 0.6)]}}


def write(root, tabs=None, res=None):
    """Write the fixture under ``root``; return the reader's keyword arguments."""
    tabs = tables() if tabs is None else tabs
    folder = root / VERSION
    folder.mkdir(parents=True)
    for name, records in tabs.items():
        (folder / f"{name}.json").write_text(json.dumps(records))
    (root / "results.json").write_text(json.dumps(results() if res is None else res))
    depth_dir = root / "depth"
    depth_dir.mkdir()
    for sd in tabs["sample_data"][:2]:
        stem = sd["filename"].rsplit("/", 1)[1].rsplit(".", 1)[0]
        np.save(depth_dir / f"{stem}.npy", np.full((H, W), FAR_M, np.float32))
    return dict(dataroot=root, version=VERSION, detections=root / "results.json", depth=depth_dir)


@pytest.fixture
def reader(tmp_path):
    return NuScenesReader(**write(tmp_path))


def frames(reader):
    (scene,) = reader.scenes()
    return list(scene.frames)


def test_scene_attributes(reader):
    (scene,) = reader.scenes()
    assert (scene.name, scene.condition, scene.split, len(scene)) == ("scene-0001", "nuscenes", "test", 2)
    assert reader.uncovered_scenes == ()


def test_camera_is_the_calibrated_sensor_with_the_image_size(reader):
    expected = Camera.from_nuscenes(K, CAM_ROTATION, CAM_TRANSLATION, W, H)
    for frame in frames(reader):
        cam = frame.camera
        assert (cam.width, cam.height) == (W, H)
        np.testing.assert_array_equal(cam.K, expected.K)
        np.testing.assert_allclose(cam.cam_to_ego, expected.cam_to_ego, atol=1e-15)
        # and the rotation is the one the fixture means: camera z forward = ego x, x right = ego -y
        np.testing.assert_allclose(cam.cam_to_ego[:3, :3], [[0, 0, 1], [-1, 0, 0], [0, -1, 0]],
                                   atol=1e-12)


def test_ground_truth_in_the_ego_frame(reader):
    f0, f1 = frames(reader)
    # car at global (102, 60, 1), ego (100, 50) facing +y: ego (60 - 50, -(102 - 100), 1);
    # heading 90 - 90 = 0. Pedestrian at (100, 40, 1): ego (-10, 0, 1), heading 0 - 90.
    np.testing.assert_allclose(f0.gt_boxes3d, [[10.0, -2.0, 1.0, 2.0, 4.0, 1.5, 0.0],
                                               [-10.0, 0.0, 1.0, 0.6, 0.7, 1.8, -math.pi / 2]],
                               atol=1e-12)
    assert f0.gt_classes.tolist() == ["car", "pedestrian"]  # the animal is left out
    assert f0.gt_ids.tolist() == [0, 1]
    # the car: level 3 (60-80 %) -> 0.8; the pedestrian behind the camera: not in view -> 0
    assert f0.gt_visibility.tolist() == [0.8, 0.0]
    # sample 1: car at (102, 61, 1), ego at (100, 55): ego (6, -2, 1), same instance id
    np.testing.assert_allclose(f1.gt_boxes3d, [[6.0, -2.0, 1.0, 2.0, 4.0, 1.5, 0.0]], atol=1e-12)
    assert f1.gt_ids.tolist() == [0] and f1.gt_visibility.tolist() == [0.6]


def test_detections_in_the_ego_frame(reader):
    f0, f1 = frames(reader)
    # car at global (101.5, 60, 1) heading 180: ego (10, -1.5, 1), heading 180 - 90 = 90
    np.testing.assert_allclose(f0.det_boxes3d, [[10.0, -1.5, 1.0, 2.0, 4.0, 1.5, math.pi / 2]],
                               atol=1e-12)
    assert f0.det_classes.tolist() == ["car"] and f0.det_scores.tolist() == [0.9]
    # pedestrian at (99, 65, 0.9) heading 0, ego at (100, 55): ego (10, 1, 0.9), heading -90
    np.testing.assert_allclose(f1.det_boxes3d, [[10.0, 1.0, 0.9, 0.6, 0.7, 1.8, -math.pi / 2]],
                               atol=1e-12)
    assert f1.det_classes.tolist() == ["pedestrian"] and f1.det_scores.tolist() == [0.6]


def test_time_speed_and_maps(reader):
    f0, f1 = frames(reader)
    assert (f0.index, f1.index) == (0, 1)
    assert (f0.timestamp, f1.timestamp) == (0.0, 0.5)
    # 5 m between the key-frame images' ego poses in 0.5 s (the sweep's pose is not used)
    assert f0.ego_speed == pytest.approx(10.0) and f1.ego_speed == pytest.approx(10.0)
    assert f0.depth_est.dtype == np.float32 and f0.depth_est.shape == (H, W)
    assert f0.depth_true is None and f0.labels is None


def test_a_depth_folder_object_is_accepted(tmp_path):
    kwargs = write(tmp_path)
    kwargs["depth"] = DepthFolder(kwargs["depth"])
    assert len(frames(NuScenesReader(**kwargs))) == 2


def test_the_monitor_runs_on_a_frame(reader):
    f0 = frames(reader)[0]
    P, _ = project_boxes(f0.det_boxes3d, f0.camera)
    assert P.shape == (1, 5)
    # paint the detected car into the depth map at its camera depth, the rest far away
    cx, cy, w, h, d = P[0]
    depth = f0.depth_est.copy()
    depth[int(cy - h / 2):int(cy + h / 2), int(cx - w / 2):int(cx + w / 2)] = d
    prior = np.full((H, W), 1.0 / FAR_M, np.float32)
    # a 160 x 90 image: full resolution and small boxes (the defaults suit 1600 x 900)
    # the painted frame has no road: the view check (which would call it "no ground") is off
    config = MonitorConfig(retrieval=RetrievalConfig(method="paper", paper=RetrievalParams(downsample=1, min_size=4.0)),
                           visibility=VisibilityParams(min_in_range_share=0.0, min_ground_ratio=0.0))
    monitor = RiskMonitor(fuzzcore.load(shipped_rules()), prior, f0.camera, config)
    report = monitor.step(depth, f0.det_boxes3d, f0.det_scores)
    assert report.status == OK, report.reason
    np.testing.assert_allclose(report.P, P)
    assert report.S.shape[0] >= 1 and 0.0 <= report.risk <= 1.0


def test_category_mapping():
    assert category_to_detection_name("vehicle.bus.bendy") == "bus"
    assert category_to_detection_name("human.pedestrian.police_officer") == "pedestrian"
    assert category_to_detection_name("human.pedestrian.stroller") is None


def test_uncovered_scenes_are_listed_and_named_scenes_are_checked(tmp_path):
    tabs = tables()
    tabs["scene"].append({"token": "sc1", "log_token": "log0", "nbr_samples": 0, "name": "scene-0002",
                          "description": "", "first_sample_token": "", "last_sample_token": ""})
    kwargs = write(tmp_path, tabs)
    reader = NuScenesReader(**kwargs)
    assert [s.name for s in reader.scenes()] == ["scene-0001"]
    assert reader.uncovered_scenes == ("scene-0002",)
    with pytest.raises(ValueError, match="no scene named 'scene-9'"):
        NuScenesReader(**kwargs, scene_names=["scene-9"])


def _drop(name, token):
    def edit(tabs, res):
        tabs[name] = [r for r in tabs[name] if r["token"] != token]
    return edit


def _set(name, index, key, value):
    def edit(tabs, res):
        tabs[name][index][key] = value
    return edit


def _results(edit_results):
    def edit(tabs, res):
        edit_results(res)
    return edit


@pytest.mark.parametrize("edit, error, message", [
    (_drop("sample_data", "sd1"), ValueError, "sample 's1' has no key-frame sample_data from camera 'CAM_FRONT'"),
    (_set("sample_data", 1, "is_key_frame", False), ValueError, "sample 's1' has no key-frame"),
    (_set("sample_annotation", 0, "instance_token", "i-x"), ValueError,
     r"sample_annotation\[token=a0\]\.instance_token: 'i-x' is not a token of table 'instance'"),
    (_set("sample_annotation", 0, "size", [2.0, 0.0, 1.5]), ValueError,
     r"sample_annotation\[token=a0\]\.size: .* must be > 0"),
    (_set("sample_annotation", 0, "visibility_token", "9"), ValueError,
     r"sample_annotation\[token=a0\]\.visibility_token: '9'"),
    (_set("ego_pose", 0, "rotation", [1.0, 1.0, 0.0, 0.0]), ValueError,
     r"ego_pose\[token=ep0\]\.rotation: .* not a unit quaternion"),
    (_set("sample", 0, "next", "s9"), ValueError, r"sample\[token=s0\]\.next: 's9' is not a token"),
    (_set("visibility", 0, "level", "low"), ValueError, r"visibility\[token=1\]\.level: 'low'"),
    (_set("sample_data", 0, "width", "wide"), ValueError, r"sample_data\[token=sd0\]\.width"),
    (_results(lambda r: r["results"].update(s9=[])), ValueError,
     "results has 1 sample tokens that are not in the tables' sample.json, first 's9'"),
    (_results(lambda r: r["results"].pop("s1")), ValueError,
     "results has no entry for sample 's1' of scene 'scene-0001'"),
    (_results(lambda r: r["results"]["s0"][0].pop("detection_score")), ValueError,
     r"results\[s0\]\[0\]: field 'detection_score' is missing"),
    (_results(lambda r: r["results"]["s0"][0].update(detection_name="van")), ValueError,
     r"results\[s0\]\[0\]\.detection_name: 'van'"),
    (_results(lambda r: r["results"]["s0"][0].update(detection_score=1.5)), ValueError,
     r"results\[s0\]\[0\]\.detection_score: 1.5, must be in \[0, 1\]"),
    (_results(lambda r: r["results"]["s0"][0].update(sample_token="s1")), ValueError,
     r"results\[s0\]\[0\]\.sample_token: 's1', expected 's0'"),
    (_results(lambda r: r["results"].update(s0={})), ValueError, r"results\[s0\] is a dict"),
    (_results(lambda r: r.pop("meta")), ValueError, "field 'meta' is missing"),
    # issue 13, item 17: NaN (json reads the NaN literal) and huge numbers name the file and token
    (_set("sample_annotation", 0, "rotation", [math.nan, 0.0, 0.0, 1.0]), ValueError,
     r"sample_annotation.json: sample_annotation\[token=a0\]\.rotation: \[nan, 0.0, 0.0, 1.0\] is not a list "
     r"of 4 finite numbers"),
    (_set("sample_annotation", 0, "size", [math.nan, 4.0, 1.5]), ValueError,
     r"sample_annotation\[token=a0\]\.size: \[nan, 4.0, 1.5\] is not a list of 3 finite numbers"),
    (_set("ego_pose", 0, "translation", [10**400, 0, 0]), ValueError,
     r"ego_pose\[token=ep0\]\.translation: .* is not a list of 3 finite numbers"),
    (_results(lambda r: r["results"]["s0"][0].update(rotation=[math.nan] * 4)), ValueError,
     r"results\[s0\]\[0\]\.rotation: \[nan, nan, nan, nan\] is not a list of 4 finite numbers"),
    (_results(lambda r: r["results"]["s0"][0].update(size=[1.0, math.inf, 1.0])), ValueError,
     r"results\[s0\]\[0\]\.size: \[1.0, inf, 1.0\] is not a list of 3 finite numbers"),
    (_results(lambda r: r["results"]["s0"][0].update(detection_score=math.nan)), ValueError,
     r"results\[s0\]\[0\]\.detection_score: nan is not a finite number"),
])
def test_malformed_input_is_a_clear_error(tmp_path, edit, error, message):
    tabs, res = tables(), results()
    edit(tabs, res)
    with pytest.raises(error, match=message):
        frames(NuScenesReader(**write(tmp_path, tabs, res)))


def test_missing_table_is_named(tmp_path):
    kwargs = write(tmp_path)
    (tmp_path / VERSION / "instance.json").unlink()
    with pytest.raises(FileNotFoundError, match="instance.json"):
        NuScenesReader(**kwargs)


def test_missing_version_folder_is_named(tmp_path):
    kwargs = write(tmp_path)
    with pytest.raises(FileNotFoundError, match="v1.0-trainval"):
        NuScenesReader(**{**kwargs, "version": "v1.0-trainval"})


@pytest.mark.parametrize("file", [f"{VERSION}/sample.json", "results.json"])
def test_malformed_json_names_the_file(tmp_path, file):
    kwargs = write(tmp_path)
    (tmp_path / file).write_text('{"token": ')
    with pytest.raises(ValueError, match=f"{file.split('/')[-1]}: not valid JSON"):
        NuScenesReader(**kwargs)


def test_unknown_camera_lists_the_channels(tmp_path):
    with pytest.raises(ValueError, match=r"no sensor has channel 'CAM_BACK'; channels: \['CAM_FRONT', 'LIDAR_TOP'\]"):
        NuScenesReader(**write(tmp_path), camera="CAM_BACK")


def test_missing_depth_map_names_the_frame(tmp_path):
    kwargs = write(tmp_path)
    (kwargs["depth"] / "n000__CAM_FRONT__1.npy").unlink()
    (scene,) = NuScenesReader(**kwargs).scenes()
    scene.frame(0)
    with pytest.raises(FileNotFoundError, match=r"no map n000__CAM_FRONT__1.npy .* sample_data\[token=sd1\]"):
        scene.frame(1)


def test_depth_of_the_wrong_size_names_the_file(tmp_path):
    kwargs = write(tmp_path)
    np.save(kwargs["depth"] / "n000__CAM_FRONT__0.npy", np.full((H, W + 1), 5.0, np.float32))
    (scene,) = NuScenesReader(**kwargs).scenes()
    with pytest.raises(ValueError, match=r"n000__CAM_FRONT__0.npy\): depth_est is"):
        scene.frame(0)


def test_features_command_runs_on_nuscenes(tmp_path, capsys):
    kwargs = write(tmp_path)
    # the detected car of sample 0 painted into its depth map, as in the monitor test
    f0 = frames(NuScenesReader(**kwargs))[0]
    (cx, cy, w, h, d), = project_boxes(f0.det_boxes3d, f0.camera)[0]
    depth = f0.depth_est.copy()
    depth[int(cy - h / 2):int(cy + h / 2), int(cx - w / 2):int(cx + w / 2)] = d
    np.save(kwargs["depth"] / "n000__CAM_FRONT__0.npy", depth)
    save_prior(tmp_path / "prior.npy", np.full((H, W), 1.0 / FAR_M, np.float32))
    (tmp_path / "config.yaml").write_text("retrieval:\n  method: paper\n  paper:\n    downsample: 1\n    min_size: 4.0\n"
                                          # no road: view check off
                                          "visibility:\n  min_in_range_share: 0.0\n  min_ground_ratio: 0.0\n")
    out = tmp_path / "f.csv"
    argv = ["features", "-o", str(out), "--split", "all", "--config", str(tmp_path / "config.yaml"),
            "--nuscenes", str(tmp_path), "--version", VERSION, "--detections", str(kwargs["detections"]),
            "--depth-dir", str(kwargs["depth"]), "--prior", str(tmp_path / "prior.npy")]
    assert main(argv) == 0, capsys.readouterr().err
    printed = capsys.readouterr().out
    assert "Data: nuScenes v1.0-mini" in printed and "1 scenes (0 more not in the detections)" in printed
    with open(out) as f:
        rows = list(csv.DictReader(f))
    # frame 0 has the painted car, covered by its detection; the frame 1 depth map is empty,
    # and its features come from the detector's objects alone (each IoU 1, RDD 0)
    assert [(r["scene"], r["frame"], r["condition"]) for r in rows] == [("scene-0001", "0", "nuscenes"),
                                                                      ("scene-0001", "1", "nuscenes")]
    assert (float(rows[1]["iou"]), float(rows[1]["rdd"])) == (1.0, 0.0)


def test_nuscenes_option_needs_its_companions(tmp_path, capsys):
    kwargs = write(tmp_path)
    argv = ["features", "-o", str(tmp_path / "f.csv"), "--nuscenes", str(tmp_path), "--version", VERSION,
            "--detections", str(kwargs["detections"])]
    assert main(argv) == 2
    assert "--nuscenes needs --prior PRIOR.npy, --depth-dir DIR" in capsys.readouterr().err


def test_a_scene_with_one_sample_has_no_speed(tmp_path):
    tabs, res = tables(), results()
    tabs["sample"][0]["next"] = ""
    tabs["sample"][1]["scene_token"] = "sc1"
    tabs["scene"].append({"token": "sc1", "log_token": "log0", "nbr_samples": 1, "name": "scene-0002",
                          "description": "", "first_sample_token": "s1", "last_sample_token": "s1"})
    kwargs = write(tmp_path, tabs, res)
    with pytest.raises(ValueError, match=r"scene\[token=sc0\]\.first_sample_token: scene 'scene-0001' has one"):
        NuScenesReader(**kwargs)
