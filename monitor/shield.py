"""The controller shield: turns the risk stream into a deceleration request (paper, Sec. IV-B).

The paper's shield starts to decelerate the vehicle whenever the monitor's risk exceeds a
threshold (0.5). :class:`Shield` adds two optional refinements against chattering on a
noisy risk stream:

- hysteresis: once engaged, it stays engaged until the risk falls to ``release`` or below
  (``release == threshold``, the default, is the paper's plain threshold);
- a hold: it stays engaged at least ``hold_frames`` frames after the last frame above the
  threshold.

And one against braking for what is not in the way (``path_half_width``): the monitor's risk
says how much of what the depth view sees the detector misses, anywhere in its corridor, and
a detector calibrated to real data misses half of the traffic around the car in most
frames. With a path gate the risk engages the shield only while one of those missed objects
(a depth-view object no detection covers, :attr:`monitor.RiskReport.unseen`) stands in the
ego's path within its reach, the distance it needs to stop at the shield's deceleration plus
a headway and a margin, and it releases (after the hold) when none is left there: as the car
itself brakes for a detected obstacle in its path within its stopping distance, the shield
brakes for an unseen one. A frame without a view (``unseen`` None: an invalid frame or one
the view cannot see through) is not gated: its fail-safe risk engages the shield as before.

A NaN risk is never "below the threshold": it engages the shield, gate or no gate (the
monitor never produces one; this guards other risk sources).
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

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

    def reach(self, speed: float) -> float:
        """Metres ahead of the front bumper in which an unseen object counts at ``speed``
        m/s: the braking distance at the shield's deceleration, plus ``headway`` seconds of
        travel and the ``margin``."""
        c = self.config
        return speed * speed / (2.0 * c.deceleration) + speed * c.headway + c.margin

    def update(self, risk: float, speed: float | None = None, unseen=None) -> ShieldDecision:
        """The decision for the next frame.

        Parameters
        ----------
        risk : float
            The monitor's risk (a real number; NaN engages).
        speed : float, optional
            The ego's speed, m/s (>= 0); needed with a path gate, ignored without.
        unseen : ndarray of shape (k, 3) or None
            The report's :attr:`~monitor.RiskReport.unseen` (``x, y_min, y_max`` per object,
            ego frame, metres); None for a frame without a view. Read only with a path gate.
        """
        if isinstance(risk, bool) or not isinstance(risk, numbers.Real):
            raise ValueError(f"risk = {risk!r}, expected a number (a risk in [0, 1], or NaN)")
        risk = float(risk)
        c = self.config
        in_path = c.path_half_width is None or self._in_path(speed, unseen)
        if math.isnan(risk) or (risk > c.threshold and in_path):
            self.engaged, self._since_trigger = True, 0
        elif self.engaged:
            self._since_trigger += 1
            if (risk <= c.release or not in_path) and self._since_trigger > c.hold_frames:
                self.engaged = False
        return ShieldDecision(self.engaged, c.deceleration if self.engaged else 0.0, risk)

    def _in_path(self, speed, unseen) -> bool:
        """An unseen object in the path within reach, or no view to tell (True)."""
        if isinstance(speed, bool) or not isinstance(speed, numbers.Real) or not speed >= 0 \
                or not math.isfinite(speed):
            raise ValueError(f"speed = {speed!r}: a shield with a path gate needs the ego's speed, "
                             "a finite number of m/s >= 0")
        if unseen is None:
            return True
        unseen = np.asarray(unseen, dtype=np.float64)
        if unseen.ndim != 2 or unseen.shape[1] != 3 or not np.isfinite(unseen).all():
            raise ValueError(f"unseen has shape {unseen.shape}: expected finite (k, 3) rows "
                             "x, y_min, y_max (RiskReport.unseen)")
        w = self.config.path_half_width
        x, y_min, y_max = unseen.T
        ahead = x - self.config.front
        return bool(np.any((ahead <= self.reach(float(speed))) & (y_max >= -w) & (y_min <= w)))
