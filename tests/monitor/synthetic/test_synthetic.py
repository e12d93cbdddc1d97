"""The synthetic scene generator: ray cast, layout, error models, conditions, determinism."""
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from monitor.geometry.boxes import DEFAULT_RANGE_M
from monitor.geometry.camera import Camera, project_boxes
from monitor.datasets.frames import (
    LABEL_MARKING, LABEL_ROAD, LABEL_SIDEWALK, LABEL_SKY, LABEL_STRUCTURE,
)
from monitor.synthetic import (
    CONDITIONS, DEPTH_ERROR_PARTS, generate_frames, generate_scene, get_condition, shade, without_depth_errors,
)
from monitor.synthetic.conditions import DETECTOR_CLASSES, DepthErrors, DetectorErrors
from monitor.synthetic.degrade import (
    detect, detection_probability, estimate_depth, lognormal_blocks, smooth_field,
)
from monitor.synthetic.raycast import ground_points, render_depth, render_depth_reference
from monitor.synthetic.suite import Benchmark
from monitor.synthetic.scene import (
    ACTOR_CLASSES, EGO_FRONT_M, EGO_HALF_WIDTH_M, EGO_REAR_M, make_layout,
)


def small_front_camera(scale: float = 0.1) -> Camera:
    """nuScenes CAM_FRONT with the image scaled by ``scale`` (K scaled, same pose)."""
    front = Camera.nuscenes_front()
    K = np.diag([scale, scale, 1.0]) @ front.K
    return Camera(K, round(front.width * scale), round(front.height * scale), front.cam_to_ego)


def pitched_camera(pitch: float, height: float = 1.5, size=(160, 90), f=100.0) -> Camera:
    """A camera at (0, 0, height) looking along +x, tilted down by ``pitch`` radians."""
    s, c = np.sin(pitch), np.cos(pitch)
    T = np.eye(4)
    T[:3, 0] = [0.0, -1.0, 0.0]  # camera x (right) in the ego frame
    T[:3, 1] = [-s, 0.0, -c]  # camera y (down)
    T[:3, 2] = [c, 0.0, -s]  # camera z (forward)
    T[:3, 3] = [0.0, 0.0, height]
    K = np.array([[f, 0.0, size[0] / 2], [0.0, f, size[1] / 2], [0.0, 0.0, 1.0]])
    return Camera(K, size[0], size[1], T)


# --------------------------------------------------------------------------- ray casting

def test_empty_road_depth_follows_camera_height_and_pitch():
    pitch, h, f = 0.08, 1.5, 100.0
    camera = pitched_camera(pitch, h, f=f)
    render = render_depth(camera, np.zeros((0, 7)))
    # row v looks down by atan(y_n) + pitch: the ground is h / (y_n cos(pitch) + sin(pitch)) away
    y_n = (np.arange(camera.height) + 0.5 - camera.height / 2) / f
    down = y_n * np.cos(pitch) + np.sin(pitch)
    expected = np.where(down > 0, h / np.where(down > 0, down, 1.0), np.inf)
    assert np.any(np.isinf(expected)) and np.any(np.isfinite(expected))  # horizon in view
    np.testing.assert_allclose(render.depth, np.broadcast_to(expected[:, None], render.depth.shape),
                               rtol=1e-6)
    assert render.depth.dtype == np.float32
    np.testing.assert_array_equal(render.labels == LABEL_SKY, np.isinf(render.depth))
    np.testing.assert_array_equal(render.labels[np.isfinite(render.depth)], LABEL_ROAD)


def test_empty_road_depth_nuscenes_front_from_the_ground_plane_in_camera_coordinates():
    camera = small_front_camera(0.1)
    R, t = camera.cam_to_ego[:3, :3], camera.cam_to_ego[:3, 3]
    up_cam = R.T @ [0.0, 0.0, 1.0]  # the ground is {P : up_cam . P = -t_z} in camera coordinates
    j, i = np.mgrid[0:camera.height, 0:camera.width]
    rays = np.linalg.solve(camera.K, np.stack([i.ravel() + 0.5, j.ravel() + 0.5,
                                               np.ones(i.size)]))  # z = 1
    along = up_cam @ rays
    expected = np.full(i.size, np.inf)
    expected[along < 0] = -t[2] / along[along < 0]
    render = render_depth(camera, np.zeros((0, 7)))
    np.testing.assert_allclose(render.depth.ravel(), expected, rtol=1e-6)
    bottom = render.depth[-1, camera.width // 2]
    assert 3.0 < bottom < 8.0  # ~1.5 m high, ~30 degrees half field of view vertically


def test_a_box_straight_ahead_renders_at_its_front_face_depth():
    camera = pitched_camera(0.0, 1.5, f=100.0)  # optical axis level, 1.5 m high, 160 x 90
    box = np.array([[10.0, 0.0, 0.9, 2.2, 4.0, 1.8, 0.0]])  # front face at x = 8 m
    render = render_depth(camera, box)
    centre = (camera.height // 2, camera.width // 2)  # pixel centre 0.5 px off the axis
    assert render.labels[centre] == 1
    assert render.depth[centre] == pytest.approx(8.0, rel=1e-6)
    # the face spans y in [-1.1, 1.1], z in [0, 1.8] at 8 m: u in 80 -+ 100 * 1.1 / 8 =
    # [66.25, 93.75], v in 45 + 100 * (1.5 - [1.8, 0]) / 8 = [41.25, 63.75]; pixel i is
    # the point i + 0.5, so columns 66..93 and rows 41..63
    columns = np.flatnonzero((render.labels == 1).any(axis=0))
    rows = np.flatnonzero((render.labels == 1).any(axis=1))
    assert (columns[0], columns[-1]) == (66, 93)
    assert (rows[0], rows[-1]) == (41, 63)
    assert render.visible_px[0] == render.silhouette_px[0] == 28 * 23


@pytest.mark.parametrize("box", [
    [12.0, 2.0, 0.8, 1.9, 4.5, 1.6, 0.4],
    [6.0, -3.0, 0.9, 0.7, 0.7, 1.8, -1.2],
    [25.0, 5.0, 1.4, 2.5, 7.0, 2.8, 2.9],
])
def test_rendered_extent_matches_project_boxes(box):
    camera = small_front_camera(0.25)  # 400 x 225
    render = render_depth(camera, np.array([box]))
    boxes2d, kept = project_boxes(np.array([box]), camera)
    assert kept.tolist() == [0]
    cx, cy, w, h, d = boxes2d[0]
    columns = np.flatnonzero((render.labels == 1).any(axis=0))
    rows = np.flatnonzero((render.labels == 1).any(axis=1))
    # pixel i covers [i, i + 1): the rendered extent is within a pixel of the projection
    assert abs(columns[0] - (cx - w / 2)) <= 1.0 and abs(columns[-1] + 1 - (cx + w / 2)) <= 1.0
    assert abs(rows[0] - (cy - h / 2)) <= 1.0 and abs(rows[-1] + 1 - (cy + h / 2)) <= 1.0
    # and its nearest pixel is no nearer than the box's smallest camera depth
    assert render.depth[render.labels == 1].min() >= d - 1e-4


def _reference_equal(camera, boxes, structure=None, structure_labels=None):
    fast = render_depth(camera, boxes, structure, structure_labels)
    slow = render_depth_reference(camera, boxes, structure, structure_labels)
    np.testing.assert_array_equal(fast.labels, slow.labels)
    np.testing.assert_allclose(fast.depth, slow.depth, rtol=1e-6)
    np.testing.assert_allclose(fast.background, slow.background, rtol=1e-6)
    np.testing.assert_array_equal(fast.silhouette_px, slow.silhouette_px)
    np.testing.assert_array_equal(fast.visible_px, slow.visible_px)
    return fast


def test_structure_is_rendered_labelled_and_in_the_background_but_not_counted():
    camera = small_front_camera(0.1)
    car = np.array([[12.0, 0.0, 0.9, 2.0, 4.5, 1.8, 0.0]])
    structure = np.array([
        [20.0, -9.0, 6.0, 10.0, 30.0, 12.0, 0.0],   # a building facade on the right
        [8.0, -5.0, 3.0, 0.2, 0.2, 6.0, 0.0],       # a pole on the right sidewalk
        [20.0, 5.15, 0.075, 0.3, 60.0, 0.15, 0.0],  # the left curb
        [30.0, 0.0, 0.9, 2.0, 4.5, 1.8, 0.0],       # a wall behind the car, same width
    ])
    codes = np.array([LABEL_STRUCTURE, LABEL_STRUCTURE, LABEL_SIDEWALK, LABEL_STRUCTURE])
    render = _reference_equal(camera, car, structure, codes)
    plain = render_depth(camera, car)
    # the car is counted as before: structure behind it changes nothing of it
    assert render.visible_px[0] == plain.visible_px[0] > 0
    assert render.silhouette_px.shape == (1,)
    assert {LABEL_STRUCTURE, LABEL_SIDEWALK, 1} <= set(np.unique(render.labels).tolist())
    # the background is the depth without the car: the wall shows through where the car was
    car_px = render.labels == 1
    assert np.all(render.background[car_px] > render.depth[car_px])
    np.testing.assert_array_equal(render.background[~car_px], render.depth[~car_px])
    # without structure the background is the empty road
    np.testing.assert_array_equal(plain.background, render_depth(camera, np.zeros((0, 7))).depth)
    with pytest.raises(ValueError, match="structure_labels"):
        render_depth(camera, car, structure, np.array([1, 0, -3, -4]))
    with pytest.raises(ValueError, match="structure_labels"):
        render_depth(camera, car, structure, np.array([-4, -4]))


def test_renderer_equals_numpy_reference_with_occlusion_near_plane_and_camera_inside():
    camera = small_front_camera(0.1)
    boxes = np.array([
        [10.0, 0.0, 0.9, 2.0, 4.5, 1.8, 0.1],     # car ahead
        [14.0, 0.5, 1.5, 2.5, 7.0, 3.0, 0.0],     # truck behind it, partly hidden
        [2.2, 0.0, 1.77, 1.0, 1.0, 0.5, 0.0],     # just above the camera, cut by the near plane
        [1.7, 0.0, 1.5, 0.5, 0.5, 0.5, 0.0],      # the camera inside it: all at `near`
        [-10.0, 0.0, 0.9, 2.0, 4.5, 1.8, 0.0],    # behind the camera
    ])
    render = _reference_equal(camera, boxes)
    assert np.all(render.depth == np.float32(camera.near))  # the view is blocked at `near`
    assert set(np.unique(render.labels).tolist()) == {3, 4}  # (ties go to the first box)
    render = _reference_equal(camera, boxes[[0, 1, 2, 4]])
    assert render.silhouette_px[1] > render.visible_px[1] > 0  # occluded truck
    assert np.any(render.depth[render.labels == 3] == np.float32(camera.near))  # clipped
    assert render.silhouette_px[3] == 0  # behind the camera


@given(st.lists(st.tuples(
    st.floats(-5.0, 40.0), st.floats(-10.0, 10.0), st.floats(0.0, 3.0),
    st.floats(0.2, 4.0), st.floats(0.2, 10.0), st.floats(0.2, 4.0), st.floats(-3.2, 3.2)),
    min_size=0, max_size=6))
def test_renderer_equals_numpy_reference_on_random_boxes(rows):
    boxes = np.array(rows, dtype=np.float64).reshape(-1, 7)
    _reference_equal(small_front_camera(0.04), boxes)
    # the first half as structure, the rest as actors
    half = len(boxes) // 2
    _reference_equal(small_front_camera(0.04), boxes[half:], boxes[:half])


def test_render_rejects_bad_input():
    camera = small_front_camera(0.05)
    with pytest.raises(ValueError, match=r"boxes3d\[0, 3\] \(w\)"):
        render_depth(camera, [[5.0, 0.0, 0.5, 0.0, 1.0, 1.0, 0.0]])
    with pytest.raises(ValueError, match="boxes3d"):
        render_depth(camera, [[5.0, 0.0, np.nan, 1.0, 1.0, 1.0, 0.0]])
    below = pitched_camera(0.0, height=-1.0)
    with pytest.raises(ValueError, match="above the ground"):
        render_depth(below, np.zeros((0, 7)))
    with pytest.raises(ValueError, match="expected a Camera"):
        render_depth("front", np.zeros((0, 7)))


def test_ground_points_of_a_pitched_camera():
    pitch, h, f = 0.1, 1.6, 100.0
    camera = pitched_camera(pitch, h, f=f)
    x, y = ground_points(camera)
    j, i = np.mgrid[0:camera.height, 0:camera.width]
    x_n, y_n = (i + 0.5 - 80) / f, (j + 0.5 - 45) / f
    down = y_n * np.cos(pitch) + np.sin(pitch)
    hit = down > 0
    t = h / down[hit]
    np.testing.assert_allclose(x[hit], t * (np.cos(pitch) - y_n[hit] * np.sin(pitch)), rtol=1e-9)
    np.testing.assert_allclose(y[hit], -t * x_n[hit], rtol=1e-9, atol=1e-12)
    assert np.all(np.isinf(x[~hit])) and np.all(np.isinf(y[~hit]))


# --------------------------------------------------------------------------- layout

def _footprints_overlap(a, b) -> bool:
    """Separating-axis test of two oriented rectangles (x, y, w, l, yaw)."""
    def corners(x, y, w, l, yaw):
        c, s = np.cos(yaw), np.sin(yaw)
        local = np.array([[1, 1], [1, -1], [-1, -1], [-1, 1]]) * [l / 2, w / 2]
        return local @ np.array([[c, s], [-s, c]]) + [x, y]
    pa, pb = corners(*a), corners(*b)
    for yaw in (a[4], b[4]):
        for axis in ([np.cos(yaw), np.sin(yaw)], [-np.sin(yaw), np.cos(yaw)]):
            qa, qb = pa @ axis, pb @ axis
            if qa.max() < qb.min() or qb.max() < qa.min():
                return False
    return True


def test_layout_keeps_actors_off_the_ego_and_near_objects_in_most_frames():
    camera = Camera.nuscenes_front()
    ego = (0.5 * (EGO_FRONT_M + EGO_REAR_M), 0.0, 2 * EGO_HALF_WIDTH_M,
           EGO_FRONT_M - EGO_REAR_M, 0.0)  # x, y, w, l, yaw
    near_counts, far_counts = [], []
    for seed in range(12):
        layout = make_layout(seed, 9.5, rare_per_scene=4.0)
        for t in np.arange(20) * 0.5:
            boxes, classes, ids = layout.frame_boxes(t)
            for x, y, z, w, l, h, yaw in boxes:
                assert not _footprints_overlap(ego, (x, y, w, l, yaw)), (seed, t, x, y)
            assert np.all(np.hypot(boxes[:, 0], boxes[:, 1]) <= 80.0)
            np.testing.assert_allclose(boxes[:, 2], boxes[:, 5] / 2)  # on the ground
            boxes2d, _ = project_boxes(boxes, camera)
            near_counts.append(np.count_nonzero(boxes2d[:, 4] <= DEFAULT_RANGE_M))
            far_counts.append(np.count_nonzero(boxes2d[:, 4] > DEFAULT_RANGE_M))
    near_counts, far_counts = np.array(near_counts), np.array(far_counts)
    assert np.mean(near_counts >= 3) >= 0.8  # "several within 20 m in most frames"
    assert np.mean(far_counts >= 1) >= 0.8  # "some farther"


def test_structure_lines_both_sides_of_the_road_and_stays_off_it():
    for seed in range(8):
        layout = make_layout(seed, 9.5, rare_per_scene=0.15)
        road, st_ = layout.road, layout.structure
        kinds = st_.kinds.tolist()
        assert {"curb", "pole", "building"} <= set(kinds), seed
        x, y, z, w, l, h, _ = st_.boxes.T
        right, left = y < 0, y > 0
        assert right.any() and left.any()
        # nothing stands on the carriageway: every box lies beyond a kerb, except tree
        # crowns, which may hang over the road edge but only above 2 m
        inner = np.where(right, y + w / 2 - road.right_kerb, road.left_kerb - (y - w / 2))
        crown = st_.kinds == "crown"
        assert np.all(inner[~crown] <= 1e-9), seed
        assert np.all(z[crown] - h[crown] / 2 >= 2.0) and np.all(inner[crown] <= 1.5)
        # curbs are low and cover the whole stretch the ego sees
        curb = st_.kinds == "curb"
        np.testing.assert_allclose(h[curb], 0.15)
        assert np.all(x[curb] - l[curb] / 2 <= -80.0) and np.all(x[curb] + l[curb] / 2 >= 80.0)
        np.testing.assert_array_equal(st_.labels[curb], LABEL_SIDEWALK)
        assert np.all(st_.labels[~curb] == LABEL_STRUCTURE)
        # the structure does not depend on the rare rate (its own random numbers)
        np.testing.assert_array_equal(make_layout(seed, 9.5, rare_per_scene=5.0).structure.boxes, st_.boxes)


def test_every_condition_has_the_same_street_structure():
    camera = small_front_camera(0.1)
    frames = {c: next(generate_frames(c, 4, n_frames=1, camera=camera)) for c in CONDITIONS}
    structure = frames["nominal"].labels == LABEL_STRUCTURE
    assert np.count_nonzero(structure) > 0.05 * structure.size
    for frame in frames.values():
        np.testing.assert_array_equal(frame.labels == LABEL_STRUCTURE, structure)


def test_layout_sizes_and_instance_ids():
    layout = make_layout(5, 9.5, rare_per_scene=4.0)
    actors = layout.actors
    assert set(actors.classes.tolist()) <= set(ACTOR_CLASSES)
    for name in set(actors.classes.tolist()):
        mean = np.array(ACTOR_CLASSES[name].size)
        sizes = actors.sizes[actors.classes == name]
        assert np.all(sizes > 0.3 * mean) and np.all(sizes < 3.0 * mean), name
    b0, _, ids0 = layout.frame_boxes(0.0)
    b1, _, ids1 = layout.frame_boxes(9.5)
    common, i0, i1 = np.intersect1d(ids0, ids1, return_indices=True)
    np.testing.assert_array_equal(b0[i0, 3:6], b1[i1, 3:6])  # an instance keeps its size


def test_rare_rate_adds_rare_actors_without_changing_the_traffic():
    rare = {name for name, c in ACTOR_CLASSES.items() if c.rare}
    plain = make_layout(3, 9.5, rare_per_scene=0.0)
    many = make_layout(3, 9.5, rare_per_scene=6.0)
    n = plain.actors.classes.size
    np.testing.assert_array_equal(many.actors.classes[:n], plain.actors.classes)
    np.testing.assert_array_equal(many.actors.p_a[:n], plain.actors.p_a)
    assert not rare & set(plain.actors.classes.tolist())
    counts = [np.isin(make_layout(s, 9.5, 6.0).actors.classes, list(rare)).sum() for s in range(40)]
    # Poisson(6) draws, a few left out when no crossing place is free: mean a little below 6
    assert 4.5 < np.mean(counts) <= 6.5


# --------------------------------------------------------------------------- error models

def test_smooth_field_has_unit_variance_and_is_smooth():
    rng = np.random.default_rng(0)
    fields = np.stack([smooth_field(rng, (40, 60), 6.0) for _ in range(300)])
    assert fields.dtype == np.float32
    assert abs(fields.mean()) < 0.05
    assert 0.93 < fields.var() < 1.05
    neighbour = np.corrcoef(fields[:, :, :-1].ravel(), fields[:, :, 1:].ravel())[0, 1]
    assert neighbour > 0.95  # 1 px apart, 6 px correlation length: exp(-1/24) ~ 0.96


def test_lognormal_blocks_are_constant_on_blocks_with_the_stated_spread():
    noise = lognormal_blocks(np.random.default_rng(1), (10, 14), 3, 0.2)
    assert noise.shape == (10, 14) and noise.dtype == np.float32
    coarse = noise[::3, ::3]
    np.testing.assert_array_equal(noise, np.repeat(np.repeat(coarse, 3, 0), 3, 1)[:10, :14])
    assert np.unique(coarse).size == coarse.size
    many = lognormal_blocks(np.random.default_rng(2), (400, 500), 2, 0.2)[::2, ::2]
    assert np.log(many).std() == pytest.approx(0.2, rel=0.02)  # 50,000 blocks
    assert np.log(many).mean() == pytest.approx(0.0, abs=0.004)


def _quiet_depth_errors(**changes) -> DepthErrors:
    base = DepthErrors(
        scale_log_bias=0.0, scale_log_std=0.0, field_rel0=0.0, field_rel_per_m=0.0,
        field_px=8.0, grain_log_std=0.0, grain_px=1.0, edge_blur_px=0.0, fade_prob=0.0,
        fade_min=0.0, artifact_rate=0.0, artifact_px=(5.0, 10.0), artifact_factor=(0.5, 0.8),
    )
    return replace(base, **changes)


def test_depth_log_error_grows_with_distance_as_stated():
    errors = _quiet_depth_errors(scale_log_bias=-0.05, scale_log_std=0.02, field_rel0=0.02,
                                 field_rel_per_m=0.004, grain_log_std=0.01)
    true = np.full((48, 96), 10.0, dtype=np.float32)
    true[:, 48:] = 40.0
    labels = np.zeros(true.shape, dtype=np.int16)
    rng = np.random.default_rng(7)
    logs = np.stack([np.log(estimate_depth(true, labels, true, errors, rng) / true)
                     for _ in range(400)])
    near, far = logs[:, :, :48], logs[:, :, 48:]
    # log(D_est / D) ~ N(bias, s^2 + (rel0 + rel_per_m D)^2 + grain^2)
    expected_near = np.sqrt(0.02 ** 2 + (0.02 + 0.004 * 10) ** 2 + 0.01 ** 2)  # 0.0640
    expected_far = np.sqrt(0.02 ** 2 + (0.02 + 0.004 * 40) ** 2 + 0.01 ** 2)  # 0.1814
    assert near.std() == pytest.approx(expected_near, rel=0.08)
    assert far.std() == pytest.approx(expected_far, rel=0.08)
    assert near.mean() == pytest.approx(-0.05, abs=0.01)
    assert far.mean() == pytest.approx(-0.05, abs=0.02)


def test_nominal_depth_error_is_larger_at_40_than_at_10_m():
    true = np.full((45, 80), 10.0, dtype=np.float32)
    true[:, 40:] = 40.0
    labels = np.zeros(true.shape, dtype=np.int16)
    rng = np.random.default_rng(3)
    errors = replace(CONDITIONS["nominal"].depth, artifact_rate=0.0)
    rel = np.stack([estimate_depth(true, labels, true, errors, rng, px_scale=0.05) / true - 1
                    for _ in range(200)])
    # measured away from the 10/40 m step, which the edge blur smears
    assert np.abs(rel[:, :, 30:35]).mean() * 1.5 < np.abs(rel[:, :, 45:50]).mean()


def test_fade_blends_objects_into_the_background_and_output_is_capped():
    errors = _quiet_depth_errors(fade_prob=1.0, fade_min=1.0, max_depth=50.0)
    true = np.full((20, 30), 60.0, dtype=np.float32)  # beyond max_depth
    true[5:10, 5:10] = 4.0
    true[0, :] = np.inf  # sky
    labels = np.zeros(true.shape, dtype=np.int16)
    labels[5:10, 5:10] = 1
    background = np.full(true.shape, 30.0, dtype=np.float32)
    est = estimate_depth(true, labels, background, errors, np.random.default_rng(0))
    np.testing.assert_allclose(est[5:10, 5:10], 30.0, rtol=1e-6)  # fully faded
    assert np.all(est[labels == 0] == 50.0)  # far road and sky read max_depth
    half = estimate_depth(true, labels, background, _quiet_depth_errors(fade_prob=1.0,
                          fade_min=0.5, max_depth=50.0), np.random.default_rng(0))
    inside = half[5:10, 5:10]
    assert np.all(inside >= np.exp(0.5 * np.log(4.0) + 0.5 * np.log(30.0)) * (1 - 1e-6))
    assert np.all(inside <= 30.0 * (1 + 1e-6))


def test_without_depth_errors_sets_only_the_named_parts_to_zero():
    snow = CONDITIONS["snow"]  # every part of its depth error is on
    fields = {f for part in DEPTH_ERROR_PARTS.values() for f in part}
    assert all(getattr(snow.depth, f) != 0 for f in fields - {"scale_log_bias"})
    for part, zeroed in DEPTH_ERROR_PARTS.items():
        ablated = without_depth_errors(snow, [part])
        assert (ablated.name, ablated.detector, ablated.rare_per_scene) == ("snow", snow.detector, snow.rare_per_scene)
        for name in vars(snow.depth):
            expected = 0.0 if name in zeroed else getattr(snow.depth, name)
            assert getattr(ablated.depth, name) == expected, (part, name)
        assert ablated.description.endswith(f"depth without {part}")
    with pytest.raises(ValueError, match=r"\['glare'\].*fade, grain, blobs, blur, scale"):
        without_depth_errors(snow, ["blobs", "glare"])


def test_depth_without_any_error_is_the_true_depth_capped():
    camera = small_front_camera(0.1)
    boxes = np.array([[9.0, 0.0, 0.9, 2.0, 4.5, 1.8, 0.0], [15.0, -4.0, 0.85, 0.7, 0.7, 1.7, 1.0]])
    render = render_depth(camera, boxes)
    exact = without_depth_errors(CONDITIONS["night"], DEPTH_ERROR_PARTS)
    for seed in range(5):
        est = estimate_depth(render.depth, render.labels, render.background, exact.depth,
                             np.random.default_rng(seed), px_scale=0.1)
        np.testing.assert_array_equal(est, np.minimum(render.depth, np.float32(exact.depth.max_depth)))
    noisy = estimate_depth(render.depth, render.labels, render.background, CONDITIONS["night"].depth,
                           np.random.default_rng(0), px_scale=0.1)
    assert not np.array_equal(noisy, np.minimum(render.depth, np.float32(80.0)))


def test_benchmark_ablation_makes_its_scenes_and_prior_without_those_errors():
    exact = Benchmark(conditions=("snow",), scenes_per_condition=1, n_frames=2, prior_scenes=1,
                      depth_off=tuple(DEPTH_ERROR_PARTS))
    [scene] = exact.scenes()
    for frame in scene.frames:
        np.testing.assert_array_equal(frame.depth_est, np.minimum(frame.depth_true, np.float32(80.0)))
    true_prior = np.mean([1.0 / np.minimum(f.depth_true.astype(np.float64), 80.0)
                          for f in generate_frames("nominal", 100000, n_frames=2)], axis=0)
    np.testing.assert_allclose(exact.prior(), true_prior, rtol=1e-6)
    [scene] = Benchmark(conditions=("snow",), scenes_per_condition=1, n_frames=2, depth_off=("blobs",)).scenes()
    expected = generate_frames(without_depth_errors(CONDITIONS["snow"], ["blobs"]), scene.seed, n_frames=2)
    for got, want in zip(scene.frames, expected, strict=True):
        np.testing.assert_array_equal(got.depth_est, want.depth_est)
    with pytest.raises(ValueError, match="glare"):
        Benchmark(depth_off=("glare",))


def test_estimated_depth_is_finite_positive_and_reproducible_in_every_condition():
    camera = small_front_camera(0.1)
    boxes = np.array([[9.0, 0.0, 0.9, 2.0, 4.5, 1.8, 0.0], [15.0, -4.0, 0.85, 0.7, 0.7, 1.7, 1.0]])
    render = render_depth(camera, boxes)
    background = render_depth(camera, np.zeros((0, 7))).depth
    for name, cond in CONDITIONS.items():
        a = estimate_depth(render.depth, render.labels, background, cond.depth,
                           np.random.default_rng(11), px_scale=0.1)
        b = estimate_depth(render.depth, render.labels, background, cond.depth,
                           np.random.default_rng(11), px_scale=0.1)
        np.testing.assert_array_equal(a, b)
        assert a.dtype == np.float32 and np.all(np.isfinite(a)) and np.all(a > 0), name
        assert a.max() <= cond.depth.max_depth


def test_error_models_reject_bad_input():
    errors = CONDITIONS["nominal"].depth
    good = np.full((4, 5), 10.0, dtype=np.float32)
    labels = np.zeros((4, 5), dtype=np.int16)
    rng = np.random.default_rng(0)
    bad = good.copy()
    bad[1, 1] = np.nan
    with pytest.raises(ValueError, match="depth_true has values that are not > 0"):
        estimate_depth(bad, labels, good, errors, rng)
    with pytest.raises(ValueError, match="expected the same"):
        estimate_depth(good, labels[:3], good, errors, rng)
    with pytest.raises(ValueError, match="labels has dtype int64, expected int16"):
        estimate_depth(good, labels.astype(np.int64), good, errors, rng)
    camera = small_front_camera(0.05)
    boxes, classes = _cars_at([10.0], camera)
    with pytest.raises(ValueError, match=r"gt_classes has \['unicorn'\]"):
        detect(camera, boxes, np.array(["unicorn"]), np.ones(1), np.ones(1), _detector(), rng)
    with pytest.raises(ValueError, match="one per box"):
        detect(camera, boxes, classes, np.ones(2), np.ones(1), _detector(), rng)


def _detector(**changes) -> DetectorErrors:
    return replace(CONDITIONS["nominal"].detector, **changes)


def _cars_at(distances, camera, cls="car"):
    origin = camera.cam_to_ego[:3, 3]
    n = len(distances)
    boxes = np.zeros((n, 7))
    boxes[:, 0] = origin[0] + np.asarray(distances)
    boxes[:, 1] = origin[1]
    boxes[:, 2] = origin[2]  # centre level with the camera: distance exactly d
    boxes[:, 3:6] = ACTOR_CLASSES[cls].size
    return boxes, np.full(n, cls)


def test_detection_rate_follows_distance_class_and_occlusion():
    camera = small_front_camera(0.1)
    errors = _detector(recall_max=0.9, recall_half_m=30.0, recall_slope=2.0,
                       occlusion_power=1.5, fp_per_frame=0.0)
    rng = np.random.default_rng(5)
    n = 4000
    cases = [  # class, distance, visibility, probability by hand
        ("car", 10.0, 1.0, 0.9 / (1 + (10 / 30) ** 2)),                    # 0.81
        ("car", 40.0, 1.0, 0.9 / (1 + (40 / 30) ** 2)),                    # 0.324
        ("car", 10.0, 0.25, 0.9 * 0.25 ** 1.5 / (1 + (10 / 30) ** 2)),     # 0.10125
        ("animal", 10.0, 1.0, 0.9 * 0.15 / (1 + (10 / 30) ** 2)),          # 0.1215
    ]
    for cls, d, vis, p in cases:
        boxes, classes = _cars_at(np.full(n, d), camera, cls)
        out = detect(camera, boxes, classes, np.full(n, vis), np.full(n, 10 ** 6), errors, rng)
        rate = np.unique(out.source).size / n
        assert rate == pytest.approx(p, abs=4 * np.sqrt(p * (1 - p) / n)), (cls, d, vis)
        np.testing.assert_allclose(
            detection_probability(errors, classes[:1], np.array([d]), np.array([vis])), p)
        if cls == "animal":
            assert set(out.classes.tolist()) <= {"pedestrian", "barrier"}
    boxes, classes = _cars_at(np.full(50, 5.0), camera)
    few_pixels = np.full(50, errors.min_visible_px * 0.1 ** 2 - 1)
    out = detect(camera, boxes, classes, np.ones(50), few_pixels, errors, rng)
    assert out.source.size == 0


def test_detection_depth_error_grows_with_distance_as_stated():
    camera = small_front_camera(0.1)
    errors = _detector(recall_max=1.0, recall_half_m=1e4, lateral_rad=0.0, depth_bias=0.02,
                       depth_rel0=0.03, depth_rel_per_m=0.004, fp_per_frame=0.0)
    rng = np.random.default_rng(9)
    origin = camera.cam_to_ego[:3, 3]
    for d, sigma in ((10.0, 0.03 + 0.004 * 10), (40.0, 0.03 + 0.004 * 40)):
        boxes, classes = _cars_at(np.full(3000, d), camera)
        out = detect(camera, boxes, classes, np.ones(3000), np.full(3000, 10 ** 6), errors, rng)
        assert out.source.size == 3000
        log_ratio = np.log(np.linalg.norm(out.boxes3d[:, :3] - origin, axis=1) / d)
        assert log_ratio.std() == pytest.approx(sigma, rel=0.06)
        assert log_ratio.mean() == pytest.approx(0.02, abs=4 * sigma / np.sqrt(3000))
        # moved along the viewing ray only
        np.testing.assert_allclose(out.boxes3d[:, 1:3], boxes[:, 1:3], atol=1e-9)
        assert np.all(np.diff(out.scores) <= 0)  # sorted by decreasing score


def test_sizes_yaw_and_false_positives_have_the_stated_spread():
    camera = small_front_camera(0.1)
    errors = _detector(recall_max=1.0, recall_half_m=1e4, size_log_std=0.1, yaw_std=0.05,
                       yaw_flip_prob=0.2, confusion_prob=0.0, fp_per_frame=3.0)
    n = 3000
    boxes, classes = _cars_at(np.full(n, 15.0), camera)
    out = detect(camera, boxes, classes, np.ones(n), np.full(n, 10 ** 6),
                 errors, np.random.default_rng(2))
    tp = out.source >= 0
    assert np.log(out.boxes3d[tp, 3:6] / boxes[0, 3:6]).std(axis=0) == pytest.approx(
        [0.1, 0.1, 0.1], rel=0.07)
    flipped = np.abs(out.boxes3d[tp, 6]) > np.pi / 2
    assert flipped.mean() == pytest.approx(0.2, abs=0.03)
    assert np.all(out.classes[tp] == "car")
    fps = [np.count_nonzero(detect(camera, boxes[:0], classes[:0], np.zeros(0), np.zeros(0),
                                   errors, np.random.default_rng(s)).source == -1)
           for s in range(400)]
    assert np.mean(fps) == pytest.approx(3.0, abs=4 * np.sqrt(3.0 / 400))
    assert np.all((out.scores > 0) & (out.scores < 1))


# --------------------------------------------------------------------------- conditions

def test_conditions_table_shows_the_papers_findings():
    nominal = CONDITIONS["nominal"]
    assert list(CONDITIONS) == ["nominal", "rare", "noise", "rain", "snow", "night"]
    for name in ("noise", "snow"):  # Table II: the detector falls below the depth pipeline
        cond = CONDITIONS[name]
        assert cond.detector.recall_max <= 0.6 * nominal.detector.recall_max
        assert cond.detector.fp_per_frame > nominal.detector.fp_per_frame
    night = CONDITIONS["night"]  # Table III: the depth network loses objects at night
    assert night.depth.fade_prob >= 5 * nominal.depth.fade_prob
    assert night.detector.recall_max > CONDITIONS["noise"].detector.recall_max
    assert CONDITIONS["rare"].rare_per_scene >= 10 * nominal.rare_per_scene
    for cls in ("animal", "wheelchair", "debris"):
        assert DETECTOR_CLASSES[cls].recall_factor <= 0.3
    assert set(DETECTOR_CLASSES) == set(ACTOR_CLASSES)


def test_condition_lookup_and_validation():
    assert get_condition("night") is CONDITIONS["night"]
    with pytest.raises(ValueError, match="condition = 'fog', expected one of nominal, rare"):
        get_condition("fog")
    with pytest.raises(ValueError, match=r"DepthErrors.fade_prob = 1.5, must be .* \[0, 1\]"):
        replace(CONDITIONS["night"].depth, fade_prob=1.5)
    with pytest.raises(ValueError, match=r"DetectorErrors.recall_max = nan"):
        replace(CONDITIONS["nominal"].detector, recall_max=float("nan"))
    with pytest.raises(ValueError, match="artifact_px"):
        replace(CONDITIONS["nominal"].depth, artifact_px=(20.0, 5.0))


# --------------------------------------------------------------------------- whole scenes

def test_same_seed_same_scene_and_same_traffic_across_conditions():
    camera = small_front_camera(0.05)
    a = generate_scene("night", seed=4, n_frames=3, camera=camera)
    b = generate_scene("night", seed=4, n_frames=3, camera=camera)
    fields = ("depth_est", "depth_true", "labels", "gt_boxes3d", "gt_classes", "gt_ids",
              "gt_visibility", "det_boxes3d", "det_classes", "det_scores")
    for fa, fb in zip(a.frames, b.frames):
        for name in fields:
            np.testing.assert_array_equal(getattr(fa, name), getattr(fb, name), err_msg=name)
    other = generate_scene("night", seed=5, n_frames=3, camera=camera)
    assert not np.array_equal(other.frames[0].depth_est, a.frames[0].depth_est)
    snow = generate_scene("snow", seed=4, n_frames=3, camera=camera)
    for fa, fs in zip(a.frames, snow.frames):  # same rare rate: the same ground truth
        np.testing.assert_array_equal(fa.gt_boxes3d, fs.gt_boxes3d)
        np.testing.assert_array_equal(fa.depth_true, fs.depth_true)
    assert not np.array_equal(a.frames[0].depth_est, snow.frames[0].depth_est)
    mixed = replace(CONDITIONS["night"], depth=CONDITIONS["snow"].depth)
    for fa, fs, fm in zip(a.frames, snow.frames, generate_frames(mixed, 4, n_frames=3,
                                                                camera=camera)):
        np.testing.assert_array_equal(fm.depth_est, fs.depth_est)  # snow's depth errors
        np.testing.assert_array_equal(fm.det_boxes3d, fa.det_boxes3d)  # night's detector
        np.testing.assert_array_equal(fm.det_scores, fa.det_scores)


def test_generated_frames_are_consistent():
    camera = small_front_camera(0.1)
    scene = generate_scene("rare", seed=2, n_frames=4, frame_interval=0.5, camera=camera)
    assert scene.synthetic and scene.condition == "rare" and scene.seed == 2
    assert [f.timestamp for f in scene.frames] == [0.0, 0.5, 1.0, 1.5]
    for frame in scene.frames:
        labels = frame.labels
        assert set(np.unique(labels[labels <= 0]).tolist()) <= {
            LABEL_SKY, LABEL_ROAD, LABEL_MARKING, LABEL_SIDEWALK, LABEL_STRUCTURE}
        assert {LABEL_ROAD, LABEL_MARKING, LABEL_SIDEWALK, LABEL_STRUCTURE} <= set(np.unique(labels).tolist())
        assert labels.max() <= frame.gt_ids.size
        np.testing.assert_array_equal(np.isinf(frame.depth_true), labels == LABEL_SKY)
        assert np.all(np.isfinite(frame.depth_est)) and np.all(frame.depth_est > 0)
        visible = np.unique(labels[labels > 0]) - 1
        assert np.all(frame.gt_visibility[visible] > 0)
        hidden = np.setdiff1d(np.arange(frame.gt_ids.size), visible)
        assert np.all(frame.gt_visibility[hidden] == 0)
        assert set(frame.det_classes.tolist()) <= {
            "car", "truck", "bus", "trailer", "construction_vehicle", "pedestrian",
            "motorcycle", "bicycle", "traffic_cone", "barrier"}
    a, b = (scene.frames[0].gt_boxes3d, scene.frames[1].gt_boxes3d)
    assert not np.array_equal(a, b)  # things move


def test_generate_frames_checks_arguments_at_once():
    with pytest.raises(ValueError, match="seed = -1"):
        generate_frames("nominal", -1)
    with pytest.raises(ValueError, match="n_frames = 0"):
        generate_frames("nominal", 0, n_frames=0)
    with pytest.raises(ValueError, match="frame_interval = 0"):
        generate_frames("nominal", 0, frame_interval=0)
    with pytest.raises(ValueError, match="condition = 'dusk'"):
        generate_frames("dusk", 0)


def test_shade_draws_classes_and_sky():
    camera = small_front_camera(0.1)
    frame = next(generate_frames("nominal", seed=1, n_frames=1, camera=camera))
    picture = shade(frame)
    assert picture.shape == (camera.height, camera.width, 3) and picture.dtype == np.uint8
    sky = frame.labels == LABEL_SKY
    assert np.all(picture[sky][:, 2] > picture[sky][:, 0])  # blue sky
    marking, road = frame.labels == LABEL_MARKING, frame.labels == LABEL_ROAD
    assert picture[marking].mean() > picture[road].mean() + 50
