"""Synthetic frames: the ray cast of one 1600 x 900 frame, and a whole generated frame.

Run: ``python -m pytest benchmarks/bench_raycast.py --benchmark-only -q``

Group "ray cast 1600x900, 15 boxes" (target: well under 50 ms), answers checked first:

- ``render_depth``: the Numba renderer (each box tested on its projected extent only);
- ``render_depth_reference``: the same in vectorised NumPy over every pixel and box
  (the obviously complete implementation; 3 rounds, it takes seconds).

Group "one synthetic frame 1600x900": everything :func:`generate_frames` does per frame
(layout at time t, ray cast of all ~100 actors within 80 m, ground paint, depth estimate,
detections), in each condition; the compile time of the kernels is reported apart.
"""
import time

import numpy as np
import pytest

from monitor.geometry.camera import Camera
from monitor.synthetic import CONDITIONS, generate_frames, warm_up
from monitor.synthetic.raycast import render_depth, render_depth_reference
from monitor.synthetic.scene import make_layout

CAMERA = Camera.nuscenes_front()


def _boxes(seed=2025, n=15):
    """The n nearest actors ahead of the ego in a generated layout (a busy street)."""
    boxes, _, _ = make_layout(seed, 9.5, rare_per_scene=1.0).frame_boxes(3.0)
    ahead = boxes[boxes[:, 0] > 3.0]
    return ahead[np.argsort(np.hypot(ahead[:, 0], ahead[:, 1]))[:n]]


BOXES = _boxes()


@pytest.fixture(scope="module")
def warm_up_seconds():
    start = time.perf_counter()
    warm_up()
    return time.perf_counter() - start


@pytest.fixture(scope="module")
def reference():
    return render_depth_reference(CAMERA, BOXES)


def _check(render, reference):
    assert BOXES.shape == (15, 7)
    assert np.count_nonzero(render.visible_px) >= 8  # most boxes are in view
    np.testing.assert_array_equal(render.labels, reference.labels)
    np.testing.assert_allclose(render.depth, reference.depth, rtol=1e-6)


@pytest.mark.benchmark(group="ray cast 1600x900, 15 boxes", warmup=True)
def test_render_depth(benchmark, warm_up_seconds, reference):
    benchmark.extra_info["warm_up_s"] = warm_up_seconds
    _check(render_depth(CAMERA, BOXES), reference)
    benchmark(render_depth, CAMERA, BOXES)


@pytest.mark.benchmark(group="ray cast 1600x900, 15 boxes")
def test_render_depth_reference(benchmark, reference):
    _check(render_depth(CAMERA, BOXES), reference)
    benchmark.pedantic(render_depth_reference, args=(CAMERA, BOXES), rounds=3, iterations=1)


@pytest.mark.benchmark(group="one synthetic frame 1600x900", warmup=True)
@pytest.mark.parametrize("condition", list(CONDITIONS))
def test_generate_frame(benchmark, warm_up_seconds, condition):
    frames = generate_frames(condition, seed=7, n_frames=200, camera=CAMERA)
    first = next(frames)
    assert first.depth_est.shape == (900, 1600) and first.gt_ids.size > 20
    benchmark.pedantic(next, args=(frames,), rounds=40, iterations=1, warmup_rounds=2)
