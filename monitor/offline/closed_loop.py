"""The monitor and its shield in a closed loop with traffic (paper, Sec. IV-B).

Per step of ``dt`` seconds, in one :class:`~monitor.offline.scenarios.World`:

1. the actors become ego-frame boxes; :func:`~monitor.synthetic.render_depth` ray-casts
   them and the street's structure, the front camera's true depth;
   :func:`~monitor.synthetic.degrade.estimate_depth` and
   :func:`~monitor.synthetic.degrade.detect` degrade it and the detections under the
   scenario's condition;
2. the **baseline** driver brakes at ``brake`` m/s^2 when a detection (score >= ``min_score``)
   lies in its corridor, or will by the time the ego gets there (its track's lateral speed,
   :class:`~monitor.offline.tracking.Tracker`, over at most ``predict_s`` seconds; a track
   with a lateral speed that the detector missed in this frame counts at its predicted
   centre, :meth:`~monitor.offline.tracking.Tracker.coasting`), within
   its stopping distance plus a margin (from the speed its brake
   would act at, the commands already on their way acting first, and with the frames it
   takes to confirm counted as reaction) in ``confirm_frames``
   consecutive frames (it sees only what its detector sees; one frame is not enough, as a
   tracker confirms a track) and keeps braking until nothing was in reach for
   ``release_frames`` frames (a track coasts through missed detections); otherwise it
   accelerates back to its cruise speed at ``comfort``;
3. a **shielded** driver is the same driver plus the :class:`~monitor.RiskMonitor` on the same
   frame and a :class:`~monitor.shield.Shield` (given the frame's time, the ego's speed, the
   report's unseen objects and how much of each came out of the road of the frames before,
   :meth:`~monitor.RiskMonitor.emerged`, for a path-gated shield): the larger of the two
   decelerations wins;
4. a command takes effect ``reaction`` seconds later (perception, decision and actuation).

Drivers in one scenario (the baseline, the default shield, a sweep's settings) share the
world and its frames for as long as their commands agree; where they part, the world is
copied and each copy goes on with its drivers (:func:`run_scenario`). Frame ``k`` draws its
depth and detector errors from the ``k``-th child of the seed's stream in every copy, so two
drivers see the same noise in the same situation.

A shield that had braked before the hazard came into view, for something else, meets it
slower than the baseline does, and may avoid it for that alone. ``from_onset`` drives the
first shield setting once more, switched on at the hazard's onset (below): what that car
avoids, the shield avoids by what it does about the hazard.

A run ends at a collision (of the ego's front: the hazard or whatever it hits; or the rear:
the follower), when the ego stops or has passed the hazard (hazard kinds), when it arrives at
the end of its route (hazard-free drives), or at the time limit.

Avoidability (:func:`required_gap`): the hazard's *onset* is the first frame at which it can
be seen (visible pixels in the image, within the monitor's range, and after its event: the
lead's braking, the cut-in, the pedestrian's first step). A run is physically avoidable by
the shield when the gap at onset exceeds what the ego needs to stop at the shield's
deceleration (``ShieldConfig.deceleration``, its gentle stage; a shield with an emergency
stage may also avoid some of the others) after the reaction time, the hazard moving on as
it does. From the onset to the end of the baseline's drive, the onset also counts the
frames and those in which the baseline's detector reported the hazard (score >=
``min_score``): a collision with a hazard the detector saw is the planner's to avoid, one
with a hazard it missed is the monitor's.

A hazard that moves into the path (a pedestrian stepping out, a cut-in) can be avoided from
its onset only by a driver that foresees it, as a tracker of a detection does. The onset
therefore also records its *entry*, the first frame from the onset at which the hazard
overlaps the ego's path (:meth:`World.hazard_in_path`), with the same avoidability test: a
shield that brakes for what stands in the path can avoid a collision only where the gap at
entry allows it, unless it too predicts.
"""
from __future__ import annotations

import copy
import math
from collections import deque
from dataclasses import asdict, dataclass, field
from typing import NamedTuple

import numpy as np

from monitor.config import ShieldConfig
from monitor.geometry.camera import Camera
from monitor.geometry.boxes import DEFAULT_RANGE_M
from monitor.geometry.boxes3d import footprints
from monitor.offline.attribution import what_lies_there
from monitor.offline.scenarios import EGO_CENTRE_M, ScenarioSpec, World, advance, build_world, reach
from monitor.offline.tracking import Tracker
from monitor.risk_monitor import RiskMonitor, shift_earlier
from monitor.shield import Shield
from monitor.synthetic import Condition, get_condition, render_depth
from monitor.synthetic.degrade import REFERENCE_WIDTH_PX, Detections, detect, estimate_depth
from monitor.synthetic.scene import EGO_FRONT_M, EGO_HALF_WIDTH_M
from monitor.walkers import walker_positions

BASELINE = "baseline"
#: Appended to a shield's label for its drive switched on at the hazard's onset (``run_scenario``'s ``from_onset``).
FROM_ONSET = " from onset"


@dataclass(frozen=True)
class Driver:
    """The ego's driver, the same with and without the shield.

    Attributes
    ----------
    dt : float
        Seconds per step (one camera frame per step).
    reaction : float
        Seconds from a frame to the command taking effect; a whole number of steps.
    brake : float
        The baseline's deceleration for a detected obstacle, m/s^2.
    comfort : float
        Acceleration back to the cruise speed, m/s^2.
    margin : float
        Metres kept beyond the stopping distance.
    corridor : float
        Half width of the ego's path in which a detection counts, metres.
    confirm_frames : int
        Consecutive frames with a detection in reach before the baseline brakes.
    release_frames : int
        Consecutive frames without one before it stops braking.
    min_score : float
        Detections scoring below it are ignored.
    predict_s : float
        Seconds ahead over which a detection's tracked lateral motion counts: one that will be
        in the corridor by the time the ego reaches it (at most this many seconds) counts now;
        0: only what is in the corridor now.
    """

    dt: float = 0.1
    reaction: float = 0.2
    brake: float = 6.0
    comfort: float = 1.5
    margin: float = 2.0
    corridor: float = EGO_HALF_WIDTH_M + 0.3
    confirm_frames: int = 2
    release_frames: int = 5
    min_score: float = 0.3
    predict_s: float = 2.0

    def __post_init__(self):
        for name in ("dt", "brake", "comfort", "corridor"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} = {value!r}, must be a finite number > 0")
        for name in ("reaction", "margin", "predict_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} = {value!r}, must be a finite number >= 0")
        steps = self.reaction / self.dt
        if abs(steps - round(steps)) > 1e-9:
            raise ValueError(f"reaction = {self.reaction} s, must be a whole number of steps of dt = {self.dt} s")
        for name in ("confirm_frames", "release_frames"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} = {value!r}, must be an integer >= 1")
        if not 0.0 <= self.min_score <= 1.0:
            raise ValueError(f"min_score = {self.min_score!r}, must be in [0, 1]")

    @property
    def delay_steps(self) -> int:
        return int(round(self.reaction / self.dt))


def stopping_distance(speed: float, decel: float, reaction: float) -> float:
    """Metres from a decision to standstill: ``speed * reaction + speed^2 / (2 decel)``."""
    return speed * reaction + speed * speed / (2.0 * decel)


def required_gap(speed: float, decel: float, reaction: float, hazard_speed: float = 0.0,
                 hazard_decel: float = 0.0) -> float:
    """The smallest gap at which the ego stops short of a hazard ahead in its path, metres.

    The ego drives on at ``speed`` for ``reaction`` s, then brakes at ``decel`` to a stop;
    the hazard moves along the path at ``hazard_speed``, braking at ``hazard_decel`` to a
    stop (0: at a constant speed). The answer is the largest amount by which the ego's
    travel exceeds the hazard's, 0 if it never does (a static hazard: exactly
    :func:`stopping_distance`).
    """
    t_stop = reaction + speed / decel
    t = np.linspace(0.0, t_stop, 4001)
    braking = np.clip(t - reaction, 0.0, None)
    ego = speed * np.minimum(t, reaction) + speed * braking - 0.5 * decel * braking ** 2
    if hazard_decel > 0.0:
        moving = np.minimum(t, hazard_speed / hazard_decel)
        other = hazard_speed * moving - 0.5 * hazard_decel * moving ** 2
    else:
        other = hazard_speed * t
    return float(max(np.max(ego - other), 0.0))


def in_reach(detections: np.ndarray, speed: float, driver: Driver, lateral_speed: np.ndarray | None = None) -> bool:
    """Is a detection in the corridor within the stopping distance at ``speed`` plus the
    margin, the frames it takes to confirm a track counted as reaction?

    ``detections``: boxes ``x, y, z, w, l, h, yaw`` in the ego frame (rear axle origin),
    shape (k, 7), those the driver trusts. ``lateral_speed`` (k,), m/s along y
    (:meth:`Tracker.update`): each footprint swept across the path for the time the ego takes
    to reach it at ``speed``, at most ``driver.predict_s``; None: each where it stands.
    """
    feet = footprints(detections)
    ahead = feet[:, 0] - EGO_FRONT_M
    low, high = feet[:, 1], feet[:, 2]
    if lateral_speed is not None:
        horizon = np.minimum(np.maximum(ahead, 0.0) / speed, driver.predict_s) if speed > 0 else driver.predict_s
        shift = lateral_speed * horizon
        low, high = low + np.minimum(shift, 0.0), high + np.maximum(shift, 0.0)
    in_path = (high > -driver.corridor) & (low < driver.corridor)
    # a detection confirmed confirm_frames - 1 frames from now: those frames' travel counts too
    limit = reach(speed, driver.brake, driver.reaction + (driver.confirm_frames - 1) * driver.dt, driver.margin)
    return bool(np.any(in_path & (ahead > -1.0) & (ahead < limit)))


@dataclass
class Run:
    """One driver's drive through one scenario.

    Attributes
    ----------
    kind, condition : str
    seed : int
    driver : str
        ``"baseline"`` or the shield's settings, ``"t0.50 r0.50 h0"``, followed by
        :data:`FROM_ONSET` for its drive switched on at the hazard's onset.
    regime : str
        ``parking`` or ``urban``.
    cruise : float
        m/s.
    outcome : str
        ``collision`` (the ego's front hit something), ``rear-ended``, ``stopped``, ``passed``,
        ``arrived`` or ``timeout``.
    hazard : dict or None
        What the hazard is: ``class`` (its actor class: ``animal``, ``debris``,
        ``wheelchair``, ``pedestrian``, ``car``) and ``size`` (``w, l, h``, metres); None for a
        hazard-free drive.
    hit : str
        Class of what the ego hit ("" if nothing).
    impact_speed, closing_speed : float
        The ego's speed and the speed at which it closed in on what it hit, m/s (0 without).
    final_gap : float
        Gap to the hazard when the run ended, metres (0 at a collision with it; NaN without).
    trip_time : float
        Seconds to the end of the route (hazard-free drives; the time limit if it never
        arrived; NaN for hazard kinds).
    frames : int
    braking_frames : int
        Frames in which a deceleration was applied.
    engaged_frames : int
        Frames in which the shield was engaged.
    onset : dict or None
        At the hazard's onset (computed on the baseline's drive): ``time``, ``gap``, ``speed``,
        ``required`` (the gap the shield's deceleration needs) and ``avoidable``; ``frames``
        from the onset to the end of the baseline's drive and ``seen_frames``, those in which
        the baseline's detector reported the hazard (score >= the driver's ``min_score``);
        ``entry``: ``time``, ``gap``, ``speed``, ``required`` and ``avoidable`` at the first
        of those frames in which the hazard overlapped the ego's path (None if it never did).
    history : dict of lists
        Per frame: ``time``, ``speed``, ``gap`` (to the hazard, NaN without), ``risk`` (NaN for
        the baseline), ``engaged``, ``decel`` (applied, m/s^2).
    engagements : list of dict
        Each time the shield engaged (empty for the baseline): ``time``, ``speed``, the
        ``deceleration`` it requested, its ``cause`` (:attr:`monitor.shield.ShieldDecision.cause`)
        and the unseen ``objects`` that counted (``x, y_min, y_max``, ego frame, metres), and
        what each really lay on (``on``, :func:`monitor.offline.attribution.what_lies_there`).
    """

    kind: str
    condition: str
    seed: int
    driver: str
    regime: str
    cruise: float
    outcome: str = "timeout"
    hazard: dict | None = None
    hit: str = ""
    impact_speed: float = 0.0
    closing_speed: float = 0.0
    final_gap: float = float("nan")
    trip_time: float = float("nan")
    frames: int = 0
    braking_frames: int = 0
    engaged_frames: int = 0
    onset: dict | None = None
    history: dict = field(default_factory=lambda: {k: [] for k in HISTORY_KEYS})
    engagements: list = field(default_factory=list)

    @property
    def collided(self) -> bool:
        return self.outcome == "collision"

    def to_dict(self) -> dict:
        """JSON-ready (NaN as None)."""
        def clean(value):
            if isinstance(value, float) and not math.isfinite(value):
                return None
            if isinstance(value, dict):
                return {k: clean(v) for k, v in value.items()}
            if isinstance(value, list):
                return [clean(v) for v in value]
            return value
        return clean(asdict(self))


HISTORY_KEYS = ("time", "speed", "gap", "risk", "engaged", "decel")


def driver_label(config: ShieldConfig | None) -> str:
    """``baseline`` or ``t{threshold} r{release} h{hold_frames}``, with `` p{path_half_width}``
    for a path-gated shield and `` c{confirm_frames}/{confirm_window}`` for one that confirms,
    followed by ``<{confirm_width}`` when only objects under that width are confirmed (and
    `` n{confirm_near}`` when every object near the bumper is, ``/{confirm_window}`` after it
    when what floats there is in every frame of the window, `` g{confirm_edge}`` when every
    edge of the path is, `` o{confirm_emerged}`` when every object out of the road is,
    `` k{confirm_contact}`` when every object that touches the road too little is),
    `` e{emergency}`` for a gate with an emergency stage, `` m{memory}`` for one that
    remembers and `` w{walker_horizon}`` for one that watches walkers (`` u{unseen_walkers}``
    when unseen ones too)."""
    if config is None:
        return BASELINE
    gate = "" if config.path_half_width is None else f" p{config.path_half_width:.2f}"
    if config.path_half_width is not None and config.confirm_frames > 1:
        gate += f" c{config.confirm_frames}/{config.confirm_window}"
        if config.confirm_width is not None:
            gate += f"<{config.confirm_width:.2f}"
            if config.confirm_near is not None:
                gate += f" n{config.confirm_near:g}"
                if config.confirm_near_all and config.confirm_contact is not None \
                        and config.confirm_window > config.confirm_frames:
                    gate += f"/{config.confirm_window}"
            if config.confirm_edge is not None:
                gate += f" g{config.confirm_edge:g}"
            if config.confirm_emerged is not None:
                gate += f" o{config.confirm_emerged:g}"
            if config.confirm_contact is not None:
                gate += f" k{config.confirm_contact:g}"
    if config.path_half_width is not None and config.emergency is not None:
        gate += f" e{config.emergency:g}"
    if config.path_half_width is not None and config.memory is not None:
        gate += f" m{config.memory:g}"
    if config.walker_horizon is not None:
        gate += f" w{config.walker_horizon:g}"
        if config.unseen_walkers is not None:
            gate += f" u{config.unseen_walkers:g}"
    return f"t{config.threshold:.2f} r{config.release:.2f} h{config.hold_frames}{gate}"


class Perception:
    """The front camera's frames of a world: true depth, estimated depth, detections.

    Parameters
    ----------
    camera : Camera
    """

    def __init__(self, camera: Camera):
        if not isinstance(camera, Camera):
            raise ValueError(f"camera is a {type(camera).__name__}, expected a monitor.geometry.camera.Camera")
        self.camera = camera
        self.px_scale = camera.width / REFERENCE_WIDTH_PX

    def frame(self, world: World, condition, seeds: tuple[np.random.SeedSequence, np.random.SeedSequence]
              ) -> "PerceivedFrame":
        """The camera's frame of ``world`` now, under ``condition``.

        ``seeds`` seed the depth errors and the detector errors; a generator is made afresh
        from each, so the same seeds give the same errors every time.
        """
        boxes, classes, hazard_row = world.frame_boxes()
        render = render_depth(self.camera, boxes, *world.frame_structure())
        depth_rng, detector_rng = (np.random.default_rng(s) for s in seeds)
        depth = estimate_depth(render.depth, render.labels, render.background, condition.depth, depth_rng,
                               self.px_scale)
        dets = detect(self.camera, boxes, classes, render.visibility, render.visible_px, condition.detector,
                      detector_rng)
        visible, distance = 0, float("inf")
        if hazard_row >= 0:
            visible = int(render.visible_px[hazard_row])
            distance = float(np.linalg.norm(boxes[hazard_row, :3] - self.camera.cam_to_ego[:3, 3]))
        return PerceivedFrame(depth, dets, visible, distance, hazard_row, render.labels, classes)


class PerceivedFrame(NamedTuple):
    """One frame of :meth:`Perception.frame`.

    Attributes
    ----------
    depth : ndarray of shape (H, W), float32
        The estimated depth, metres.
    detections : Detections
        The detector's output (``source``: the row of each detection's actor).
    visible : int
        Visible pixels of the hazard (0 without one).
    distance : float
        The hazard's distance from the camera, metres (inf without one).
    hazard_row : int
        The hazard's row among the actors, -1 without one.
    labels : ndarray of shape (H, W), int16
        What each pixel shows (the ray cast's label map: ``k + 1`` for actor ``k``).
    classes : ndarray of shape (n,), str
        The actors' classes.
    """

    depth: np.ndarray
    detections: Detections
    visible: int
    distance: float
    hazard_row: int
    labels: np.ndarray
    classes: np.ndarray


class _Member:
    """One driver's state inside a branch; a shield ``from_onset`` acts only from the hazard's onset on."""

    def __init__(self, run: Run, shield: Shield | None, driver: Driver, sensor: np.ndarray,
                 from_onset: bool = False):
        self.run, self.shield, self.from_onset = run, shield, from_onset
        self.tracker = Tracker(sensor) if driver.predict_s > 0 else None
        self.confirmed = self.missed = 0
        self.braking = False
        self.queue = deque([0.0] * driver.delay_steps)  # commands on their way to the brakes

    def acting(self, onset: dict | None) -> bool:
        """Does the member's shield decide in this frame (``onset``: the hazard's, None before it)?"""
        return self.shield is not None and (onset is not None or not self.from_onset)


def run_scenario(spec: ScenarioSpec, perception: Perception, monitor: RiskMonitor | None,
                 shields=(), driver: Driver = Driver(), condition: Condition | None = None,
                 from_onset: bool = False) -> list[Run]:
    """Drive one scenario with the baseline and with each shield setting.

    Parameters
    ----------
    spec : ScenarioSpec
    perception : Perception
    monitor : RiskMonitor or None
        Needed when ``shields`` is not empty; its camera must be the perception's.
    shields : sequence of ShieldConfig
    driver : Driver
    condition : Condition, optional
        Degradations to use instead of those named by ``spec.condition`` (a variant).
    from_onset : bool
        Also drive the first shield setting switched on at the hazard's onset: before it the
        car drives as the baseline's does, and its shield starts afresh there (it knows none of
        the frames before). What that car avoids, the shield avoids by what it did about the
        hazard, not by having braked before for something else. Without a hazard (no onset)
        it is the baseline's drive.

    Returns
    -------
    list of Run
        The baseline first, then one per shield setting, in order; with ``from_onset``, last,
        the first setting's from the onset (``driver``: its label and :data:`FROM_ONSET`).
    """
    shields = list(shields)
    if shields and monitor is None:
        raise ValueError("shield settings were given without a monitor")
    if from_onset and not shields:
        raise ValueError("from_onset needs a shield setting to switch on at the onset")
    if monitor is not None and monitor.camera is not perception.camera and \
            (monitor.camera.width, monitor.camera.height) != (perception.camera.width, perception.camera.height):
        raise ValueError("the monitor's camera and the perception's differ in image size")
    condition = get_condition(spec.condition) if condition is None else get_condition(condition)
    max_range = monitor.config.max_range if monitor is not None else DEFAULT_RANGE_M
    shield_decel = (monitor.config.shield if monitor is not None else ShieldConfig()).deceleration
    world = build_world(spec, reaction=driver.reaction, brake=driver.brake, margin=driver.margin)
    # (setting, switched on at the onset) per driver
    configs = [(None, False)] + [(c, False) for c in shields] + ([(shields[0], True)] if from_onset else [])
    members = [_Member(Run(spec.kind, spec.condition, int(spec.seed),
                           driver_label(c) + (FROM_ONSET if late else ""), world.regime, world.speed,
                           hazard=_what(world)),
                       Shield(c) if c is not None else None, driver, perception.camera.cam_to_ego[:2, 3], late)
               for c, late in configs]
    n_steps = int(math.ceil(world.max_time / driver.dt - 1e-9))
    # spawned once: SeedSequence.spawn counts its children, so a second spawn would differ
    streams = [seq.spawn(2) for seq in np.random.SeedSequence([int(spec.seed), 1]).spawn(n_steps)]
    # a world, its drivers, the monitor's reports of its last frames with the ego's travel since
    branches = [(world, members, [])]
    onset = None
    for step in range(n_steps):
        next_branches = []
        for world, group, earlier in branches:
            frame = perception.frame(world, condition, streams[step])
            depth, dets, hazard_row = frame.depth, frame.detections, frame.hazard_row
            hazard = world.hazard
            if onset is None and group[0].shield is None and hazard is not None and frame.visible > 0 \
                    and world.time >= hazard.onset - 1e-9 and frame.distance <= max_range:
                onset = {**_situation(world, driver, shield_decel), "frames": 0, "seen_frames": 0, "entry": None}
            if onset is not None and group[0].shield is None:  # the baseline's drive, from the onset
                onset["frames"] += 1
                onset["seen_frames"] += bool(np.any((dets.source == hazard_row) & (dets.scores >= driver.min_score)))
                if onset["entry"] is None and world.hazard_in_path():
                    onset["entry"] = _situation(world, driver, shield_decel)
            report = None
            if any(m.acting(onset) for m in group):
                report = monitor.step(depth, dets.boxes3d, dets.scores)
                before, earlier = shift_earlier(earlier, report, world.ego.speed * driver.dt)
                emerged = monitor.emerged(report, before)
                walkers = walker_positions(dets.boxes3d, dets.classes, dets.scores,
                                           monitor.config.detections.min_score)
            else:  # no report of this frame: a shield switched on later knows none of the frames before it
                earlier = []
            trusted = dets.boxes3d[dets.scores >= driver.min_score]
            parts: dict[tuple, list] = {}
            for m in group:
                boxes, lateral = trusted, None
                if m.tracker is not None:
                    lateral = m.tracker.update(trusted[:, :2], world.time, world.ego.position[0])
                    centres, speeds = m.tracker.coasting()
                    coasting = np.zeros((len(centres), 7))
                    coasting[:, :2] = centres  # a point: the tracker keeps no size
                    boxes, lateral = np.vstack([trusted, coasting]), np.concatenate([lateral, speeds])
                seen = in_reach(boxes, _acting_speed(world, m.queue, driver.dt), driver, lateral)
                m.confirmed, m.missed = (m.confirmed + 1, 0) if seen else (0, m.missed + 1)
                if m.confirmed >= driver.confirm_frames:
                    m.braking = True
                elif m.missed >= driver.release_frames:
                    m.braking = False
                decel = driver.brake if m.braking else 0.0
                engaged = False
                if m.acting(onset):
                    decision = m.shield.update(report.risk, speed=world.ego.speed, unseen=report.unseen,
                                               time=world.time, emerged=emerged, walkers=walkers,
                                               contact=report.unseen_contact)
                    if decision.engaged and not (m.run.history["engaged"] and m.run.history["engaged"][-1]):
                        m.run.engagements.append({"time": world.time, "speed": world.ego.speed,
                                                  "deceleration": decision.deceleration,
                                                  "cause": decision.cause,
                                                  "objects": [list(o) for o in decision.objects],
                                                  "on": what_lies_there(decision.objects, depth, frame.labels,
                                                                        frame.classes, perception.camera)})
                    engaged, decel = decision.engaged, max(decel, decision.deceleration)
                m.queue.append(-decel if decel > 0 else driver.comfort)
                applied = m.queue.popleft()
                h = m.run.history
                for key, value in zip(HISTORY_KEYS, (world.time, world.ego.speed, world.hazard_gap(),
                                                     report.risk if m.acting(onset) else float("nan"),
                                                     engaged, max(-applied, 0.0))):
                    h[key].append(value)
                m.run.frames += 1
                m.run.braking_frames += applied < 0
                m.run.engaged_frames += engaged
                parts.setdefault((applied,) + tuple(m.queue), []).append(m)
            for k, (key, part) in enumerate(parts.items()):
                branch_world = world if k == len(parts) - 1 else copy.deepcopy(world)
                if _advance(branch_world, key[0], part, driver):
                    next_branches.append((branch_world, part, earlier))
        branches = next_branches
        if not branches:
            break
    for world, group, _ in branches:  # out of time
        for m in group:
            _finish(m.run, world, "timeout")
    runs = [m.run for m in members]
    for run in runs:
        run.onset = onset
    return runs


def _acting_speed(world: World, queue: deque, dt: float) -> float:
    """The ego's speed when a command given now takes effect: the commands on their way
    (m/s^2, one step of ``dt`` each) act first."""
    speed = world.ego.speed + dt * sum(queue)
    return min(max(speed, 0.0), max(world.ego.speed, world.ego.cruise))


def _situation(world: World, driver: Driver, decel: float) -> dict:
    """The gap to the hazard now, and whether braking at ``decel`` from now stops short of it."""
    hazard = world.hazard
    speed_along = float(hazard.actor.speed * math.cos(hazard.actor.heading))
    need = required_gap(world.ego.speed, decel, driver.reaction, max(speed_along, 0.0), hazard.decel)
    gap = world.hazard_gap()
    return {"time": world.time, "gap": gap, "speed": float(world.ego.speed), "required": need,
            "avoidable": bool(gap > need)}


def _advance(world: World, command: float, group: list[_Member], driver: Driver) -> bool:
    """Step the branch's world with the applied command; False when its runs have ended."""
    world.ego.command = command
    hit = world.collision(driver.dt)
    if hit is not None:
        actor, fraction = hit
        _, speed = advance(world.ego.speed, command, fraction * driver.dt, world.ego.cruise)
        ahead = actor.position[0] > world.ego.position[0]
        closing = speed - actor.speed * math.cos(actor.heading)
        for m in group:
            run = m.run
            run.outcome = "collision" if ahead else "rear-ended"
            run.hit, run.impact_speed, run.closing_speed = actor.actor_class, float(speed), float(abs(closing))
            run.final_gap = 0.0 if world.hazard is not None and actor is world.hazard.actor else world.hazard_gap()
            if world.hazard is None:
                run.trip_time = world.max_time
        return False
    before = world.ego.position[0] - EGO_CENTRE_M  # metres of the route covered
    world.step(driver.dt)
    if world.hazard is None:
        after = world.ego.position[0] - EGO_CENTRE_M
        if after >= world.route:
            fraction = (world.route - before) / (after - before)  # of the step, when it arrived
            for m in group:
                m.run.trip_time = world.time - driver.dt * (1.0 - fraction)
                _finish(m.run, world, "arrived")
            return False
    elif world.ego.speed <= 0.0:
        for m in group:
            _finish(m.run, world, "stopped")
        return False
    elif world.hazard_passed():
        for m in group:
            _finish(m.run, world, "passed")
        return False
    return True


def _what(world: World) -> dict | None:
    """``Run.hazard`` of a drive in ``world``: the hazard's class and size, None without one."""
    if world.hazard is None:
        return None
    actor = world.hazard.actor
    return {"class": actor.actor_class, "size": [actor.WIDTH, actor.LENGTH, actor.height]}


def _finish(run: Run, world: World, outcome: str) -> None:
    run.outcome, run.final_gap = outcome, world.hazard_gap()
    if world.hazard is None and outcome == "timeout":
        run.trip_time = world.max_time
