"""What an engaging object lay on: ray-cast frames with a car, a wall and a patch of road
read too near, whose places are known by construction."""
import numpy as np
import pytest

from monitor.datasets.frames import LABEL_ROAD
from monitor.offline.attribution import what_lies_there
from monitor.synthetic.raycast import render_depth

CLASSES = np.array(["car"])


@pytest.fixture(scope="module")
def street(camera):
    """A car 12 m ahead in the path (its rear at x = 9.75 m) and a wall 6 m to the left."""
    car = np.array([[12.0, 0.0, 0.75, 1.8, 4.5, 1.5, 0.0]])
    wall = np.array([[20.0, 6.5, 1.5, 1.0, 30.0, 3.0, 0.0]])  # its face toward the road at y = 6
    render = render_depth(camera, car, wall)
    depth = np.where(np.isfinite(render.depth), render.depth, 80.0).astype(np.float32)
    return depth, render.labels


def test_objects_on_a_car_on_a_wall_and_on_nothing(camera, street):
    depth, labels = street
    objects = [[9.75, -0.9, 0.9],  # the car's rear face
               [12.0, 5.9, 6.5],  # the wall's face
               [12.0, 2.0, 3.0]]  # empty road: its pixels lie on the road, under the heights
    assert what_lies_there(objects, depth, labels, CLASSES, camera) == ["car", "structure", "none"]
    assert what_lies_there(np.zeros((0, 3)), depth, labels, CLASSES, camera) == []


def test_a_patch_of_road_read_too_near_lies_on_the_road(camera, street):
    # the road's pixels read at 0.6 of their depth: each lands 0.6 of the way from the camera
    # to where it lies, 0.4 of the camera's height above the road; the road 6-7 m ahead and
    # within 0.5 m of the centreline lands at x = cx + 0.6 (6 - cx) .. cx + 0.6 (7 - cx)
    depth, labels = street
    near = np.where(labels == LABEL_ROAD, 0.6 * depth, depth).astype(np.float32)
    cx, cy, cz = camera.cam_to_ego[:3, 3]
    assert 0.4 * cz > 0.15  # lifted into the heights that count
    x0 = cx + 0.6 * (6.0 - cx)
    patch = [[x0, 0.6 * -0.5 + 0.4 * cy, 0.6 * 0.5 + 0.4 * cy]]
    assert what_lies_there(patch, near, labels, CLASSES, camera) == ["road"]
    # through the true depth nothing lies there: the road's pixels stay on the road
    assert what_lies_there(patch, depth, labels, CLASSES, camera) == ["none"]
