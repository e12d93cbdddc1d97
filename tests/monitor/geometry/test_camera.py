"""Tests for monitor.geometry.camera: quaternions, poses, 3D boxes, the camera, projection."""
import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import linprog

from monitor.geometry.boxes3d import (as_boxes3d, box_corners, boxes3d_from_quaternions, footprints,
                                      transform_boxes)
from monitor.geometry.camera import Camera, MIN_EXTENT_PX, project_boxes
from monitor.geometry.poses import (invert_pose, pose_matrix, quaternion_to_rotation, transform_points, yaw_from_quaternion)

FX = 1266.417203046554
CX, CY = 816.2670197447984, 491.50706579294757

# the ideal front camera: camera z -> ego x, camera x -> ego -y, camera y -> ego -z
IDEAL_Q = [0.5, -0.5, 0.5, -0.5]


def ideal_front(translation=(1.5, 0.0, 1.5)):
    return Camera.from_nuscenes([[FX, 0, CX], [0, FX, CY], [0, 0, 1]], IDEAL_Q, translation)


def simple_camera(cx=100.0, cy=50.0, near=0.1):
    """Camera frame = ego frame (identity pose): 3D boxes are given in camera coordinates
    and their yaw turns them about the optical axis. fx = fy = 100, image 200 x 100."""
    return Camera(np.array([[100.0, 0, cx], [0, 100.0, cy], [0, 0, 1]]), 200, 100, np.eye(4),
                  near)


def yaw_quaternion(theta):
    return [math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2)]


# ------------------------------------------------------------ quaternions and poses


def test_rotation_of_a_yaw_quaternion_by_hand():
    c, s = math.cos(0.5), math.sin(0.5)
    np.testing.assert_allclose(quaternion_to_rotation(yaw_quaternion(0.5)),
                               [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-15)
    assert yaw_from_quaternion(yaw_quaternion(0.5)) == pytest.approx(0.5)
    assert yaw_from_quaternion(-np.array(yaw_quaternion(0.5))) == pytest.approx(0.5)


def test_rotation_of_the_ideal_camera_quaternion_by_hand():
    # w = .5, x = -.5, y = .5, z = -.5:
    # R00 = 1 - 2(y2 + z2) = 0, R01 = 2(xy - wz) = 0, R02 = 2(xz + wy) = 1
    # R10 = 2(xy + wz) = -1, R11 = 1 - 2(x2 + z2) = 0, R12 = 2(yz - wx) = 0
    # R20 = 2(xz - wy) = 0, R21 = 2(yz + wx) = -1, R22 = 1 - 2(x2 + y2) = 0
    np.testing.assert_allclose(quaternion_to_rotation(IDEAL_Q),
                               [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], atol=1e-15)


def test_quaternions_batch_and_tolerance():
    qs = np.array([yaw_quaternion(0.1), yaw_quaternion(-2.0), IDEAL_Q])
    assert quaternion_to_rotation(qs).shape == (3, 3, 3)
    np.testing.assert_allclose(yaw_from_quaternion(qs)[:2], [0.1, -2.0])
    # a slightly denormalised quaternion is normalised; a wrong one is an error
    q = np.array(yaw_quaternion(0.3)) * (1 + 5e-4)
    assert yaw_from_quaternion(q) == pytest.approx(0.3)
    with pytest.raises(ValueError, match=r"q_wxyz has norm 2.0, expected a unit quaternion"):
        yaw_from_quaternion([2.0, 0, 0, 0])
    with pytest.raises(ValueError, match=r"q_wxyz\[1\] has norm 0.0"):
        quaternion_to_rotation([[1.0, 0, 0, 0], [0.0, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"q_wxyz has shape \(3,\)"):
        quaternion_to_rotation([1.0, 0, 0])


def test_pose_and_inverse_by_hand():
    # 90 degrees about z, then + (10, 0, 0): (1, 0, 0) -> (0, 1, 0) + (10, 0, 0)
    T = pose_matrix(yaw_quaternion(math.pi / 2), [10.0, 0.0, 0.0])
    np.testing.assert_allclose(transform_points([[1.0, 0.0, 0.0]], T), [[10.0, 1.0, 0.0]],
                               atol=1e-12)
    np.testing.assert_allclose(transform_points([[10.0, 1.0, 0.0]], invert_pose(T)),
                               [[1.0, 0.0, 0.0]], atol=1e-12)
    np.testing.assert_allclose(invert_pose(T) @ T, np.eye(4), atol=1e-12)


@pytest.mark.parametrize("T, message", [
    (np.eye(3), r"T has shape \(3, 3\)"),
    (np.diag([1.0, 1.0, 2.0, 1.0]), r"T\[:3, :3\] is not a rotation"),
    (np.diag([1.0, 1.0, -1.0, 1.0]), r"not a rotation"),  # a reflection
    (np.vstack([np.eye(4)[:3], [0, 0, 1, 1]]), r"T has last row"),
    (np.full((4, 4), np.nan), r"T\[0, 0\] = nan: must be finite"),
])
def test_bad_poses_are_rejected(T, message):
    with pytest.raises(ValueError, match=message):
        invert_pose(T)


# ---------------------------------------------------------------------- 3D boxes


def test_box_corners_by_hand():
    # centre (1, 2, 3), w = 2, l = 4, h = 6, yaw 90 degrees:
    # heading (0, 1, 0) * l/2 = (0, 2, 0); lateral (-1, 0, 0) * w/2 = (-1, 0, 0); up (0, 0, 3)
    # corner 0 = c + heading + lateral + up = (0, 4, 6), corner 1 = c + heading - lateral + up
    corners = box_corners([[1, 2, 3, 2, 4, 6, math.pi / 2]])
    expected = [[0, 4, 6], [2, 4, 6], [2, 4, 0], [0, 4, 0],
                [0, 0, 6], [2, 0, 6], [2, 0, 0], [0, 0, 0]]
    np.testing.assert_allclose(corners[0], expected, atol=1e-12)
    assert box_corners(np.empty((0, 7))).shape == (0, 8, 3)


def test_footprints_against_the_corners():
    # a car ahead along x (l 4, w 2), the same turned 90 degrees, one at 30 degrees: the
    # footprint is the ground rectangle's extent, the min x and the y span of its corners
    boxes = as_boxes3d([[10, 0, 0.8, 2, 4, 1.6, 0], [10, 3, 0.8, 2, 4, 1.6, math.pi / 2],
                        [20, -1, 0.8, 2, 4, 1.6, math.radians(30)]])
    corners = box_corners(boxes)
    expected = np.column_stack([corners[:, :, 0].min(axis=1), corners[:, :, 1].min(axis=1),
                                corners[:, :, 1].max(axis=1)])
    np.testing.assert_allclose(footprints(boxes), expected, atol=1e-12)
    np.testing.assert_allclose(footprints(boxes)[:2], [[8, -1, 1], [9, 1, 5]], atol=1e-12)  # by hand
    assert footprints(np.empty((0, 7))).shape == (0, 3)


@pytest.mark.parametrize("boxes, message", [
    (np.zeros((2, 6)), r"boxes3d has shape \(2, 6\), expected \(n, 7\)"),
    ([[0, 0, 0, 1, 0, 1, 0]], r"boxes3d\[0, 4\] \(l\) = 0.0: box sizes must be > 0"),
    ([[0, 0, 0, 1, 1, -1, 0]], r"boxes3d\[0, 5\] \(h\)"),
    ([[0, 0, 0, 1, 1, 1, np.nan]], r"boxes3d\[0, 6\] = nan: must be finite"),
    ([["x"] * 7], r"boxes3d has dtype <U1"),
])
def test_bad_3d_boxes_are_rejected(boxes, message):
    with pytest.raises(ValueError, match=message):
        as_boxes3d(boxes)


def test_boxes_from_nuscenes_records():
    b = boxes3d_from_quaternions([[1, 2, 3]], [[1.8, 4.5, 1.6]], [yaw_quaternion(0.7)])
    np.testing.assert_allclose(b, [[1, 2, 3, 1.8, 4.5, 1.6, 0.7]])
    assert boxes3d_from_quaternions(np.empty((0, 3)), np.empty((0, 3)),
                                    np.empty((0, 4))).shape == (0, 7)
    with pytest.raises(ValueError, match="centres, sizes_wlh and rotations_wxyz have 1, 2"):
        boxes3d_from_quaternions([[1, 2, 3]], [[1, 1, 1]] * 2, [[1, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"rotations_wxyz\[0\] has norm 3.0"):
        boxes3d_from_quaternions([[1, 2, 3]], [[1, 1, 1]], [[3, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"sizes_wlh\[0, 1\] \(l\) = 0.0: .*> 0"):
        boxes3d_from_quaternions([[1, 2, 3]], [[1, 0, 1]], [[1, 0, 0, 0]])


def test_global_to_ego_by_hand():
    # ego at global (100, 200, 0) heading 30 degrees; a box 10 m straight ahead of it,
    # parallel to it, 1 m up: in the ego frame it is at (10, 0, 1) with yaw 0
    yaw = math.radians(30)
    ego_to_global = pose_matrix(yaw_quaternion(yaw), [100.0, 200.0, 0.0])
    box_global = [[100 + 10 * math.cos(yaw), 200 + 10 * math.sin(yaw), 1.0, 2, 4, 1.5, yaw]]
    box_ego = transform_boxes(box_global, invert_pose(ego_to_global))
    np.testing.assert_allclose(box_ego, [[10, 0, 1, 2, 4, 1.5, 0]], atol=1e-12)
    back = transform_boxes(box_ego, ego_to_global)
    np.testing.assert_allclose(back, box_global, atol=1e-12)


def test_transform_that_tilts_up_is_rejected():
    tilt = pose_matrix([math.cos(0.5), math.sin(0.5), 0, 0], [0, 0, 0])  # 57 deg about x
    with pytest.raises(ValueError, match=r"T\[2, 2\] = .*tilts the up axis"):
        transform_boxes([[0, 0, 0, 1, 1, 1, 0]], tilt)


# ------------------------------------------------------------------------ camera


def test_nuscenes_front_camera_geometry():
    cam = Camera.nuscenes_front()
    assert (cam.width, cam.height, cam.near) == (1600, 900, 0.1)
    np.testing.assert_array_equal(cam.K, [[FX, 0, CX], [0, FX, CY], [0, 0, 1]])
    np.testing.assert_allclose(cam.cam_to_ego[:3, 3], [1.70079118954, 0.0159456324149,
                                                       1.51095763913])
    R = cam.cam_to_ego[:3, :3]
    # within 0.01 of the ideal front camera: z forward, x right (-y ego), y down (-z ego)
    np.testing.assert_allclose(R, quaternion_to_rotation(IDEAL_Q), atol=0.01)
    # a point on the optical axis projects to the principal point
    np.testing.assert_allclose(cam.project([[0.0, 0.0, 10.0]]), [[CX, CY]])
    p = np.array([[10.0, -2.0, 0.5], [3.0, 4.0, 1.0]])
    np.testing.assert_allclose(cam.camera_to_ego(cam.ego_to_camera(p)), p, atol=1e-12)
    np.testing.assert_allclose(cam.ego_to_cam @ cam.cam_to_ego, np.eye(4), atol=1e-12)


def test_project_is_the_pinhole_formula():
    K = np.array([[500.0, 2.0, 320.0], [0.0, 400.0, 240.0], [0.0, 0.0, 1.0]])
    cam = Camera(K, 640, 480, np.eye(4))
    # u = (fx X + s Y) / Z + cx, v = fy Y / Z + cy
    # (1, 2, 4): u = (500 + 4) / 4 + 320 = 446, v = 800 / 4 + 240 = 440
    # (-3, 0.5, 10): u = (-1500 + 1) / 10 + 320 = 170.1, v = 200 / 10 + 240 = 260
    np.testing.assert_allclose(cam.project([[1, 2, 4], [-3, 0.5, 10]]),
                               [[446, 440], [170.1, 260]])
    with pytest.raises(ValueError, match=r"points_cam\[1\] = \[0.0, 0.0, -1.0\]: z must be > 0"):
        cam.project([[0, 0, 1], [0, 0, -1]])


@pytest.mark.parametrize("kwargs, message", [
    ({"K": np.eye(2)}, r"K = .*expected \(3, 3\) intrinsics"),
    ({"K": np.diag([100.0, 100.0, 2.0])}, r"K = "),
    ({"K": np.diag([-100.0, 100.0, 1.0])}, r"fx, fy > 0"),
    ({"width": 0}, r"width = 0, expected a positive integer"),
    ({"height": 900.0}, r"height = 900.0"),
    ({"width": True}, r"width = True"),
    ({"near": 0.0}, r"near = 0.0, expected a finite distance >= 1e-3 m"),
    ({"near": np.nan}, r"near = nan"),
    ({"cam_to_ego": 2 * np.eye(4)}, r"cam_to_ego has last row"),
])
def test_bad_cameras_are_rejected(kwargs, message):
    args = {"K": np.diag([100.0, 100.0, 1.0]), "width": 200, "height": 100,
            "cam_to_ego": np.eye(4)} | kwargs
    with pytest.raises(ValueError, match=message):
        Camera(**args)


def test_camera_is_frozen_and_its_arrays_read_only():
    cam = simple_camera()
    with pytest.raises(dataclasses.FrozenInstanceError):
        cam.near = 1.0
    with pytest.raises(ValueError):
        cam.K[0, 0] = 1.0
    with pytest.raises(ValueError):
        cam.cam_to_ego[0, 3] = 1.0


# -------------------------------------------------------------------- projection


def test_box_fully_in_view_matches_the_pinhole_formula_by_hand():
    # ideal camera at ego (1.5, 0, 1.5); box centre (10, 0, 0.5), l = 4, w = 2, h = 1:
    # ego x [8, 12] -> camera Z [6.5, 10.5]; ego y [-1, 1] -> camera X [-1, 1];
    # ego z [0, 1] -> camera Y = 1.5 - z in [0.5, 1.5]
    boxes2d, kept = project_boxes([[10, 0, 0.5, 2, 4, 1, 0]], ideal_front())
    u0, u1 = CX - FX * 1 / 6.5, CX + FX * 1 / 6.5   # X = -1 and +1 at the nearest Z
    v0, v1 = CY + FX * 0.5 / 10.5, CY + FX * 1.5 / 6.5  # smallest Y far, largest Y near
    np.testing.assert_allclose(boxes2d, [[(u0 + u1) / 2, (v0 + v1) / 2, u1 - u0, v1 - v0, 6.5]])
    np.testing.assert_array_equal(kept, [0])
    # the paper's distance: closest point of the box to the ego origin is (8, 0, 0)
    boxes2d, _ = project_boxes([[10, 0, 0.5, 2, 4, 1, 0]], ideal_front(), "ego_closest")
    assert boxes2d[0, 4] == pytest.approx(8.0)


def test_boxes_in_view_match_projected_corners():
    cam = Camera.nuscenes_front()
    rng = np.random.default_rng(3)
    n = 200
    boxes = np.column_stack([rng.uniform(8, 40, n), rng.uniform(-4, 4, n), rng.uniform(0, 2, n),
                             rng.uniform(0.5, 2, (n, 3)), rng.uniform(-np.pi, np.pi, n)])
    corners = cam.ego_to_camera(box_corners(boxes).reshape(-1, 3)).reshape(n, 8, 3)
    X, Y, Z = corners[..., 0], corners[..., 1], corners[..., 2]
    u = FX * X / Z + CX  # the pinhole formula, K has no skew
    v = FX * Y / Z + CY
    inside = (Z.min(1) > 0.1) & (u.min(1) > 0) & (u.max(1) < 1600) & (v.min(1) > 0) \
        & (v.max(1) < 900)
    assert inside.sum() > 100
    boxes2d, kept = project_boxes(boxes[inside], cam)
    np.testing.assert_array_equal(kept, np.arange(inside.sum()))
    u0, u1, v0, v1 = u[inside].min(1), u[inside].max(1), v[inside].min(1), v[inside].max(1)
    expected = np.column_stack([(u0 + u1) / 2, (v0 + v1) / 2, u1 - u0, v1 - v0,
                                Z[inside].min(1)])
    np.testing.assert_allclose(boxes2d, expected, rtol=1e-10, atol=1e-8)


def test_box_straddling_the_near_plane_by_hand():
    # camera = ego frame, fx = fy = 100, (cx, cy) = (100, 50), near 0.1, 200 x 100 pixels.
    # Box X [-0.05, 0.05], Y [-0.02, 0.02], Z [-1, 1]: half of it is behind the camera.
    # Its visible part is Z in [0.1, 1]; the extent is widest at Z = 0.1:
    # u = 100 * +-0.05 / 0.1 + 100 = 50 .. 150, v = 100 * +-0.02 / 0.1 + 50 = 30 .. 70.
    # (Projecting only the four corners in front, at Z = 1, would give u = 95 .. 105.)
    boxes2d, kept = project_boxes([[0, 0, 0, 0.04, 0.1, 2, 0]], simple_camera())
    np.testing.assert_allclose(boxes2d, [[100, 50, 100, 40, 0.1]])
    np.testing.assert_array_equal(kept, [0])


def test_box_straddling_the_near_plane_and_the_image_border_by_hand():
    # same camera; box X [1, 2], Y [-0.5, 0.5], Z [-1, 3].
    # In the image: u = 100 X / Z + 100 <= 200 needs X <= Z, so the visible part starts at
    # Z = 1 (X = 1): camera depth d = 1, not the near plane's 0.1.
    # u: smallest at X = 1, Z = 3: 100 / 3 + 100 = 133.33..; largest cut at the border, 200.
    # v = 100 Y / Z + 50 with |Y| <= 0.5 <= Z / 2: from 0 (Y = -0.5, Z = 1) to 100.
    boxes2d, _ = project_boxes([[1.5, 0, 1, 1, 1, 4, 0]], simple_camera())
    u0 = 100 / 3 + 100
    np.testing.assert_allclose(boxes2d, [[(u0 + 200) / 2, 50, 200 - u0, 100, 1.0]])


def test_diagonal_box_is_clipped_as_an_outline_not_as_a_rectangle():
    # camera = ego frame with the principal point at the image corner (cx = cy = 0), so the
    # image is X >= 0, Y >= 0. A thin rod at depth Z [9.9, 10.1] turned 45 degrees about the
    # optical axis: heading (1, -1) / sqrt 2, length 5 sqrt 2, centre (0.5, 0.5); width
    # 0.2 sqrt 2, so it fills 0.8 <= X + Y <= 1.2 for |X - Y| <= 5.
    # Visible: X, Y >= 0 -> X from 0 to 1.2 (at Y = 0), the same for Y; nearest Z 9.9:
    # u = 100 X / Z in [0, 120 / 9.9]. The whole rod spans X [-2.1, 3.1]: cutting its
    # bounding rectangle at the border instead would give u up to 310 / 9.9.
    rod = [[0.5, 0.5, 10, 0.2 * math.sqrt(2), 5 * math.sqrt(2), 0.2, -math.pi / 4]]
    boxes2d, _ = project_boxes(rod, simple_camera(cx=0.0, cy=0.0))
    e = 120 / 9.9
    np.testing.assert_allclose(boxes2d, [[e / 2, e / 2, e, e, 9.9]])


def test_boxes_without_a_visible_part_are_dropped():
    cam = simple_camera(cx=0.0, cy=0.0)  # image: X >= 0, Y >= 0 (and u <= 200, v <= 100)
    boxes = [[0, 0, -5, 1, 1, 1, 0],       # wholly behind the camera
             [-3, 2, 5, 1, 1, 1, 0],       # in front, left of the image (X < 0)
             [0.5, 0.5, 0.05, 1, 1, 0.09, 0],  # in front of the camera but before near
             [-0.5, 0.5, 5, 1, 1, 1, 0],   # X [-1, 0]: touches the border u = 0 only
             [0.5, 0.5, 5, 1, 1, 1, 0]]    # visible
    boxes2d, kept = project_boxes(boxes, cam)
    np.testing.assert_array_equal(kept, [4])
    empty, none = project_boxes(np.empty((0, 7)), cam)
    assert empty.shape == (0, 5) and none.shape == (0,)


def test_visible_extent_threshold():
    # centre X = -0.5 + e, l = 1: X [-1 + e, e] at depth [4.5, 5.5]; the image is X >= 0,
    # so the visible width is 100 * e / 4.5 pixels (largest at the nearest depth)
    cam = simple_camera(cx=0.0, cy=0.0)
    e = 2 * MIN_EXTENT_PX * 4.5 / 100  # twice the threshold; e / 4: half of it
    boxes2d, kept = project_boxes([[-0.5 + e, 0.5, 5, 1, 1, 1, 0],
                                   [-0.5 + e / 4, 0.5, 5, 1, 1, 1, 0]], cam)
    np.testing.assert_array_equal(kept, [0])
    assert boxes2d[0, 2] == pytest.approx(2 * MIN_EXTENT_PX)


def test_ego_closest_distance_by_hand():
    cam = Camera.nuscenes_front()
    boxes = [[10, 3, 0.8, 2, 4, 1.6, 0],            # closest point (8, 2, 0.8) -> sqrt(68)
             [20, 0, 0.8, 2, 4, 1.6, math.pi / 2],  # turned: x [19, 21] -> 19
             [10, 4, 5, 2, 2, 2, 0]]                # above: (9, 3, 4) -> sqrt(81 + 9 + 16)
    boxes2d, kept = project_boxes(boxes, cam, distance="ego_closest")
    np.testing.assert_array_equal(kept, [0, 1, 2])
    np.testing.assert_allclose(boxes2d[:, 4], [math.sqrt(68), 19, math.sqrt(106)])
    by_depth, _ = project_boxes(boxes, cam)
    np.testing.assert_array_equal(by_depth[:, :4], boxes2d[:, :4])


def test_bad_projection_arguments():
    with pytest.raises(ValueError, match="distance = 'euclid'"):
        project_boxes(np.empty((0, 7)), simple_camera(), distance="euclid")
    with pytest.raises(ValueError, match="camera is a dict"):
        project_boxes(np.empty((0, 7)), {})


# ----------------------------------------- against the nuScenes way of clipping boxes

EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
         (0, 4), (1, 5), (2, 6), (3, 7)]


def _hull(points):
    """Convex hull, counter-clockwise (Andrew's monotone chain)."""
    pts = sorted(set(map(tuple, points)))
    if len(pts) <= 2:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def _clip(polygon, inside, cut):
    """One Sutherland-Hodgman step."""
    out = []
    for k, cur in enumerate(polygon):
        prev = polygon[k - 1]
        if inside(cur):
            if not inside(prev):
                out.append(cut(prev, cur))
            out.append(cur)
        elif inside(prev):
            out.append(cut(prev, cur))
    return out


def _cut_at(axis, value):
    def cut(a, b):
        t = (value - a[axis]) / (b[axis] - a[axis])
        return tuple(a[i] + t * (b[i] - a[i]) for i in range(2))
    return cut


def _reference_extent(box, cam):
    """nuScenes-devkit style: clip the 12 edges at the near plane, project, intersect the
    convex outline with the image; the depth by linear programming over the box."""
    corners = cam.ego_to_camera(box_corners([box])[0])
    near = cam.near
    points = [c for c in corners if c[2] >= near]
    for i, j in EDGES:
        a, b = corners[i], corners[j]
        if (a[2] - near) * (b[2] - near) < 0:
            points.append(a + (near - a[2]) / (b[2] - a[2]) * (b - a))
    if not points:
        return None
    polygon = _hull(cam.project(np.array(points)))
    for axis, value, keep_above in [(0, 0.0, True), (0, cam.width, False),
                                    (1, 0.0, True), (1, cam.height, False)]:
        def inside(p, axis=axis, value=value, keep_above=keep_above):
            return p[axis] >= value if keep_above else p[axis] <= value
        polygon = _clip(polygon, inside, _cut_at(axis, value))
        if not polygon:
            return None
    poly = np.array(polygon)
    # depth: p = centre + E s, s in [-1, 1]^3, E = half-edge vectors from the corners
    centre = corners.mean(0)
    E = np.column_stack([(corners[0] - corners[4]) / 2, (corners[0] - corners[1]) / 2,
                         (corners[0] - corners[3]) / 2])
    K, W, H = cam.K, cam.width, cam.height
    ez = np.array([0.0, 0.0, 1.0])
    A = np.array([-ez, -K[0], K[0] - W * ez, -K[1], K[1] - H * ez])  # A p <= b
    b = np.array([-near, 0.0, 0.0, 0.0, 0.0])
    lp = linprog(E[2], A_ub=A @ E, b_ub=b - A @ centre, bounds=[(-1, 1)] * 3, method="highs")
    assert lp.status == 0
    return (poly[:, 0].min(), poly[:, 0].max(), poly[:, 1].min(), poly[:, 1].max(),
            centre[2] + lp.fun)


def test_projection_matches_the_nuscenes_way_of_clipping():
    cam = Camera.nuscenes_front()
    rng = np.random.default_rng(11)
    n = 300
    boxes = np.column_stack([rng.uniform(-6, 40, n), rng.uniform(-20, 20, n),
                             rng.uniform(-1, 3, n), rng.uniform(0.3, 4, n),
                             rng.uniform(0.3, 12, n), rng.uniform(0.3, 4, n),
                             rng.uniform(-np.pi, np.pi, n)])
    boxes2d, kept = project_boxes(boxes, cam)
    row = {int(k): i for i, k in enumerate(kept)}
    n_clipped = 0
    for i, box in enumerate(boxes):
        ref = _reference_extent(box, cam)
        if ref is None or ref[1] - ref[0] < 0.01 or ref[3] - ref[2] < 0.01:
            assert i not in row or min(boxes2d[row[i], 2:4]) < 0.01
            continue
        u0, u1, v0, v1, depth = ref
        n_clipped += u0 == 0 or u1 == cam.width or v0 == 0 or v1 == cam.height
        np.testing.assert_allclose(boxes2d[row[i]],
                                   [(u0 + u1) / 2, (v0 + v1) / 2, u1 - u0, v1 - v0, depth],
                                   rtol=1e-7, atol=1e-6)
    assert len(kept) > 60 and n_clipped > 20  # the sample exercises the clipping


def test_ground_extents_of_projected_boxes_are_their_near_faces():
    camera = Camera.nuscenes_front()
    # a car 10 m ahead and one in the right lane: near faces at x = 10 - 2 = 8 m and
    # 14 - 2.25 = 11.75 m, spanning y = 0 -+ 0.9 and -3.5 -+ 0.95 (their bottom corners)
    boxes3d = np.array([[10.0, 0.0, 0.75, 1.8, 4.0, 1.5, 0.0], [14.0, -3.5, 0.8, 1.9, 4.5, 1.6, 0.0]])
    P, _ = project_boxes(boxes3d, camera, "camera_depth")
    extents = camera.ground_extents(P)
    np.testing.assert_allclose(extents[0], [8.0, -0.9, 0.9], atol=0.02)
    # the right-lane car's box also holds its left side, seen at a slant beyond the rear face:
    # its near x and outer edge are the rear face's (the camera sits at x = 1.70 m, so the
    # rear face is 10.05 m deep), its inner edge the far left corner's pixel (x = 16.25 m,
    # y = -2.55 m, 14.55 m deep) back-projected at the rear face's depth:
    # -2.55 * 10.05 / 14.55 = -1.76 m, nearer the path than the car is
    np.testing.assert_allclose(extents[1], [11.75, -4.45, -2.55 * 10.05 / 14.55], atol=0.05)
    assert camera.ground_extents(np.zeros((0, 5))).shape == (0, 3)
