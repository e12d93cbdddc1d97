"""The controller shield: turns the risk stream into a deceleration request (paper, Sec. IV-B).

The paper's shield starts to decelerate the vehicle whenever the monitor's risk exceeds a
threshold (0.5). :class:`Shield` adds two optional refinements against chattering on a
noisy risk stream:

- hysteresis: once engaged, it stays engaged until the risk falls to ``release`` or below
  (``release == threshold``, the default, is the paper's plain threshold);
- a hold: it stays engaged at least ``hold_frames`` frames after the last frame above the
  threshold.

A NaN risk is never "below the threshold": it engages the shield (the monitor never
produces one; this guards other risk sources).
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from monitor.config import ShieldConfig


@dataclass(frozen=True)
class ShieldDecision:
    """The shield's output for one frame: whether it brakes, and how hard (m/s^2)."""

    engaged: bool
    deceleration: float
    risk: float


class Shield:
    """Risk in, deceleration request out, one frame at a time.

    Parameters
    ----------
    config : ShieldConfig, optional
        Threshold, release, hold and deceleration (default: the paper's plain 0.5
        threshold); the ``shield`` section of :class:`monitor.config.MonitorConfig`.

    Examples
    --------
    >>> shield = Shield(ShieldConfig(threshold=0.6, release=0.3))
    >>> shield.update(0.7).engaged, shield.update(0.4).engaged, shield.update(0.2).engaged
    (True, True, False)
    """

    def __init__(self, config: ShieldConfig = ShieldConfig()):
        if not isinstance(config, ShieldConfig):
            raise ValueError(f"config is a {type(config).__name__} ({config!r}), expected a "
                             "ShieldConfig, e.g. Shield(ShieldConfig(threshold=0.5)) or "
                             "Shield(load_config().shield)")
        self.config = config
        self.reset()

    def reset(self) -> None:
        """Forget the history (a new drive)."""
        self.engaged = False
        self._since_trigger = 0

    def update(self, risk: float) -> ShieldDecision:
        """The decision for the next frame's risk (a real number; NaN engages)."""
        if isinstance(risk, bool) or not isinstance(risk, numbers.Real):
            raise ValueError(f"risk = {risk!r}, expected a number (a risk in [0, 1], or NaN)")
        risk = float(risk)
        c = self.config
        if math.isnan(risk) or risk > c.threshold:
            self.engaged, self._since_trigger = True, 0
        elif self.engaged:
            self._since_trigger += 1
            if risk <= c.release and self._since_trigger > c.hold_frames:
                self.engaged = False
        return ShieldDecision(self.engaged, c.deceleration if self.engaged else 0.0, risk)
