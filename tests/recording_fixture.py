"""Recording folders (monitor.datasets.recordings format) written from synthetic frames, for tests."""
from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import onnx
import yaml
from onnx import TensorProto, helper

from monitor.depth.prior import build_prior, save_prior
from monitor.synthetic import generate_frames, shade

A, B = 20.0, 2.0  # the tiny depth model: depth = A * mean over channels of RGB / 255 + B metres


def _boxes(boxes, extra):
    return [{"translation": b[0:3], "size": b[3:6], "yaw": b[6], **e} for b, e in zip(boxes.tolist(), extra)]


def write_recording(folder: Path, *, condition="nominal", seed=3, n_frames=10, ground_truth=True,
                    depth=True) -> list:
    """A recording of a synthetic scene: camera.yaml, frames.jsonl, depth/, detections.jsonl and
    (``ground_truth``) ground_truth.jsonl; returns the generated frames."""
    frames = list(generate_frames(condition, seed, n_frames=n_frames))
    camera = frames[0].camera
    folder.mkdir(parents=True)
    (folder / "camera.yaml").write_text(yaml.safe_dump({
        "width": camera.width, "height": camera.height, "intrinsics": camera.K.tolist(),
        "cam_to_ego": camera.cam_to_ego.tolist(), "near": camera.near}))
    if depth:
        (folder / "depth").mkdir()
    lines = {"frames": [], "detections": [], "ground_truth": []}
    for f in frames:
        key = f"{f.index:06d}"
        if depth:
            np.save(folder / "depth" / f"{key}.npy", f.depth_est)
        lines["frames"].append({"frame": key, "timestamp": f.timestamp, "ego_speed": f.ego_speed})
        lines["detections"].append({"frame": key, "detections": _boxes(f.det_boxes3d, [
            {"detection_name": c, "detection_score": s} for c, s in zip(f.det_classes.tolist(),
                                                                        f.det_scores.tolist())])})
        lines["ground_truth"].append({"frame": key, "annotations": _boxes(f.gt_boxes3d, [
            {"category_name": c, "instance_id": i, "visibility": v}
            for c, i, v in zip(f.gt_classes.tolist(), f.gt_ids.tolist(), f.gt_visibility.tolist())])})
    if not ground_truth:
        del lines["ground_truth"]
    for name, rows in lines.items():
        (folder / f"{name}.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    return frames


def write_prior(path: Path, frames) -> Path:
    """The mean inverse depth of ``frames``' estimated depth maps."""
    save_prior(path, build_prior((str(f.index), f.depth_est) for f in frames).mean())
    return path


def read_rows(out: Path) -> dict[str, list[dict]]:
    """``{scene file: rows}`` of a ``fuzzrisk monitor`` output, without the measured timings."""
    rows = {}
    for path in sorted((out / "scenes").glob("*.jsonl")):
        rows[path.name] = [{k: v for k, v in json.loads(line).items() if k != "timings_ms"}
                           for line in path.read_text().splitlines()]
    return rows


def write_images(folder: Path, frames) -> None:
    """The frames' shaded camera images as ``images/<key>.png``."""
    (folder / "images").mkdir()
    for f in frames:
        cv2.imwrite(str(folder / "images" / f"{f.index:06d}.png"), shade(f)[:, :, ::-1])


def mean_model(path, batch="N", output_shape=None):
    """A tiny ONNX depth model: depth = A * mean_c(x) + B for input (batch, 3, 32, 64), output
    (batch, 1, 32, 64) (the zoedepth preset: x = RGB / 255)."""
    nodes = [helper.make_node("ReduceMean", ["image"], ["m"], axes=[1], keepdims=1),
             helper.make_node("Mul", ["m", "a"], ["am"]), helper.make_node("Add", ["am", "b"], ["depth"])]
    graph = helper.make_graph(
        nodes, "tiny", [helper.make_tensor_value_info("image", TensorProto.FLOAT, [batch, 3, 32, 64])],
        [helper.make_tensor_value_info("depth", TensorProto.FLOAT, output_shape or [batch, 1, 32, 64])],
        initializer=[helper.make_tensor("a", TensorProto.FLOAT, [], [A]),
                     helper.make_tensor("b", TensorProto.FLOAT, [], [B])])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, str(path))
    return path
