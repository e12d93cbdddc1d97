"""Hostile frames for RiskMonitor.step: frames the depth view cannot see through, and
features no rule covers, must not read as "no risk" (issue 13, items 1 and 5).

The camera is nuScenes CAM_FRONT (1600 x 900, 1.5 m above the road); the prior is the
inverse depth of the empty road. The lowest image row sees the road about 4.2 m ahead:
the row is 450 px below the principal point, fy = 1266 px, so the ray dips
atan(450 / 1266) = 19.6 degrees and meets the ground at 1.5 / tan(19.6 deg) = 4.2 m.
"""
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fuzzcore
from monitor.config import MonitorConfig, RetrievalConfig, RiskConfig, load_config
from monitor.depth.visibility import VisibilityParams, check_view
from monitor.geometry.camera import Camera
from monitor.risk_monitor import NO_OBJECTS, NO_RULE_FIRED, NO_VIEW, OK, RiskMonitor
from monitor.shipped import shipped_rules
from monitor.synthetic import render_depth

CAMERA = Camera.nuscenes_front()
H, W = CAMERA.height, CAMERA.width
FAR_M = 80.0  # the sky, as a depth network reports it
NONE = np.zeros((0, 7))
#: a car whose rear is 8 m ahead on the optical axis: x, y, z (centre), w, l, h, yaw
CAR_8M = np.array([[8.0 + 2.25, 0.0, 0.75, 1.8, 4.5, 1.5, 0.0]])


#: these frames are about the paper's depth view and its visibility check (the default view
#: is the geometric one, which calls its own blind frames: tests/monitor/depth/test_geometric.py)
PAPER = replace(MonitorConfig(), retrieval=RetrievalConfig(method="paper"))


def _render(boxes):
    result = render_depth(CAMERA, boxes)
    return np.where(np.isfinite(result.depth), result.depth, FAR_M).astype(np.float32), result.labels


@pytest.fixture(scope="module")
def road():
    return _render(NONE)[0]


@pytest.fixture(scope="module")
def monitor(road):
    return RiskMonitor(fuzzcore.load(shipped_rules()), (1.0 / road).astype(np.float32), CAMERA, PAPER)


def test_empty_road_is_still_no_objects(monitor, road):
    # the rule must not fire on the plain road: the bottom rows see it at 4.2 m (> 3 m),
    # all of the lower half lies within 20 m at its bottom, and it comes nearer downwards
    assert check_view(road) == ""
    report = monitor.step(road, NONE)
    assert report.status == NO_OBJECTS and report.risk == monitor.config.risk.no_objects


@pytest.mark.parametrize("metres, rule", [
    (1.0, "view blocked"), (2.0, "view blocked"), (1e-30, "view blocked"), (2.99, "view blocked"),
    (3.5, "no ground"), (8.0, "no ground"), (19.0, "no ground"),  # a wall filling the view: no edges
    (25.0, "no ground"), (1e6, "no ground"), (1e30, "no ground"),  # nothing within range
])
def test_uniform_depth_map_is_no_view_with_fail_safe_risk(monitor, metres, rule):
    report = monitor.step(np.full((H, W), metres, np.float32), NONE)
    assert report.status == NO_VIEW and report.risk == 1.0
    assert report.reason.startswith(rule)


def test_ninety_percent_at_two_metres_is_blocked(monitor):
    depth = np.full((H, W), FAR_M, np.float32)
    depth[H // 10:] = 2.0  # the lower 90 % of the rows
    report = monitor.step(depth, NONE)
    assert report.status == NO_VIEW and report.risk == 1.0 and "view blocked" in report.reason


def test_object_made_invalid_is_not_no_risk(monitor):
    depth, labels = _render(CAR_8M)
    seen = monitor.step(depth, NONE)
    assert seen.status == OK and seen.risk > 0.75  # the missed car: IoU~ 0, RDD~ 1
    car = labels == 1
    # the car's pixels: 7.6 % of the frame, under the 30 % invalid limit
    assert 0.05 < car.mean() < 0.3
    depth[car] = np.nan
    report = monitor.step(depth, NONE)
    assert report.status == NO_VIEW and report.risk == 1.0 and report.reason.startswith("hidden region")


def test_small_invalid_holes_do_not_fire(monitor, road):
    # holes of 39 x 39 px cannot hold the 40 x 40 square
    depth = road.copy()
    for r in range(500, 850, 80):
        for c in range(100, 1500, 120):
            depth[r:r + 39, c:c + 39] = np.nan
    assert check_view(depth) == ""
    depth[600:640, 700:740] = np.nan  # one 40 x 40 hole does
    assert check_view(depth).startswith("hidden region: the invalid pixels of the lower 50% of the image hold "
                                        "a 40 x 40 square (centre at row 620, column 720)")


def test_rules_can_be_turned_off_and_risk_configured(road):
    config = replace(PAPER, visibility=VisibilityParams(blocked_share=1.0, min_in_range_share=0.0,
                                                                  min_ground_ratio=0.0, hidden_size=None),
                     risk=RiskConfig(no_view=0.7))
    monitor = RiskMonitor(fuzzcore.load(shipped_rules()), (1.0 / road).astype(np.float32), CAMERA, config)
    for metres in (1.0, 10.0, 1e6):
        assert monitor.step(np.full((H, W), metres, np.float32), NONE).status == NO_OBJECTS
    on = RiskMonitor(fuzzcore.load(shipped_rules()), (1.0 / road).astype(np.float32), CAMERA,
                     replace(PAPER, risk=RiskConfig(no_view=0.7)))
    assert on.step(np.full((H, W), 1.0, np.float32), NONE).risk == 0.7


def test_visibility_config_keys(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("visibility:\n  blocked_range: 2.0\n  hidden_size: null\nrisk:\n  no_view: 0.9\n")
    config = load_config(path)
    assert config.visibility.blocked_range == 2.0 and config.visibility.hidden_size is None
    assert config.risk.no_view == 0.9 and config.risk.no_rule_fired == 1.0
    path.write_text("visibility:\n  band: 0.0\n")
    with pytest.raises(ValueError, match=r"visibility.band = 0.0, must be in \(0, 1\]"):
        load_config(path)
    path.write_text("visibility:\n  max_range: 5.0\n")  # the top-level max_range holds everywhere
    with pytest.raises(ValueError, match="unknown key visibility.max_range"):
        load_config(path)


@settings(max_examples=25)
@given(metres=st.floats(1e-38, 3.3e38, allow_subnormal=False), share=st.floats(0.55, 1.0),
       noise=st.integers(0, 2**32 - 1))
def test_mostly_uniform_frames_never_read_as_no_risk(monitor, metres, share, noise):
    # the lower `share` of the rows at one depth (+-1 % noise): a surface filling the view
    rng = np.random.default_rng(noise)
    depth = np.full((H, W), FAR_M, np.float32)
    rows = int(share * H)
    depth[H - rows:] = (metres * rng.uniform(0.99, 1.01, (rows, W))).astype(np.float32)
    report = monitor.step(depth, NONE)
    assert report.status not in (NO_OBJECTS, OK) or report.risk > 0.5
    assert report.risk > 0.5


# ----------------------------------------------------------------------------- item 5
def test_no_rule_fired_is_its_own_status(road, tmp_path):
    path = tmp_path / "gap.yaml"
    path.write_text(_gap_text())
    fis = fuzzcore.load(path)
    # the engine's own answer where nothing fires: the midpoint 0.5 (the shield needs > 0.5)
    assert fis.infer(iou=1.0, rdd=0.0) == 0.5
    prior = (1.0 / road).astype(np.float32)
    depth, _ = _render(CAR_8M)
    monitor = RiskMonitor(fis, prior, CAMERA, PAPER)
    # the car detected where it is: IoU~ high, RDD~ near 0, so "rdd is high" does not fire
    report = monitor.step(depth, CAR_8M)
    assert report.status == NO_RULE_FIRED and report.risk == 1.0 and report.fired == []
    assert abs(report.rdd) < 0.5 and report.iou > 0.3 and "no rule of 'gap' fired" in report.reason
    # missed: RDD~ = 1 fires the rule, and the report is the rule base's
    missed = monitor.step(depth, NONE)
    assert missed.status == OK and missed.risk == pytest.approx(fis.infer(iou=0.0, rdd=1.0))
    quiet = RiskMonitor(fis, prior, CAMERA, replace(PAPER, risk=RiskConfig(no_rule_fired=0.25)),
                        explain=False)
    report = quiet.step(depth, CAR_8M)
    assert report.status == NO_RULE_FIRED and report.risk == 0.25
    assert monitor.fis is fis  # the user's system is kept as given


def _gap_text():
    return """name: gap
inputs:
  iou:
    range: [0.0, 1.0]
    terms: {any: [trapmf, 0.0, 0.0, 1.0, 1.0]}
  rdd:
    range: [-1.0, 1.0]
    terms: {high: [trapmf, 0.5, 0.8, 1.0, 1.0]}
outputs:
  risk:
    range: [0.0, 1.0]
    terms: {high: [trapmf, 0.5, 0.75, 1.0, 1.0]}
rules:
  - if iou is any and rdd is high then risk is high
"""
