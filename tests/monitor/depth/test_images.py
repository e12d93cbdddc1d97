"""Depth from camera images: batches equal single calls, errors, and fuzzrisk monitor --depth-model."""
import shutil

import cv2
import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper

from monitor.cli import main
from monitor.depth.images import DepthModel, read_image
from monitor.depth.onnx_model import OnnxDepthEstimator
from recording_fixture import A, B, mean_model, read_rows, write_images, write_prior, write_recording

def doubled_model(path):
    """A model that answers one image with two maps: output (2, 1, 32, 64)."""
    nodes = [helper.make_node("ReduceMean", ["image"], ["m"], axes=[1], keepdims=1),
             helper.make_node("Concat", ["m", "m"], ["depth"], axis=0)]
    graph = helper.make_graph(
        nodes, "doubled", [helper.make_tensor_value_info("image", TensorProto.FLOAT, [1, 3, 32, 64])],
        [helper.make_tensor_value_info("depth", TensorProto.FLOAT, [2, 1, 32, 64])])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, str(path))
    return path


def images(seed=0):
    rng = np.random.default_rng(seed)
    return [rng.integers(0, 256, size=shape, dtype=np.uint8)
            for shape in [(32, 64, 3), (90, 160, 3), (32, 64, 3), (45, 80, 3), (32, 64, 3)]]


@pytest.mark.parametrize("batch", ["N", 1])
def test_a_batch_is_the_same_as_one_call_per_image(tmp_path, batch):
    est = OnnxDepthEstimator(mean_model(tmp_path / "m.onnx", batch), "zoedepth", device="cpu", threads=1)
    assert est.max_batch == (None if batch == "N" else 1)
    ims = images()
    batched = est.estimate_batch(ims)
    assert [d.shape for d in batched] == [im.shape[:2] for im in ims]
    for im, depth in zip(ims, batched):
        np.testing.assert_array_equal(depth, est(im))
    # the 32 x 64 image needs no resize: the formula per pixel
    np.testing.assert_allclose(batched[0], A * ims[0].astype(np.float64).mean(axis=2) / 255 + B, rtol=1e-5)


def test_an_output_that_is_not_a_depth_map_names_the_model(tmp_path):
    est = OnnxDepthEstimator(doubled_model(tmp_path / "two.onnx"), "zoedepth", device="cpu")
    with pytest.raises(ValueError, match=r"two.onnx: output 'depth' has shape \(2, 1, 32, 64\) for a batch of 1"):
        est.estimate_batch([images()[0]])


def test_unreadable_images_are_named_and_do_not_stop_the_batch(tmp_path):
    good = tmp_path / "a.png"
    cv2.imwrite(str(good), images()[0][:, :, ::-1])
    (tmp_path / "b.jpg").write_bytes(b"not a jpeg")
    image_depth = DepthModel(mean_model(tmp_path / "m.onnx"), "zoedepth", device="cpu", batch_size=2,
                             save_dir=tmp_path).build()
    out = image_depth([("a", good), ("b", tmp_path / "b.jpg"), ("c", tmp_path / "c.png")])
    np.testing.assert_array_equal(out[0], image_depth.estimator(read_image(good)))
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), out[0])  # saved for reuse
    assert out[1] == f"image {tmp_path / 'b.jpg'}: OpenCV cannot decode it; expected a JPEG, PNG or other " \
                     "image file OpenCV reads"
    assert out[2] == f"image {tmp_path / 'c.png'} does not exist"


@pytest.fixture(scope="module")
def image_recording(tmp_path_factory):
    root = tmp_path_factory.mktemp("img")
    frames = write_recording(root / "drive", n_frames=3, depth=False)
    write_images(root / "drive", frames)
    return root, write_prior(root / "prior.npy", frames), mean_model(root / "m.onnx")


def test_monitor_on_images_equals_monitor_on_the_saved_depth_maps(image_recording, tmp_path):
    root, prior, model = image_recording
    saved = tmp_path / "saved"
    saved.mkdir()
    assert main(["monitor", "-o", str(tmp_path / "img"), "--recording", str(root / "drive"), "--prior", str(prior),
                 "--depth-model", str(model), "--depth-batch", "2", "--depth-device", "cpu",
                 "--save-depth", str(saved)]) == 0
    image = read_image(root / "drive" / "images" / "000001.png")
    expected = A * image.astype(np.float64).mean(axis=2) / 255 + B  # up to the 64 x 32 round trip
    depth = np.load(saved / "000001.npy")
    assert depth.shape == image.shape[:2] and abs(np.median(depth - expected)) < 0.5
    # the saved maps as the recording's depth/: the same reports
    rec = tmp_path / "drive"
    shutil.copytree(root / "drive", rec, ignore=shutil.ignore_patterns("images"))
    shutil.copytree(saved, rec / "depth")
    assert main(["monitor", "-o", str(tmp_path / "dep"), "--recording", str(rec), "--prior", str(prior)]) == 0
    assert read_rows(tmp_path / "img") == read_rows(tmp_path / "dep")


def test_an_unreadable_image_is_an_unprocessed_frame(image_recording, tmp_path):
    root, prior, model = image_recording
    rec = tmp_path / "drive"
    shutil.copytree(root / "drive", rec)
    (rec / "images" / "000002.png").write_bytes(b"truncated")
    assert main(["monitor", "-o", str(tmp_path / "out"), "--recording", str(rec), "--prior", str(prior),
                 "--depth-model", str(model)]) == 0
    rows = read_rows(tmp_path / "out")["drive.jsonl"]
    assert [r["status"] == "unprocessed" for r in rows] == [False, False, True]
    assert f"image {rec / 'images' / '000002.png'}: OpenCV cannot decode it" in rows[2]["error"]


def test_a_model_that_does_not_fit_its_preset_is_an_error(image_recording, tmp_path, capsys):
    root, prior, _ = image_recording
    model = mean_model(tmp_path / "dav2.onnx")  # 32 x 64 is no multiple of 14
    assert main(["monitor", "-o", str(tmp_path / "out"), "--recording", str(root / "drive"), "--prior",
                 str(prior), "--depth-model", str(model), "--depth-preset", "depth_anything_v2_metric"]) == 2
    assert "dav2.onnx: input height 32 is not a multiple of 14 as preset 'depth_anything_v2_metric' expects" \
           in capsys.readouterr().err
