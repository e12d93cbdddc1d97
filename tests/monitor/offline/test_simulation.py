"""Closed-loop safeguarding: the baseline planner, and the shield against an unseen obstacle."""
from dataclasses import replace

import numpy as np
import pytest

import fuzzcore
from monitor.synthetic.suite import Benchmark
from monitor.risk_monitor import RiskMonitor
from monitor.shipped import shipped_rules
from monitor.offline.simulation import Scenario, planner_brakes, run_trial, summarise
from monitor.synthetic import get_condition
from monitor.synthetic.scene import EGO_FRONT_M

NOMINAL = get_condition("nominal")
#: a detector that never reports anything: the obstacle is unseen, no false positives either
BLIND = replace(NOMINAL, detector=replace(NOMINAL.detector, recall_max=0.0, fp_per_frame=0.0))


@pytest.fixture(scope="module")
def monitor():
    bench = Benchmark(conditions=("nominal",), prior_scenes=1, n_frames=6)
    return RiskMonitor(fuzzcore.load(shipped_rules()), bench.prior(), bench.camera, explain=False)


def test_planner_brakes_for_a_detection_within_stopping_distance():
    scenario = Scenario(speed=5.0, brake=5.0, margin=1.0)  # stopping distance 2.5 m, reach 3.5 m
    across = lambda gap, y=0.0: np.array([[EGO_FRONT_M + gap + 0.4, y, 0.7, 0.8, 2.0, 1.4, np.pi / 2]])
    assert planner_brakes(across(3.0), 5.0, scenario)           # 3.0 m ahead, inside 3.5 m
    assert not planner_brakes(across(4.0), 5.0, scenario)       # beyond the reach
    assert not planner_brakes(across(3.0, y=4.0), 5.0, scenario)  # beside the path
    assert not planner_brakes(np.zeros((0, 7)), 5.0, scenario)


def test_unseen_obstacle_baseline_collides_at_full_speed(monitor):
    scenario = Scenario(distance=12.0)
    trial = run_trial(scenario, BLIND, seed=3, camera=monitor.camera, monitor=None)
    # nothing detected, nothing braked: it arrives at its initial speed
    assert trial.collided and trial.impact_speed == scenario.speed and not any(trial.detected)
    assert trial.time[-1] == pytest.approx(0.1 * (len(trial.time) - 1))


def test_shield_stops_the_car_before_the_unseen_obstacle(monitor):
    scenario = Scenario(distance=12.0)
    trial = run_trial(scenario, BLIND, seed=3, camera=monitor.camera, monitor=monitor)
    assert not trial.collided and trial.speed[-1] >= 0 and trial.min_gap > 0
    # the depth view saw what the detector did not: risk above the threshold, shield on
    assert any(trial.shield_engaged) and max(trial.risk) > 0.5


def test_trials_reproduce_under_a_seed(monitor):
    a = run_trial(Scenario(distance=10.0), "rare", 5, monitor.camera, monitor)
    b = run_trial(Scenario(distance=10.0), "rare", 5, monitor.camera, monitor)
    assert a == b


def test_summary_counts():
    def t(collided):
        from monitor.offline.simulation import Trial
        return Trial(0, False, collided, 4.2 if collided else 0.0, 0.0)
    s = summarise([(t(True), t(False)), (t(True), t(True)), (t(False), t(False)), (t(False), t(True))])
    assert (s["baseline_collisions"], s["shielded_collisions"], s["shield_induced"]) == (2, 2, 1)
    assert s["avoidance_rate"] == 0.5 and s["mean_impact_speed_baseline"] == 4.2


def test_scenario_refuses_bad_values():
    with pytest.raises(ValueError, match="speed = -1"):
        Scenario(speed=-1)
