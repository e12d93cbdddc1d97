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
