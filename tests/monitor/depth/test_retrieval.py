"""Depth-based retrieval: kernels against NumPy, known objects on analytic scenes, errors."""
from __future__ import annotations

import dataclasses
from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from monitor.depth import _retrieval_kernels as kernels
from monitor.geometry.boxes import iou
from monitor.geometry.camera import Camera
from monitor.report.retrieval_figure import save_retrieval_figure
from monitor.depth.prior import build_prior
from monitor.depth.retrieval import (
    InvalidDepthError,
    RetrievalParams,
    Retriever,
    retrieve,
    retrieve_stages,
    warmup,
)

# --- analytic scenes: a level pinhole camera over a flat road, fronto-parallel objects ------

_CAM = Camera.nuscenes_front()
_CAM_HEIGHT = float(_CAM.cam_to_ego[2, 3])  # 1.51 m above the ground
_SKY = 80.0  # what a saturated monocular network reads for the sky (ZoeDepth outdoor)


def _scene(objects, scale=1.0, horizon_shift_px=0.0):
    """Depth map of the road plus objects, and the objects' true boxes.

    The camera is nuScenes CAM_FRONT scaled by ``scale`` and level, so a road pixel at row
    v (pixel centre v + 0.5) below the horizon row cy has depth Z = fy * h / (v + 0.5 - cy).
    ``horizon_shift_px`` moves the horizon (a pitch of the car). ``objects`` are
    (X, Z, width, height) in metres: lateral offset, depth, size of an upright rectangle
    facing the camera and standing on the road. Returns float32 (H, W) depth and the
    float64 (n, 5) true boxes ``cx, cy, w, h, d`` of the objects' visible rectangles.
    """
    f = _CAM.K[0, 0] * scale
    cx, cy = _CAM.K[0, 2] * scale, _CAM.K[1, 2] * scale + horizon_shift_px
    height, width = int(_CAM.height * scale), int(_CAM.width * scale)
    v = np.arange(height) + 0.5
    below = v > cy
    road = np.full(height, _SKY)
    road[below] = np.minimum(f * _CAM_HEIGHT / (v[below] - cy), _SKY)
    depth = np.repeat(road[:, None], width, axis=1)
    truth = []
    for x, z, w, h in sorted(objects, key=lambda o: -o[1]):  # far first, near ones cover them
        u0, u1 = cx + f * (x - w / 2) / z, cx + f * (x + w / 2) / z
        v0, v1 = cy + f * (_CAM_HEIGHT - h) / z, cy + f * _CAM_HEIGHT / z
        cols = (np.arange(width) + 0.5 >= u0) & (np.arange(width) + 0.5 < u1)
        rows = (v >= v0) & (v < v1)
        block = depth[np.ix_(rows, cols)]
        depth[np.ix_(rows, cols)] = np.minimum(block, z)
        u0, u1, v0, v1 = max(u0, 0), min(u1, width), max(v0, 0), min(v1, height)
        truth.append(((u0 + u1) / 2, (v0 + v1) / 2, u1 - u0, v1 - v0, z))
    return depth.astype(np.float32), np.array(truth, dtype=np.float64).reshape(-1, 5)


def _prior(n=8, seed=0, scale=1.0):
    """Prior of empty-road frames whose horizon jitters by +-2 px (the car pitching)."""
    rng = np.random.default_rng(seed)
    frames = ((str(k), _scene([], scale, rng.uniform(-2, 2))[0]) for k in range(n))
    return build_prior(frames).mean()


PRIOR = _prior()
PRIOR_HALF = _prior(scale=0.5)
# (X, Z, width, height) metres; laid out so that no two overlap in the image (touching
# objects merge into one contour, as they would in the paper's pipeline)
NEAR = [(-2.5, 7.0, 1.8, 1.5), (3.0, 11.0, 1.9, 1.7), (0.4, 14.0, 0.6, 1.75), (-1.5, 18.0, 2.5, 2.8)]
FAR = [(14.0, 30.0, 1.8, 1.5), (26.0, 45.0, 2.0, 3.0)]


def _match(found, truth):
    """Best IoU of each true box over the found ones, and the found box it goes with."""
    if len(found) == 0:
        return np.zeros(len(truth)), np.full(len(truth), -1)
    overlaps = iou(truth[:, None, :], found[None, :, :])
    return overlaps.max(axis=1), overlaps.argmax(axis=1)


# --- the per-pixel passes against NumPy ------------------------------------------------------


def _block_prior(prior):
    """Slow and obvious: the mean of the finite prior values of each 2 x 2 block."""
    rows, cols = -(-prior.shape[0] // 2), -(-prior.shape[1] // 2)
    out = np.full((rows, cols), np.nan, dtype=np.float32)
    for bi in range(rows):
        for bj in range(cols):
            block = [float(p) for p in prior[2 * bi:2 * bi + 2, 2 * bj:2 * bj + 2].ravel() if np.isfinite(p)]
            if block:
                out[bi, bj] = sum(block) / len(block)
    return out


def _foreground_numpy(depth, prior, downsample, full_scale):
    """Straight NumPy, the same float32 operations in the same order as the kernels."""
    with np.errstate(divide="ignore", invalid="ignore"):
        if downsample == 1:
            valid = np.isfinite(depth) & (depth > 0) & np.isfinite(prior)
            values = np.where(valid, np.maximum(np.float32(1.0) / depth - prior, np.float32(0.0)),
                              np.float32(-1.0)).astype(np.float32)
            n_invalid = int((~valid).sum())
        else:  # block mean of 1/D over valid depths minus the block's mean prior
            valid = np.isfinite(depth) & (depth > 0)
            inverse = np.where(valid, np.float32(1.0) / depth, np.float32(0.0)).astype(np.float32)
            count = valid.astype(np.int32)
            pad = ((0, depth.shape[0] % 2), (0, depth.shape[1] % 2))  # empty pixels; x + 0 is exact
            inverse, count = np.pad(inverse, pad), np.pad(count, pad)
            total = inverse[0::2] + inverse[1::2]                     # top + bottom, then the pair
            total = total[:, 0::2] + total[:, 1::2]
            count = count[0::2] + count[1::2]
            count = count[:, 0::2] + count[:, 1::2]
            block_prior = _block_prior(prior)
            known = np.isfinite(block_prior)
            mean = total / np.maximum(count, 1).astype(np.float32) - block_prior
            values = np.where((count > 0) & known, np.maximum(mean, np.float32(0.0)), np.float32(-1.0))
            n_invalid = int((~valid).sum() + count[~known].sum())
    scale_max = full_scale if full_scale is not None else max(float(values.max()), 0.0)
    scale = np.float32(255.0 / scale_max) if scale_max > 0 else np.float32(0.0)
    quantised = np.floor(np.minimum(values * scale + np.float32(0.5), np.float32(255.0)))
    image = np.where(values > 0, quantised, 0).astype(np.uint8)
    return image, values < 0, scale_max, n_invalid


def _random_frame(seed, shape=(37, 53), invalid_share=0.1):
    rng = np.random.default_rng(seed)
    depth = rng.uniform(0.5, 90.0, size=shape).astype(np.float32)
    prior = rng.uniform(0.0, 0.5, size=shape).astype(np.float32)
    holes = rng.random(shape) < invalid_share
    depth[holes] = rng.choice(np.array([np.nan, np.inf, -np.inf, 0.0, -2.0], np.float32), int(holes.sum()))
    prior[rng.random(shape) < invalid_share / 4] = np.nan
    return depth, prior


@given(st.integers(0, 2**31 - 1), st.floats(0.0, 0.5), st.sampled_from([1, 2]),
       st.sampled_from([None, 0.1, 2.0]), st.sampled_from([(37, 53), (36, 54), (1, 1), (2, 3)]))
def test_foreground_equals_numpy_bit_for_bit(seed, share, downsample, full_scale, shape):
    depth, prior = _random_frame(seed, shape=shape, invalid_share=share)
    params = RetrievalParams(downsample=downsample, full_scale=full_scale, max_invalid_fraction=1.0)
    stages = Retriever(prior, params).stages(depth)
    image, invalid, scale_max, n_invalid = _foreground_numpy(depth, prior, downsample, full_scale)
    np.testing.assert_array_equal(stages.foreground, image)
    np.testing.assert_array_equal(stages.invalid, invalid)
    assert stages.invalid_fraction == n_invalid / depth.size
    assert stages.full_scale == scale_max


@given(st.integers(0, 2**31 - 1), st.sampled_from([(37, 53), (36, 54), (1, 1), (3, 2)]))
def test_block_minima_are_the_smallest_valid_depth_of_each_block(seed, shape):
    depth, prior = _random_frame(seed, shape=shape, invalid_share=0.4)
    rows, cols = -(-shape[0] // 2), -(-shape[1] // 2)
    values, nearest = np.empty((rows, cols), np.float32), np.empty((rows, cols), np.float32)
    kernels.foreground_pairs(depth, _block_prior(prior), values, nearest)
    for bi in range(rows):
        for bj in range(cols):
            block = depth[2 * bi:2 * bi + 2, 2 * bj:2 * bj + 2].ravel()
            valid = [float(d) for d in block if np.isfinite(d) and d > 0]
            assert nearest[bi, bj] == (min(valid) if valid else np.inf)


def test_foreground_u8_rows_and_columns_mark_the_non_zero_pixels():
    values = np.array([[0.0, 0.0, 0.0], [0.0, 2.0, -1.0], [0.001, 0.0, 0.0]], np.float32)
    image = np.empty((3, 3), np.uint8)
    invalid = np.zeros((3, 3), np.uint8)
    rows, cols = np.empty(3, np.uint8), np.empty(3, np.uint8)
    kernels.foreground_u8(values, np.float32(127.5), image, rows, cols, invalid, True)
    # 2 * 127.5 = 255; 0.001 * 127.5 + 0.5 = 0.63 -> 0; -1 marks an invalid pixel
    np.testing.assert_array_equal(image, [[0, 0, 0], [0, 255, 0], [0, 0, 0]])
    np.testing.assert_array_equal(rows != 0, [False, True, False])
    np.testing.assert_array_equal(cols != 0, [False, True, False])
    np.testing.assert_array_equal(invalid, [[0, 0, 0], [0, 0, 1], [0, 0, 0]])


@given(st.integers(0, 2**31 - 1))
def test_rect_min_depth_against_a_slow_reference(seed):
    depth, _ = _random_frame(seed, shape=(20, 30), invalid_share=0.3)
    rng = np.random.default_rng(seed)
    x, y = rng.integers(0, 30, 12), rng.integers(0, 20, 12)
    rects = np.stack([x, y, rng.integers(1, 31 - x), rng.integers(1, 21 - y)], axis=1).astype(np.int64)
    got = kernels.rect_min_depth(depth, rects)
    for k, (x0, y0, w, h) in enumerate(rects):
        window = [float(d) for d in depth[y0:y0 + h, x0:x0 + w].ravel() if np.isfinite(d) and d > 0]
        if window:
            assert got[k] == min(window)
        else:
            assert np.isnan(got[k])


@given(st.integers(0, 2**31 - 1), st.integers(0, 3), st.sampled_from([1, 3, 5]))
def test_blur_and_canny_on_the_non_zero_region_equal_them_on_the_frame(seed, n_objects, blur_size):
    # Retriever blurs and runs Canny on the non-zero region plus a margin only: must be exact.
    rng = np.random.default_rng(seed)
    objects = [(rng.uniform(-6, 6), rng.uniform(4, 25), rng.uniform(0.4, 3), rng.uniform(0.5, 3))
               for _ in range(n_objects)]
    depth, _ = _scene(objects, scale=0.5)
    depth *= np.exp(rng.normal(0, 0.01, depth.shape)).astype(np.float32)
    params = RetrievalParams(blur_size=blur_size)
    stages = Retriever(PRIOR_HALF, params).stages(depth)
    image = stages.foreground
    for _ in range(2 if blur_size > 1 else 0):
        image = cv2.blur(image, (blur_size, blur_size), borderType=cv2.BORDER_REPLICATE)
    full = cv2.Canny(image, params.canny_low, params.canny_high, apertureSize=3, L2gradient=False)
    np.testing.assert_array_equal(stages.edges, full)


# --- known objects -----------------------------------------------------------------------------


def test_near_objects_are_recovered_and_far_ones_dropped():
    depth, truth = _scene(NEAR + FAR)
    found = retrieve(depth, PRIOR)
    near = truth[truth[:, 4] <= 20]
    best, which = _match(found, near)
    # measured with the default parameters: recall 4/4 at IoU >= 0.5; IoU 0.91 (18 m),
    # 0.87 (14 m), 0.90 (11 m), 0.93 (7 m). The bottoms are short: 1/D - prior fades to 0
    # where an object meets the road, so the box stops a little above the contact line.
    recall = np.mean(best >= 0.5)
    assert recall == 1.0
    assert best.mean() >= 0.88 and best.min() >= 0.8
    # one box per near object, and d is the object's depth (the road in a box is farther)
    assert len(found) == len(near)
    np.testing.assert_allclose(found[which, 4], near[:, 4], rtol=0.02)
    assert np.all(found[:, 4] <= 20.0)
    np.testing.assert_array_equal(np.argsort(found[:, 4], kind="stable"), np.arange(len(found)))


def test_full_resolution_recovers_them_too():
    depth, truth = _scene(NEAR + FAR)
    found = retrieve(depth, PRIOR, RetrievalParams(downsample=1))
    best, _ = _match(found, truth[truth[:, 4] <= 20])
    assert np.all(best >= 0.5)  # measured: IoU 0.89 / 0.85 / 0.89 / 0.92 (18, 14, 11, 7 m)


def test_one_absurd_pixel_flattens_the_frame_only_with_per_frame_normalisation():
    depth, truth = _scene([NEAR[1]])
    cx, cy = truth[0, :2]
    depth[int(cy), int(cx) - 60] = 0.05  # 20 1/m; its 2 x 2 block averages about 5 1/m
    assert len(retrieve(depth, PRIOR)) == 1                       # fixed full_scale: saturates
    peak = retrieve_stages(depth, PRIOR, RetrievalParams(full_scale=None))
    # the block is the peak: the 11 m car drops to 3 grey levels, too faint for Canny
    assert peak.full_scale > 4.0 and len(peak.boxes) == 0


def test_an_empty_road_gives_no_boxes():
    depth, _ = _scene([], horizon_shift_px=1.0)
    boxes = retrieve(depth, PRIOR)
    assert boxes.shape == (0, 5) and boxes.dtype == np.float64


def test_range_and_size_limits():
    depth, _ = _scene([NEAR[0], NEAR[2]])
    found = retrieve(depth, PRIOR)
    assert len(found) == 2
    # max_range below the nearer object's 7 m: nothing left
    assert len(retrieve(depth, PRIOR, RetrievalParams(max_range=6.9))) == 0
    # the pole (0.6 m wide at 14 m) goes when min_size exceeds its box's width
    narrow = found[found[:, 4] > 10][0, 2]
    assert len(retrieve(depth, PRIOR, RetrievalParams(min_size=narrow))) == 2
    kept = retrieve(depth, PRIOR, RetrievalParams(min_size=narrow + 1))
    assert len(kept) == 1 and kept[0, 4] == pytest.approx(7.0, rel=0.02)


def test_holes_in_an_object_are_masked_not_turned_into_boxes():
    depth, truth = _scene([NEAR[0]])
    clean = retrieve(depth, PRIOR)
    cx, cy, w, h, _ = truth[0]
    holed = depth.copy()
    y0, x0 = int(cy - h / 4), int(cx - w / 4)
    holed[y0:y0 + int(h / 3), x0:x0 + int(w / 3)] = np.nan       # a hole inside the car
    holed[5:40, 10:60] = 0.0                                     # and a dead patch in the sky
    stages = retrieve_stages(holed, PRIOR)
    assert 0 < stages.invalid_fraction < 0.05
    np.testing.assert_allclose(stages.boxes, clean)
    assert not stages.edges[stages.invalid].any()


def test_pixels_without_a_prior_are_invalid():
    depth, _ = _scene([NEAR[1]])
    prior = PRIOR.copy()
    prior[:, :40] = np.nan
    prior[::2, 100] = np.nan  # one pixel per block: the block mean of the other three stands
    stages = retrieve_stages(depth, prior)  # 2 x 2 blocks: block columns 0-19 have no prior
    assert stages.invalid[:, :20].all() and not stages.invalid[:, 20:].any()
    assert stages.invalid_fraction == pytest.approx(40 / depth.shape[1])
    full = retrieve_stages(depth, prior, RetrievalParams(downsample=1))  # per pixel
    assert full.invalid[:, :40].all() and full.invalid[::2, 100].all()
    assert full.invalid.sum() == 40 * depth.shape[0] + depth.shape[0] // 2


def test_a_mostly_invalid_frame_raises_with_the_fraction():
    depth, _ = _scene(NEAR)
    depth[:, : int(0.6 * depth.shape[1])] = np.nan  # the 11 m car stays visible
    with pytest.raises(InvalidDepthError, match=r"60\.\d% invalid.*max_invalid_fraction = 30\.0%") as info:
        retrieve(depth, PRIOR)
    assert isinstance(info.value, ValueError)
    assert info.value.invalid_fraction == pytest.approx(0.6, abs=0.01)
    assert info.value.max_invalid_fraction == 0.3
    # a looser limit accepts the same frame
    assert len(retrieve(depth, PRIOR, RetrievalParams(max_invalid_fraction=0.7))) >= 1


def test_percentile_depth_ignores_a_few_outlier_pixels():
    depth, truth = _scene([NEAR[1]])
    cx, cy, w, h, z = truth[0]
    spiky = depth.copy()
    spiky[int(cy), int(cx)] = 0.5                   # one absurdly near pixel inside the object
    assert retrieve(spiky, PRIOR)[0, 4] == pytest.approx(0.5)
    robust = retrieve(spiky, PRIOR, RetrievalParams(depth_percentile=5.0))
    assert robust[0, 4] == pytest.approx(z, rel=0.01)


def test_retriever_reuse_is_deterministic_and_stages_do_not_alias():
    retriever = Retriever(PRIOR)
    a, _ = _scene(NEAR[:2])
    b, _ = _scene(NEAR[2:])
    first = retriever.stages(a)
    kept = first.foreground.copy()
    retriever.stages(b)
    np.testing.assert_array_equal(first.foreground, kept)
    np.testing.assert_array_equal(retriever(a), first.boxes)
    np.testing.assert_array_equal(retrieve(a, PRIOR), first.boxes)


def test_input_errors():
    depth, _ = _scene([])
    with pytest.raises(ValueError, match=r"depth has shape \(899, 1600\) \(H, W\), expected \(900, 1600\)"):
        retrieve(depth[:-1], PRIOR)
    for bad, message in [(depth.astype(np.int32), "dtype int32"), (depth.astype(np.complex64), "dtype complex64"),
                         (depth > 1, "dtype bool"), (depth.astype(str), "dtype <U"),
                         (np.ma.masked_invalid(depth), "masked array"), ([[1.0], [1.0, 2.0]], "not an array")]:
        with pytest.raises(ValueError, match=message):
            retrieve(bad, PRIOR)
    with pytest.raises(ValueError, match="inf or negative"):
        retrieve(depth, np.full_like(PRIOR, -1.0))
    with pytest.raises(ValueError, match="expected RetrievalParams"):
        Retriever(PRIOR, {"canny_low": 1})


def test_float64_depth_is_worked_on_as_float32():
    depth, _ = _scene(NEAR[:2])
    expected = retrieve(depth, PRIOR)
    assert len(expected) == 2
    np.testing.assert_array_equal(retrieve(depth.astype(np.float64), PRIOR), expected)
    np.testing.assert_array_equal(retrieve(np.asfortranarray(depth), PRIOR), expected)
    # beyond float32's range is inf: an invalid pixel, not a number
    huge = np.full(depth.shape, 1e300)
    with pytest.raises(InvalidDepthError, match="100.0% invalid"):
        retrieve(huge, PRIOR)


@given(st.integers(0, 2**31 - 1), st.sampled_from([(37, 53), (36, 54), (1, 1), (2, 3), (3, 1)]))
def test_block_means_kernel_against_a_slow_reference(seed, shape):
    _, prior = _random_frame(seed, shape=shape, invalid_share=0.8)
    out = np.empty((-(-shape[0] // 2), -(-shape[1] // 2)), np.float32)
    kernels.block_means(prior, out)
    np.testing.assert_array_equal(out, _block_prior(prior))


def test_one_retriever_shared_by_threads_gives_the_single_threaded_boxes():
    retriever = Retriever(PRIOR)
    scenes = [_scene(NEAR[k:k + 2])[0] for k in range(len(NEAR) - 1)] + [_scene([])[0]]
    expected = [retriever(d) for d in scenes]
    assert sum(len(e) for e in expected) >= len(scenes) - 1  # most scenes hold objects
    work = [k % len(scenes) for k in range(6 * len(scenes))]
    with ThreadPoolExecutor(max_workers=4) as pool:
        got = list(pool.map(lambda k: retriever(scenes[k]), work))
    for k, boxes in zip(work, got):
        np.testing.assert_array_equal(boxes, expected[k])


@pytest.mark.parametrize(
    "change, message",
    [
        ({"canny_low": -1.0}, "canny_low = -1.0"),
        ({"canny_low": 50.0, "canny_high": 40.0}, "canny_high = 40.0, must be finite and >= canny_low"),
        ({"min_size": float("nan")}, "min_size = nan"),
        ({"blur_size": 4}, "blur_size = 4, must be an odd integer"),
        ({"blur_size": 3.0}, "blur_size = 3.0"),
        ({"downsample": 3}, r"downsample = 3, must be one of \(1, 2\)"),
        ({"full_scale": 0.0}, "full_scale = 0.0"),
        ({"max_range": 0.0}, "max_range = 0.0"),
        ({"depth_percentile": 101.0}, "depth_percentile = 101.0"),
        ({"max_invalid_fraction": 1.5}, "max_invalid_fraction = 1.5"),
    ],
)
def test_params_are_validated(change, message):
    with pytest.raises(ValueError, match=message):
        dataclasses.replace(RetrievalParams(), **change)


def test_params_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        RetrievalParams().canny_low = 3.0


def test_warm_up_runs():
    warmup()


def test_stage_figure_is_written(tmp_path):
    depth, _ = _scene(NEAR + FAR)
    depth[10:30, 10:30] = np.nan
    rgb = np.zeros(depth.shape + (3,), np.uint8)
    rgb[..., 1] = 90
    stages = save_retrieval_figure(tmp_path / "stages.png", depth, PRIOR, rgb, panel_width=200)
    png = cv2.imread(str(tmp_path / "stages.png"))
    assert png is not None and png.shape[1] == 800 and png.shape[0] > 100
    assert png.std() > 10  # not a blank canvas
    np.testing.assert_array_equal(stages.boxes, retrieve(depth, PRIOR))
    with pytest.raises(ValueError, match="must end in .png"):
        save_retrieval_figure(tmp_path / "stages.jpg", depth, PRIOR)
    with pytest.raises(ValueError, match=r"expected a uint8 \(900, 1600, 3\) RGB frame"):
        save_retrieval_figure(tmp_path / "s.png", depth, PRIOR, rgb[:10])
