"""Fixtures of the closed-loop tests."""
import numpy as np
import pytest

from monitor.geometry.camera import Camera


@pytest.fixture(scope="module")
def camera():
    """nuScenes' front camera at half resolution (800 x 450), to keep the tests quick."""
    front = Camera.nuscenes_front()
    return Camera(np.diag([0.5, 0.5, 1.0]) @ front.K, 800, 450, front.cam_to_ego)
