"""The closed loop with traffic: stopping distances by hand, detected and unseen obstacles,
reproducibility, serial against parallel, and the measures on hand-made runs."""
import math
import re
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("highway_env", reason="the closed loop needs the 'sim' extra (highway-env)")

import fuzzcore  # noqa: E402
from monitor.cli.simulate import markdown  # noqa: E402
from monitor.config import ShieldConfig, load_config  # noqa: E402
from monitor.depth.prior import build_prior  # noqa: E402
from monitor.offline import safety_measures as sm  # noqa: E402
from monitor.offline.closed_loop import (  # noqa: E402
    BASELINE, FROM_ONSET, Driver, Perception, Run, driver_label, in_reach, required_gap, run_scenario,
    stopping_distance,
)
from monitor.offline.scenarios import ScenarioSpec, advance, build_world  # noqa: E402
from monitor.risk_monitor import RiskMonitor  # noqa: E402
from monitor.shipped import shipped_rules  # noqa: E402
from monitor.synthetic import generate_frames, get_condition  # noqa: E402
from monitor.synthetic.conditions import DETECTOR_CLASSES, DetectorClass  # noqa: E402
from monitor.synthetic.degrade import Detections  # noqa: E402
from monitor.synthetic.scene import EGO_HALF_WIDTH_M  # noqa: E402

NOMINAL = get_condition("nominal")
_EXACT_DETECTOR = replace(
    NOMINAL.detector, recall_max=1.0, recall_half_m=1e4, occlusion_power=0.0, min_visible_px=0.0,
    depth_rel0=0.0, depth_rel_per_m=0.0, lateral_rad=0.0, size_log_std=0.0, yaw_std=0.0, yaw_flip_prob=0.0,
    confusion_prob=0.0, fp_per_frame=0.0, tp_logit=10.0, score_logit_std=0.0)
#: a detector that reports every visible object where it is, with no false positives
SHARP = replace(NOMINAL, detector=_EXACT_DETECTOR)
#: a detector that reports nothing at all
BLIND = replace(NOMINAL, detector=replace(NOMINAL.detector, recall_max=0.0, fp_per_frame=0.0))


@pytest.fixture(scope="module")
def monitor(camera):
    prior = build_prior((f"{s}/{f.index}", f.depth_est) for s in (100000, 100001)
                        for f in generate_frames("nominal", s, n_frames=10, camera=camera)).mean()
    config = load_config()
    # half the image: the depth view's smallest box is half as many pixels
    paper = config.retrieval.paper
    config = replace(config, retrieval=replace(config.retrieval,
                                               paper=replace(paper, min_size=paper.min_size / 2)))
    return RiskMonitor(fuzzcore.load(shipped_rules()), prior, camera, config, explain=False)


@pytest.fixture(scope="module")
def perception(monitor):
    return Perception(monitor.camera)


def _rare_seed(regime: str, classes=("animal", "wheelchair")) -> int:
    """The first seed whose rare-object scenario has this speed regime and hazard class."""
    for seed in range(100):
        world = build_world(ScenarioSpec("rare-object", "nominal", seed))
        if world.regime == regime and world.hazard.actor.actor_class in classes:
            return seed
    raise AssertionError("no such seed in 0..99")


def test_stopping_distance_by_hand():
    # 10 m/s, 0.2 s reaction: 2 m; then 10^2 / (2 * 5) = 10 m of braking
    assert stopping_distance(10.0, 5.0, 0.2) == pytest.approx(12.0)
    assert required_gap(10.0, 5.0, 0.2) == pytest.approx(12.0, abs=1e-9)
    # a lead at 10 m/s braking at 10 m/s^2 covers 10^2 / 20 = 5 m; the ego needs 12: 7 m of gap
    assert required_gap(10.0, 5.0, 0.2, 10.0, 10.0) == pytest.approx(7.0, abs=1e-3)
    # a hazard as fast as the ego, never braking: the ego never gains on it
    assert required_gap(10.0, 5.0, 0.2, 10.0, 0.0) == 0.0


def test_driver_label_names_each_setting():
    assert driver_label(None) == BASELINE
    assert driver_label(ShieldConfig()) == "t0.30 r0.30 h5 p1.25 c2/3<0.30 n2.5 o0.8 k0.5 e6 m1 w1 u1"
    assert driver_label(ShieldConfig(confirm_edge=0.3, confirm_emerged=0.5, confirm_contact=0.4)) == \
        "t0.30 r0.30 h5 p1.25 c2/3<0.30 n2.5 g0.3 o0.5 k0.4 e6 m1 w1 u1"
    assert driver_label(ShieldConfig(walker_horizon=None)) == "t0.30 r0.30 h5 p1.25 c2/3<0.30 n2.5 o0.8 k0.5 e6 m1"
    assert driver_label(ShieldConfig(confirm_near_all=True)) == \
        "t0.30 r0.30 h5 p1.25 c2/3<0.30 n2.5/3 o0.8 k0.5 e6 m1 w1 u1"
    assert driver_label(ShieldConfig(confirm_near_all=True, confirm_contact=None)) == \
        "t0.30 r0.30 h5 p1.25 c2/3<0.30 n2.5 o0.8 e6 m1 w1 u1"
    assert driver_label(ShieldConfig(unseen_walkers=None)) == "t0.30 r0.30 h5 p1.25 c2/3<0.30 n2.5 o0.8 k0.5 e6 m1 w1"
    assert driver_label(ShieldConfig(threshold=0.5, release=0.4, hold_frames=0, path_half_width=None,
                                     walker_horizon=None)) == \
        "t0.50 r0.40 h0"


def test_advance_integrates_exactly():
    # 8 m/s braking at 6 m/s^2 in steps of 0.1 s: stops after 4/3 s, 8^2 / 12 = 5.333 m
    speed, distance = 8.0, 0.0
    for _ in range(20):
        step, speed = advance(speed, -6.0, 0.1, 8.0)
        distance += step
    assert speed == 0.0 and distance == pytest.approx(64.0 / 12.0, abs=1e-12)
    # 3 m/s accelerating at 1.5 m/s^2 to 4 m/s: 2/3 s at 3.5 m/s mean, then 1/3 s at 4 m/s
    assert advance(3.0, 1.5, 1.0, 4.0) == pytest.approx((3.5 * 2 / 3 + 4.0 / 3, 4.0))
    assert advance(5.0, 0.0, 0.5, 5.0) == (2.5, 5.0)


@pytest.fixture
def rare_objects_detected(monkeypatch):
    """The detector recalls animals, wheelchairs and debris like cars (recall factor 1)."""
    for name in ("animal", "wheelchair", "debris"):
        monkeypatch.setitem(DETECTOR_CLASSES, name, DetectorClass("pedestrian", 1.0, ("bicycle",)))


def _paper(monitor):
    """The paper's shield: the risk alone decides, above 0.5, no hold."""
    return replace(monitor.config.shield, threshold=0.5, release=0.5, path_half_width=None, hold_frames=0,
                   walker_horizon=None)


def test_always_detected_obstacle_no_collision_and_braking_distance(rare_objects_detected, perception, monitor):
    seed = _rare_seed("urban")
    spec = ScenarioSpec("rare-object", "nominal", seed)
    driver = Driver()
    # the default shield, and the paper's at 0.4, which brakes in pulses before the obstacle
    # is in the baseline's reach: the baseline sizes its reach on the speed its brake will act
    # at, so the pulses' release cannot make it late
    pulsing = replace(_paper(monitor), threshold=0.4, release=0.4)
    base, *shielded = run_scenario(spec, perception, monitor, [monitor.config.shield, pulsing], driver,
                                   condition=SHARP)
    assert base.outcome == "stopped" and all(r.outcome == "stopped" for r in shielded)
    # the baseline's brake goes on delay_steps frames after the frame it decided in; from that
    # frame it covers v * reaction + v^2 / (2 brake) to standstill
    h = base.history
    first = next(k for k, d in enumerate(h["decel"]) if d > 0)
    decided = first - driver.delay_steps
    v = h["speed"][decided]
    assert h["speed"][first] == v  # cruising until the brake acts
    travelled = h["gap"][decided] - base.final_gap
    assert travelled == pytest.approx(v * 0.2 + v * v / 12.0, abs=1e-9)
    assert base.final_gap > 0 and all(r.final_gap > 0 for r in shielded)
    # the hazard, reported in every frame from its onset to the baseline's stop
    assert base.onset["seen_frames"] == base.onset["frames"] == base.frames - round(base.onset["time"] / 0.1)


@pytest.mark.parametrize("lateral, predict_s, reached", [
    (None, 2.0, False),   # 2.7-3.3 m to the left, the corridor 1.25 m either side
    (-1.5, 2.0, True),    # 1 s to reach it (5 m at 5 m/s): its near side sweeps to 1.2 m
    (-1.4, 2.0, False),   # ... to 1.3 m
    (2.0, 2.0, False),    # walking away
    (-1.5, 0.5, False),   # swept over 0.5 s only: to 1.95 m
])
def test_in_reach_sweeps_a_detection_across_the_path_by_hand(lateral, predict_s, reached):
    # a 0.6 m box whose near side is 5 m ahead of the bumper; at 5 m/s the reach is
    # 5 * (0.2 + 0.1) + 5^2 / 12 + 2 = 5.58 m (reaction and one frame to confirm, brake 6)
    box = np.array([[3.8 + 5.0 + 0.3, 3.0, 0.5, 0.6, 0.6, 1.0, 0.0]])
    driver = Driver(predict_s=predict_s)
    speeds = None if lateral is None else np.array([lateral])
    assert in_reach(box, 5.0, driver, speeds) is reached
    assert not in_reach(box + [1.0, 0, 0, 0, 0, 0, 0], 5.0, driver, np.array([-3.0]))  # 6 m: out of reach


def test_a_walker_always_detected_the_planner_that_predicts_stops_for(perception):
    # a pedestrian stepping out, detected where it is in every frame it is visible: wherever
    # the baseline's own brake can stop short from the onset (the frames it takes to confirm
    # counted as reaction), the planner that sweeps each track across the path stops short;
    # braking only for what is in the corridor now comes too late where the walker enters it
    # less than a stopping distance ahead
    driver = Driver()
    avoidable = late = 0
    for seed in range(6):
        spec = ScenarioSpec("pedestrian", "nominal", seed)
        (now,) = run_scenario(spec, perception, None, driver=Driver(predict_s=0.0), condition=SHARP)
        (ahead,) = run_scenario(spec, perception, None, driver=driver, condition=SHARP)
        onset = ahead.onset
        need = required_gap(onset["speed"], driver.brake, driver.reaction + (driver.confirm_frames - 1) * driver.dt)
        if onset["gap"] > need:
            avoidable += 1
            assert not ahead.collided and ahead.outcome in ("stopped", "passed"), seed
            late += now.collided
    assert avoidable >= 4 and late >= 2


def test_a_walker_enters_the_path_when_its_side_crosses_the_ego_s_by_hand(perception):
    # no detection, no shield: the baseline drives on at its cruise speed while a pedestrian
    # steps out across its path (world frame: y to the right, the ego's centreline y = 0)
    for seed in range(4):
        spec = ScenarioSpec("pedestrian", "nominal", seed)
        world = build_world(spec)
        walker = world.hazard.actor
        (base,) = run_scenario(spec, perception, None, condition=BLIND)
        onset, entry = base.onset, base.onset["entry"]
        # frame k sees the walker moved in the frames before it that started at or after its start
        k = 0
        while walker.position[1] - 0.5 * walker.LENGTH - 0.1 * walker.walk_speed * max(0, k - math.ceil(
                walker.start / 0.1 - 1e-9)) >= EGO_HALF_WIDTH_M:
            k += 1
        assert entry["time"] == pytest.approx(0.1 * k), seed
        assert entry["gap"] == pytest.approx(onset["gap"] - base.cruise * (entry["time"] - onset["time"])), seed
        assert entry["speed"] == base.cruise
        assert entry["required"] == pytest.approx(stopping_distance(base.cruise, 3.0, 0.2))
        assert entry["avoidable"] == (entry["gap"] > entry["required"])


class _EveryOther(Perception):
    """The perception with the hazard's detection dropped in every other frame."""

    def __init__(self, camera):
        super().__init__(camera)
        self.frames = 0

    def frame(self, world, condition, seeds):
        frame = super().frame(world, condition, seeds)
        self.frames += 1
        if self.frames % 2:
            dets = frame.detections
            k = dets.source != frame.hazard_row
            frame = frame._replace(detections=Detections(dets.boxes3d[k], dets.classes[k], dets.scores[k],
                                                         dets.source[k]))
        return frame


def test_a_walker_detected_in_every_other_frame_the_planner_follows_its_track(monitor):
    # a pedestrian stepping out, detected where it is but only in every other frame: the
    # planner counts a track that had a lateral speed at its predicted centre in the frames
    # the detector misses (Tracker.coasting), so its count of frames in reach goes on; it
    # stops for 6 of the 10 the baseline's brake could stop for from the onset (counting
    # only each frame's detections, 1 of them)
    driver = Driver()
    avoidable = stopped = 0
    for seed in range(12):
        (run,) = run_scenario(ScenarioSpec("pedestrian", "nominal", seed), _EveryOther(monitor.camera), None,
                              driver=driver, condition=SHARP)
        onset = run.onset
        need = required_gap(onset["speed"], driver.brake, driver.reaction + (driver.confirm_frames - 1) * driver.dt)
        if onset["gap"] > need:
            avoidable += 1
            stopped += not run.collided
    assert avoidable == 10 and stopped >= 5


def test_the_walker_gate_brakes_for_a_walker_the_detector_reports_before_she_steps_in(perception, monitor):
    # a detector that reports every walker where she is and a planner that brakes only for
    # what stands in its path now (no prediction): it hits the walker where she steps in
    # less than a stopping distance ahead, and so does the shield without its walker gate
    # (the detector covers her: nothing is unseen). With the gate the shield engages for her
    # before she enters the path, and stops short wherever the gap then allows a stop at the
    # emergency deceleration after the reaction time
    driver = Driver(predict_s=0.0)
    watching = monitor.config.shield  # the shipped shield watches walkers within 1 s
    assert watching.walker_horizon == 1.0
    blind = replace(watching, walker_horizon=None)
    hits = room = 0
    for seed in range(7):
        spec = ScenarioSpec("pedestrian", "nominal", seed)
        base, plain, gated = run_scenario(spec, perception, monitor, [blind, watching],
                                          driver=driver, condition=SHARP)
        if not base.collided:
            continue
        hits += 1
        assert plain.collided, seed
        walker = [e for e in gated.engagements if e["cause"] == "walker"]
        assert walker and walker[0]["time"] < base.onset["entry"]["time"], seed
        # where she stood then, and what the frame shows there (her, or the car she steps out behind)
        assert len(walker[0]["on"]) == len(walker[0]["objects"]) >= 1, seed
        k = gated.history["time"].index(walker[0]["time"])
        if gated.history["gap"][k] > required_gap(gated.history["speed"][k], 6.0, driver.reaction):
            room += 1
            assert not gated.collided, seed
    assert hits >= 5 and room >= 4


def test_unseen_walkers_brake_for_a_walker_only_the_depth_view_sees_before_she_steps_in(perception, monitor,
                                                                                        monkeypatch):
    # the sharp detector blind to pedestrians, and the planner without prediction: the walker
    # gate has nothing to follow, and the shield brakes for her once she is in the path. With
    # unseen walkers it follows the depth view's sighting of her beside the path and engages
    # before she enters it, and stops short wherever the gap then allows a stop at the
    # emergency deceleration after the reaction time. Most often the view does not show her
    # unseen beside the path: the box of the parked car she steps out behind covers her in the
    # image (seeds 0-7 here: once)
    monkeypatch.setitem(DETECTOR_CLASSES, "pedestrian", DetectorClass("pedestrian", 0.0, ()))
    driver = Driver(predict_s=0.0)
    sees = monitor.config.shield  # the shipped shield follows unseen walkers up to 1 m wide
    assert sees.unseen_walkers == 1.0
    hits = early = room = 0
    for seed in range(8):
        spec = ScenarioSpec("pedestrian", "nominal", seed)
        base, plain, seeing = run_scenario(spec, perception, monitor, [replace(sees, unseen_walkers=None), sees],
                                           driver=driver, condition=SHARP)
        if not base.collided:
            continue
        hits += 1
        entry = base.onset["entry"]["time"]
        assert not [e for e in plain.engagements if e["cause"] in ("walker", "unseen walker")], seed
        walker = [e for e in seeing.engagements if e["cause"] == "unseen walker"]
        if not (walker and walker[0]["time"] < entry):
            continue
        early += 1
        assert walker[0]["on"] == ["pedestrian"], seed  # what the view saw there: her
        # earlier than the shield without the option engaged, for her or anything else
        assert all(e["time"] > walker[0]["time"] for e in plain.engagements), seed
        k = seeing.history["time"].index(walker[0]["time"])
        if seeing.history["gap"][k] > required_gap(seeing.history["speed"][k], 6.0, driver.reaction):
            room += 1
            assert not seeing.collided, seed
    assert hits >= 5 and early >= 1 and room >= 1, (hits, early, room)


def test_unseen_obstacle_baseline_collides_shield_stops(perception, monitor):
    seed = _rare_seed("parking")
    spec = ScenarioSpec("rare-object", "nominal", seed)
    every = replace(monitor.config.shield, confirm_width=None)  # every object confirmed first
    base, shielded, confirming = run_scenario(spec, perception, monitor, [monitor.config.shield, every],
                                              condition=BLIND)
    assert base.collided and base.braking_frames == 0
    assert base.impact_speed == pytest.approx(base.cruise)  # nothing braked it
    obstacle = build_world(spec).hazard.actor  # the same scenario built again: what the runs record
    assert base.hazard == shielded.hazard == {"class": obstacle.actor_class,
                                              "size": [obstacle.WIDTH, obstacle.LENGTH, obstacle.height]}
    assert base.hazard["class"] in ("animal", "debris", "wheelchair")
    assert base.onset is not None and base.onset["avoidable"]
    assert base.onset["seen_frames"] == 0 and base.onset["frames"] == base.frames - round(base.onset["time"] / 0.1)
    assert not shielded.collided and shielded.engaged_frames > 0 and shielded.final_gap > 0
    # it stands in the ego's lane: in the path from its onset
    assert base.onset["entry"] == {k: base.onset[k] for k in ("time", "gap", "speed", "required", "avoidable")}
    # the obstacle stands where it stood, seen before it came within reach: confirmed by then
    # (here in the same frame), at most two frames later, and avoided
    first = [r.history["engaged"].index(True) for r in (shielded, confirming)]
    assert not confirming.collided and first[0] <= first[1] <= first[0] + 2


def test_the_emergency_stage_stops_where_the_gentle_one_cannot(perception, monitor):
    # unseen animals and wheelchairs at urban speed (seeds 0-14): when one first comes within
    # the monitor's range, the gap is about 17 m, less than 3 m/s^2 needs at 10-13 m/s after
    # the reaction time and more than 6 m/s^2 needs. The staged shield stops for every one
    # whose gap 6 m/s^2 allows; the one-stage shield, braking at 3 m/s^2, hits at least 3
    one = replace(monitor.config.shield, emergency=None)
    room = gentle_hits = 0
    for seed in range(15):
        spec = ScenarioSpec("rare-object", "nominal", seed)
        world = build_world(spec)
        if world.regime != "urban" or world.hazard.actor.actor_class not in ("animal", "wheelchair"):
            continue
        base, staged, gentle = run_scenario(spec, perception, monitor, [monitor.config.shield, one],
                                            condition=BLIND)
        assert base.collided and max(gentle.history["decel"]) == 3.0
        if base.onset["gap"] > required_gap(base.onset["speed"], 6.0, 0.2):
            room += 1
            assert not staged.collided and max(staged.history["decel"]) == 6.0, seed
            gentle_hits += gentle.collided
    assert room >= 6 and gentle_hits >= 3


def test_the_path_gated_shield_stops_for_the_unseen_obstacle_and_not_for_unseen_traffic(perception, monitor):
    paper = _paper(monitor)
    gated = replace(paper, path_half_width=1.25)
    # the same blind detector and obstacle: the obstacle stands in the path, the gate opens
    spec = ScenarioSpec("rare-object", "nominal", _rare_seed("parking"))
    base, shielded = run_scenario(spec, perception, monitor, [gated], condition=BLIND)
    assert base.collided and not shielded.collided and shielded.engaged_frames > 0
    assert shielded.driver.endswith(" p1.25 c2/3<0.30 n2.5 o0.8 k0.5 e6 m1")
    # each engagement says why: the first for an unseen object in the path, where the
    # obstacle stood then (the frame's hazard gap is measured from the ego's front, x from
    # its origin 3.8 m behind); the baseline has none
    assert base.engagements == []
    first = shielded.engagements[0]
    k = shielded.history["time"].index(first["time"])
    assert shielded.history["engaged"][k] and (k == 0 or not shielded.history["engaged"][k - 1])
    assert first["cause"] in ("at once", "confirmed") and first["deceleration"] in (3.0, 6.0)
    assert first["speed"] == shielded.history["speed"][k]
    gap = shielded.history["gap"][k]
    assert any(abs(x - 3.8 - gap) < 1.5 and y_min <= 1.25 and y_max >= -1.25 for x, y_min, y_max in first["objects"])
    # and what it lay on, looked up in the frame's ground truth: the obstacle
    assert len(first["on"]) == len(first["objects"])
    assert shielded.hazard["class"] in [on for (x, _, _), on in zip(first["objects"], first["on"])
                                        if abs(x - 3.8 - gap) < 1.5]
    onsets = sum(e and not (j and shielded.history["engaged"][j - 1]) for j, e in enumerate(shielded.history["engaged"]))
    assert len(shielded.engagements) == onsets
    # a hazard-free drive with the blind detector: the risk is the rule base's worst whenever
    # traffic is in view. The paper's shield brakes in every frame and never arrives; the
    # gated one brakes only while something stands in the path within reach (a quarter of
    # the frames here) and arrives
    drive = ScenarioSpec("hazard-free", "nominal", 0)
    base, alone, path, late = run_scenario(drive, perception, monitor, [paper, gated], condition=BLIND,
                                           from_onset=True)
    assert alone.engaged_frames == alone.frames and alone.outcome == "timeout"
    assert path.outcome == "arrived" and 0 < path.engaged_frames < 0.5 * path.frames
    # without a hazard there is no onset: the paper's shield switched on there never is
    assert {**late.to_dict(), "driver": BASELINE} == base.to_dict()


def test_a_shield_switched_on_at_the_onset_drives_as_the_baseline_before_it(perception, monitor, monkeypatch):
    # a blind detector: the gated shield brakes for traffic it cannot see at 2.0 s, before the
    # walker (seed 0) comes into view at 2.2 s
    spec = ScenarioSpec("pedestrian", "nominal", 0)
    asked = []  # per call, how many frames before it emerged was given
    emerged = monitor.emerged
    monkeypatch.setattr(monitor, "emerged", lambda report, before: asked.append(len(before)) or emerged(report, before))
    base, shielded, late = run_scenario(spec, perception, monitor, [monitor.config.shield], condition=BLIND,
                                        from_onset=True)
    assert late.driver == shielded.driver + FROM_ONSET and late.onset == base.onset
    k = base.history["time"].index(base.onset["time"])
    assert shielded.engagements[0]["time"] < base.onset["time"] and any(shielded.history["engaged"][:k])
    # before the onset: the baseline's drive, no risk, nothing engaged
    for key in ("time", "speed", "gap", "decel"):
        assert late.history[key][:k] == base.history[key][:k], key
    assert not any(late.history["engaged"][:k]) and np.isnan(late.history["risk"][:k]).all()
    # from the onset on its shield decides, afresh
    assert not np.isnan(late.history["risk"][k:]).any()
    assert late.engagements and late.engagements[0]["time"] >= base.onset["time"]
    assert late.engaged_frames == sum(late.history["engaged"]) > 0
    # the monitor ran where a shield decided: before the onset in one branch a frame (the one
    # all shared, then the shield's once it braked); from the onset in two, the switched-on
    # shield's knowing none of the frames before it
    assert asked[:k] == [0, 1] + [2] * (k - 2)
    assert sorted(asked[k:k + 2]) == [0, 2] and sorted(asked[k + 2:k + 4]) == [1, 2]
    with pytest.raises(ValueError, match="from_onset needs a shield setting"):
        run_scenario(spec, perception, monitor, [], from_onset=True)


def test_seeds_reproduce_and_differ(perception, monitor):
    spec = ScenarioSpec("cut-in", "rain", 3)
    first = [r.to_dict() for r in run_scenario(spec, perception, monitor, [monitor.config.shield])]
    again = [r.to_dict() for r in run_scenario(spec, perception, monitor, [monitor.config.shield])]
    assert first == again
    other = [r.to_dict() for r in run_scenario(replace(spec, seed=4), perception, monitor, [monitor.config.shield])]
    assert other[0]["history"] != first[0]["history"]


def test_branches_equal_separate_runs(perception, monitor):
    """Drivers sharing a world until they part give the runs they give alone."""
    spec = ScenarioSpec("lead-brake", "nominal", 5)
    strict = replace(monitor.config.shield, threshold=0.8, release=0.8)
    together = run_scenario(spec, perception, monitor, [monitor.config.shield, strict])
    alone = run_scenario(spec, perception, monitor, [strict])
    assert together[2].to_dict() == alone[1].to_dict()
    assert together[0].to_dict() == alone[0].to_dict()


def _run(kind, seed, driver, outcome="stopped", avoidable=True, trip=float("nan"), frames=10, braking=0,
         engaged=0, impact=0.0, seen=0, in_path=True, what="debris", causes=(), first=((), ())):
    hazard = None if kind == "hazard-free" else {"class": what, "size": [0.6, 0.6, 0.3]}
    engagements = [{"cause": c, "objects": [], "on": []} for c in causes]
    if engagements:  # the first one's objects and what they lay on
        engagements[0].update(objects=list(first[0]), on=list(first[1]))
    run = Run(kind, "nominal", seed, driver, "urban", 10.0, outcome=outcome, hazard=hazard, impact_speed=impact,
              trip_time=trip, frames=frames, braking_frames=braking, engaged_frames=engaged,
              engagements=engagements)
    run.onset = {"time": 1.0, "speed": 10.0, "avoidable": avoidable, "frames": 6, "seen_frames": seen,
                 "entry": {"avoidable": in_path}}
    return run


def test_measures_by_hand():
    shield = "t0.50 r0.50 h0"
    late = shield + FROM_ONSET
    runs = [
        # 4 hazard scenarios: baseline hits 3 (2 avoidable), the shield avoids 2 and hits 1 at 4 m/s
        # seeds 0 and 2 are animals, 1 and 3 debris. Switched on at the onset, the shield hits
        # seed 0's animal (it avoided it for having braked before) and stops for seed 1's debris
        _run("rare-object", 0, BASELINE, "collision", impact=10.0, what="animal"),
        _run("rare-object", 0, shield, what="animal"), _run("rare-object", 0, late, "collision", what="animal"),
        # seed 1's hazard the detector reported in 3 of the 6 frames from its onset: seen; it
        # could no longer be avoided once it entered the path
        _run("rare-object", 1, BASELINE, "collision", impact=8.0, seen=3, in_path=False),
        _run("rare-object", 1, shield, "collision", impact=4.0), _run("rare-object", 1, late),
        _run("rare-object", 2, BASELINE, "collision", avoidable=False, impact=9.0, what="animal"),
        _run("rare-object", 2, shield, what="animal"), _run("rare-object", 2, late, what="animal"),
        _run("rare-object", 3, BASELINE), _run("rare-object", 3, shield), _run("rare-object", 3, late),
        # 3 drives: the shield brakes in two (trip 12 s instead of 10 s: +20 %; and +0 %), the
        # first engaged at once (by two objects: on a car 8 m ahead, on the road 6 m ahead), then
        # once confirmed, the second first in a frame without a view (no object)
        _run("hazard-free", 0, BASELINE, "arrived", trip=10.0), _run("hazard-free", 0, shield, "arrived", trip=12.0,
                                                                     braking=5, engaged=4,
                                                                     causes=("at once", "confirmed"),
                                                                     first=([[8.0, -0.5, 0.5], [6.0, 0.2, 0.6]],
                                                                            ["car", "road"])),
        _run("hazard-free", 1, BASELINE, "arrived", trip=10.0), _run("hazard-free", 1, shield, "arrived", trip=10.0),
        _run("hazard-free", 2, BASELINE, "arrived", trip=10.0), _run("hazard-free", 2, shield, "arrived", trip=10.0,
                                                                     engaged=1, causes=("no view",)),
    ]
    s = sm.summarise(runs, shield)
    h = s["by_kind"]["rare-object"]
    assert (h["baseline_collisions"], h["shielded_collisions"]) == (3, 1)
    assert h["avoidance_rate"] == pytest.approx(2 / 3)
    assert h["avoidance_rate_avoidable"] == pytest.approx(1 / 2)  # seeds 0 and 1, seed 0 avoided
    # switched on at the onset: seed 1 of the two avoidable ones avoided
    assert h["avoidance_rate_avoidable_from_onset"] == pytest.approx(1 / 2)
    assert h["avoidance_rate_avoidable_from_onset_interval"] == sm.wilson_interval(1, 2)
    table = markdown({**s, "command": "fuzzrisk simulate"}, [], shield, 7, 1.0, 1, None)
    assert "## Hazards (baseline collisions" in table and "## Hazard-free drives" in table
    assert re.search(r"\| rare-object \| all \| 4 \| 75% \| 25% \| 67% \| 50% of 2 \[\d+%, \d+%\] \| "
                     r"50% \[\d+%, \d+%\] \| ", table)
    assert (h["avoidable_missed_collisions"], h["avoidance_rate_avoidable_missed"]) == (1, 1.0)  # seed 0
    assert (h["avoidable_in_path_collisions"], h["avoidance_rate_avoidable_in_path"]) == (1, 1.0)  # seed 0
    assert h["avoidance_rate_avoidable_in_path_interval"] == sm.wilson_interval(1, 1)
    assert h["avoidance_rate_unavoidable"] == 1.0 and h["impact_speed_shielded"] == 4.0
    # by the hazard's class: the animals' avoidable collision (seed 0) avoided, the debris' (seed 1) not
    animal, debris = s["by_hazard"]["animal"], s["by_hazard"]["debris"]
    assert list(s["by_hazard"]) == ["animal", "debris"]
    assert (animal["runs"], animal["baseline_collisions"], animal["unavoidable_collisions"]) == (2, 2, 1)
    assert (animal["avoidable_collisions"], animal["avoidance_rate_avoidable"]) == (1, 1.0)
    assert (debris["runs"], debris["avoidable_collisions"], debris["avoidance_rate_avoidable"]) == (2, 1, 0.0)
    assert (animal["avoidance_rate_avoidable_from_onset"], debris["avoidance_rate_avoidable_from_onset"]) == (0.0, 1.0)
    a = s["by_kind"]["hazard-free"]
    assert a["false_brake_rate"] == pytest.approx(2 / 3) and a["added_trip_time"] == pytest.approx(0.2 / 3)
    assert a["braking_share"] == pytest.approx(5 / 30)
    assert list(a["first_engagement"].items()) == [("no view", 1), ("at once", 1)]  # in CAUSES' order
    assert a["first_engaged_on"] == {"road": 1}  # the nearest of the first engagement's objects
    g = s["overall"]["guerin"]
    # hazard: baseline 3 / 7 runs, shield 1 / 7; reward 1/trip: mean(1/12, 1/10, 1/10) vs 1/10
    assert g["safety_gain"] == pytest.approx(2 / 7) and g["residual_hazard"] == pytest.approx(1 / 7)
    assert g["availability_cost"] == pytest.approx(1 - (1 / 12 + 2 / 10) / 3 / (1 / 10))
    assert h["avoidance_rate_avoidable_interval"] == sm.wilson_interval(1, 2)
    assert h["avoidance_rate_avoidable_missed_interval"] == sm.wilson_interval(1, 1)
    assert a["false_brake_rate_interval"] == sm.wilson_interval(2, 3)
    # t interval of (0.2, 0.0, 0.0): mean 0.0667, s = 0.1155, t(0.975, 2 dof) = 4.3027
    lo, hi = a["added_trip_time_interval"]
    half = 4.3027 * 0.11547 / 3 ** 0.5
    assert (lo, hi) == pytest.approx((0.2 / 3 - half, 0.2 / 3 + half), abs=1e-4)
    with pytest.raises(ValueError, match="expected 'baseline'"):
        sm.pair_runs(runs[1:], shield)
    # without the drives from the onset the measure is not known; with some, every hazard needs one
    h = sm.summarise([r for r in runs if r.driver != late], shield)["overall"]["hazard"]
    assert math.isnan(h["avoidance_rate_avoidable_from_onset"])
    assert np.isnan(h["avoidance_rate_avoidable_from_onset_interval"]).all()
    assert h["avoidance_rate_avoidable"] == pytest.approx(1 / 2)
    with pytest.raises(ValueError, match=r"\('rare-object', 'nominal', 1\)\] have no drive of "
                                         r"'t0.50 r0.50 h0 from onset'"):
        sm.summarise([r for r in runs if not (r.driver == late and r.seed == 1)], shield)


@pytest.mark.parametrize("k, n, lo, hi", [  # Newcombe (1998), Table I, method 3 (Wilson's score)
    (81, 263, 0.2553, 0.3662), (15, 148, 0.0624, 0.1605), (0, 20, 0.0, 0.1611), (1, 29, 0.0061, 0.1718),
])
def test_wilson_interval_as_published(k, n, lo, hi):
    assert sm.wilson_interval(k, n) == pytest.approx((lo, hi), abs=5e-5)


def test_intervals_without_trials_are_undefined():
    assert all(math.isnan(v) for v in sm.wilson_interval(0, 0) + sm.mean_interval([0.3]))
