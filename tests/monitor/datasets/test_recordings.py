"""Recording folders: the nuScenes fixture written as a recording gives the same reports; errors."""
import json
import shutil

import numpy as np
import pytest
import yaml

from monitor.cli import main
from monitor.datasets.nuscenes import NuScenesReader
from monitor.datasets.recordings import RecordingReader
from monitor.depth.prior import save_prior
from monitor.geometry.camera import project_boxes
from recording_fixture import read_rows
from test_nuscenes import CAM_ROTATION, CAM_TRANSLATION, FAR_M, H, K, VERSION, W, results, tables, write

# a 160 x 90 image without a road: full resolution, small boxes, the view check off
CONFIG = ("retrieval:\n  method: paper\n  paper:\n    downsample: 1\n    min_size: 4.0\n"
          "visibility:\n  min_in_range_share: 0.0\n  min_ground_ratio: 0.0\n")


@pytest.fixture
def nuscenes(tmp_path):
    """The nuScenes fixture with the detected car painted into sample 0's depth map."""
    kwargs = write(tmp_path / "nus")
    (scene,) = NuScenesReader(**kwargs).scenes()
    f0 = scene.frame(0)
    (cx, cy, w, h, d), = project_boxes(f0.det_boxes3d, f0.camera)[0]
    depth = f0.depth_est.copy()
    depth[int(cy - h / 2):int(cy + h / 2), int(cx - w / 2):int(cx + w / 2)] = d
    np.save(kwargs["depth"] / "n000__CAM_FRONT__0.npy", depth)
    save_prior(tmp_path / "prior.npy", np.full((H, W), 1.0 / FAR_M, np.float32))
    (tmp_path / "config.yaml").write_text(CONFIG)
    return kwargs


def as_recording(kwargs, folder, detections):
    """The nuScenes fixture as a recording folder: the calibrated sensor as camera.yaml, the ego
    poses in frames.jsonl, the same depth maps, ground truth in the ego frame, and the detections
    as the results file keyed by frame (global frame) or as ego-frame JSON lines."""
    tabs, res = tables(), results()
    (scene,) = NuScenesReader(**kwargs).scenes()
    records = scene.records()
    folder.mkdir()
    (folder / "camera.yaml").write_text(yaml.safe_dump({"width": W, "height": H, "intrinsics": K,
                                                        "rotation": CAM_ROTATION, "translation": CAM_TRANSLATION}))
    poses = {p["token"]: p for p in tabs["ego_pose"]}
    key_of = {r.token: r.key for r in records}
    with open(folder / "frames.jsonl", "w") as f:
        for r, sd in zip(records, tabs["sample_data"][:2]):
            pose = poses[sd["ego_pose_token"]]
            f.write(json.dumps({"frame": r.key, "timestamp": r.timestamp,
                                "ego_pose": {"translation": pose["translation"], "rotation": pose["rotation"]}}) + "\n")
    shutil.copytree(kwargs["depth"], folder / "depth")
    with open(folder / "ground_truth.jsonl", "w") as f:
        for r in records:
            f.write(json.dumps({"frame": r.key, "annotations": [
                {"translation": b[:3], "size": b[3:6], "yaw": b[6], "category_name": c, "instance_id": i,
                 "visibility": v} for b, c, i, v in zip(r.gt_boxes3d.tolist(), r.gt_classes.tolist(),
                                                        r.gt_ids.tolist(), r.gt_visibility.tolist())]}) + "\n")
    if detections == "results":
        renamed = {key_of[t]: [{**box, "sample_token": key_of[t]} for box in boxes]
                   for t, boxes in res["results"].items()}
        (folder / "detections.json").write_text(json.dumps({"meta": res["meta"], "results": renamed}))
    else:
        with open(folder / "detections.jsonl", "w") as f:
            for r in records:
                f.write(json.dumps({"frame": r.key, "detections": [
                    {"translation": b[:3], "size": b[3:6], "yaw": b[6], "detection_name": c, "detection_score": s}
                    for b, c, s in zip(r.det_boxes3d.tolist(), r.det_classes.tolist(),
                                       r.det_scores.tolist())]}) + "\n")
    return records


@pytest.mark.parametrize("detections", ["results", "lines"])
def test_nuscenes_and_the_recording_folder_give_the_same_reports(tmp_path, nuscenes, detections):
    as_recording(nuscenes, tmp_path / "scene-0001", detections)
    common = ["--config", str(tmp_path / "config.yaml"), "--prior", str(tmp_path / "prior.npy")]
    assert main(["monitor", "-o", str(tmp_path / "a"), "--nuscenes", str(nuscenes["dataroot"]), "--version",
                 VERSION, "--detections", str(nuscenes["detections"]), "--depth-dir", str(nuscenes["depth"]),
                 *common]) == 0
    assert main(["monitor", "-o", str(tmp_path / "b"), "--recording", str(tmp_path / "scene-0001"), *common]) == 0
    a, b = read_rows(tmp_path / "a"), read_rows(tmp_path / "b")
    assert list(a) == list(b) == ["scene-0001.jsonl"]
    assert [r.pop("token") for r in a["scene-0001.jsonl"]] == ["s0", "s1"]
    assert [r.pop("token") for r in b["scene-0001.jsonl"]] == [None, None]
    assert a == b
    rows = a["scene-0001.jsonl"]
    # the second depth map is empty: its features are the detector's objects alone
    assert [r["status"] for r in rows] == ["ok", "ok"] and rows[0]["target"] is not None
    assert (rows[1]["iou"], rows[1]["rdd"]) == (1.0, 0.0)


def test_records_of_the_recording_match_the_nuscenes_frames(tmp_path, nuscenes):
    records = as_recording(nuscenes, tmp_path / "scene-0001", "results")
    reader = RecordingReader(tmp_path / "scene-0001")
    assert reader.has_ground_truth and len(reader) == 2 and reader.camera.same_as(records[0].camera)
    for mine, theirs in zip(reader.records(), records):
        np.testing.assert_allclose(mine.det_boxes3d, theirs.det_boxes3d, atol=1e-12)
        assert mine.ego_speed == pytest.approx(theirs.ego_speed) == pytest.approx(10.0)
        np.testing.assert_array_equal(mine.gt_visibility, theirs.gt_visibility)
        assert mine.depth_path.name == f"{theirs.key}.npy" and mine.image_path is None


def _edit_lines(path, k, **changes):
    lines = [json.loads(x) for x in path.read_text().splitlines()]
    lines[k].update(changes)
    for key in [key for key, v in changes.items() if v is None]:
        del lines[k][key]
    path.write_text("".join(json.dumps(x) + "\n" for x in lines))


@pytest.mark.parametrize("edit, error, message", [
    (lambda d: (d / "camera.yaml").unlink(), FileNotFoundError, "camera calibration camera.yaml is missing"),
    (lambda d: _edit_lines(d / "frames.jsonl", 1, timestamp=0.0), ValueError,
     r"frames.jsonl: line 2 \(frame n000__CAM_FRONT__1\).timestamp: 0.0, not after"),
    (lambda d: _edit_lines(d / "frames.jsonl", 1, ego_pose=None), ValueError,
     r"ego_speed: missing, and no ego_pose here"),
    (lambda d: _edit_lines(d / "detections.jsonl", 0, frame="n000__CAM_FRONT__7"), ValueError,
     r"detections.jsonl: line 1 \(frame n000__CAM_FRONT__7\): frame 'n000__CAM_FRONT__7' is not in frames.jsonl"),
    (lambda d: _edit_lines(d / "detections.jsonl", 0, detections=[{"translation": [1, 2, 3]}]), ValueError,
     r"detections.jsonl: line 1 \(frame n000__CAM_FRONT__0\).detections\[0\]: field 'detection_name' is missing"),
    (lambda d: (d / "depth" / "n000__CAM_FRONT__1.npy").unlink(), FileNotFoundError,
     "has no map for frame 'n000__CAM_FRONT__1'"),
    (lambda d: (d / "detections.json").write_text("{}"), FileNotFoundError,
     "needs exactly one of detections.jsonl .* found both"),
    (lambda d: (d / "ground_truth.jsonl").write_text('{"frame": "n000__CAM_FRONT__0", "annotations": []}\n'),
     ValueError, "ground_truth.jsonl: no line for frame 'n000__CAM_FRONT__1'"),
])
def test_malformed_recordings_are_clear_errors(tmp_path, nuscenes, edit, error, message):
    as_recording(nuscenes, tmp_path / "rec", "lines")
    edit(tmp_path / "rec")
    with pytest.raises(error, match=message):
        RecordingReader(tmp_path / "rec")


def test_results_for_a_frame_not_in_the_recording(tmp_path, nuscenes):
    as_recording(nuscenes, tmp_path / "rec", "results")
    path = tmp_path / "rec" / "detections.json"
    data = json.loads(path.read_text())
    data["results"]["s9"] = []
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"detections.json: results has 1 sample tokens that are not in "
                                         r".*frames.jsonl \(the frame keys\), first 's9'"):
        RecordingReader(tmp_path / "rec")


def test_images_are_needed_for_a_depth_network(tmp_path, nuscenes):
    as_recording(nuscenes, tmp_path / "rec", "lines")
    with pytest.raises(FileNotFoundError, match="no images/ folder of camera images"):
        RecordingReader(tmp_path / "rec", need_images=True)
