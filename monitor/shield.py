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
    threshold : float in [0, 1]
        Engage when the risk is above it.
    release : float in [0, threshold], optional
        Disengage when the risk is at or below it (default: ``threshold``).
    hold_frames : int >= 0
        Frames to stay engaged after the last frame above ``threshold``.
    deceleration : float > 0
        Requested deceleration while engaged, m/s^2.
    """

    def __init__(self, threshold: float = 0.5, release: float | None = None, hold_frames: int = 0,
                 deceleration: float = 3.0):
        self.config = ShieldConfig(threshold, threshold if release is None else release, hold_frames,
                                   deceleration)
        self.reset()

    @classmethod
    def from_config(cls, config: ShieldConfig) -> "Shield":
        return cls(config.threshold, config.release, config.hold_frames, config.deceleration)

    def reset(self) -> None:
        """Forget the history (a new drive)."""
        self.engaged = False
        self._since_trigger = 0

    def update(self, risk: float) -> ShieldDecision:
        """The decision for the next frame's risk."""
        c = self.config
        if math.isnan(risk) or risk > c.threshold:
            self.engaged, self._since_trigger = True, 0
        elif self.engaged:
            self._since_trigger += 1
            if risk <= c.release and self._since_trigger > c.hold_frames:
                self.engaged = False
        return ShieldDecision(self.engaged, c.deceleration if self.engaged else 0.0, risk)
