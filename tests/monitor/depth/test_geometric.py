"""The geometric depth view: analytic scenes ray-cast exactly, kernels against NumPy, errors.

Scenes are rendered with :func:`monitor.synthetic.raycast.render_depth` (a flat road and
oriented boxes) through nuScenes' CAM_FRONT; the sky (inf) reads 80 m, as a saturated
monocular network reads it. An object's truth is its visible extent in the label map (the
pixels where it is the nearest hit) and the nearest camera depth of those pixels.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import ndimage

from monitor.depth import _geometric_kernels as kernels
from monitor.depth.geometric import (
    BlindViewError, CORRIDOR_STEP_M, EMERGED_MARGIN, GeometricParams, GeometricRetriever, warmup,
)
from monitor.geometry.boxes import iou
from monitor.geometry.camera import Camera
from monitor.geometry.corridor import Corridor
from monitor.synthetic.raycast import render_depth

_SKY = 80.0
CAMERA = Camera.nuscenes_front()

# x, y, z, w, l, h, yaw (ego frame, metres): z is the box centre, so z = h / 2 stands on the road
CAR_AHEAD = [16.0, 0.2, 0.865, 1.95, 4.6, 1.73, 0.0]        # rear face at x = 13.7
PEDESTRIAN = [9.0, -1.0, 0.885, 0.67, 0.73, 1.77, 0.0]      # in the corridor's right half
WALL = [15.0, 6.5, 2.0, 0.4, 30.0, 4.0, 0.0]                # beside the road, left
POLE = [8.0, -5.5, 2.0, 0.2, 0.2, 4.0, 0.0]                 # on the sidewalk, right
CAR_NEXT_LANE = [14.0, -3.5, 0.865, 1.95, 4.6, 1.73, 0.0]   # the lane to the right
#: the ego lane alone (the default corridor, 3.5 m either side, holds half of each neighbour)
EGO_LANE = GeometricParams(corridor_half_width=1.75)


@pytest.fixture(scope="module", autouse=True)
def compiled():
    warmup()


def _render(boxes, camera=CAMERA):
    render = render_depth(camera, np.array(boxes, dtype=np.float64).reshape(-1, 7))
    return np.minimum(render.depth, np.float32(_SKY)), render.labels


def _truth(labels, depth, k):
    """Visible extent ``cx, cy, w, h`` and nearest depth of box k (pixel i spans [i, i + 1))."""
    rows, cols = np.nonzero(labels == k + 1)
    x0, x1, y0, y1 = cols.min(), cols.max() + 1, rows.min(), rows.max() + 1
    return np.array([(x0 + x1) / 2, (y0 + y1) / 2, x1 - x0, y1 - y0,
                     float(depth[labels == k + 1].min())])


def _match(found, truth):
    """The found box with the largest IoU with ``truth``, and that IoU."""
    scores = np.array([iou(f, truth) for f in found])
    best = int(np.argmax(scores))
    return found[best], scores[best]


def _pitched(camera, degrees):
    """``camera`` with its mounting pitched nose-down by ``degrees`` about the ego y axis
    through the camera centre (the world as seen from a car on a grade change)."""
    a = math.radians(degrees)
    R = np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0],
                  [-math.sin(a), 0.0, math.cos(a)]])  # +a turns +x (forward) towards -z
    T = camera.cam_to_ego.copy()
    T[:3, :3] = R @ T[:3, :3]
    return Camera(camera.K, camera.width, camera.height, T)


# --------------------------------------------------------------------------- analytic scenes

def test_objects_in_the_corridor_are_found_wall_pole_and_next_lane_are_not():
    boxes = [CAR_AHEAD, PEDESTRIAN, WALL, POLE, CAR_NEXT_LANE]
    depth, labels = _render(boxes)
    view = GeometricRetriever(CAMERA, EGO_LANE).view(depth)
    assert view.ground_fitted and view.valid_fraction == 1.0
    np.testing.assert_allclose(view.ground, [0.0, 0.0, 0.0], atol=5e-3)  # the road is z = 0
    assert view.boxes.shape == (2, 5)  # the pedestrian and the car ahead, nothing else
    for k in (1, 0):  # nearest first
        truth = _truth(labels, depth, k)
        found, score = _match(view.boxes, truth)
        # the blocks lose the bottom 0.2 m (the height band) and up to a block (4 px) per side
        assert score > 0.8
        # fronto-parallel faces: every block of the object reads its one depth
        assert found[4] == pytest.approx(truth[4], rel=1e-3)
    # the pedestrian's front face is at x = 9 - 0.73 / 2 = 8.635 m
    assert view.free_distance == pytest.approx(8.635, abs=0.01)
    assert view.boxes[0, 4] < view.boxes[1, 4]
    # where they stand, from their blocks: the pedestrian's face at x = 8.635 m spans
    # y = -1 -+ 0.335, the car's rear face at x = 13.7 m spans y = 0.2 -+ 0.975; the 5th and
    # 95th percentiles of the blocks' y lie within a block's width (4 px: 0.03 m at 8.6 m,
    # 0.04 m at 13.7 m) plus 5 % of the span inside the true edges
    pedestrian, car = view.extents
    assert pedestrian[0] == pytest.approx(8.635, abs=0.01) and car[0] == pytest.approx(13.7, abs=0.02)
    for (x, lo, hi), (y, half) in zip((pedestrian, car), ((-1.0, 0.335), (0.2, 0.975))):
        assert y - half <= lo <= y - half + 0.05 * 2 * half + 0.05
        assert y + half - 0.05 * 2 * half - 0.05 <= hi <= y + half


def test_a_ledge_along_the_road_is_no_object_low_debris_is_one():
    # a kerb-like ledge 0.24 m tall, 0.3 m wide and 8 m long along the lane's right edge (a
    # kerb as the depth lifts it; its top reads 0.25 m: a block across its top edge takes
    # the ledge's depth at the block's centre, a little above it), a block of debris as low
    # and as narrow (top 0.26 m, 0.32 m across) but no longer than it is wide, and debris
    # 0.6 m wide and 0.3 m tall ahead in the lane
    ledge = [12.0, -1.6, 0.12, 0.3, 8.0, 0.24, 0.0]
    block = [9.0, 0.0, 0.125, 0.35, 0.35, 0.25, 0.0]
    debris = [13.0, 0.9, 0.15, 0.6, 0.6, 0.3, 0.0]
    depth, labels = _render([ledge, block, debris])
    view = GeometricRetriever(CAMERA, EGO_LANE).view(depth)
    assert view.boxes.shape == (2, 5)
    for k in (1, 2):  # the block and the debris: the parts of them in the height band
        assert max(_inside(box, _truth(labels, depth, k)) for box in view.boxes) > 0.8
    off = GeometricRetriever(CAMERA, replace(EGO_LANE, ledge_height=None)).view(depth)
    assert off.boxes.shape == (3, 5)  # without the rule the ledge is an object too
    assert max(_inside(box, _truth(labels, depth, 0)) for box in off.boxes) > 0.8


# a street's structure and its traffic beside the lane, for a corridor wide enough to hold both
BUILDING = [15.0, 6.5, 4.0, 0.4, 30.0, 8.0, 0.0]            # 8 m frontage, left: face at y = 6.3
TALL_POLE = [12.0, -5.5, 3.0, 0.2, 0.2, 6.0, 0.0]           # 6 m pole on the right sidewalk
PARKED_CAR = [12.0, -4.5, 0.865, 1.95, 4.6, 1.73, 0.0]      # on the right shoulder
CAR_BY_WALL = [18.0, 4.9, 0.865, 1.95, 4.6, 1.73, 0.0]      # left side at y = 5.875, 0.425 m off the face
WIDE = dict(corridor_half_width=8.0)


def _inside(box, truth):
    """Share of ``box``'s area inside ``truth`` (a tall thing's band part is a small box in it)."""
    w = min(box[0] + box[2] / 2, truth[0] + truth[2] / 2) - max(box[0] - box[2] / 2, truth[0] - truth[2] / 2)
    h = min(box[1] + box[3] / 2, truth[1] + truth[3] / 2) - max(box[1] - box[3] / 2, truth[1] - truth[3] / 2)
    return max(w, 0.0) * max(h, 0.0) / (box[2] * box[3])


def test_what_rises_above_structure_height_is_taken_out_and_the_traffic_beside_it_kept():
    boxes = [CAR_AHEAD, PEDESTRIAN, PARKED_CAR, CAR_BY_WALL, BUILDING, TALL_POLE]
    depth, labels = _render(boxes)
    truths = [_truth(labels, depth, k) for k in range(len(boxes))]

    def view(**params):
        return GeometricRetriever(CAMERA, GeometricParams(**WIDE, **params)).view(depth).boxes

    def found(S):
        return [k for k in range(len(boxes)) if any(_inside(b, truths[k]) > 0.8 for b in S)]

    plain, ruled = view(structure_height=None), view(structure_height=3.5)
    # the wide corridor alone takes the structure in with the traffic, and the car by the
    # wall is part of the building's object (one cell apart on the ground)
    assert found(plain) == [0, 1, 2, 4, 5]
    # the building and the pole rise above 3.5 m: their cells go; four objects are left, one
    # per road user, the car by the wall included (its cells are its own), with their boxes
    assert len(ruled) == 4
    for k in (0, 1, 2, 3):
        found_box, score = _match(ruled, truths[k])
        assert score > 0.75 and found_box[4] == pytest.approx(truths[k][4], rel=0.01)
    # a truck 4 m tall ahead stays traffic under the default-like 4.2 m
    truck = [16.0, 0.0, 2.0, 2.5, 10.0, 4.0, 0.0]
    depth_truck, _ = _render([truck])
    assert GeometricRetriever(CAMERA, GeometricParams(structure_height=4.2))(depth_truck).shape == (1, 5)


# low on the road: the top of a box 0.3 m tall lies along the road but the box stands on it
DEBRIS = [7.0, 0.0, 0.15, 0.6, 0.6, 0.3, 0.0]
# a board 1 m tall hanging 0.5 m above the road (a trailer's raised rear): the road beneath
# it is seen, but it stands upright
RAISED_REAR = [11.0, 0.0, 1.0, 1.8, 0.2, 1.0, 0.0]


def test_a_patch_of_road_read_too_near_floats_and_is_no_object_what_stands_stays():
    road, _ = _render([])
    off = GeometricParams(max_incline=None)
    for factor in (0.5, 0.7):  # a blob 60-80 px tall, read at half or 0.7 of the road's depth
        blob = road.copy()
        blob[680:760, 700:900] *= np.float32(factor)
        # it rises 0.45-0.75 m above the road: without the rule an obstacle ...
        assert GeometricRetriever(CAMERA, off)(blob).shape == (1, 5)
        # ... with it none: its inverse depth grows down the image 1 / factor times as fast
        # as the road's, and the road beneath it is 1 / factor times farther
        assert GeometricRetriever(CAMERA)(blob).shape == (0, 5)
    # what stands on the road, or hangs upright above it, is kept as it was
    boxes = [CAR_AHEAD, PEDESTRIAN, DEBRIS, RAISED_REAR]
    depth, labels = _render(boxes)
    ruled, plain = GeometricRetriever(CAMERA)(depth), GeometricRetriever(CAMERA, off)(depth)
    np.testing.assert_array_equal(ruled, plain)
    for k in range(len(boxes)):
        assert _match(ruled, _truth(labels, depth, k))[1] > 0.3  # debris: its top 0.1 m only


def test_a_patch_whose_edge_is_smeared_into_the_road_in_places_still_floats():
    # the network smears the bottom edge of a patch read at 0.6-0.7 of the road's depth into
    # the road beneath it over part of its width: a skirt, its log depth running from the
    # patch's to the road's over 24 rows, under the first 80 or 140 of its 200 columns
    road, _ = _render([])
    for factor in (0.6, 0.7):
        for end in (780, 840):
            blob = road.copy()
            blob[680:760, 700:900] *= np.float32(factor)
            w = (np.arange(760, 784)[:, None] - 759) / 25.0
            blob[760:784, 700:end] = np.exp((1 - w) * np.log(blob[759, 700:end])
                                            + w * np.log(road[784, 700:end]))
            # the skirt touches the road: with contact asked of 0.35 of the columns it stays
            assert GeometricRetriever(CAMERA, GeometricParams(min_contact=0.35))(blob).shape == (1, 5)
            # it lies along the road and touches it in under 9 columns of 10: no object
            assert GeometricRetriever(CAMERA)(blob).shape == (0, 5)


def test_at_the_image_bottom_a_patch_read_too_near_floats_what_stands_stays():
    # the bottom row sees the road 6.3 m ahead of the ego origin (2.5 m ahead of the bumper):
    # nothing lies beneath what the bottom edge cuts, so contact cannot be told
    road, _ = _render([])
    blob = road.copy()
    blob[848:900, 700:900] *= np.float32(0.5)  # read at half the road's depth: incline 2
    off = GeometricParams(max_incline=None)
    assert GeometricRetriever(CAMERA, off)(blob).shape == (1, 5)
    assert GeometricRetriever(CAMERA)(blob).shape == (0, 5)
    # cut by the bottom edge too: a box 0.8 m tall 1.5 m ahead of the bumper (an upright face,
    # incline about 0) and debris 0.3 m tall 1.5-2.1 m ahead, of which only the top is in view
    # (it lies along the road: incline 1.5 / (1.5 - 0.3) = 1.25, under 1.5)
    for box in ([5.5, 0.0, 0.4, 0.8, 0.4, 0.8, 0.0], [5.6, 0.0, 0.15, 0.8, 0.6, 0.3, 0.0]):
        depth, labels = _render([box])
        assert (labels[-1] == 1).any()  # cut by the image's bottom edge
        ruled, plain = GeometricRetriever(CAMERA)(depth), GeometricRetriever(CAMERA, off)(depth)
        np.testing.assert_array_equal(ruled, plain)
        assert _match(ruled, _truth(labels, depth, 0))[1] > 0.5


def test_a_wide_patch_of_road_read_a_little_too_near_hides_nothing_and_is_no_object():
    road, _ = _render([])
    rows, cols = np.mgrid[0:road.shape[0], 0:road.shape[1]].astype(np.float32)
    # the smooth part of a network's error: the road read up to 25 % too near over a patch
    # some 300 x 150 px, without an edge (the road's height error is 0.25 x 1.5 m at its
    # centre, 0.2 m where the factor is 0.87)
    bump = np.exp(-0.5 * (((cols - 800) / 120) ** 2 + ((rows - 700) / 50) ** 2))
    patch = road * (1 - np.float32(0.25) * bump)
    # without the rule it is an object, and the floating test keeps it (it touches the road
    # beneath it: no edge below either) ...
    assert GeometricRetriever(CAMERA, GeometricParams(min_occlusion=None))(patch).shape == (1, 5)
    # ... with it none: above its top the road goes on at the road's depth
    assert GeometricRetriever(CAMERA)(patch).shape == (0, 5)


def test_a_flat_patch_must_hide_by_its_depth_what_stands_above_it_is_the_same_surface():
    # a network's smooth error reads the road 16 % too near over a wide patch: it lies
    # 0.24 m above the road (rows 692-780, 6.5-9.3 m ahead), rises nowhere, and farther up the
    # image the same error goes on after a gap of two block rows read 8 % too near (under
    # min_height): rows 640-684 stand 0.24 m above the road again, then fade into it
    road, _ = _render([])
    factor = np.ones(road.shape, np.float32)
    cols = slice(600, 1000)
    factor[692:780, cols] = 0.84
    factor[684:692, cols] = 0.92
    factor[640:684, cols] = 0.84
    factor[600:640, cols] = np.linspace(1.0, 0.84, 40, dtype=np.float32)[:, None]
    patch = road * factor
    # what stands right above the near part is the far part: counted as something behind it
    # when flatness is not known (rule 8 off), the near part hides something and stays ...
    assert GeometricRetriever(CAMERA, GeometricParams(min_rise=None))(patch).shape == (1, 5)
    # ... a flat object must hide by its depth, and neither part does: no object
    assert GeometricRetriever(CAMERA)(patch).shape == (0, 5)
    # debris 0.22 m tall: with min_rise 0.5 m nothing under 0.6 m rises, so it is flat too,
    # but above its top the image sees the road 1.2 times farther: it stays
    debris = [8.0, 0.0, 0.11, 0.6, 0.6, 0.22, 0.0]
    depth, labels = _render([debris])
    for params in (GeometricParams(), GeometricParams(min_rise=0.5)):
        found = GeometricRetriever(CAMERA, params)(depth)
        assert found.shape == (1, 5) and _match(found, _truth(labels, depth, 0))[1] > 0.3


def test_a_gate_arm_across_the_path_is_an_object():
    # a parking barrier's arm, 0.1 m thick and 2.5 m long, 1 m above the road, 6 or 9 m ahead:
    # flat (too thin to rise), floating (the road beneath it is farther), upright (one depth
    # down its rows), and it hides the road far behind it: every rule keeps it
    for x in (6.0, 9.0):
        arm = [x, 0.0, 1.0, 2.5, 0.1, 0.1, 0.0]
        depth, labels = _render([arm])
        view = GeometricRetriever(CAMERA).view(depth)
        assert view.boxes.shape == (1, 5) and _match(view.boxes, _truth(labels, depth, 0))[1] > 0.5
        np.testing.assert_allclose(view.extents[0], [x - 0.05, -1.25, 1.25], atol=0.15)


def test_each_object_says_how_much_of_it_stands_on_the_road():
    # a car, a pedestrian and debris meet the road along their whole width (the road right
    # beneath each column's lowest block at its depth); the raised rear and the gate arm hang
    # above it (the road beneath them 1.5 / (1.5 - 0.5) and 1.5 / (1.5 - 0.95) times farther
    # than their bottoms, both over CONTACT_RATIO 1.2); a box cut by the image's bottom edge
    # has nothing beneath it to tell
    arm = [9.0, 0.0, 1.0, 2.5, 0.1, 0.1, 0.0]
    cut = [5.5, 0.0, 0.4, 0.8, 0.4, 0.8, 0.0]
    for boxes, expected in (([CAR_AHEAD, PEDESTRIAN, DEBRIS], [1.0, 1.0, 1.0]), ([RAISED_REAR], [0.0]),
                            ([arm], [0.0]), ([cut], [np.nan])):
        depth, labels = _render(boxes)
        view = GeometricRetriever(CAMERA).view(depth)
        assert view.contact.shape == (len(view.boxes),) and view.contact.dtype == np.float64
        for k, share in enumerate(expected):
            found, score = _match(view.boxes, _truth(labels, depth, k))
            assert score > 0.3
            row = int(np.flatnonzero((view.boxes == found).all(axis=1))[0])
            np.testing.assert_equal(view.contact[row], share)
    assert GeometricRetriever(CAMERA).view(_render([])[0]).contact.shape == (0,)


def test_what_stands_hides_what_is_behind_it_and_is_kept():
    # the objects of the floating test, a wall behind a car (above its roof the image sees
    # the wall, a few metres behind), and a child 0.7 m in front of a car (above the child's
    # head the image sees the car's rear, no depth edge at 14.2 / 13.5 = 1.05 times the
    # child's camera depth, but it stands above the road)
    car_at_wall = [16.0, 0.2, 0.865, 1.95, 4.6, 1.73, 0.0]
    wall_behind = [21.0, 0.0, 2.0, 12.0, 0.4, 4.0, 0.0]
    child = [15.0, 0.2, 0.5, 0.4, 0.3, 1.0, 0.0]
    car_behind_child = [18.15, 0.2, 0.865, 1.95, 4.6, 1.73, 0.0]  # rear face at x = 15.85
    off = GeometricParams(min_occlusion=None)
    for boxes in ([CAR_AHEAD, PEDESTRIAN, DEBRIS, RAISED_REAR], [car_at_wall, wall_behind],
                  [child, car_behind_child]):
        depth, labels = _render(boxes)
        ruled, plain = GeometricRetriever(CAMERA)(depth), GeometricRetriever(CAMERA, off)(depth)
        np.testing.assert_array_equal(ruled, plain)
        assert _match(ruled, _truth(labels, depth, 0))[1] > 0.3


def test_where_an_object_stands_is_where_it_rises():
    # a car beside the path (its near side at y = -2.03 m, its rear 10 m ahead of the ego
    # origin) and, beside it towards the path, a patch of road 12-14 m ahead read 20 % too
    # near: it lies 0.3 m above the road at 9.6-11.2 m, next to the car on the grid, which
    # groups the two. The patch would bring the car into the path (y up to -0.86 m); where
    # the car stands is where it rises, as on the clean frame
    car = [12.3, -3.0, 0.865, 1.95, 4.6, 1.73, 0.0]
    depth, labels = _render([car])
    rows, cols = np.mgrid[0:depth.shape[0], 0:depth.shape[1]] + 0.5
    rays = np.linalg.inv(CAMERA.K) @ np.stack([cols.ravel(), rows.ravel(), np.ones(rows.size)])
    ego = CAMERA.cam_to_ego[:3, :3] @ (rays * depth.ravel()) + CAMERA.cam_to_ego[:3, 3:4]
    x, y = (a.reshape(depth.shape) for a in ego[:2])
    patch = (labels == 0) & (x > 12.0) & (x < 14.0) & (y > -2.6) & (y < 0.3)
    read = depth.copy()
    read[patch] *= np.float32(0.8)
    clean = GeometricRetriever(CAMERA).view(depth)
    grouped = GeometricRetriever(CAMERA).view(read)
    plain = GeometricRetriever(CAMERA, GeometricParams(min_rise=None)).view(read)
    assert clean.extents.shape == grouped.extents.shape == plain.extents.shape == (1, 3)
    assert grouped.boxes[0, 2] > 1.5 * clean.boxes[0, 2]  # one object, the patch's pixels in its box
    assert plain.extents[0, 2] > -1.0  # without the rule: into the path
    np.testing.assert_allclose(grouped.extents, clean.extents, atol=0.05)
    assert clean.extents[0, 0] == pytest.approx(10.0, abs=0.1)
    assert clean.extents[0, 2] == pytest.approx(-3.0 + 1.95 / 2, abs=0.05)
    # what rises nowhere keeps the extents of all its blocks: the floating blob of the test
    # above, without the rules that drop it
    road, _ = _render([])
    blob = road.copy()
    blob[680:760, 700:900] *= np.float32(0.5)
    off = GeometricParams(max_incline=None, min_occlusion=None)
    flat = GeometricRetriever(CAMERA, off).view(blob)
    assert flat.extents.shape == (1, 3)  # one object, 0.75 m above the road, that rises nowhere
    np.testing.assert_array_equal(flat.extents,
                                  GeometricRetriever(CAMERA, replace(off, min_rise=None)).view(blob).extents)


def test_occlusion_by_hand():
    rows, cols, stride = 8, 5, 4
    q0, qu, qv = -0.05, 0.0, 0.01   # the road's inverse depth 0.01 / m more per pixel down
    v = (np.arange(rows) + 0.5) * stride
    road = (1.0 / (q0 + qv * v)).astype(np.float32)  # q per row: -0.03, 0.01, 0.05, ... 0.21
    labels = np.full((rows, cols), -1, np.int32)
    labels[5:7, :] = 0                         # one component, rows 5-6, in every column
    ds = np.tile(road[:, None], (1, cols))
    ds[0] = 80.0                               # the sky, above the horizon
    xs = np.ones((rows, cols), np.float32)
    ys = np.zeros((rows, cols), np.float32)
    zs = np.zeros((rows, cols), np.float32)    # on the plane z = 0 unless said
    ds[5:7, :] = 6.0                           # the road at row 5 is 1 / 0.17 = 5.9 m away
    # column 0: above it the road at the road's depths (7.7, 11.1, 20 m): hides nothing
    # column 1: what is above is farther than the road would be, but by less than 1.1 x:
    # the road's depth ratios from row 5 to rows 4 and 2 are 0.17 / 0.13 and 0.17 / 0.05
    ds[4, 1], ds[3, 1], ds[2, 1] = 6.0 * 0.17 / 0.13 * 1.05, 0.0, 6.0 * 0.17 / 0.05 * 1.08
    # column 2: the third valid block above is 1.15 x farther than the road there: hides
    ds[4, 2], ds[3, 2], ds[2, 2] = 6.0, 6.0, 6.0 * 0.17 / 0.05 * 1.15
    # column 3: the block right above stands 0.3 m above the road (something behind): hides,
    # but not by its depth (6.5 m, under 1.1 x the road's ratio times 6 m)
    ds[4, 3], zs[4, 3] = 6.5, 0.3
    # column 4: no valid block above: not counted
    ds[:5, 4] = 0.0
    out = kernels.occlusion(labels, np.array([0], np.int64), ds, xs, ys, zs,
                            np.zeros(3), np.array([q0, qu, qv]), stride, 0.2, 1.1, 3)
    np.testing.assert_allclose(out, [[2 / 4, 1 / 4]])  # either; by depth alone (column 2)
    # a component whose top is in row 0 (the image's edge): no column counted
    edge = np.full((rows, cols), -1, np.int32)
    edge[0:2, 1:3] = 0
    out = kernels.occlusion(edge, np.array([0, -1], np.int64), ds, xs, ys, zs,
                            np.zeros(3), np.array([q0, qu, qv]), stride, 0.2, 1.1, 3)
    assert out.shape == (1, 2) and np.isnan(out).all()


def test_surface_shape_by_hand():
    rows, cols, stride, road = 12, 3, 4, 0.01
    v = (np.arange(rows) + 0.5) * stride   # the block rows' pixel rows
    labels = np.full((rows, cols), -1, np.int32)
    labels[2:6, :] = 0                     # upright: one depth, 6 m, down its rows
    labels[9:11, 1:] = 1                   # lying: its inverse depth grows 2x the road's slope
    ds = np.full((rows, cols), 6.0, np.float32)
    ds[9:11, 1:] = (1.0 / (0.1 + 2 * road * v[9:11]))[:, None]
    ds[6, 0] = 6.6                         # under object 0: column 0 at 1.1 x its depth, then
                                           # 6.0 and 6.0 (touches: the largest ratio is 1.1)
    ds[6, 1], ds[7, 1] = 0.0, 9.0          # column 1: no point, then 1.5 x (does not touch)
    ds[6, 2] = 8.0                         # column 2: 8 / 6 > 1.2 (does not)
    ds[11, 1] = 1.0 / (0.1 + road * v[11])  # under object 1: column 1 the road, 1.7 x farther,
    ds[11, 2] = ds[10, 2] * 1.1            # column 2 something at 1.1 x (touches)
    out = kernels.surface_shape(labels, np.array([0, 1], np.int64), ds, stride, road, 1.2, 3)
    assert out[0, 0] == pytest.approx(0.0, abs=1e-9) and out[0, 1] == pytest.approx(1 / 3)
    assert out[1, 0] == pytest.approx(2.0, rel=1e-5) and out[1, 1] == pytest.approx(0.5)
    # a component not wanted; one in a single row (no slope) with nothing below (no column
    # counted)
    one_row = np.full((rows, cols), -1, np.int32)
    one_row[rows - 1, :] = 0
    out = kernels.surface_shape(one_row, np.array([0, -1], np.int64), ds, stride, road, 1.2, 3)
    assert out.shape == (1, 2) and np.isnan(out).all()


def test_what_stood_there_a_frame_before_did_not_come_out_of_the_road():
    retriever, travel = GeometricRetriever(CAMERA), 1.0
    boxes = [CAR_AHEAD, PEDESTRIAN]
    now = retriever.view(_render(boxes)[0])
    assert len(now.points) == len(now.boxes) == 2
    for points, (x, y, z, w, length, h, _) in zip(now.points, sorted(boxes)):  # rows nearest first
        # each object's blocks lie on its box (a block at its edge reads its nearest depth: 0.2 m)
        assert np.all(np.abs(points - [x, y, z]) <= np.array([length, w, h]) / 2 + 0.2)
    # the frame before, 1 m back: each object 1 m farther; its blocks, put back, land on it
    before = retriever.view(_render([[b[0] + travel, *b[1:]] for b in boxes])[0]).road_depth
    assert np.all(retriever.emerged(now.points, before, travel) < 0.05)
    # the frame before saw the empty road: its line of sight to a block put back meets the
    # ground (z = 0) before the sky's 80 m, or the sky; it saw the block's place free where
    # it met the ground farther than the block by more than the margin
    empty = retriever.view(_render([])[0]).road_depth
    centre = CAMERA.cam_to_ego[:3, 3]
    for points, share in zip(now.points, retriever.emerged(now.points, empty, travel)):
        back = points + [travel, 0.0, 0.0]
        below = back[:, 2] < centre[2]
        ground = centre + (back - centre) * (centre[2] / np.where(below, centre[2] - back[:, 2], np.nan))[:, None]
        depth = CAMERA.ego_to_camera(np.nan_to_num(ground))[:, 2]
        beyond = depth > CAMERA.ego_to_camera(back)[:, 2] * (1.0 + EMERGED_MARGIN)
        assert 0.2 < share == pytest.approx(np.mean(below & (depth < _SKY) & beyond), abs=0.05)


def test_a_view_without_its_blocks_is_the_same_view():
    depth = _render([CAR_AHEAD, PEDESTRIAN])[0]
    kept, lean = GeometricRetriever(CAMERA).view(depth), GeometricRetriever(CAMERA, keep_blocks=False).view(depth)
    assert lean.road_depth is None and lean.points == ()
    assert kept.road_depth.shape == (-(-CAMERA.height // 4), -(-CAMERA.width // 4)) and len(kept.points) == 2
    for name in ("boxes", "extents", "free_distance", "ground", "valid_fraction"):
        np.testing.assert_array_equal(getattr(lean, name), getattr(kept, name))
    with pytest.raises(ValueError, match="keep_blocks = 1, expected True or False"):
        GeometricRetriever(CAMERA, keep_blocks=1)


def test_a_patch_of_road_read_too_near_came_out_of_the_road():
    rules_off = GeometricParams(max_incline=None, min_occlusion=None)  # so that the patch is an object
    retriever, travel = GeometricRetriever(CAMERA, rules_off), 1.2
    road, _ = _render([])
    blob = road.copy()
    blob[680:760, 700:900] *= np.float32(0.6)
    now = retriever.view(blob)
    assert now.boxes.shape == (1, 5)
    # the frame before read the road right: every block of the patch stood where it saw the road
    assert retriever.emerged(now.points, retriever.view(road).road_depth, travel).tolist() == [1.0]
    # the same patch read in the frame before too (where the ego's travel puts it then): 0
    shifted = road.copy()
    shifted[680:760, 700:900] *= np.float32(0.6)
    assert retriever.emerged(now.points, retriever.view(shifted).road_depth, 0.0).tolist() == [0.0]
    # road seen behind the patch's place, but not farther than the margin: nothing emerged;
    # farther than the margin behind its farthest block: all of it
    depths = CAMERA.ego_to_camera(now.points[0])[:, 2]
    within = np.full(now.road_depth.shape, depths.min() * (1.0 + 0.9 * EMERGED_MARGIN), dtype=np.float16)
    beyond = np.full(now.road_depth.shape, depths.max() * (1.0 + 1.1 * EMERGED_MARGIN), dtype=np.float16)
    assert retriever.emerged(now.points, within, 0.0).tolist() == [0.0]
    assert retriever.emerged(now.points, beyond, 0.0).tolist() == [1.0]
    # where the frame before had no valid depth nothing can be told
    blind = np.full(now.road_depth.shape, np.nan, dtype=np.float16)
    assert np.isnan(retriever.emerged(now.points, blind, travel)).all()
    assert retriever.emerged((), blind, travel).shape == (0,)
    with pytest.raises(ValueError, match=r"before is an array of int64 \(3, 3\), expected the road"):
        retriever.emerged(now.points, np.zeros((3, 3), dtype=np.int64), travel)
    with pytest.raises(ValueError, match="before is a list"):
        retriever.emerged(now.points, [[1]], travel)
    with pytest.raises(ValueError, match="travel = nan, expected the finite metres"):
        retriever.emerged(now.points, blind, float("nan"))


def test_an_empty_road_has_no_object_and_an_infinite_free_distance():
    depth, _ = _render([WALL, POLE])
    view = GeometricRetriever(CAMERA).view(depth)
    assert view.boxes.shape == (0, 5) and view.boxes.dtype == np.float64
    assert view.free_distance == math.inf and view.ground_fitted


def test_objects_beyond_the_range_limit_are_not_reported():
    far_car = [26.0, 0.0, 0.865, 1.95, 4.6, 1.73, 0.0]  # rear face at 23.7 m: 22 m camera depth
    depth, _ = _render([far_car])
    assert GeometricRetriever(CAMERA)(depth).shape == (0, 5)
    view = GeometricRetriever(CAMERA, GeometricParams(max_range=30.0)).view(depth)
    assert view.boxes.shape == (1, 5)
    assert view.boxes[0, 4] == pytest.approx(23.7 - CAMERA.cam_to_ego[0, 3], rel=1e-3)


@pytest.mark.parametrize("pitch_deg", [-3.0, 3.0])
def test_a_tilted_road_is_fitted_and_its_objects_found(pitch_deg):
    # the camera pitched by the grade change: in the frame the view believes in, the road
    # and everything on it turn by the same angle about the camera centre
    boxes = [CAR_AHEAD, PEDESTRIAN, POLE]
    depth, labels = _render(boxes, _pitched(CAMERA, pitch_deg))
    view = GeometricRetriever(CAMERA).view(depth)
    assert view.ground_fitted
    a, b, c = view.ground
    # nose down by p: the road rises ahead at slope tan(p); it passes under the camera
    # (x = 1.70 m, z = 1.51 m) at depth 1.51 / cos(p) below it along the tilted normal
    slope = math.tan(math.radians(pitch_deg))
    assert a == pytest.approx(slope, abs=2e-3) and abs(b) < 2e-3
    cam_x, cam_z = CAMERA.cam_to_ego[0, 3], CAMERA.cam_to_ego[2, 3]
    assert c == pytest.approx(cam_z - cam_z / math.cos(math.radians(pitch_deg)) - slope * cam_x,
                              abs=0.02)
    assert view.boxes.shape == (2, 5)
    for k in (0, 1):
        truth = _truth(labels, depth, k)
        found, score = _match(view.boxes, truth)
        assert score > 0.75 and found[4] == pytest.approx(truth[4], rel=0.01)


def test_a_mounting_pitched_beyond_the_bounds_is_blind_not_empty():
    # pitched up by 8 degrees: the road reads farther than the mounting says, under z = 0
    depth, _ = _render([CAR_AHEAD], _pitched(CAMERA, -8.0))
    with pytest.raises(BlindViewError, match="under the road plane") as error:
        GeometricRetriever(CAMERA).view(depth)
    assert error.value.reason == "below_ground" and error.value.fraction > 0.2


def test_a_surface_filling_the_view_at_1_m_is_one_near_object():
    depth = np.ones((CAMERA.height, CAMERA.width), dtype=np.float32)
    view = GeometricRetriever(CAMERA).view(depth)
    assert not view.ground_fitted and view.ground_support == 0.0  # no road to be seen
    np.testing.assert_array_equal(view.ground, [0.0, 0.0, 0.0])
    assert view.boxes.shape == (1, 5)
    np.testing.assert_allclose(view.boxes[0], [800.0, 450.0, 1600.0, 900.0, 1.0])
    # the surface is 1 m ahead of the camera, which is 1.70 m ahead of the ego origin (the
    # camera looks along +x up to 0.4 degrees)
    assert view.free_distance == pytest.approx(CAMERA.cam_to_ego[0, 3] + 1.0, abs=0.01)


def test_40_percent_invalid_pixels_scattered_still_finds_the_objects():
    boxes = [CAR_AHEAD, PEDESTRIAN, WALL]
    depth, labels = _render(boxes)
    holes = np.random.default_rng(0).random(depth.shape) < 0.4
    bad = np.array([np.nan, np.inf, 0.0, -1.0], dtype=np.float32)
    damaged = np.where(holes, bad[np.arange(depth.size).reshape(depth.shape) % 4], depth)
    view = GeometricRetriever(CAMERA).view(damaged.astype(np.float32))
    assert view.valid_fraction == pytest.approx(0.6, abs=0.005)
    assert view.corridor_valid_fraction == pytest.approx(0.6, abs=0.01)
    assert view.boxes.shape == (2, 5)
    for k in (0, 1):
        truth = _truth(labels, depth, k)
        found, score = _match(view.boxes, truth)
        assert score > 0.8 and found[4] == pytest.approx(truth[4], rel=1e-3)


def test_invalid_pixels_over_the_corridor_make_the_view_blind():
    depth, _ = _render([CAR_AHEAD])
    covered = depth.copy()
    covered[500:, 500:1100] = np.nan  # the road ahead: 27 % of the frame
    with pytest.raises(BlindViewError, match="look at the corridor") as error:
        GeometricRetriever(CAMERA).view(covered)
    assert error.value.reason == "corridor_invalid" and error.value.fraction > 0.5
    covered = depth.copy()
    covered[:500] = np.inf  # 56 % of the frame, the corridor's road untouched
    with pytest.raises(BlindViewError, match="depth map's pixels are invalid") as error:
        GeometricRetriever(CAMERA).view(covered)
    assert error.value.reason == "invalid"
    assert error.value.fraction == pytest.approx(500 / 900)


def test_a_curved_path_keeps_what_lies_on_it():
    # a car in the next lane to the left, 14 m ahead: off the straight corridor, on an arc
    # y = R - sqrt(R^2 - x^2) through (14, 3.5): R = (14^2 + 3.5^2) / 7 = 29.75 m
    car = [16.3, 3.5, 0.865, 1.95, 4.6, 1.73, 0.0]  # rear face at x = 14
    depth, labels = _render([car])
    retriever = GeometricRetriever(CAMERA, EGO_LANE)
    assert retriever(depth).shape == (0, 5)
    assert GeometricRetriever(CAMERA)(depth).shape == (1, 5)  # the default corridor holds it
    truth = _truth(labels, depth, 0)
    arc = Corridor(1.75, curvature=1 / 29.75)
    xs = np.linspace(0.0, 29.0, 59)
    polyline = Corridor(1.75, polyline=np.column_stack([xs, 29.75 - np.sqrt(29.75**2 - xs**2)]))
    for corridor in (arc, polyline):
        found = retriever(depth, corridor)
        assert found.shape == (1, 5)
        assert iou(found[0], truth) > 0.8 and found[0, 4] == pytest.approx(truth[4], rel=1e-3)


def test_the_view_is_deterministic_and_the_call_gives_the_views_boxes():
    depth, _ = _render([CAR_AHEAD, PEDESTRIAN])
    retriever = GeometricRetriever(CAMERA)
    first = retriever.view(depth)
    np.testing.assert_array_equal(first.boxes, retriever(depth))
    np.testing.assert_array_equal(first.ground, GeometricRetriever(CAMERA).view(depth).ground)


# --------------------------------------------------------------------------- kernels vs NumPy

def _small_camera():
    return Camera(np.diag([0.1, 0.1, 1.0]) @ CAMERA.K, 160, 90, CAMERA.cam_to_ego)


def _block_points_numpy(depth, stride, edge_spread, camera):
    height, width = depth.shape
    rows, cols = -(-height // stride), -(-width // stride)
    valid = np.isfinite(depth) & (depth > 0)
    out = np.zeros((4, rows, cols))
    invalid = np.zeros((rows, cols), dtype=np.int64)
    M = camera.cam_to_ego[:3, :3] @ np.linalg.inv(camera.K)
    for r in range(rows):
        for c in range(cols):
            i0, i1 = r * stride, min(r * stride + stride, height)
            j0, j1 = c * stride, min(c * stride + stride, width)
            n = valid[i0:i1, j0:j1].sum()
            invalid[r, c] = (i1 - i0) * (j1 - j0) - n
            if n:
                block = depth[i0:i1, j0:j1][valid[i0:i1, j0:j1]].astype(np.float64)
                edge = block.max() > (1 + edge_spread) * block.min()
                d = block.min() if edge else block.sum() / n
                point = camera.cam_to_ego[:3, 3] + d * M @ [(j0 + j1) / 2, (i0 + i1) / 2, 1.0]
                out[:, r, c] = [*point, d]
    return out, invalid


@pytest.mark.parametrize("stride, edge_spread, width", [(1, 0.15, 160), (3, 0.15, 160), (4, 0.15, 160),
                                                        (4, 100.0, 160), (4, 0.15, 158), (8, 0.15, 158)])
def test_block_points_equals_numpy(stride, edge_spread, width):
    # 90 rows: a last band of 2 rows at stride 4 (of 4 at stride 8: the loop written for four
    # rows); 158 columns: a last block of 2 columns (of 6 at stride 8)
    camera = _small_camera()
    rng = np.random.default_rng(stride)
    depth = rng.uniform(10.0, 12.0, (90, width)).astype(np.float32)
    depth[:, 80:] = rng.uniform(3.0, 40.0, (90, width - 80))  # smooth on the left, edges on the right
    depth[rng.random(depth.shape) < 0.2] = np.nan
    depth[rng.random(depth.shape) < 0.05] = -2.0
    depth[:9, :9] = np.inf  # a block (or more) with no valid pixel
    rows, cols = -(-90 // stride), -(-width // stride)
    points = np.empty((4, rows, cols), dtype=np.float32)
    invalid = np.empty((rows, cols), dtype=np.int32)
    M = np.ascontiguousarray(camera.cam_to_ego[:3, :3] @ np.linalg.inv(camera.K))
    n = kernels.block_points(depth, stride, edge_spread, M, np.ascontiguousarray(camera.cam_to_ego[:3, 3]),
                             *points, invalid)
    expected, expected_invalid = _block_points_numpy(depth, stride, edge_spread, camera)
    np.testing.assert_array_equal(invalid, expected_invalid)
    assert n == expected_invalid.sum() == np.count_nonzero(~(np.isfinite(depth) & (depth > 0)))
    np.testing.assert_allclose(points, expected, rtol=1e-5, atol=1e-4)


def test_block_points_loops_written_for_four_give_the_plain_loops_bits():
    # the kernel's band and block loops written out for a stride of 4 against a plain float32
    # loop in Python that adds each block's pixels row by row, as the kernel's general loops do
    rng = np.random.default_rng(4)
    depth = rng.uniform(3.0, 40.0, (40, 46)).astype(np.float32)  # a last block of 2 columns
    depth[rng.random(depth.shape) < 0.2] = np.nan
    M = np.ascontiguousarray(CAMERA.cam_to_ego[:3, :3] @ np.linalg.inv(CAMERA.K))
    origin = np.ascontiguousarray(CAMERA.cam_to_ego[:3, 3])
    points = np.empty((4, 10, 12), dtype=np.float32)
    kernels.block_points(depth, 4, 0.15, M, origin, *points, np.empty((10, 12), dtype=np.int32))
    for r in range(10):
        for c in range(12):
            pixels = depth[4 * r:4 * r + 4, 4 * c:4 * c + 4]
            column_sums = [np.float32(0.0)] * pixels.shape[1]
            for row in pixels:  # down the band, then across the block
                column_sums = [s + (d if d > 0 else np.float32(0.0)) for s, d in zip(column_sums, row)]
            total = np.float32(0.0)
            for s in column_sums:
                total = np.float32(total + s)
            valid = pixels[pixels > 0]
            edge = valid.max() > np.float32(1.15) * valid.min()
            d = valid.min() if edge else np.float32(total / np.float32(valid.size))
            u, v = 4 * c + 0.5 * pixels.shape[1], 4 * r + 2.0
            ray = [M[k, 0] * u + M[k, 1] * v + M[k, 2] for k in range(3)]
            expected = [np.float32(origin[k] + d * ray[k]) for k in range(3)] + [d]
            assert list(points[:, r, c]) == expected, (r, c)


def _cloud(seed, n=3000):
    """Points of a road ``z = 0.02 x - 0.01 y + 0.1`` with noise, plus boxes of clutter."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(2.0, 35.0, n), rng.uniform(-10.0, 10.0, n)
    z = 0.02 * x - 0.01 * y + 0.1 + rng.normal(0.0, 0.03, n)
    clutter = rng.random(n) < 0.3
    z[clutter] = rng.uniform(0.2, 3.0, clutter.sum())
    d = rng.uniform(1.0, 30.0, n)
    d[rng.random(n) < 0.05] = 0.0  # no point
    return [a.astype(np.float32) for a in (x, y, z, d)]


def test_ground_candidates_ransac_and_refine_equal_numpy():
    x, y, z, d = _cloud(1)
    out = np.empty(x.size, dtype=np.int64)
    band0, slope, x_max = 0.65, math.tan(math.radians(6.0)), 30.0
    n = kernels.ground_candidates(x, y, z, d, x_max, band0, slope, out)
    x64, y64, z64 = (a.astype(np.float64) for a in (x, y, z))
    mask = (d > 0) & (x >= 0) & (x <= x_max) & (np.abs(z64) <= band0 + slope * np.hypot(x64, y64))
    np.testing.assert_array_equal(out[:n], np.flatnonzero(mask))
    idx = out[:n]

    uniforms = np.random.default_rng(5).random((40, 3))
    n_score, tol, max_offset = 500, 0.1, 0.5
    best, best_score = (0.0, 0.0, 0.0), 0
    step = max(1, n // n_score)
    for u in uniforms:  # the textbook: plane through three points, inliers counted
        p = np.array([[x64[i], y64[i], z64[i]] for i in idx[np.minimum((u * n).astype(int), n - 1)]])
        normal = np.cross(p[1] - p[0], p[2] - p[0])
        if abs(normal[2]) <= 1e-6 * np.linalg.norm(normal):
            continue
        a, b = -normal[0] / normal[2], -normal[1] / normal[2]
        c = p[0, 2] - a * p[0, 0] - b * p[0, 1]
        if a * a + b * b > slope**2 or abs(c) > max_offset:
            continue
        scored = idx[::step]
        score = np.count_nonzero(np.abs(z64[scored] - (a * x64[scored] + b * y64[scored] + c)) <= tol)
        if score > best_score:
            best, best_score = (a, b, c), score
    *plane, score = kernels.ransac_plane(x, y, z, idx, n, uniforms, n_score, tol, slope, max_offset)
    assert score == best_score > 0
    # the same triple; a nearly collinear one amplifies the last bits of the arithmetic
    np.testing.assert_allclose(plane, best, rtol=1e-5, atol=1e-7)

    *refit, inliers = kernels.refine_plane(x, y, z, idx, n, *plane, tol)
    a, b, c = plane
    near = idx[np.abs(z64[idx] - (a * x64[idx] + b * y64[idx] + c)) <= tol]
    lstsq = np.linalg.lstsq(np.column_stack([x64[near], y64[near], np.ones(near.size)]), z64[near],
                            rcond=None)[0]
    assert inliers == near.size
    np.testing.assert_allclose(refit, lstsq, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(refit, [0.02, -0.01, 0.1], atol=0.01)  # the road it was made of


def test_ransac_finds_nothing_when_every_plane_is_out_of_bounds():
    x, y, z, d = _cloud(2)
    steep = (z + 0.3 * x).astype(np.float32)  # a 17 degree slope: beyond max_tilt
    idx = np.arange(x.size, dtype=np.int64)
    *plane, score = kernels.ransac_plane(x, y, steep, idx, x.size, np.random.default_rng(0).random((30, 3)),
                                         1000, 0.1, math.tan(math.radians(6.0)), 0.5)
    assert score == 0 and plane == [0.0, 0.0, 0.0]


def test_classify_equals_numpy():
    x, y, z, d = _cloud(3)
    corridor = Corridor(1.75, curvature=0.02)
    centre, tan = corridor.table(40.0, CORRIDOR_STEP_M)
    obstacle, inside, tall = (np.empty(x.size, np.uint8) for _ in range(3))
    road = np.empty(x.size, np.float32)
    plane = (0.02, -0.01, 0.1)
    n_valid, n_below = kernels.classify(x, y, z, d, *plane, 0.2, 2.5, 20.0, 0.05, centre, tan,
                                        CORRIDOR_STEP_M, 1.75, 1.0, obstacle, inside, tall, road)
    x64, y64, z64, d64 = (a.astype(np.float64) for a in (x, y, z, d))
    h = z64 - (0.02 * x64 - 0.01 * y64 + 0.1)
    valid = d64 > 0
    expected = valid & (h >= 0.2) & (h <= 2.5) & (d64 <= 20.0)
    row = np.minimum((x64 / CORRIDOR_STEP_M).astype(int), centre.size - 1)
    tangent_x = (row + 0.5) * CORRIDOR_STEP_M  # the centreline's tangent line at the row's middle
    lateral = np.abs(y64 - centre[row] - tan[row] * (x64 - tangent_x)) / np.hypot(1.0, tan[row])
    np.testing.assert_array_equal(obstacle, expected)
    np.testing.assert_array_equal(inside, expected & (lateral <= 1.75))
    np.testing.assert_array_equal(tall, valid & (h > 1.0))
    np.testing.assert_array_equal(road, np.where(valid, np.where((h >= -0.05) & (h < 0.2), d, 0.0), np.nan))
    assert (road > 0).any() and (road == 0).any() and np.isnan(road).any()
    assert 0 < tall.sum() < valid.sum()
    assert n_valid == valid.sum() and n_below == (valid & (h < -0.05)).sum()
    assert 0 < inside.sum() < expected.sum()


def test_footprint_blocks_equals_numpy():
    rng = np.random.default_rng(4)
    gx, gy = rng.uniform(-2.0, 40.0, 3000), rng.uniform(-6.0, 6.0, 3000)
    gd = np.where(rng.random(3000) < 0.2, np.inf, gx * 1.1)  # no ground hit above the horizon
    centre, tan = Corridor(1.75, curvature=-0.02).table(40.0, CORRIDOR_STEP_M)
    out = np.empty(3000, dtype=np.int64)
    n = kernels.footprint_blocks(gx, gy, gd, 20.0, centre, tan, CORRIDOR_STEP_M, 1.75, out)
    row = np.clip((gx / CORRIDOR_STEP_M).astype(int), 0, centre.size - 1)
    lateral = np.abs(gy - centre[row] - tan[row] * (gx - (row + 0.5) * CORRIDOR_STEP_M)) \
        / np.hypot(1.0, tan[row])
    expected = np.flatnonzero((gd <= 20.0) & (gx >= 0) & (lateral <= 1.75))
    assert 0 < expected.size < 3000
    np.testing.assert_array_equal(out[:n], expected)


def test_object_points_equal_numpy():
    rng = np.random.default_rng(4)
    labels = rng.integers(-1, 5, size=(30, 40)).astype(np.int32)
    xs, ys, zs = (rng.normal(size=(30, 40)).astype(np.float32) for _ in range(3))
    row_of = np.array([1, -1, 0, 2, -1, -1], dtype=np.int64)  # components 0..4, then label -1
    points, offsets = np.full((1200, 3), np.nan), np.empty(4, dtype=np.int64)
    kernels.object_points(labels, row_of, xs, ys, zs, 3, points, offsets)
    for row, component in enumerate((2, 0, 3)):
        mine = labels == component  # row-major, as the kernel goes
        np.testing.assert_array_equal(points[offsets[row]:offsets[row + 1]],
                                      np.column_stack([xs[mine], ys[mine], zs[mine]]))
    assert offsets[0] == 0 and offsets[3] == np.isin(labels, (0, 2, 3)).sum()


def _label_numpy(xs, ys, obstacle, x0, y0, cell, shape):
    """Occupancy grid labelled by scipy (8-connected), numbered by first block (row-major)."""
    gi = np.clip(np.floor((xs - x0) / cell).astype(int), 0, shape[0] - 1)
    gj = np.clip(np.floor((ys - y0) / cell).astype(int), 0, shape[1] - 1)
    grid = np.zeros(shape, bool)
    grid[gi[obstacle], gj[obstacle]] = True
    cells, _ = ndimage.label(grid, structure=np.ones((3, 3)))
    raw = np.where(obstacle, cells[gi, gj], 0)
    labels = np.full(xs.shape, -1)
    order = {}
    for k in np.flatnonzero(raw.ravel()):
        labels.flat[k] = order.setdefault(raw.flat[k], len(order))
    return labels, len(order)


def test_label_objects_equals_scipy_on_the_occupancy_grid():
    rng = np.random.default_rng(7)
    xs = rng.uniform(0.0, 12.0, (30, 40)).astype(np.float32)
    ys = rng.uniform(-6.0, 6.0, (30, 40)).astype(np.float32)
    obstacle = (rng.random((30, 40)) < 0.15).astype(np.uint8)
    shape = (40, 40)
    parent, ids = np.empty(shape, np.int32), np.empty(shape, np.int32)
    labels = np.empty((30, 40), np.int32)
    n = kernels.label_objects(xs, ys, obstacle, 0.0, -6.0, 0.3, parent, ids, labels)
    expected, n_expected = _label_numpy(xs, ys, obstacle.astype(bool), 0.0, -6.0, 0.3, shape)
    assert n == n_expected > 5
    np.testing.assert_array_equal(labels, expected)


def test_clear_structure_equals_numpy():
    rng = np.random.default_rng(9)
    xs = rng.uniform(0.0, 12.0, (30, 40)).astype(np.float32)
    ys = rng.uniform(-6.0, 6.0, (30, 40)).astype(np.float32)
    tall = (rng.random((30, 40)) < 0.02).astype(np.uint8)
    tall[0, 0], xs[0, 0] = 1, 50.0  # off the grid: marks nothing
    obstacle = (rng.random((30, 40)) < 0.3).astype(np.uint8)
    corridor = obstacle * (rng.random((30, 40)) < 0.5).astype(np.uint8)
    shape = (40, 40)
    gi, gj = np.floor(xs / 0.3).astype(int), np.floor((ys + 6.0) / 0.3).astype(int)
    on = (gi >= 0) & (gi < shape[0]) & (gj >= 0) & (gj < shape[1])
    marked = np.zeros(shape, bool)
    marked[gi[(tall > 0) & on], gj[(tall > 0) & on]] = True
    marked = ndimage.binary_dilation(marked, structure=np.ones((3, 3)))
    cleared = (obstacle > 0) & on & marked[np.clip(gi, 0, 39), np.clip(gj, 0, 39)]
    expected_obstacle, expected_corridor = obstacle * ~cleared, corridor * ~cleared
    n = kernels.clear_structure(xs, ys, tall, 0.0, -6.0, 0.3, np.empty(shape, np.int32), obstacle, corridor)
    assert n == cleared.sum() > 20
    np.testing.assert_array_equal(obstacle, expected_obstacle)
    np.testing.assert_array_equal(corridor, expected_corridor)


def test_object_stats_equals_numpy():
    rng = np.random.default_rng(8)
    labels = rng.integers(-1, 6, (20, 30)).astype(np.int32)
    labels[labels == 4] = -1  # component 4 has no block
    ds = rng.uniform(2.0, 20.0, (20, 30)).astype(np.float32)
    xs = rng.uniform(2.0, 20.0, (20, 30)).astype(np.float32)
    corridor = (rng.random((20, 30)) < 0.1).astype(np.uint8) * (labels >= 0)
    ys = rng.uniform(-8.0, 8.0, (20, 30)).astype(np.float32)
    corridor[labels == 5] = 0  # component 5 lies outside the corridor
    stats = kernels.object_stats(labels, 6, corridor.astype(np.uint8), ds, xs, ys, 3, 5.0, 10.0)
    for m in range(6):
        rows, cols = np.nonzero(labels == m)
        inside = (labels == m) & (corridor > 0)
        if m == 4:
            assert stats[m, 4] == 0 and np.isnan(stats[m, 7])
            continue
        np.testing.assert_array_equal(stats[m, :6], [rows.min(), rows.max(), cols.min(), cols.max(),
                                                     rows.size, inside.sum()])
        assert stats[m, 6] == (xs[inside].min() if inside.any() else np.inf)
        if inside.sum() >= 3:
            assert stats[m, 7] == pytest.approx(np.percentile(ds[labels == m].astype(np.float64), 5.0),
                                                rel=1e-12)
            side = ys[labels == m].astype(np.float64)
            np.testing.assert_allclose(stats[m, 8:], np.percentile(side, [10.0, 90.0]), rtol=1e-12)
        else:
            assert np.isnan(stats[m, 7:]).all()
    assert np.isnan(stats[5, 7:]).all()


def test_standing_equals_numpy():
    rng = np.random.default_rng(10)
    rows, cols, cell, x0, y0 = 20, 30, 0.5, 2.0, -8.0
    labels = rng.integers(-1, 6, (rows, cols)).astype(np.int32)
    xs = rng.uniform(2.0, 9.0, (rows, cols)).astype(np.float32)
    ys = rng.uniform(-8.0, 8.0, (rows, cols)).astype(np.float32)
    zs = rng.uniform(-0.2, 1.0, (rows, cols)).astype(np.float32)
    flat = labels == 2  # component 2: a flat patch, alone on its part of the grid
    xs[flat] = rng.uniform(10.5, 11.5, int(flat.sum()))
    zs[flat] = 0.4 + 0.01 * rng.random(int(flat.sum()))
    ds = rng.uniform(2.0, 20.0, (rows, cols)).astype(np.float32)
    ds[rng.random((rows, cols)) < 0.1] = np.nan  # invalid blocks count for no cell
    corridor = (rng.random((rows, cols)) < 0.5).astype(np.uint8)
    corridor[labels == 3] = 0  # component 3 lies outside the corridor
    plane = np.array([0.01, -0.02, 0.05])
    index = np.array([0, 1, 2, 3, -1, 4])  # component 4 not wanted
    nx, ny = 20, 32
    low, high = np.empty((nx, ny), np.float32), np.empty((nx, ny), np.float32)
    out = kernels.standing(labels, index, corridor, xs, ys, zs, ds, plane, 0.1, 0.9, x0, y0, cell,
                           low, high, 0.3, 10.0, 0, rows - 1)
    # by NumPy: each cell's range of heights in [0.1, 0.9]; a block rises when a cell of its
    # 3 x 3 neighbourhood spans 0.3 m or more
    h = zs.astype(np.float64) - (0.01 * xs - 0.02 * ys + 0.05)
    gi, gj = np.floor((xs - x0) / cell).astype(int), np.floor((ys - y0) / cell).astype(int)
    span = np.full((nx, ny), -np.inf)
    counted = (ds > 0) & (h >= 0.1) & (h <= 0.9)
    for i in range(nx):
        for j in range(ny):
            here = counted & (gi == i) & (gj == j)
            if here.any():
                span[i, j] = h[here].max() - h[here].min()
    rises = np.zeros((rows, cols), bool)
    for r in range(rows):
        for c in range(cols):
            i, j = gi[r, c], gj[r, c]
            rises[r, c] = (span[max(i - 1, 0):i + 2, max(j - 1, 0):j + 2] >= 0.3).any()
    assert out.shape == (5, 4)
    for m in (0, 1, 2, 3, 5):
        mine = labels == m
        up = mine & rises
        inside_up, inside = up & (corridor > 0), mine & (corridor > 0)
        x = xs[inside_up].min() if inside_up.any() else xs[inside].min() if inside.any() else np.inf
        side = ys[up if up.any() else mine].astype(np.float64)
        np.testing.assert_allclose(out[index[m]], [x, *np.percentile(side, [10.0, 90.0]), up.sum()],
                                   rtol=1e-12)
    assert not rises[flat].any() and rises[labels == 0].any() and np.isinf(out[3, 0])
    # objects in rows 5-14 only: their rows are all the kernel needs to look at
    band = labels.copy()
    band[:5], band[15:] = -1, -1
    whole = kernels.standing(band, index, corridor, xs, ys, zs, ds, plane, 0.1, 0.9, x0, y0, cell,
                             low, high, 0.3, 10.0, 0, rows - 1)
    np.testing.assert_array_equal(kernels.standing(band, index, corridor, xs, ys, zs, ds, plane, 0.1,
                                                   0.9, x0, y0, cell, low, high, 0.3, 10.0, 5, 14), whole)
    assert np.isfinite(whole[:, 1]).all()


def test_ledge_shape_equals_numpy():
    rng = np.random.default_rng(9)
    labels = rng.integers(-1, 6, (20, 30)).astype(np.int32)
    xs = rng.uniform(2.0, 20.0, (20, 30)).astype(np.float32)
    ys = rng.uniform(-8.0, 8.0, (20, 30)).astype(np.float32)
    zs = rng.uniform(0.0, 2.0, (20, 30)).astype(np.float32)
    plane = np.array([0.01, -0.02, 0.05])  # a tilted road
    index = np.array([-1, 1, -1, 0, 2, -1])  # components 3, 1 and 4, in that order
    shape = kernels.ledge_shape(labels, index, xs, ys, zs, plane, 10.0, 95.0)
    assert shape.shape == (3, 2)
    for m in (3, 1, 4):
        x, y, z = (a[labels == m].astype(np.float64) for a in (xs, ys, zs))
        top = np.percentile(z - (0.01 * x - 0.02 * y + 0.05), 95.0)
        along = np.percentile(x, 90.0) - np.percentile(x, 10.0)
        np.testing.assert_allclose(shape[index[m]], [top, along], rtol=1e-12)
    assert kernels.ledge_shape(labels, np.full(6, -1), xs, ys, zs, plane, 10.0, 95.0).shape == (0, 2)


def test_surface_shape_equals_numpy():
    rng = np.random.default_rng(9)
    rows, cols, stride, road = 30, 20, 4, 0.004
    labels = rng.integers(-1, 5, (rows, cols)).astype(np.int32)
    ds = rng.uniform(2.0, 20.0, (rows, cols)).astype(np.float32)
    ds[(rng.random((rows, cols)) < 0.1) & (labels < 0)] = np.nan  # no point
    index = np.array([0, -1, 1, 2, 3], np.int64)                    # component 1 not wanted
    out = kernels.surface_shape(labels, index, ds, stride, road, 1.2, 3)
    for m, j in enumerate(index):
        if j < 0:
            continue
        r, c = np.nonzero(labels == m)
        slope = np.polyfit((r + 0.5) * stride, 1.0 / ds[r, c].astype(np.float64), 1)[0]
        assert out[j, 0] == pytest.approx(slope / road, rel=1e-9, abs=1e-9)
        touching = []
        for col in np.unique(c):
            low = r[c == col].max()
            below = ds[low + 1:, col].astype(np.float64)
            below = below[below > 0][:3]
            if below.size:
                touching.append(below.max() / ds[low, col] <= 1.2)
        assert out[j, 1] == pytest.approx(np.mean(touching))


# --------------------------------------------------------------------------- errors

@pytest.mark.parametrize("field, value, text", [
    ("stride", 0, "stride = 0, must be an integer >= 1"),
    ("stride", 2.0, "stride = 2.0"),
    ("min_height", 3.0, "min_height must be below max_height"),
    ("max_range", math.inf, "max_range = inf, must be a finite number > 0"),
    ("cell_size", 0.0, "cell_size = 0.0"),
    ("depth_percentile", 101.0, r"depth_percentile = 101.0, must be in \[0, 100\]"),
    ("max_tilt_deg", 50.0, "max_tilt_deg = 50.0"),
    ("max_invalid_fraction", 1.5, r"max_invalid_fraction = 1.5, must be a share in \[0, 1\]"),
    ("seed", -1, "seed = -1"),
    ("structure_height", 2.0, "structure_height must be above max_height"),
    ("structure_height", -1.0, r"structure_height = -1.0, must be a finite number of metres > 0 or None"),
    ("max_incline", 0.0, r"max_incline = 0.0, must be a finite share .* > 0, or None"),
    ("max_incline", True, "max_incline = True"),
    ("min_contact", 1.5, r"min_contact = 1.5, must be a share in \[0, 1\]"),
    ("min_occlusion", -0.1, r"min_occlusion = -0.1, must be a share in \[0, 1\], or None"),
    ("min_occlusion", True, "min_occlusion = True"),
    ("ledge_height", 0.2, r"ledge_height = 0.2, must be metres above the road over min_height = 0.2"),
    ("ledge_height", True, "ledge_height = True"),
    ("ledge_width", 0.0, "ledge_width = 0.0, must be a finite number of metres > 0"),
    ("min_rise", 0.0, r"min_rise = 0.0, must be a finite number of metres > 0, or None"),
    ("min_rise", True, "min_rise = True"),
])
def test_params_are_validated(field, value, text):
    with pytest.raises(ValueError, match=text):
        GeometricParams(**{field: value})


def test_bad_input_is_refused_with_a_clear_message():
    retriever = GeometricRetriever(_small_camera())
    with pytest.raises(ValueError, match="expected a float32"):
        retriever(np.ones((90, 160)))
    with pytest.raises(ValueError, match="depth is 90x160 .* image is 160x90"):
        retriever(np.ones((160, 90), np.float32))
    with pytest.raises(ValueError, match="corridor is a float"):
        retriever(np.ones((90, 160), np.float32), 0.02)
    with pytest.raises(ValueError, match="expected a Camera"):
        GeometricRetriever("front")
    low = CAMERA.cam_to_ego.copy()
    low[2, 3] = -0.1
    with pytest.raises(ValueError, match="above the ground"):
        GeometricRetriever(Camera(CAMERA.K, CAMERA.width, CAMERA.height, low))
