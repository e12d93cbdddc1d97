"""The RiskMonitor end to end on scenes with known answers, hostile frames, threads, warm-up."""
import json
import re
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np
import pytest

import fuzzcore
from monitor.geometry.camera import Camera, project_boxes
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from monitor.config import MonitorConfig, RetrievalConfig, RiskConfig, ShieldConfig
from monitor.depth.geometric import EMERGED_MARGIN, GeometricRetriever
from monitor.risk_monitor import (EMERGED_FRAMES, INVALID_INPUT, NO_OBJECTS, NO_VIEW, OK, STATUSES,
                                   InvalidFrameError, RiskMonitor, RiskReport, shift_earlier, unseen_emerged)
from monitor.shipped import shipped_rules
from monitor.synthetic import render_depth

CAMERA = Camera.nuscenes_front()
#: the paper's depth view (the default is the geometric one: its tests are below)
PAPER = replace(MonitorConfig(), retrieval=RetrievalConfig(method="paper"))
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
    return RiskMonitor(fis, prior, CAMERA, PAPER)


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
    assert report.status == NO_OBJECTS and report.risk == monitor.config.risk.no_objects
    assert np.isnan(report.iou) and "no safety-critical object" in report.reason


_H, _W = 900, 1600
_NAN_ROW = np.array([[np.nan, 0, 0, 1, 1, 1, 0]])
_GOOD = "good"  # stands for the valid input of the frame's other parts


def _ragged():
    return [[1.0, 2.0], [3.0]]


#: (depth, detections, scores, words of the reason); every one is a frame step must survive
HOSTILE = [
    # depth maps
    (np.full((_H, _W), np.nan, np.float32), _GOOD, None, "100.0% invalid"),
    (np.full((_H, _W), np.inf), _GOOD, None, "100.0% invalid"),
    (np.full((_H, _W), 1e300), _GOOD, None, "100.0% invalid"),  # beyond float32: inf
    (np.full((_H, _W), -1.0, np.float32), _GOOD, None, "100.0% invalid"),
    (np.zeros((_H, _W), np.float32), _GOOD, None, "100.0% invalid"),
    (np.ones((_H, _W), np.complex64), _GOOD, None, "depth has dtype complex64"),
    (np.full((_H, _W), "5.0"), _GOOD, None, "depth has dtype <U3"),
    (np.ones((_H, _W), np.int32), _GOOD, None, "depth has dtype int32"),
    (np.ones((_H, _W), bool), _GOOD, None, "depth has dtype bool"),
    (np.ma.masked_less(np.ones((_H, _W), np.float32), 0.5), _GOOD, None, "depth is a masked array"),
    (np.ones((90, 160), np.float32), _GOOD, None, "depth has shape (90, 160)"),
    (np.ones((_H, _W, 1), np.float32), _GOOD, None, "depth has shape (900, 1600, 1)"),
    (np.ones((0, 0), np.float32), _GOOD, None, "depth has shape (0, 0)"),
    (np.float32(5.0), _GOOD, None, "depth has shape ()"),
    (None, _GOOD, None, "depth has dtype object"),
    ("depth.png", _GOOD, None, "depth has dtype <U9"),
    (_ragged(), _GOOD, None, "depth is not an array of depths"),
    # detections
    (_GOOD, _NAN_ROW, None, "detections[0, 0] = nan"),
    (_GOOD, np.array([[5.0, 0, 0, 1, np.inf, 1, 0]]), None, "detections[0, 4] = inf"),
    (_GOOD, np.array([[5.0, 0, 0, 1e30, 1e30, 1e30, 0]]), None, "detections[0, 3] (w) = 1e+30: box sizes must be within 1000"),
    (_GOOD, np.array([[1e30, 0, 0, 1, 1, 1, 0]]), None, "detections[0, 0] (x) = 1e+30: centre coordinates must be within 100000"),
    (_GOOD, np.array([[5.0, 0, 0, 1, 0.0, 1, 0]]), None, "detections[0, 4] (l) = 0.0: box sizes must be > 0"),
    (_GOOD, np.array([[5.0, 0, 0, -1, 1, 1, 0]]), None, "detections[0, 3] (w) = -1.0"),
    (_GOOD, PEDESTRIAN.astype(complex), None, "detections has dtype complex128"),
    (_GOOD, PEDESTRIAN.astype(str), None, "detections has dtype <U"),
    (_GOOD, None, None, "detections has dtype object"),
    (_GOOD, np.ma.masked_array(PEDESTRIAN), None, "detections is a masked array"),
    (_GOOD, np.zeros((3, 5)), None, "detections has shape (3, 5)"),
    (_GOOD, PEDESTRIAN[0], None, "detections has shape (7,)"),
    (_GOOD, [], None, "detections has shape (0,)"),
    (_GOOD, _ragged(), None, "detections is not an array of numbers"),
    (_GOOD, PEDESTRIAN.astype(bool), None, "detections has dtype bool"),
    # scores
    (_GOOD, PEDESTRIAN, [0.5 + 0.5j], "scores has dtype complex128"),
    (_GOOD, PEDESTRIAN, [np.nan], "scores[0] = nan"),
    (_GOOD, PEDESTRIAN, [1.5], "scores[0] = 1.5, expected a score in [0, 1]"),
    (_GOOD, PEDESTRIAN, [-0.1], "scores[0] = -0.1"),
    (_GOOD, PEDESTRIAN, ["0.9"], "scores has dtype <U3"),
    (_GOOD, PEDESTRIAN, [0.9, 0.9], "scores has shape (2,), expected (1,)"),
    (_GOOD, PEDESTRIAN, 0.9, "scores has shape ()"),
    (_GOOD, PEDESTRIAN, np.ma.masked_array([0.9], mask=[True]), "scores is a masked array"),
    (_GOOD, PEDESTRIAN, [True], "scores has dtype bool"),
]


@pytest.mark.parametrize("depth, detections, scores, reason", HOSTILE)
def test_hostile_frames_give_the_fail_safe_not_an_exception(monitor, scene_depth, depth, detections, scores,
                                                            reason):
    depth = scene_depth if isinstance(depth, str) and depth == _GOOD else depth
    detections = PEDESTRIAN if isinstance(detections, str) and detections == _GOOD else detections
    report = monitor.step(depth, detections, scores)
    assert report.status == INVALID_INPUT and report.risk == 1.0
    assert reason in report.reason
    if "% invalid" in reason:  # judged by the retrieval, from the pixels
        return
    with pytest.raises(InvalidFrameError, match=re.escape(reason)):  # the rules, raised, for a caller that asks
        monitor.check_frame(depth, detections, scores)
    if not reason.startswith("depth"):
        with pytest.raises(InvalidFrameError, match=re.escape(reason)):
            monitor.project(detections, scores)


def test_a_valid_frame_passes_the_check_as_float32_and_kept_detections(monitor, scene_depth):
    depth, boxes = monitor.check_frame(scene_depth.astype(np.float64), np.vstack([PEDESTRIAN, PEDESTRIAN]),
                                       [0.9, 0.1])
    assert depth.dtype == np.float32 and depth.flags.c_contiguous
    np.testing.assert_array_equal(depth, scene_depth)
    np.testing.assert_array_equal(boxes, PEDESTRIAN)  # 0.1 < min_score 0.3: dropped
    # integer detections are real numbers: accepted
    assert monitor.step(scene_depth, np.zeros((0, 7), np.int64)).status == OK


def test_a_bug_in_a_stage_raises_instead_of_becoming_a_report(monitor, scene_depth, monkeypatch):
    import monitor.risk_monitor as module

    def broken(*args):
        raise ValueError("a bug")

    monkeypatch.setattr(module, "align", broken)
    with pytest.raises(ValueError, match="a bug"):
        monitor.step(scene_depth, PEDESTRIAN)


_SMALL = Camera(CAMERA.K * np.array([[0.1], [0.1], [1.0]]), 160, 90, CAMERA.cam_to_ego)


@pytest.fixture(scope="module")
def small_monitor(fis):
    depth = render_depth(_SMALL, np.zeros((0, 7))).depth
    prior = (1.0 / np.where(np.isfinite(depth), depth, FAR_M)).astype(np.float32)
    retrieval = PAPER.retrieval
    return RiskMonitor(fis, prior, _SMALL, replace(PAPER, retrieval=replace(
        retrieval, paper=replace(retrieval.paper, min_size=4.0))))


_floats = st.floats(allow_nan=True, allow_infinity=True, width=64)
_depths = st.one_of(
    hnp.arrays(st.sampled_from([np.float32, np.float64, np.float16]), st.just((90, 160)),
               elements=st.one_of(st.floats(-1e3, 1e3, width=16), st.sampled_from([np.nan, np.inf, 0.0]))),
    hnp.arrays(hnp.scalar_dtypes(), hnp.array_shapes(min_dims=0, max_dims=3, max_side=4)),
)
_detections = st.one_of(
    hnp.arrays(np.float64, st.tuples(st.integers(0, 4), st.just(7)), elements=_floats),
    hnp.arrays(np.float64, st.tuples(st.integers(0, 4), st.just(7)), elements=st.floats(-60, 60)),
    hnp.arrays(hnp.scalar_dtypes(), hnp.array_shapes(min_dims=0, max_dims=3, max_side=8)),
)


@settings(max_examples=60, deadline=None)
@given(_depths, _detections, st.one_of(st.none(), hnp.arrays(np.float64, st.integers(0, 4), elements=_floats)))
def test_random_frames_never_raise(small_monitor, depth, detections, scores):
    report = small_monitor.step(depth, detections, scores)
    assert report.status in STATUSES and 0.0 <= report.risk <= 1.0
    if report.status == INVALID_INPUT:
        assert report.reason and report.risk == small_monitor.config.risk.fail_safe


def _frames():
    """Frames with known, different answers: pedestrians detected, missed, misplaced; empty road."""
    frames = []
    for k, x in enumerate([7.0, 9.0, 11.0, 13.0]):
        person = np.array([[x, 0.8 - 0.5 * k, 0.9, 0.7, 0.7, 1.8, 0.0]])
        depth = _depth(person)
        frames += [(depth, person), (depth, np.zeros((0, 7))), (depth, person + [[3.0, 1.5, 0, 0, 0, 0, 0]])]
    frames.append((_depth(np.zeros((0, 7))), np.zeros((0, 7))))
    return frames


def _summary(report):
    return report.status, report.risk, report.S.tobytes(), report.P.tobytes(), report.reason


def test_threads_give_the_single_threaded_reports(monitor):
    frames = _frames()
    expected = [_summary(monitor.step(d, p)) for d, p in frames]
    assert len({e[1] for e in expected}) >= 4 and {e[0] for e in expected} == {OK, NO_OBJECTS}
    order = [k % len(frames) for k in range(120)]
    with ThreadPoolExecutor(max_workers=4) as pool:
        got = list(pool.map(lambda k: _summary(monitor.step(*frames[k])), order))
    assert [g for g in got] == [expected[k] for k in order]


_FIRST_FRAME = textwrap.dedent("""
    import json, sys
    import numpy as np
    import fuzzcore
    from fuzzcore import _kernels
    from dataclasses import replace
    from monitor.config import MonitorConfig, RetrievalConfig
    from monitor.depth import _geometric_kernels, _retrieval_kernels
    from monitor.geometry import _box_kernels, _camera_kernels
    from monitor.geometry.camera import Camera
    from monitor.risk_monitor import RiskMonitor
    from monitor.shipped import shipped_rules
    from monitor.synthetic import render_depth

    camera = Camera.nuscenes_front()
    empty = render_depth(camera, np.zeros((0, 7))).depth
    prior = (1.0 / np.where(np.isfinite(empty), empty, 80.0)).astype(np.float32)
    person = np.array([[9.0, 0.8, 0.9, 0.7, 0.7, 1.8, 0.0]])
    depth = render_depth(camera, person).depth
    depth = np.where(np.isfinite(depth), depth, 80.0).astype(np.float32)
    config = replace(MonitorConfig(), retrieval=RetrievalConfig(method=sys.argv[2]))
    monitor = RiskMonitor(fuzzcore.load(shipped_rules()), prior, camera, config,
                          warmup=sys.argv[1] == "warm")

    def signatures():
        modules = (_kernels, _retrieval_kernels, _geometric_kernels, _box_kernels, _camera_kernels)
        return {f"{m.__name__}.{n}": len(d.signatures) for m in modules for n, d in vars(m).items()
                if hasattr(d, "signatures")}

    before = signatures()
    reports = [monitor.step(depth, person), monitor.step(depth, np.zeros((0, 7)))]
    after = signatures()
    print(json.dumps({"status": [r.status for r in reports],
                      "compiled": sorted(k for k in after if after[k] != before[k])}))
""")


@pytest.mark.parametrize("mode, method", [("warm", "paper"), ("cold", "paper"), ("warm", "geometric"),
                                          ("cold", "geometric")])
def test_the_first_step_after_construction_compiles_nothing(mode, method):
    # a fresh process: kernels other tests compiled in this one would hide a missing warm-up
    out = subprocess.run([sys.executable, "-c", _FIRST_FRAME, mode, method], capture_output=True,
                         text=True, check=True).stdout
    result = json.loads(out.strip().splitlines()[-1])
    assert result["status"] == [OK, OK]  # every stage ran: retrieval, projection, alignment, rules
    if mode == "warm":
        assert result["compiled"] == []
    else:  # without warmup the same frames compile (or load) kernels inside step: the test can fail
        kernels = {"paper": "_retrieval_kernels", "geometric": "_geometric_kernels"}[method]
        assert any(kernels in k for k in result["compiled"])
        assert any("_box_kernels" in k for k in result["compiled"])


def test_fail_safe_is_configurable(fis, prior):
    config = replace(PAPER, risk=RiskConfig(fail_safe=0.9))
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


# --------------------------------------------------------------------------- the geometric view

@pytest.fixture(scope="module")
def geometric_monitor(fis, prior):
    config = replace(MonitorConfig(), retrieval=RetrievalConfig(method="geometric"))
    return RiskMonitor(fis, prior, CAMERA, config)


@pytest.fixture(scope="module")
def emerging_monitor(fis, prior):
    """The geometric view for a shield that confirms what came out of the road."""
    config = MonitorConfig(retrieval=RetrievalConfig(method="geometric"), shield=ShieldConfig(confirm_emerged=0.5))
    return RiskMonitor(fis, prior, CAMERA, config)


def test_the_geometric_view_sees_the_pedestrian_where_the_detector_does(geometric_monitor, fis,
                                                                         scene_depth):
    report = geometric_monitor.step(scene_depth, PEDESTRIAN)
    assert report.status == OK and len(report.S) == 1 and len(report.P) == 1
    # the pedestrian's front face is 9 - 0.35 - 1.70 = 6.95 m from the camera in both views;
    # S lacks the bottom 0.2 m of the 1.8 m (the height band): IoU about 1.6 / 1.8
    assert report.S[0, 4] == pytest.approx(report.P[0, 4], rel=1e-3)
    assert report.iou > 0.8 and abs(report.rdd) < 0.01
    assert report.risk == pytest.approx(fis.infer(iou=report.iou, rdd=report.rdd), abs=0)
    missed = geometric_monitor.step(scene_depth, np.zeros((0, 7)))
    assert missed.status == OK and missed.iou == 0.0 and missed.rdd == 1.0


def test_the_geometric_view_ignores_a_wall_beside_the_road(geometric_monitor, monitor):
    wall = np.array([[15.0, 6.0, 2.0, 0.4, 30.0, 4.0, 0.0]])
    report = geometric_monitor.step(_depth(wall), np.zeros((0, 7)))
    assert report.status == NO_OBJECTS
    assert monitor.step(_depth(wall), np.zeros((0, 7))).status == OK  # the paper's view: an object


def test_no_objects_states_its_risk_and_the_geometric_view_its_free_distance(geometric_monitor, monitor):
    road = _depth(np.zeros((0, 7)))
    for mon in (geometric_monitor, monitor):
        report = mon.step(road, np.zeros((0, 7)))
        assert report.status == NO_OBJECTS and report.risk == mon.config.risk.no_objects
        assert f"risk.no_objects = {mon.config.risk.no_objects:g}" in report.reason
    assert geometric_monitor.step(road, np.zeros((0, 7))).free_distance == np.inf
    assert np.isnan(monitor.step(road, np.zeros((0, 7))).free_distance)  # the paper's view: unmeasured
    # with the pedestrian: its front face, 9 - 0.35 = 8.65 m ahead of the ego origin
    seen = geometric_monitor.step(_depth(PEDESTRIAN), PEDESTRIAN)
    assert seen.status == OK and seen.free_distance == pytest.approx(8.65, abs=0.01)
    assert seen.to_dict()["free_distance"] == seen.free_distance
    # strict JSON (no Infinity, no NaN) holds every case: measured, free to the range, unmeasured
    for report, stored in ((seen, seen.free_distance), (geometric_monitor.step(road, PEDESTRIAN), "inf"),
                           (monitor.step(road, PEDESTRIAN), None)):
        assert json.loads(json.dumps(report.to_dict(), allow_nan=False))["free_distance"] == stored


def test_a_surface_filling_the_view_is_a_near_object_to_the_geometric_view_and_no_view_to_the_paper(
        geometric_monitor, monitor):
    near = np.ones((CAMERA.height, CAMERA.width), dtype=np.float32)  # a surface 1 m ahead
    assert monitor.step(near, np.zeros((0, 7))).status == NO_VIEW  # the visibility check: blocked
    report = geometric_monitor.step(near, np.zeros((0, 7)))
    # the geometric view sees it (one object at 1 m), the hidden-region check alone is left
    assert report.status == OK and report.S.shape == (1, 5) and report.S[0, 4] == 1.0
    assert report.iou == 0.0 and report.rdd == 1.0  # undetected: the worst scores
    hidden = _depth(np.zeros((0, 7)))
    hidden[600:700, 700:800] = np.nan  # a 100 px square of invalid pixels in the lower half
    assert geometric_monitor.step(hidden, np.zeros((0, 7))).status == NO_VIEW


def test_a_frame_the_geometric_view_calls_blind_has_no_view(geometric_monitor, scene_depth):
    pitched = geometric_monitor.camera.cam_to_ego.copy()
    a = np.radians(-8.0)  # the camera pitched up by 8 degrees: the road reads under z = 0
    pitched[:3, :3] = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]) \
        @ pitched[:3, :3]
    depth = render_depth(Camera(CAMERA.K, CAMERA.width, CAMERA.height, pitched), PEDESTRIAN).depth
    depth = np.where(np.isfinite(depth), depth, FAR_M).astype(np.float32)
    report = geometric_monitor.step(depth, PEDESTRIAN)
    assert report.status == NO_VIEW and report.risk == geometric_monitor.config.risk.no_view
    assert "under the road plane" in report.reason and len(report.P) == 1 and len(report.S) == 0


def test_coverage_reads_a_detected_group_as_covered_where_pairs_read_a_miss(fis, prior):
    # four pedestrians abreast 9 m ahead, 0.05 m apart: the geometric view sees one object
    # (its ground grid's 0.3 m cells do not split them); the detector reports each one
    group = np.array([[9.0, y, 0.9, 0.7, 0.7, 1.8, 0.0] for y in (1.125, 0.375, -0.375, -1.125)])
    depth = _depth(group)
    covering = RiskMonitor(fis, prior, CAMERA, MonitorConfig())  # the shipped coverage matching
    report = covering.step(depth, group)
    assert report.status == OK and len(report.S) == 1 and len(report.P) == 4
    # the four detections fill the merged box but for the gaps and the 0.2 m under the
    # height band: covered, the boxes' depths agree, so "iou high, rdd medium -> risk low"
    assert report.iou > 0.9 and abs(report.rdd) < 0.01 and report.risk < 0.35
    # the paper's one-to-one pairs give the group one pedestrian's box: IoU about 1/4 < 0.3,
    # so the group counts as missed and, averaged over S as the paper does, the risk is the
    # rule base's worst
    paper = replace(MonitorConfig().alignment, matching="hungarian", beta=0.2, objects="depth")
    paired = RiskMonitor(fis, prior, CAMERA, replace(MonitorConfig(), alignment=paper)).step(depth, group)
    assert 0.2 < paired.alignment.pair_iou[0] < 0.3 and not paired.alignment.matched[0]
    assert paired.iou == 0.0 and paired.rdd == 1.0 and paired.risk > 0.75
    # over the known objects the same miss is one object in five (the four detections, none
    # partnering a counted S, score IoU 1 and RDD 0): IoU~ 4/5, RDD~ 1/5
    known = replace(MonitorConfig(), alignment=replace(paper, objects="known"))
    over_known = RiskMonitor(fis, prior, CAMERA, known).step(depth, group)
    assert over_known.iou == pytest.approx(0.8) and over_known.rdd == pytest.approx(0.2)


def test_unseen_says_where_the_objects_no_detection_covers_stand(geometric_monitor, monitor, scene_depth):
    # the pedestrian: x 9 -+ 0.35 (face at 8.65 m), y 0.8 -+ 0.35
    missed = geometric_monitor.step(scene_depth, np.zeros((0, 7)))
    assert missed.unseen.shape == (1, 3)
    x, y_min, y_max = missed.unseen[0]
    assert x == pytest.approx(8.65, abs=0.02) and 0.45 <= y_min < y_max <= 1.15 and y_max - y_min > 0.5
    seen = geometric_monitor.step(scene_depth, PEDESTRIAN)
    assert seen.status == OK and seen.unseen.shape == (0, 3)
    # the paper's view back-projects its boxes (Camera.ground_extents)
    paper = monitor.step(scene_depth, np.zeros((0, 7)))
    np.testing.assert_array_equal(paper.unseen, CAMERA.ground_extents(paper.S[~paper.alignment.matched]))
    # no view, no answer: the shield must not read "nothing unseen" into an invalid frame
    blind = geometric_monitor.step(np.full_like(scene_depth, np.nan), PEDESTRIAN)
    assert blind.unseen is None and blind.unseen_contact is None
    assert json.loads(json.dumps(missed.to_dict()))["unseen"] == missed.unseen.tolist()


def test_unseen_contact_is_the_views_contact_of_the_objects_no_detection_covers(geometric_monitor, monitor,
                                                                                 scene_depth):
    # the pedestrian stands on the road along her width (the view's rule 5 contact, 1.0)
    view = geometric_monitor._retriever.view(scene_depth)
    missed = geometric_monitor.step(scene_depth, np.zeros((0, 7)))
    np.testing.assert_array_equal(missed.unseen_contact, view.contact)
    assert missed.unseen_contact.tolist() == [1.0]
    assert geometric_monitor.step(scene_depth, PEDESTRIAN).unseen_contact.shape == (0,)
    # the paper's view does not measure it: NaN per unseen object, null in JSON
    paper = monitor.step(scene_depth, np.zeros((0, 7)))
    assert paper.unseen_contact.shape == (len(paper.unseen),) and np.isnan(paper.unseen_contact).all()
    assert json.loads(json.dumps(paper.to_dict()))["unseen_contact"] == [None] * len(paper.unseen)
    assert json.loads(json.dumps(missed.to_dict()))["unseen_contact"] == [1.0]


def test_emerged_measures_each_unseen_object_against_the_frames_before(emerging_monitor, geometric_monitor,
                                                                       monitor, scene_depth, fis, prior):
    none = np.zeros((0, 7))
    missed = emerging_monitor.step(scene_depth, none)
    road = emerging_monitor.step(_depth(none), none)
    # a frame 0.5 m back saw the pedestrian 0.5 m farther: her blocks, put back, land on her
    earlier = emerging_monitor.step(_depth(PEDESTRIAN + [0.5, 0, 0, 0, 0, 0, 0]), none)
    assert emerging_monitor.emerged(missed, [(earlier, 0.5)])[0] < 0.05
    # a frame that saw the empty road: the line of sight to one of her blocks, put back,
    # meets the ground (z = 0) where the camera reads the road, or at the far depth (80 m)
    # short of it, which the view takes for road while under min_height (0.2 m) above it;
    # the line of sight of a block above the camera's height meets the sky (but in a block of
    # the frame before that straddles the horizon, which reads its nearest depth: 0.05). A
    # block came out of the road where that road lies beyond it by more than the margin.
    centre = CAMERA.cam_to_ego[:3, 3]
    back = missed.unseen_points[0] + [0.5, 0.0, 0.0]
    under = back[:, 2] < centre[2]
    ground = centre + (back - centre) * (centre[2] / np.where(under, centre[2] - back[:, 2], np.nan))[:, None]
    read = np.minimum(CAMERA.ego_to_camera(np.nan_to_num(ground))[:, 2], FAR_M)
    read_height = centre[2] * (1.0 - read / CAMERA.ego_to_camera(np.nan_to_num(ground))[:, 2])
    beyond = read > CAMERA.ego_to_camera(back)[:, 2] * (1.0 + EMERGED_MARGIN)
    road_share = np.mean(under & (read_height < 0.2) & beyond)
    assert 0.2 < road_share
    assert emerging_monitor.emerged(missed, [(road, 0.5)])[0] == pytest.approx(road_share, abs=0.05)
    # the smallest share over the frames before: one that saw her is enough, in either place
    assert emerging_monitor.emerged(missed, [(road, 0.5), (earlier, 0.5)])[0] < 0.05
    assert emerging_monitor.emerged(missed, [(earlier, 0.5), (road, 1.0)])[0] < 0.05
    # ... of the first EMERGED_FRAMES (2) only
    assert emerging_monitor.emerged(missed, [(road, 0.5), (road, 1.0), (earlier, 0.5)])[0] == \
        pytest.approx(road_share, abs=0.05)
    # a detected pedestrian is not unseen: nothing to measure
    assert emerging_monitor.emerged(emerging_monitor.step(scene_depth, PEDESTRIAN), [(road, 0.5)]).shape == (0,)
    # not known: the first frame, frames before without a view
    assert np.isnan(emerging_monitor.emerged(missed, [])).all()
    blind = emerging_monitor.step(np.full_like(scene_depth, np.nan), none)
    assert blind.road_depth is None and np.isnan(emerging_monitor.emerged(missed, [(blind, 0.5)])).all()
    # a frame without a view has no unseen objects to measure: None, as its unseen
    assert emerging_monitor.emerged(blind, [(missed, 0.5)]) is None
    # the shipped config asks it
    shipped = geometric_monitor.step(scene_depth, none)
    assert geometric_monitor.emerged(shipped, [(road, 0.5)])[0] == pytest.approx(road_share, abs=0.05)
    # not given: a monitor whose shield does not ask keeps no blocks (its risk and unseen
    # objects the same), which a shield that asks refuses
    config = replace(geometric_monitor.config, shield=ShieldConfig(confirm_emerged=None))
    blockless = RiskMonitor(fis, prior, CAMERA, config)
    plain = blockless.step(scene_depth, none)
    assert plain.road_depth is None and plain.unseen_points == ()
    assert (plain.risk, plain.unseen.tolist()) == (missed.risk, missed.unseen.tolist())
    assert blockless.emerged(plain, [(blockless.step(_depth(none), none), 0.5)]) is None
    with pytest.raises(ValueError, match=r"earlier\[0\] is a RiskReport, expected a \(RiskReport, travel"):
        blockless.emerged(plain, [plain])
    # not measured: the paper's view does not see the road, NaN per unseen object
    paper = monitor.step(scene_depth, none)
    assert len(paper.unseen) > 0 and paper.road_depth is None
    shares = monitor.emerged(paper, [(monitor.step(scene_depth, none), 0.5)])
    assert shares.shape == (len(paper.unseen),) and np.isnan(shares).all()
    assert np.isnan(unseen_emerged(paper, [], None)).all()
    # a report without blocks cannot be measured with a view's retriever, and the geometric
    # view's road is not dropped for a missing retriever
    with pytest.raises(ValueError, match="report has 1 unseen objects and the blocks of 0: its monitor keeps"):
        unseen_emerged(plain, [(road, 0.5)], GeometricRetriever(CAMERA))
    with pytest.raises(ValueError, match=r"report carries the geometric view's road \(road_depth\): its "
                                         "emerged shares need that view's retriever, not None"):
        unseen_emerged(missed, [(road, 0.5)], None)
    with pytest.raises(ValueError, match=r"earlier\[0\] is a RiskReport, expected a \(RiskReport, travel"):
        emerging_monitor.emerged(missed, [road])
    with pytest.raises(ValueError, match="report is a dict, expected a RiskReport"):
        emerging_monitor.emerged({}, [])
    with pytest.raises(ValueError, match="travel = inf"):
        emerging_monitor.emerged(missed, [(road, float("inf"))])


def test_shift_earlier_adds_the_travel_and_keeps_the_last_frames():
    a, b, c = (RiskReport(risk=r, status=OK) for r in (0.1, 0.2, 0.3))
    start = []
    before, kept = shift_earlier(start, a, 0.4)  # the first frame: nothing before it
    assert before == [] and kept == [(a, 0.0)]
    before, kept = shift_earlier(kept, b, 0.5)
    assert before == [(a, 0.5)] and kept == [(b, 0.0), (a, 0.5)]
    before, kept = shift_earlier(kept, c, -0.25)  # backing
    assert before == [(b, -0.25), (a, 0.25)]
    assert kept == [(c, 0.0), (b, -0.25)] and len(kept) == EMERGED_FRAMES
    assert start == []  # new lists: a branching simulation may share them
