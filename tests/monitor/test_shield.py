"""The controller shield: the paper's threshold, hysteresis and hold, built from its config section."""
import numpy as np
import pytest

from monitor.config import ShieldConfig, load_config
from monitor.shield import Shield


def test_shield_threshold_as_in_the_paper():
    shield = Shield(ShieldConfig(threshold=0.5))
    decisions = [shield.update(r).engaged for r in (0.2, 0.5, 0.51, 0.49, 0.9, 0.1)]
    assert decisions == [False, False, True, False, True, False]


def test_shield_hysteresis_and_hold():
    shield = Shield(ShieldConfig(threshold=0.6, release=0.3, hold_frames=1, deceleration=2.5))
    risks = [0.7, 0.5, 0.35, 0.2, 0.2, 0.65, 0.1, 0.1]
    engaged = [shield.update(r).engaged for r in risks]
    # 0.7 engages; 0.5 and 0.35 stay engaged (above release 0.3); 0.2 releases (below 0.3,
    # 3 frames after the trigger > hold 1). 0.65 engages again; the first 0.1 is below release
    # but only 1 frame after the trigger (not > hold 1): still engaged; the second releases.
    assert engaged == [True, True, True, False, False, True, True, False]
    plain = Shield(ShieldConfig(deceleration=2.5))
    assert plain.update(0.9).deceleration == 2.5 and plain.update(0.0).deceleration == 0.0


def test_shield_from_the_configuration_section(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("shield: {threshold: 0.7, release: 0.2, hold_frames: 2}\n")
    shield = Shield(load_config(path).shield)
    assert shield.config == ShieldConfig(0.7, 0.2, 2, 3.0)
    assert Shield().config == load_config().shield


def test_shield_treats_nan_as_danger_and_takes_numpy_numbers():
    assert Shield().update(float("nan")).engaged
    assert Shield().update(np.float32(0.6)).engaged and not Shield().update(np.float64(0.4)).engaged
    held = Shield(ShieldConfig(hold_frames=np.int64(1)))
    assert [held.update(r).engaged for r in (0.9, 0.1, 0.1)] == [True, True, False]


@pytest.mark.parametrize("risk", [None, "0.7", b"0.7", True, 0.5 + 0.1j, [0.7]])
def test_update_refuses_what_is_not_a_risk(risk):
    with pytest.raises(ValueError, match=r"risk = .*expected a number \(a risk in \[0, 1\], or NaN\)"):
        Shield().update(risk)


@pytest.mark.parametrize("config", ["0.5", 0.5, {"threshold": 0.5}, None])
def test_shield_refuses_what_is_not_a_shield_config(config):
    with pytest.raises(ValueError, match="expected a ShieldConfig"):
        Shield(config)


# ------------------------------------------------------------------------- the path gate

GATED = ShieldConfig(threshold=0.5, deceleration=3.0, path_half_width=1.25, headway=0.5, margin=2.0,
                     front=3.8)


def test_reach_is_the_braking_distance_plus_headway_and_margin():
    # 10 m/s at 3 m/s^2: 100 / 6 = 16.67 m of braking, 0.5 s * 10 m/s = 5 m, 2 m margin
    assert Shield(GATED).reach(10.0) == pytest.approx(100 / 6 + 5.0 + 2.0)
    assert Shield(GATED).reach(0.0) == 2.0


@pytest.mark.parametrize("unseen, engaged", [
    # x of the nearest point (ego frame: the bumper is at 3.8 m), lateral span
    ([[3.8 + 23.0, -0.5, 0.5]], True),      # in the path, 23 m ahead of the bumper < 23.67 m
    ([[3.8 + 24.0, -0.5, 0.5]], False),     # beyond the reach
    ([[12.0, 1.3, 2.5]], False),            # beside the path: its near side at 1.3 m > 1.25 m
    ([[12.0, -2.5, -1.25]], True),          # its near side touches the path's edge
    ([[12.0, -4.0, 4.0]], True),            # spans the path
    ([[12.0, 2.0, 3.0], [12.0, 0.0, 0.4]], True),  # one of several
    (np.zeros((0, 3)), False),              # nothing unseen: high risk from elsewhere
    (None, True),                           # no view (invalid frame, blind view): not gated
])
def test_the_path_gate_engages_only_for_an_unseen_object_in_the_path_within_reach(unseen, engaged):
    shield = Shield(GATED)
    assert shield.update(0.8, 10.0, unseen).engaged is engaged
    # below the threshold nothing engages, whatever is unseen
    assert not Shield(GATED).update(0.4, 10.0, unseen).engaged
    # the paper's shield ignores the gate's inputs; NaN engages, gate or no gate
    assert Shield(ShieldConfig()).update(0.8, 10.0, unseen).engaged
    assert Shield(GATED).update(float("nan"), 10.0, unseen).engaged


def test_the_gated_shield_releases_when_the_object_leaves_the_path():
    shield = Shield(GATED)
    in_path, beside = np.array([[12.0, -0.3, 0.3]]), np.array([[12.0, 2.0, 3.0]])
    assert [shield.update(0.8, 8.0, u).engaged for u in (in_path, in_path, beside, in_path)] == \
        [True, True, False, True]


@pytest.mark.parametrize("speed, unseen, message", [
    (None, np.zeros((0, 3)), "needs the ego's speed"),
    (-1.0, np.zeros((0, 3)), "needs the ego's speed"),
    (float("nan"), np.zeros((0, 3)), "needs the ego's speed"),
    (5.0, np.zeros((2, 2)), r"unseen has shape \(2, 2\)"),
    (5.0, np.array([[np.nan, 0.0, 1.0]]), "finite"),
])
def test_the_gated_shield_refuses_missing_or_bad_inputs(speed, unseen, message):
    with pytest.raises(ValueError, match=message):
        Shield(GATED).update(0.9, speed, unseen)


@pytest.mark.parametrize("field, value, message", [
    ("path_half_width", 0.0, "path_half_width = 0.0, must be > 0 metres"),
    ("path_half_width", "wide", "path_half_width = 'wide', must be a number"),
    ("headway", -0.1, "headway = -0.1, must be >= 0 seconds"),
    ("margin", float("inf"), "margin = inf, must be >= 0 metres"),
    ("front", -1.0, "front = -1.0, must be >= 0 metres"),
])
def test_gate_settings_are_checked(field, value, message):
    with pytest.raises(ValueError, match=message):
        ShieldConfig(**{field: value})

