"""OnnxDepthEstimator: tiny ONNX graphs built with the onnx package, run for real."""
from __future__ import annotations

import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper

from monitor.depth.onnx_model import IMAGENET_MEAN, IMAGENET_STD, PRESETS, DepthPreset, OnnxDepthEstimator

OPSET = 17


def _save(path, nodes, input_shape, output_shape, initializers=(), outputs=("depth",)):
    graph = helper.make_graph(
        list(nodes), "tiny_depth",
        [helper.make_tensor_value_info("image", TensorProto.FLOAT, input_shape)],
        [helper.make_tensor_value_info(name, TensorProto.FLOAT, output_shape) for name in outputs],
        initializer=list(initializers),
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET)])
    model.ir_version = 8
    onnx.checker.check_model(model)
    onnx.save(model, str(path))
    return path


def _const(name, value):
    return helper.make_tensor(name, TensorProto.FLOAT, [], [float(value)])


def _mean_channels_model(path, input_shape, output_shape, keepdims, a, b):
    """depth = a * mean over channels of the network input + b."""
    nodes = [
        helper.make_node("ReduceMean", ["image"], ["m"], axes=[1], keepdims=keepdims),
        helper.make_node("Mul", ["m", "a"], ["am"]),
        helper.make_node("Add", ["am", "b"], ["depth"]),
    ]
    return _save(path, nodes, input_shape, output_shape, [_const("a", a), _const("b", b)])


def _flat_image(height, width, rgb):
    image = np.empty((height, width, 3), dtype=np.uint8)
    image[:] = rgb
    return image


def test_zoedepth_fixed_size_metric_output(tmp_path):
    # ZoeDepth-style export: fixed (1, 3, 32, 64) input, (1, 1, 32, 64) output in metres.
    model = _mean_channels_model(tmp_path / "zoe.onnx", [1, 3, 32, 64], [1, 1, 32, 64], 1, a=10.0, b=1.0)
    est = OnnxDepthEstimator(model, "zoedepth", device="cpu", threads=1)
    assert est.input_size(90, 160) == (32, 64)
    assert est.providers == ["CPUExecutionProvider"]
    rgb = (51, 102, 204)
    depth = est(_flat_image(90, 160, rgb))
    # RGB / 255 averaged: (0.2 + 0.4 + 0.8) / 3; depth = 10 * that + 1
    expected = 10.0 * (0.2 + 0.4 + 0.8) / 3 + 1.0
    assert depth.shape == (90, 160) and depth.dtype == np.float32
    np.testing.assert_allclose(depth, expected, rtol=1e-5)


def test_zoedepth_output_follows_the_image_and_is_resized_back(tmp_path):
    # Same size in and out, no resampling: the output must equal the per-pixel formula.
    model = _mean_channels_model(tmp_path / "zoe.onnx", [1, 3, 32, 64], [1, 1, 32, 64], 1, a=10.0, b=1.0)
    est = OnnxDepthEstimator(model, "zoedepth", device="cpu", threads=1)
    rng = np.random.default_rng(3)
    image = rng.integers(0, 256, size=(32, 64, 3), dtype=np.uint8)
    expected = 10.0 * image.astype(np.float64).mean(axis=2) / 255.0 + 1.0
    np.testing.assert_allclose(est(image), expected, rtol=1e-5)


def test_zoedepth_minus_99_becomes_nan_and_does_not_leak(tmp_path):
    # depth = -99 where the red channel is bright (> 0.5), else 5 + green: left half invalid.
    nodes = [
        helper.make_node("Slice", ["image", "r0", "r1", "axis"], ["red"]),
        helper.make_node("Slice", ["image", "g0", "g1", "axis"], ["green"]),
        helper.make_node("Greater", ["red", "half"], ["bad"]),
        helper.make_node("Add", ["green", "five"], ["good"]),
        helper.make_node("Where", ["bad", "minus99", "good"], ["depth"]),
    ]
    ints = lambda name, v: helper.make_tensor(name, TensorProto.INT64, [1], [v])  # noqa: E731
    inits = [ints("r0", 0), ints("r1", 1), ints("g0", 1), ints("g1", 2), ints("axis", 1),
             _const("half", 0.5), _const("five", 5.0), _const("minus99", -99.0)]
    model = _save(tmp_path / "zoe_bad.onnx", nodes, [1, 3, 32, 64], [1, 1, 32, 64], inits)
    est = OnnxDepthEstimator(model, "zoedepth", device="cpu", threads=1)
    image = _flat_image(90, 160, (0, 51, 0))
    image[:, :80, 0] = 255                     # left half: red -> -99 -> invalid
    depth = est(image)
    assert np.isnan(depth[:, :78]).all()       # invalid, including the resampled border
    # no blend of -99 with valid neighbours: every number is the valid 5 + 0.2
    finite = depth[np.isfinite(depth)]
    assert finite.size > 0.45 * depth.size
    np.testing.assert_allclose(finite, 5.2, rtol=1e-5)


def test_depth_anything_dynamic_size_multiple_of_14_and_bhw_output(tmp_path):
    model = _mean_channels_model(tmp_path / "da.onnx", ["batch", 3, "height", "width"],
                                 ["batch", "height", "width"], 0, a=1.0, b=3.0)
    est = OnnxDepthEstimator(model, "depth_anything_v2_metric", device="cpu", threads=1)
    # 90 x 160: short side 90 -> 518, long side 160 * 518 / 90 = 920.9 -> 66 * 14 = 924
    assert est.input_size(90, 160) == (518, 924)
    rgb = np.array([40, 120, 200])
    depth = est(_flat_image(90, 160, tuple(rgb)))
    normalised = (rgb / 255.0 - np.array(IMAGENET_MEAN)) / np.array(IMAGENET_STD)
    np.testing.assert_allclose(depth, normalised.mean() + 3.0, rtol=1e-5)


def test_relative_model_needs_a_scale_and_inverts(tmp_path):
    model = _mean_channels_model(tmp_path / "rel.onnx", [1, 3, 28, 56], [1, 28, 56], 0, a=1.0, b=3.0)
    with pytest.raises(ValueError, match="relative.*scale"):
        OnnxDepthEstimator(model, "depth_anything_v2_relative", device="cpu")
    est = OnnxDepthEstimator(model, "depth_anything_v2_relative", scale=12.0, device="cpu", threads=1)
    rgb = np.array([10, 20, 30])
    out = ((rgb / 255.0 - np.array(IMAGENET_MEAN)) / np.array(IMAGENET_STD)).mean() + 3.0
    np.testing.assert_allclose(est(_flat_image(28, 56, tuple(rgb))), 12.0 / out, rtol=1e-5)


def test_metric_scale_multiplies(tmp_path):
    model = _mean_channels_model(tmp_path / "zoe.onnx", [1, 3, 32, 32], [1, 1, 32, 32], 1, a=0.0, b=4.0)
    est = OnnxDepthEstimator(model, "zoedepth", scale=0.5, device="cpu", threads=1)
    np.testing.assert_allclose(est(_flat_image(8, 8, (1, 2, 3))), 2.0)


def test_missing_model_says_where_to_put_one(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"downloads nothing.*zoe_k\.onnx"):
        OnnxDepthEstimator(tmp_path / "zoe_k.onnx")


def test_garbage_file_is_a_clear_error(tmp_path):
    path = tmp_path / "garbage.onnx"
    path.write_bytes(b"not a model")
    with pytest.raises(ValueError, match="garbage.onnx.*cannot load"):
        OnnxDepthEstimator(path, device="cpu")


def test_model_input_checks(tmp_path):
    nhwc = _save(tmp_path / "nhwc.onnx", [helper.make_node("Identity", ["image"], ["depth"])],
                 [1, 32, 32, 3], [1, 32, 32, 3])
    with pytest.raises(ValueError, match=r"expected \(N, 3, H, W\)"):
        OnnxDepthEstimator(nhwc, device="cpu")
    odd = _mean_channels_model(tmp_path / "odd.onnx", [1, 3, 30, 60], [1, 30, 60], 0, a=1.0, b=1.0)
    with pytest.raises(ValueError, match="multiple of 14.*wrong preset"):
        OnnxDepthEstimator(odd, "depth_anything_v2_metric", device="cpu")


def test_output_selection_and_bad_output_shape(tmp_path):
    nodes = [helper.make_node("ReduceMean", ["image"], ["first"], axes=[1], keepdims=1),
             helper.make_node("Add", ["first", "one"], ["second"])]
    model = _save(tmp_path / "two.onnx", nodes, [1, 3, 32, 32], [1, 1, 32, 32],
                  [_const("one", 1.0)], outputs=("first", "second"))
    image = _flat_image(32, 32, (255, 255, 255))
    assert OnnxDepthEstimator(model, device="cpu").output_name == "first"
    np.testing.assert_allclose(OnnxDepthEstimator(model, output_name="second", device="cpu")(image), 2.0)
    with pytest.raises(ValueError, match="no output 'third'.*first, second"):
        OnnxDepthEstimator(model, output_name="third", device="cpu")
    wide = _save(tmp_path / "id.onnx", [helper.make_node("Identity", ["image"], ["depth"])],
                 [1, 3, 32, 32], [1, 3, 32, 32])
    with pytest.raises(ValueError, match=r"output 'depth' has shape \(1, 3, 32, 32\)"):
        OnnxDepthEstimator(wide, device="cpu")(image)


def test_bad_arguments(tmp_path):
    model = _mean_channels_model(tmp_path / "zoe.onnx", [1, 3, 32, 32], [1, 1, 32, 32], 1, a=1.0, b=1.0)
    with pytest.raises(ValueError, match="preset = 'zoe'"):
        OnnxDepthEstimator(model, "zoe")
    with pytest.raises(ValueError, match="scale = -1"):
        OnnxDepthEstimator(model, scale=-1.0)
    with pytest.raises(ValueError, match="device = 'tpu'"):
        OnnxDepthEstimator(model, device="tpu")
    est = OnnxDepthEstimator(model, device="cpu")
    with pytest.raises(ValueError, match=r"uint8 \(H, W, 3\) RGB"):
        est(np.zeros((8, 8), np.uint8))
    with pytest.raises(ValueError, match=r"uint8 \(H, W, 3\) RGB"):
        est(np.zeros((8, 8, 3), np.float32))


def test_cuda_request_without_cuda_is_refused(tmp_path):
    import onnxruntime

    model = _mean_channels_model(tmp_path / "zoe.onnx", [1, 3, 32, 32], [1, 1, 32, 32], 1, a=1.0, b=1.0)
    if "CUDAExecutionProvider" in onnxruntime.get_available_providers():
        assert OnnxDepthEstimator(model, device="cuda").providers[0] == "CUDAExecutionProvider"
    else:
        with pytest.raises(ValueError, match="device = 'cuda'"):
            OnnxDepthEstimator(model, device="cuda")
        assert OnnxDepthEstimator(model, device="auto").providers == ["CPUExecutionProvider"]


def test_custom_preset_and_presets_are_consistent(tmp_path):
    custom = DepthPreset("mine", (0.5, 0.5, 0.5), (0.5, 0.5, 0.5), "metric", None,
                         short_side=16, multiple_of=8, interpolation=PRESETS["zoedepth"].interpolation)
    model = _mean_channels_model(tmp_path / "dyn.onnx", [1, 3, "h", "w"], [1, 1, "h", "w"], 1, a=1.0, b=2.0)
    est = OnnxDepthEstimator(model, custom, device="cpu")
    assert est.input_size(20, 50) == (16, 40)
    # (255/255 - 0.5) / 0.5 = 1 per channel -> depth 3
    np.testing.assert_allclose(est(_flat_image(20, 50, (255, 255, 255))), 3.0, rtol=1e-6)
    with pytest.raises(ValueError, match="output = 'disparity'"):
        DepthPreset("bad", (0, 0, 0), (1, 1, 1), "disparity", None, 1, 1, 1)
