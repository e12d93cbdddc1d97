"""Depth maps from files: .npy, 16-bit PNG with a scale, folders keyed by frame."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from monitor.depth.files import DepthFolder, load_depth, save_depth_png


def _depth(seed=0, shape=(6, 9)):
    return np.random.default_rng(seed).uniform(0.5, 80.0, size=shape).astype(np.float32)


def test_npy_float32_round_trip_keeps_invalid_pixels(tmp_path):
    depth = _depth()
    depth[0, 0], depth[1, 1], depth[2, 2], depth[3, 3] = np.nan, np.inf, 0.0, -1.0
    np.save(tmp_path / "a.npy", depth)
    loaded = load_depth(tmp_path / "a.npy")
    assert loaded.dtype == np.float32 and loaded.shape == depth.shape
    np.testing.assert_array_equal(loaded, depth)  # NaN == NaN here; invalid stays invalid


@pytest.mark.parametrize("dtype", [np.float16, np.float64])
def test_npy_other_floats_become_float32(tmp_path, dtype):
    depth = np.array([[1.5, 2.25], [40.0, 0.75]], dtype=dtype)
    np.save(tmp_path / "a.npy", depth)
    loaded = load_depth(tmp_path / "a.npy")
    assert loaded.dtype == np.float32
    np.testing.assert_array_equal(loaded, depth.astype(np.float32))


@pytest.mark.parametrize(
    "array, message",
    [
        (np.ones((4, 5), dtype=np.uint16), "dtype is uint16, expected a floating-point"),
        (np.ones((2, 4, 5), dtype=np.float32), r"shape \(2, 4, 5\) \(3-D\)"),
        (np.ones(5, dtype=np.float32), r"shape \(5,\) \(1-D\)"),
    ],
)
def test_npy_wrong_dtype_or_ndim(tmp_path, array, message):
    np.save(tmp_path / "bad.npy", array)
    with pytest.raises(ValueError, match="bad.npy.*" + message):
        load_depth(tmp_path / "bad.npy")


def test_npy_that_is_not_an_array(tmp_path):
    np.savez(tmp_path / "arch.npz", a=np.ones((2, 2)))
    (tmp_path / "arch.npz").rename(tmp_path / "arch.npy")
    with pytest.raises(ValueError, match="archive"):
        load_depth(tmp_path / "arch.npy")
    np.save(tmp_path / "obj.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(ValueError, match="obj.npy: dtype object holds Python objects"):
        load_depth(tmp_path / "obj.npy")


def test_kitti_png_is_value_over_256_and_zero_is_nan(tmp_path):
    raw = np.array([[0, 256, 512], [65535, 1, 3840]], dtype=np.uint16)
    assert cv2.imwrite(str(tmp_path / "k.png"), raw)
    depth = load_depth(tmp_path / "k.png")
    assert depth.dtype == np.float32
    assert np.isnan(depth[0, 0])
    np.testing.assert_allclose(depth.ravel()[1:], [1.0, 2.0, 65535 / 256, 1 / 256, 15.0], rtol=1e-7)
    np.testing.assert_allclose(load_depth(tmp_path / "k.png", png_scale=1000.0)[1, 2], 3.84, rtol=1e-6)


def test_png_wrong_kind(tmp_path):
    assert cv2.imwrite(str(tmp_path / "eight.png"), np.ones((3, 3), np.uint8))
    with pytest.raises(ValueError, match="eight.png: pixel type is uint8, expected uint16"):
        load_depth(tmp_path / "eight.png")
    assert cv2.imwrite(str(tmp_path / "rgb.png"), np.ones((3, 3, 3), np.uint16))
    with pytest.raises(ValueError, match=r"rgb.png: image has shape \(3, 3, 3\)"):
        load_depth(tmp_path / "rgb.png")
    (tmp_path / "junk.png").write_bytes(b"junk")
    with pytest.raises(ValueError, match="junk.png: not a PNG image"):
        load_depth(tmp_path / "junk.png")
    assert cv2.imwrite(str(tmp_path / "ok.png"), np.ones((3, 3), np.uint16))
    with pytest.raises(ValueError, match="png_scale = 0"):
        load_depth(tmp_path / "ok.png", png_scale=0)


def test_unknown_extension_and_missing_file(tmp_path):
    with pytest.raises(ValueError, match=r"extension '\.exr' is not supported, expected one of \.npy, \.png"):
        load_depth(tmp_path / "d.exr")
    with pytest.raises(FileNotFoundError, match="nothere.npy does not exist"):
        load_depth(tmp_path / "nothere.npy")


def test_save_depth_png_round_trip_within_half_a_step(tmp_path):
    depth = _depth(1)
    depth[0, 0] = np.nan
    save_depth_png(tmp_path / "d.png", depth)
    back = load_depth(tmp_path / "d.png")
    assert np.isnan(back[0, 0])
    ok = np.isfinite(depth)
    assert np.max(np.abs(back[ok] - depth[ok])) <= 0.5 / 256 + 1e-6


def test_save_depth_png_refuses_what_does_not_fit(tmp_path):
    with pytest.raises(ValueError, match="does not fit a 16-bit PNG"):
        save_depth_png(tmp_path / "far.png", np.array([[300.0]], np.float32))
    with pytest.raises(ValueError, match="does not fit a 16-bit PNG"):
        save_depth_png(tmp_path / "near.png", np.array([[0.001]], np.float32))
    with pytest.raises(ValueError, match="must end in .png"):
        save_depth_png(tmp_path / "d.npy", np.ones((2, 2), np.float32))


def _folder(tmp_path):
    np.save(tmp_path / "000002.npy", np.full((4, 5), 2.0, np.float32))
    save_depth_png(tmp_path / "000000.png", np.full((4, 5), 1.0, np.float32))
    np.save(tmp_path / "000001.npy", np.full((4, 5), 3.0, np.float32))
    (tmp_path / "notes.txt").write_text("ignored")
    (tmp_path / "sub.npy").mkdir()  # a directory, ignored
    return DepthFolder(tmp_path)


def test_folder_lists_frames_sorted_and_reads_each(tmp_path):
    folder = _folder(tmp_path)
    assert folder.frames == ["000000", "000001", "000002"]
    assert len(folder) == 3 and "000001" in folder and "notes" not in folder
    assert [(f, float(d[0, 0])) for f, d in folder] == [("000000", 1.0), ("000001", 3.0), ("000002", 2.0)]
    assert folder["000002"].dtype == np.float32


def test_folder_missing_frame_and_duplicates(tmp_path):
    folder = _folder(tmp_path)
    with pytest.raises(KeyError, match="has no frame '000009'.*3 frames present"):
        folder["000009"]
    np.save(tmp_path / "000000.npy", np.ones((4, 5), np.float32))
    with pytest.raises(ValueError, match="frame '000000' exists twice"):
        DepthFolder(tmp_path)


def test_folder_bad_file_is_named(tmp_path):
    np.save(tmp_path / "000000.npy", np.ones((4, 5), np.int32))
    folder = DepthFolder(tmp_path)
    with pytest.raises(ValueError, match="000000.npy: dtype is int32"):
        folder["000000"]


def test_folder_that_does_not_exist(tmp_path):
    with pytest.raises(FileNotFoundError, match="depth folder .*nope does not exist"):
        DepthFolder(tmp_path / "nope")
