"""Closed-loop safeguarding: the monitor and shield in the loop of a simple vehicle (paper, Sec. IV-B).

The paper puts its monitor and a controller shield on a baseline AV (automated valet
parking in Prescan) facing, among others, a cow its object detector has never seen, and
reports that the shield avoids most collisions. This module is that experiment on the
synthetic generator: a stationary obstacle stands in the ego lane ``distance`` metres ahead
of a car driving at ``speed``. Every ``dt`` seconds the scene is ray-cast, the depth map and
the detections are degraded under a condition (:mod:`monitor.synthetic`), and:

- the **baseline** planner brakes at ``brake`` m/s^2 when a detection lies in the ego's
  corridor within its stopping distance plus a margin (it sees only what its detector sees);
- with the **shield**, the :class:`~monitor.RiskMonitor` runs on the same frame and the
  :class:`~monitor.shield.Shield` adds its deceleration request when the risk is high.

A trial ends when the car stops (safe) or its front reaches the obstacle with speed left (a
collision). Each seed runs with and without the shield; the detector and depth errors of
frame ``k`` of a seed come from the same random stream in both runs.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from monitor.geometry.camera import Camera
from monitor.risk_monitor import RiskMonitor
from monitor.shield import Shield
from monitor.synthetic import get_condition, render_depth
from monitor.synthetic.conditions import Condition
from monitor.synthetic.degrade import REFERENCE_WIDTH_PX, detect, estimate_depth
from monitor.synthetic.scene import EGO_FRONT_M, EGO_HALF_WIDTH_M

#: the paper's unseen cow: ``w, l, h`` metres, standing across the lane
COW_SIZE = (0.8, 2.0, 1.4)


@dataclass(frozen=True)
class Scenario:
    """The closed-loop experiment's setting.

    Attributes
    ----------
    obstacle_class : str
        Ground-truth class of the obstacle (the detector's recall depends on it; ``animal``
        is mostly missed, as the paper's cow).
    obstacle_size : tuple of float
        ``w, l, h`` metres.
    distance : float
        Initial gap between the ego's front and the obstacle, metres (the depth view's
        range limit is 20 m).
    speed : float
        Initial ego speed, m/s: 4.2 m/s = 15 km/h, a parking-lot speed, as in the paper's
        automated valet parking. (At 30 km/h on these synthetic scenes the depth view finds
        a cow-sized obstacle only within 5-7 m: too late for the shield's 3 m/s^2.)
    dt : float
        Seconds between frames.
    brake : float
        The baseline planner's deceleration for a detected obstacle, m/s^2.
    margin : float
        Extra distance the baseline planner keeps, metres.
    corridor : float
        Half width of the ego's path in which a detection counts, metres.
    max_time : float
        A trial stops after this many seconds.
    """

    obstacle_class: str = "animal"
    obstacle_size: tuple[float, float, float] = COW_SIZE
    distance: float = 20.0
    speed: float = 4.2
    dt: float = 0.1
    brake: float = 6.0
    margin: float = 2.0
    corridor: float = EGO_HALF_WIDTH_M + 0.3
    max_time: float = 15.0

    def __post_init__(self):
        for name in ("distance", "speed", "dt", "brake", "corridor", "max_time"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} = {value!r}, must be a finite number > 0")
        if self.margin < 0:
            raise ValueError(f"margin = {self.margin!r}, must be >= 0 metres")


@dataclass(frozen=True)
class Trial:
    """One drive: how it ended and its history, one entry per frame."""

    seed: int
    shielded: bool
    collided: bool
    impact_speed: float
    min_gap: float
    time: list = field(default_factory=list)
    gap: list = field(default_factory=list)
    speed: list = field(default_factory=list)
    risk: list = field(default_factory=list)
    shield_engaged: list = field(default_factory=list)
    detected: list = field(default_factory=list)


def _obstacle_box(scenario: Scenario, ego_x: float) -> np.ndarray:
    w, l, h = scenario.obstacle_size
    # standing across the lane (yaw pi/2): its length spans y, its width x
    centre_x = EGO_FRONT_M + scenario.distance + 0.5 * w - ego_x
    return np.array([[centre_x, 0.0, 0.5 * h, w, l, h, 0.5 * np.pi]])


def _planner_brakes(detections: np.ndarray, speed: float, scenario: Scenario) -> bool:
    """The baseline: brake for a detection in the corridor within stopping distance + margin."""
    if detections.shape[0] == 0:
        return False
    w, l, yaw = detections[:, 3], detections[:, 4], detections[:, 6]
    half_x = 0.5 * (np.abs(np.cos(yaw)) * l + np.abs(np.sin(yaw)) * w)  # extent along the road
    half_y = 0.5 * (np.abs(np.sin(yaw)) * l + np.abs(np.cos(yaw)) * w)  # and across it
    ahead = detections[:, 0] - half_x - EGO_FRONT_M
    in_path = np.abs(detections[:, 1]) < scenario.corridor + half_y
    reach = speed * speed / (2.0 * scenario.brake) + scenario.margin
    return bool(np.any(in_path & (ahead > -1.0) & (ahead < reach)))


def run_trial(scenario: Scenario, condition: str | Condition, seed: int, camera: Camera,
              monitor: RiskMonitor | None) -> Trial:
    """Drive one trial; ``monitor=None`` is the baseline without the shield."""
    cond = get_condition(condition)
    background = render_depth(camera, np.zeros((0, 7))).depth
    px_scale = camera.width / REFERENCE_WIDTH_PX
    shield = Shield(monitor.config.shield) if monitor is not None else None
    classes = np.array([scenario.obstacle_class])
    n_steps = int(np.ceil(scenario.max_time / scenario.dt))
    streams = np.random.SeedSequence(seed).spawn(n_steps)
    ego_x, speed = 0.0, scenario.speed
    history = {k: [] for k in ("time", "gap", "speed", "risk", "shield_engaged", "detected")}
    collided, impact_speed = False, 0.0
    for step, stream in enumerate(streams):
        gap = scenario.distance - ego_x
        if gap <= 0.0:
            collided, impact_speed = True, speed
            break
        if speed <= 0.0:
            break
        depth_rng, detector_rng = (np.random.default_rng(s) for s in stream.spawn(2))
        boxes = _obstacle_box(scenario, ego_x)
        render = render_depth(camera, boxes)
        depth = estimate_depth(render.depth, render.labels, background, cond.depth, depth_rng, px_scale)
        dets = detect(camera, boxes, classes, render.visibility, render.visible_px, cond.detector, detector_rng)
        decel = scenario.brake if _planner_brakes(dets.boxes3d, speed, scenario) else 0.0
        risk, engaged = float("nan"), False
        if monitor is not None:
            risk = monitor.step(depth, dets.boxes3d, dets.scores).risk
            decision = shield.update(risk)
            engaged = decision.engaged
            decel = max(decel, decision.deceleration)
        for key, value in (("time", step * scenario.dt), ("gap", gap), ("speed", speed), ("risk", risk),
                           ("shield_engaged", engaged), ("detected", bool((dets.source == 0).any()))):
            history[key].append(value)
        new_speed = max(speed - decel * scenario.dt, 0.0)
        ego_x += 0.5 * (speed + new_speed) * scenario.dt
        speed = new_speed
    gaps = history["gap"] or [scenario.distance]
    return Trial(seed, monitor is not None, collided, impact_speed,
                 0.0 if collided else min(min(gaps), scenario.distance - ego_x), **history)


def run_experiment(scenario: Scenario, condition: str | Condition, seeds, camera: Camera,
                   monitor: RiskMonitor, progress=None) -> list[tuple[Trial, Trial]]:
    """(baseline, shielded) trial pairs for each seed."""
    pairs = []
    for seed in seeds:
        pairs.append((run_trial(scenario, condition, seed, camera, None),
                      run_trial(scenario, condition, seed, camera, monitor)))
        if progress is not None:
            progress()
    return pairs


def summarise(pairs: list[tuple[Trial, Trial]]) -> dict:
    """Collision counts with and without the shield, and the share of the baseline's
    collisions the shield avoided (the paper's "collision avoidance rate")."""
    base = [b.collided for b, _ in pairs]
    shielded = [s.collided for _, s in pairs]
    avoided = [b and not s for (b, s) in zip(base, shielded)]
    return {
        "trials": len(pairs),
        "baseline_collisions": int(sum(base)),
        "shielded_collisions": int(sum(shielded)),
        "avoidance_rate": (sum(avoided) / sum(base)) if any(base) else float("nan"),
        "shield_induced": int(sum((not b) and s for b, s in zip(base, shielded))),
        "mean_impact_speed_baseline": float(np.mean([b.impact_speed for b, _ in pairs if b.collided]))
        if any(base) else float("nan"),
    }
