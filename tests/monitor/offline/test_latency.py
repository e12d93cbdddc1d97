"""monitor.offline.latency: per-stage step latency on synthetic frames of a camera."""
import json

import numpy as np
import pytest

import fuzzcore
from monitor.geometry.camera import Camera
from monitor.offline.latency import FRAMES_PER_SCENE, STAGES, monitor_latency
from monitor.synthetic import CONDITIONS, generate_frames

FRONT = Camera.nuscenes_front()
SMALL = Camera(np.diag([0.2, 0.2, 1.0]) @ FRONT.K, 320, 180, FRONT.cam_to_ego)


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load("rules/fuzzrisk.yaml")


@pytest.fixture(scope="module")
def measured(fis):
    return monitor_latency(fis, SMALL, frames=FRAMES_PER_SCENE + 2, repeat=3, hz=10.0, seed=5)


def test_every_stage_is_timed_on_every_step(measured):
    n = FRAMES_PER_SCENE + 2
    assert (measured.width, measured.height, measured.frames, measured.repeat) == (320, 180, n, 3)
    assert sum(measured.statuses.values()) == n
    ok = measured.statuses.get("ok", 0)
    counts = {k: v.count for k, v in measured.stages.items()}
    want = {"retrieval": 3 * n, "projection": 3 * n, "alignment": 3 * n, "step": 3 * n}
    if ok:
        want["inference"] = 3 * ok  # inference runs on frames with objects only
    assert counts == want and set(counts) <= set(STAGES)
    step = measured.stages["step"].samples_ns
    parts = sum(measured.stages[k].samples_ns for k in ("retrieval", "projection", "alignment"))
    assert (step >= parts).all()  # the whole call contains its stages


def test_object_counts_are_those_of_the_synthetic_frames(measured):
    # scene k: condition k of CONDITIONS, seed 5 + k; FRAMES_PER_SCENE frames, then the rest
    frames = list(generate_frames(list(CONDITIONS)[0], 5, n_frames=FRAMES_PER_SCENE, camera=SMALL)) \
        + list(generate_frames(list(CONDITIONS)[1], 6, n_frames=2, camera=SMALL))
    assert measured.objects["detections"] == np.mean([len(f.det_boxes3d) for f in frames])


def test_budget_share_is_the_step_over_the_frame_period(measured):
    # 10 Hz: a 100 ms = 1e8 ns period
    assert measured.frame_budget_ns == 1e8
    for p, share in measured.budget_share().items():
        assert share == measured.stages["step"].percentiles_ns[p] / 1e8
    data = json.loads(json.dumps(measured.to_dict()))
    assert data["stages"]["step"]["count"] == measured.stages["step"].count and data["hz"] == 10.0


@pytest.mark.parametrize("kwargs, message", [
    ({"frames": 0}, "frames = 0, must be an integer >= 1"),
    ({"repeat": 2.5}, "repeat = 2.5"),
    ({"hz": 0.0}, "hz = 0.0, must be a finite frame rate > 0"),
    ({"seed": -3}, "seed = -3"),
])
def test_bad_arguments_are_named(fis, kwargs, message):
    with pytest.raises(ValueError, match=message):
        monitor_latency(fis, SMALL, **kwargs)
    with pytest.raises(ValueError, match="camera is a str"):
        monitor_latency(fis, "front")
