"""The RiskMonitor end to end on scenes with known answers, its configuration and the shield."""
import json
from dataclasses import replace

import numpy as np
import pytest

import fuzzcore
from monitor.geometry.camera import Camera, project_boxes
from monitor.config import MonitorConfig, load_config
from monitor.risk_monitor import INVALID_INPUT, NO_OBJECTS, OK, RiskMonitor
from monitor.shield import Shield
from monitor.shipped import shipped_rules
from monitor.synthetic import render_depth

CAMERA = Camera.nuscenes_front()
#: a depth network reports far things (the sky) at its largest depth, not as invalid
FAR_M = 80.0
# a pedestrian 9 m ahead, slightly left: x, y, z (centre), w, l, h, yaw (ego frame)
PEDESTRIAN = np.array([[9.0, 0.8, 0.9, 0.7, 0.7, 1.8, 0.0]])


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load(shipped_rules())


@pytest.fixture(scope="module")
def prior():
    # what the road looks like with nothing on it: the mean inverse depth of an empty scene
    return (1.0 / _depth(np.zeros((0, 7)))).astype(np.float32)


def _depth(boxes):
    depth = render_depth(CAMERA, boxes).depth
    return np.where(np.isfinite(depth), depth, FAR_M).astype(np.float32)


@pytest.fixture(scope="module")
def monitor(fis, prior):
    return RiskMonitor(fis, prior, CAMERA)


@pytest.fixture(scope="module")
def scene_depth():
    return _depth(PEDESTRIAN)


def test_perfectly_detected_pedestrian_gives_low_risk(monitor, fis, scene_depth):
    report = monitor.step(scene_depth, PEDESTRIAN)
    assert report.status == OK and len(report.S) >= 1 and len(report.P) == 1
    # the depth view found the pedestrian where the detector put it
    assert report.alignment.matched.any()
    assert report.iou > 0.5 and abs(report.rdd) < 0.2
    # the same features through the rule base by hand: the monitor adds nothing to them
    assert report.risk == pytest.approx(fis.infer(iou=report.iou, rdd=report.rdd), abs=0)
    # agreeing views fire "rdd medium, iou high -> risk low": risk well below the shield's 0.5
    assert report.risk < 0.35
    assert any("iou is high" in text and "risk is low" in text for _, text, _ in report.fired)


def test_missed_pedestrian_gives_high_risk(monitor, fis, scene_depth):
    report = monitor.step(scene_depth, np.zeros((0, 7)))
    assert report.status == OK and len(report.P) == 0 and len(report.S) >= 1
    # every S unmatched: IoU~ = 0, RDD~ = 1 (the paper's worst scores)
    assert report.iou == 0.0 and report.rdd == 1.0
    assert report.risk == pytest.approx(fis.infer(0.0, 1.0), abs=0)
    assert report.risk > 0.75


def test_empty_road_reports_no_objects(monitor):
    report = monitor.step(_depth(np.zeros((0, 7))), np.zeros((0, 7)))
    assert report.status == NO_OBJECTS and report.risk == monitor.config.no_objects_risk
    assert np.isnan(report.iou) and "no safety-critical object" in report.reason


@pytest.mark.parametrize("depth, detections, reason", [
    (np.full((900, 1600), np.nan, np.float32), np.zeros((0, 7)), "invalid"),
    (np.ones((90, 160), np.float32), np.zeros((0, 7)), "shape"),
    (np.ones((900, 1600), np.int32), np.zeros((0, 7)), "dtype"),
    (None, np.array([[np.nan, 0, 0, 1, 1, 1, 0]]), "detections[0, 0]"),
    (None, np.zeros((3, 5)), "detections"),
])
def test_bad_frames_give_the_fail_safe_not_an_exception(monitor, scene_depth, depth, detections, reason):
    report = monitor.step(scene_depth if depth is None else depth, detections)
    assert report.status == INVALID_INPUT and report.risk == 1.0 and reason in report.reason


def test_fail_safe_is_configurable(fis, prior):
    config = replace(MonitorConfig(), fail_safe_risk=0.9)
    report = RiskMonitor(fis, prior, CAMERA, config).step(np.zeros((900, 1600), np.float32), np.zeros((0, 7)))
    assert report.status == INVALID_INPUT and report.risk == 0.9


def test_low_scores_are_dropped(monitor, scene_depth):
    dropped = monitor.step(scene_depth, PEDESTRIAN, scores=[0.1])
    kept = monitor.step(scene_depth, PEDESTRIAN, scores=[0.9])
    assert len(dropped.P) == 0 and len(kept.P) == 1


def test_projection_is_project_boxes(monitor):
    expected, _ = project_boxes(PEDESTRIAN, CAMERA, "camera_depth")
    np.testing.assert_array_equal(monitor.project(PEDESTRIAN), expected)


def test_report_serialises(monitor, scene_depth):
    data = json.loads(json.dumps(monitor.step(scene_depth, PEDESTRIAN).to_dict()))
    assert data["status"] == OK and len(data["P"]) == 1 and set(data["timings_ms"]) == {
        "retrieval", "projection", "alignment", "inference"}


def test_monitor_refuses_a_rule_base_without_iou_and_rdd(prior):
    other = fuzzcore.FuzzySystem(
        "x", (fuzzcore.Variable("a", (0, 1), (fuzzcore.Term("t", "trimf", (0, 0.5, 1)),)),),
        (fuzzcore.Variable("risk", (0, 1), (fuzzcore.Term("t", "trimf", (0, 0.5, 1)),)),),
        (fuzzcore.Rule((1,), (1,)),))
    with pytest.raises(ValueError, match="inputs iou and rdd"):
        RiskMonitor(other, prior, CAMERA)


# ----------------------------------------------------------------------------- config
def test_shipped_defaults_equal_the_code_defaults():
    # the YAML in the package and the dataclass defaults must not drift apart
    assert load_config() == MonitorConfig()


def test_user_config_overrides_and_refuses_unknown_keys(tmp_path):
    good = tmp_path / "good.yaml"
    good.write_text("alignment: {alpha: 0.5}\nshield: {threshold: 0.6, release: 0.4}\nmax_range: 30\n")
    config = load_config(good)
    assert (config.alpha, config.beta, config.shield.threshold, config.max_range) == (0.5, 0.2, 0.6, 30)
    assert config.retrieval.max_range == 30  # one range limit, everywhere
    for text, message in [("alignment: {gamma: 1}\n", "alignment.gamma"),
                          ("colour: red\n", "unknown key 'colour'"),
                          ("retrieval: {max_range: 5}\n", "retrieval.max_range"),
                          ("alignment: {alpha: 2}\n", "alpha"),
                          ("shield: {threshold: 0.3, release: 0.4}\n", "release")]:
        bad = tmp_path / "bad.yaml"
        bad.write_text(text)
        with pytest.raises(ValueError, match=message) as err:
            load_config(bad)
        assert str(bad) in str(err.value)


# ----------------------------------------------------------------------------- shield
def test_shield_threshold_as_in_the_paper():
    shield = Shield(threshold=0.5)
    decisions = [shield.update(r).engaged for r in (0.2, 0.5, 0.51, 0.49, 0.9, 0.1)]
    assert decisions == [False, False, True, False, True, False]


def test_shield_hysteresis_and_hold():
    shield = Shield(threshold=0.6, release=0.3, hold_frames=1, deceleration=2.5)
    risks = [0.7, 0.5, 0.35, 0.2, 0.2, 0.65, 0.1, 0.1]
    engaged = [shield.update(r).engaged for r in risks]
    # 0.7 engages; 0.5 and 0.35 stay engaged (above release 0.3); 0.2 releases (below 0.3,
    # 3 frames after the trigger > hold 1). 0.65 engages again; the first 0.1 is below release
    # but only 1 frame after the trigger (not > hold 1): still engaged; the second releases.
    assert engaged == [True, True, True, False, False, True, True, False]
    plain = Shield(deceleration=2.5)
    assert plain.update(0.9).deceleration == 2.5 and plain.update(0.0).deceleration == 0.0


def test_shield_treats_nan_as_danger():
    assert Shield().update(float("nan")).engaged
