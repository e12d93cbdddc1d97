"""The closed loop's scenario library: roads with traffic around the ego car, and a hazard.

Dynamics come from highway-env (``pip install fuzzrisk[sim]``): its road network of straight
lanes, IDM traffic (:class:`highway_env.vehicle.behavior.IDMVehicle`) that follows and reacts
to whatever is ahead of it in its lane, the ego among them, kinematic bicycle vehicles and
static :class:`~highway_env.vehicle.objects.Obstacle` s. Pedestrians are small kinematic
vehicles walking a straight line. Its RL environment loop and pygame rendering are not used.

Kinds (:data:`KINDS`), each with the same kind of traffic around the ego (a follower in the
ego lane, a second same-direction lane with traffic, oncoming lanes, parked cars or a bike
lane, pedestrians on the sidewalks):

``rare-object``
    An animal, debris or a wheelchair standing in the ego lane (the detector mostly misses
    them: :data:`~monitor.synthetic.conditions.DETECTOR_CLASSES`).
``pedestrian``
    A pedestrian stepping out from a gap between parked cars, timed to be in the ego's path
    when the ego arrives.
``lead-brake``
    The vehicle ahead in the ego lane brakes hard (5-8 m/s^2) to a stop.
``cut-in``
    A slower vehicle in the next lane changes into the ego lane just ahead of the ego.
``hazard-free``
    The same traffic, nothing in the ego's way: what the shield does there is false braking.

Coordinates: highway-env's world frame, x along the road, y to the *right* (its lanes are
numbered from left to right), heading from +x towards +y. The ego drives in lane 0 along
+x from x = 0. :meth:`World.frame_boxes` turns the actors into the ego frame of
:mod:`monitor.synthetic` (x forward, y *left*, origin on the ground at the rear axle).

The street's static structure (curbs, poles, trees, buildings, fences, hedges:
:func:`monitor.synthetic.scene.make_structure`) is rendered too; it is nobody's obstacle.

Randomness: a scenario is a pure function of ``(kind, seed)``: the traffic comes from one
stream of the seed, the hazard from another and the structure from a third, so the same seed gives the same road, speed
and traffic in every kind and every condition.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from monitor.synthetic.scene import (
    ACTOR_CLASSES, BIKE_LANE_WIDTH_M, EGO_FRONT_M, EGO_HALF_WIDTH_M, EGO_REAR_M, LANE_WIDTH_M,
    PARKING_WIDTH_M, SCENE_RADIUS_M, Road as StreetSection, Structure, make_structure,
)

try:  # the optional extra "sim"
    from highway_env.road.lane import StraightLane
    from highway_env.road.road import Road, RoadNetwork
    from highway_env.vehicle.behavior import IDMVehicle
    from highway_env.vehicle.kinematics import Vehicle
    from highway_env.vehicle.objects import Obstacle
    from highway_env.utils import are_polygons_intersecting
except ImportError:  # pragma: no cover - exercised only without the extra
    IDMVehicle = Vehicle = None

KINDS = ("rare-object", "pedestrian", "lead-brake", "cut-in", "hazard-free")
#: scenario kinds with a hazard in the ego's way
HAZARD_KINDS = KINDS[:-1]
#: speed regimes, m/s: parking lot (automated valet parking, as the paper's) and urban
SPEED_REGIMES = {"parking": (3.0, 5.0), "urban": (8.0, 14.0)}
#: the ego's extent (monitor.synthetic's ego): length, width, and its centre ahead of the rear axle
EGO_LENGTH_M = EGO_FRONT_M - EGO_REAR_M
EGO_WIDTH_M = 2.0 * EGO_HALF_WIDTH_M
EGO_CENTRE_M = 0.5 * (EGO_FRONT_M + EGO_REAR_M)
#: seconds a hazard-free drive lasts at constant speed (its route length is speed * this)
DRIVE_S = 6.0
#: the hazard-free drive's time limit, in multiples of DRIVE_S
DRIVE_LIMIT = 2.0
#: seconds a hazard run goes on after the ego would have reached the hazard at constant speed
HAZARD_SLACK_S = 3.0
_LANE_END_M = 2000.0
#: road users this far behind the ego are dropped from the world, metres
BEHIND_M = 60.0
_VEHICLE_MIX = (("car", 0.85), ("truck", 0.15))


def require_highway_env() -> None:
    """Raise ImportError with the install command when highway-env is missing."""
    if Vehicle is None:
        raise ImportError("the closed-loop simulation needs highway-env: pip install 'fuzzrisk[sim]' "
                          "(or pip install highway-env)")


@dataclass(frozen=True)
class Hazard:
    """What a scenario puts in the ego's way.

    Attributes
    ----------
    actor : object
        The highway-env object (its position, heading and speed change as the world steps).
    onset : float
        Seconds: before this the actor is no hazard yet (the lead has not braked, the cut-in
        has not begun, the pedestrian still stands).
    decel : float
        m/s^2 the hazard brakes at along the road after ``onset`` (0: keeps its speed).
    """

    actor: object
    onset: float
    decel: float


@dataclass(frozen=True)
class ScenarioSpec:
    """Which scenario: its kind, the condition it is seen under, and its seed.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    condition : str
        A key of :data:`monitor.synthetic.CONDITIONS`.
    seed : int
        >= 0; the road, speed and traffic depend only on it.
    """

    kind: str
    condition: str
    seed: int

    def __post_init__(self):
        from monitor.synthetic import CONDITIONS

        if self.kind not in KINDS:
            raise ValueError(f"kind = {self.kind!r}, expected one of {', '.join(KINDS)}")
        if self.condition not in CONDITIONS:
            raise ValueError(f"condition = {self.condition!r}, expected one of {', '.join(CONDITIONS)}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ValueError(f"seed = {self.seed!r}, must be an integer >= 0")


def _tag(actor, name: str, size) -> object:
    """Give a highway-env object its class name, footprint and height (``w, l, h`` metres)."""
    actor.actor_class = name
    actor.WIDTH, actor.LENGTH, actor.height = float(size[0]), float(size[1]), float(size[2])
    actor.diagonal = math.hypot(actor.LENGTH, actor.WIDTH)
    return actor


if Vehicle is not None:
    class Ego(Vehicle):
        """The ego car: straight along +x, its acceleration set per step by the closed loop.

        :meth:`step` integrates the commanded acceleration exactly (speed stays in
        [0, ``cruise``]), so a brake from speed v covers v^2 / (2 a).
        """

        def __init__(self, road, position, speed: float, cruise: float):
            super().__init__(road, position, 0.0, speed)
            self.cruise, self.command = cruise, 0.0

        def act(self, action=None) -> None:
            pass

        def step(self, dt: float) -> None:
            distance, self.speed = advance(self.speed, self.command, dt, self.cruise)
            self.position[0] += distance
            self.on_state_update()

    class ScriptedBrake(IDMVehicle):
        """An IDM vehicle that brakes at ``decel`` m/s^2 to a stop from time ``at`` on."""

        def __init__(self, road, position, heading, speed, at: float, decel: float):
            super().__init__(road, position, heading, speed, enable_lane_change=False)
            self.clock, self.at, self.decel = 0.0, at, decel

        def act(self, action=None) -> None:
            if self.clock < self.at:
                return super().act()
            Vehicle.act(self, {"steering": self.steering_control(self.target_lane_index),
                               "acceleration": -self.decel if self.speed > 0 else 0.0})

        def step(self, dt: float) -> None:
            self.clock += dt
            super().step(dt)
            if self.clock > self.at:
                self.speed = max(self.speed, 0.0)

    class ScriptedCutIn(IDMVehicle):
        """An IDM vehicle that changes into ``lane`` at time ``at`` (no other lane changes)."""

        def __init__(self, road, position, heading, speed, at: float, lane):
            super().__init__(road, position, heading, speed, enable_lane_change=False)
            self.clock, self.at, self.cut_lane = 0.0, at, lane

        def act(self, action=None) -> None:
            if self.clock >= self.at:
                self.target_lane_index = self.cut_lane
            super().act()

        def step(self, dt: float) -> None:
            self.clock += dt
            super().step(dt)

    class Walker(Vehicle):
        """A pedestrian: walks at ``walk_speed`` along its heading from ``start`` for ``duration`` s."""

        def __init__(self, road, position, heading, walk_speed: float, start: float, duration: float):
            super().__init__(road, position, heading, 0.0)
            self.clock, self.walk_speed, self.start, self.duration = 0.0, walk_speed, start, duration

        def act(self, action=None) -> None:
            pass

        def step(self, dt: float) -> None:
            walking = self.start <= self.clock < self.start + self.duration
            self.speed = self.walk_speed if walking else 0.0
            self.clock += dt
            self.position += self.velocity * dt  # a straight line: no lane to look up


def advance(speed: float, accel: float, dt: float, top: float) -> tuple[float, float]:
    """Exact motion under a constant acceleration for ``dt`` seconds.

    Braking stops at speed 0; accelerating stops at ``top`` (m/s) and cruises on; a speed
    already at or above ``top`` is kept.

    Returns
    -------
    distance : float
        Metres covered.
    speed : float
        m/s at the end.
    """
    if accel < 0.0:
        if speed <= -accel * dt:  # stops within the step
            return speed * speed / (-2.0 * accel), 0.0
    elif accel > 0.0 and speed < top:
        t = min(dt, (top - speed) / accel)  # accelerating for t, then cruising at the top
        end = speed + accel * t
        return 0.5 * (speed + end) * t + end * (dt - t), end
    else:
        return speed * dt, speed
    end = speed + accel * dt
    return 0.5 * (speed + end) * dt, end


class World:
    """One scenario's road, traffic, ego and hazard, stepped ``dt`` seconds at a time.

    Build one with :func:`build_world`. ``copy.deepcopy`` gives an independent copy (the
    closed loop branches a world where two drivers' decisions part).

    Attributes
    ----------
    spec : ScenarioSpec
    road : highway_env.road.road.Road
    ego : Ego
    hazard : Hazard or None
    speed : float
        The ego's cruise speed, m/s.
    regime : str
        A key of :data:`SPEED_REGIMES`.
    route : float
        Metres the ego must cover to arrive (hazard-free drives).
    max_time : float
        Seconds after which a run stops.
    time : float
        Seconds since the start.
    """

    def __init__(self, spec, road, ego, hazard, speed, regime, route, max_time, extras, structure):
        self.spec, self.road, self.ego, self.hazard = spec, road, ego, hazard
        self.speed, self.regime, self.route, self.max_time = speed, regime, route, max_time
        self.extras, self.structure = extras, structure
        self.time = 0.0

    def frame_structure(self) -> tuple[np.ndarray, np.ndarray]:
        """The street's structure within reach of the ego: ego-frame boxes (m, 7) and their
        label codes (m,) int16 (its boxes are in monitor.synthetic's frame, y left, already)."""
        boxes = self.structure.boxes.copy()
        boxes[:, 0] -= self.ego.position[0] - EGO_CENTRE_M
        keep = np.abs(boxes[:, 0]) - 0.5 * boxes[:, 4] <= SCENE_RADIUS_M
        return boxes[keep], self.structure.labels[keep]

    @property
    def obstacles(self) -> list:
        """What the ego can run into: road users in the lanes and objects, the ego excepted."""
        return [v for v in self.road.vehicles if v is not self.ego] + list(self.road.objects)

    @property
    def actors(self) -> list:
        """Everything the camera can see: the obstacles, cyclists and pedestrians on the side."""
        return self.obstacles + self.extras

    def frame_boxes(self) -> tuple[np.ndarray, np.ndarray, int]:
        """The actors within :data:`~monitor.synthetic.scene.SCENE_RADIUS_M`, in the ego frame.

        Returns
        -------
        boxes3d : ndarray of shape (n, 7), float64
            ``x, y, z, w, l, h, yaw`` (monitor.synthetic's ego frame: y left).
        classes : ndarray of shape (n,), str
        hazard_row : int
            Row of the hazard, -1 when it is not among them.
        """
        origin = self.ego.position - np.array([EGO_CENTRE_M, 0.0])
        rows, names, hazard_row = [], [], -1
        for actor in self.actors:
            dx, dy = actor.position - origin
            if math.hypot(dx, dy) > SCENE_RADIUS_M:
                continue
            if self.hazard is not None and actor is self.hazard.actor:
                hazard_row = len(rows)
            rows.append((dx, -dy, 0.5 * actor.height, actor.WIDTH, actor.LENGTH, actor.height,
                         -actor.heading))
            names.append(actor.actor_class)
        return np.array(rows, dtype=np.float64).reshape(-1, 7), np.array(names, dtype=str), hazard_row

    def hazard_gap(self) -> float:
        """Metres from the ego's front to the hazard's nearest point along the road (NaN: none)."""
        if self.hazard is None:
            return float("nan")
        return float(self.hazard.actor.polygon()[:, 0].min() - (self.ego.position[0] + 0.5 * EGO_LENGTH_M))

    def hazard_in_path(self) -> bool:
        """Does the hazard overlap the ego's path, the band of the ego's width along the road?"""
        if self.hazard is None:
            return False
        y = self.hazard.actor.polygon()[:, 1]
        return bool(y.max() > self.ego.position[1] - EGO_HALF_WIDTH_M and
                    y.min() < self.ego.position[1] + EGO_HALF_WIDTH_M)

    def hazard_passed(self) -> bool:
        """The ego's rear is past the hazard."""
        return (self.hazard is not None and
                self.ego.position[0] - 0.5 * EGO_LENGTH_M > self.hazard.actor.polygon()[:, 0].max())

    def collision(self, dt: float) -> tuple[object, float] | None:
        """The first actor the ego would touch in the next ``dt`` seconds, and when.

        Every actor moves at its current velocity, the ego with its commanded acceleration
        (swept polygons, highway-env's separating-axis test).

        Returns
        -------
        (actor, fraction) or None
            ``fraction`` of ``dt`` at which they first touch (to 1/256 of ``dt``).
        """
        ego = self.ego
        distance, _ = advance(ego.speed, ego.command, dt, ego.cruise)
        ego_poly, hits = ego.polygon(), []
        for actor in self.obstacles:
            if np.linalg.norm(actor.position - ego.position) > 0.5 * (ego.diagonal + actor.diagonal) + \
                    distance + abs(actor.speed) * dt:
                continue
            moves = np.array([distance, 0.0]), actor.velocity * dt
            if not are_polygons_intersecting(ego_poly, actor.polygon(), *moves)[1]:
                continue
            lo, hi = 0.0, 1.0
            for _ in range(8):  # the earliest fraction at which the swept polygons touch
                mid = 0.5 * (lo + hi)
                if are_polygons_intersecting(ego_poly, actor.polygon(), mid * moves[0], mid * moves[1])[1]:
                    hi = mid
                else:
                    lo = mid
            hits.append((hi, id(actor), actor))
        if not hits:
            return None
        fraction, _, actor = min(hits, key=lambda h: (h[0], h[1]))
        return actor, fraction

    def step(self, dt: float) -> None:
        """Every road user decides, then moves ``dt`` seconds (the ego by its ``command``)."""
        self.road.act()
        self.road.step(dt)
        for walker in self.extras:
            walker.step(dt)
        self.time += dt
        # what fell far behind never comes back into the front camera's view or the ego's way
        behind = self.ego.position[0] - BEHIND_M
        keep = self.hazard.actor if self.hazard is not None else None
        self.road.vehicles = [v for v in self.road.vehicles if v.position[0] > behind or v is self.ego or v is keep]
        self.extras = [w for w in self.extras if w.position[0] > behind]


def _size(rng: np.random.Generator, name: str) -> np.ndarray:
    """``w, l, h`` of one actor of class ``name`` (monitor.synthetic's size model)."""
    cls = ACTOR_CLASSES[name]
    return np.array(cls.size) * np.exp(cls.size_log_std * rng.standard_normal()) * \
        np.exp(0.05 * rng.standard_normal(3))


def _pick(rng: np.random.Generator, mix) -> str:
    names, weights = zip(*mix)
    return names[rng.choice(len(names), p=np.array(weights) / sum(weights))]


def reach(speed: float, decel: float, reaction: float, margin: float) -> float:
    """The distance a car needs to stop for a standing obstacle, plus a margin, metres:
    ``speed * reaction + speed^2 / (2 decel) + margin``."""
    return speed * reaction + speed * speed / (2.0 * decel) + margin


def build_world(spec: ScenarioSpec, *, reaction: float = 0.2, brake: float = 6.0,
                margin: float = 2.0) -> World:
    """Draw a scenario's road, traffic and hazard from its seed.

    Parameters
    ----------
    spec : ScenarioSpec
    reaction, brake, margin : float
        The baseline driver's reaction time (s), braking (m/s^2) and margin (m): the lead
        vehicle of ``lead-brake`` and ``hazard-free`` starts beyond the distance that driver
        keeps (:func:`reach`), so that it is no hazard before it brakes.

    Returns
    -------
    World
    """
    require_highway_env()
    traffic_seq, hazard_seq, structure_seq = np.random.SeedSequence(int(spec.seed)).spawn(3)
    rng = np.random.default_rng(traffic_seq)
    regime = "parking" if rng.random() < 0.5 else "urban"
    speed = float(rng.uniform(*SPEED_REGIMES[regime]))
    same_lanes = 2 if (spec.kind == "cut-in" or rng.random() < 0.5) else 1
    oncoming_lanes = int(rng.integers(1, 3))
    parking = spec.kind == "pedestrian" or rng.random() < 0.7
    density = rng.uniform(0.7, 1.4)

    network = RoadNetwork()
    for k in range(same_lanes):
        network.add_lane("a", "b", StraightLane([-_LANE_END_M, LANE_WIDTH_M * k], [_LANE_END_M, LANE_WIDTH_M * k],
                                                width=LANE_WIDTH_M, speed_limit=40.0))
    for k in range(1, oncoming_lanes + 1):
        network.add_lane("b", "a", StraightLane([_LANE_END_M, -LANE_WIDTH_M * k], [-_LANE_END_M, -LANE_WIDTH_M * k],
                                                width=LANE_WIDTH_M, speed_limit=40.0))
    road = Road(network=network, np_random=np.random.RandomState(int(spec.seed) % 2**32))
    ego = _tag(Ego(road, [EGO_CENTRE_M, 0.0], speed, speed), "car", (EGO_WIDTH_M, EGO_LENGTH_M, 1.5))
    road.vehicles.append(ego)
    front = EGO_CENTRE_M + 0.5 * EGO_LENGTH_M

    hazard_rng = np.random.default_rng(hazard_seq)
    hazard, extent = None, speed * DRIVE_S
    if spec.kind == "rare-object":
        name = _pick(hazard_rng, (("animal", 1.0), ("debris", 1.0), ("wheelchair", 1.0)))
        size = _size(hazard_rng, name)
        gap = 18.0 + speed * hazard_rng.uniform(0.5, 2.0)
        actor = _tag(Obstacle(road, [front + gap + 0.5 * max(size[:2]), hazard_rng.uniform(-0.6, 0.6)],
                              heading=hazard_rng.uniform(-np.pi, np.pi)), name, size)
        road.objects.append(actor)
        hazard, extent = Hazard(actor, 0.0, 0.0), gap + speed * HAZARD_SLACK_S
    elif spec.kind == "pedestrian":
        size = _size(hazard_rng, "pedestrian")
        y_from = LANE_WIDTH_M * (same_lanes - 0.5) + 0.5 * PARKING_WIDTH_M + 0.3
        walk = hazard_rng.uniform(1.0, 2.2)
        x = front + 18.0 + speed * hazard_rng.uniform(0.5, 2.0)
        enter = (y_from - EGO_HALF_WIDTH_M - 0.5 * size[1]) / walk
        leave = (y_from + EGO_HALF_WIDTH_M + 0.5 * size[1]) / walk
        arrive = (x - 0.5 * size[0] - front) / speed
        start = arrive - (enter + hazard_rng.uniform(0.1, 0.9) * (leave - enter))
        if start < 0.3:  # further ahead, so that it stands still at first
            x += speed * (0.3 - start)
            start = 0.3
        crossing = (y_from + LANE_WIDTH_M * (oncoming_lanes + 0.5)) / walk
        # heading -pi/2: towards -y, across the lanes (its length spans the walking direction)
        actor = _tag(Walker(road, [x, y_from], -0.5 * np.pi, walk, start, crossing), "pedestrian", size)
        road.vehicles.append(actor)
        hazard, extent = Hazard(actor, start, 0.0), x - front + speed * HAZARD_SLACK_S
        parked_gap = (x - 0.5 * size[0] - 0.6, x + 0.5 * size[0] + 0.6)
    elif spec.kind == "lead-brake":
        size = _size(hazard_rng, "car")
        gap = reach(speed, brake, reaction, margin) + hazard_rng.uniform(1.0, 8.0)
        at = hazard_rng.uniform(1.5, 4.0)
        actor = _tag(ScriptedBrake(road, [front + gap + 0.5 * size[1], 0.0], 0.0, speed, at,
                                   hazard_rng.uniform(5.0, 8.0)), "car", size)
        actor.target_speed = speed
        road.vehicles.append(actor)
        hazard = Hazard(actor, at, actor.decel)
        extent = gap + speed * (at + HAZARD_SLACK_S)
    elif spec.kind == "cut-in":
        size = _size(hazard_rng, "car")
        slower = hazard_rng.uniform(*((1.0, 2.5) if regime == "parking" else (2.0, 5.0)))
        cut_speed = max(speed - slower, 1.0)
        at = hazard_rng.uniform(1.5, 3.5)
        gap = hazard_rng.uniform(6.0, 15.0)  # its rear ahead of the ego's front when it starts over
        x = front + gap + (speed - cut_speed) * at + 0.5 * size[1]
        actor = _tag(ScriptedCutIn(road, [x, LANE_WIDTH_M], 0.0, cut_speed, at, ("a", "b", 0)), "car", size)
        actor.target_speed = cut_speed
        road.vehicles.append(actor)
        hazard = Hazard(actor, at, 0.0)
        extent = speed * (at + gap / max(speed - cut_speed, 0.5) + HAZARD_SLACK_S)
    if spec.kind == "hazard-free" and rng.random() < 0.5:
        size = _size(rng, "car")
        gap = reach(speed, brake, reaction, margin) + rng.uniform(2.0, 20.0)
        lead = _tag(IDMVehicle(road, [front + gap + 0.5 * size[1], 0.0], 0.0, speed, target_speed=speed,
                               enable_lane_change=False), "car", size)
        road.vehicles.append(lead)
    else:
        rng.random(), _size(rng, "car"), rng.uniform(2.0, 20.0)  # the same draws in every kind

    route = extent if hazard is not None else speed * DRIVE_S
    max_time = route / speed if hazard is not None else DRIVE_S * DRIVE_LIMIT
    span = (-BEHIND_M, route + SCENE_RADIUS_M)
    # a follower in the ego lane, then the other lanes' traffic, parked cars or bikes, pedestrians
    follower_gap = speed * rng.uniform(1.2, 2.5) + 5.0
    size = _size(rng, "car")
    if rng.random() < 0.6:
        road.vehicles.append(_tag(IDMVehicle(road, [EGO_CENTRE_M - 0.5 * (EGO_LENGTH_M + size[1]) - follower_gap, 0.0],
                                             0.0, speed, target_speed=speed, enable_lane_change=False), "car", size))
    for k in range(1, same_lanes):
        lane_speed = max(speed + rng.uniform(-2.0, 2.0), 1.0)
        drift = (lane_speed - speed) * max_time
        _stream(road, rng, LANE_WIDTH_M * k, 0.0, lane_speed, (8.0 / density, 30.0 / density),
                (span[0] - max(drift, 0.0), span[1] - min(drift, 0.0)), skip=hazard)
    for k in range(1, oncoming_lanes + 1):
        lane_speed = speed * rng.uniform(0.7, 1.2)
        _stream(road, rng, -LANE_WIDTH_M * k, np.pi, lane_speed, (8.0 / density, 40.0 / density),
                (span[0], span[1] + lane_speed * max_time), skip=hazard)
    shoulder = LANE_WIDTH_M * (same_lanes - 0.5) + 0.5 * (PARKING_WIDTH_M if parking else BIKE_LANE_WIDTH_M)
    extras: list = []  # cyclists and pedestrians off the lanes: drawn, moved, in nobody's lane
    if parking:
        keep_clear = parked_gap if spec.kind == "pedestrian" else None
        _parked(road, rng, shoulder, (0.8, 6.0 / density), span, keep_clear)
    else:
        bike_speed = rng.uniform(3.0, 6.0)
        _walkers(extras, rng, shoulder, "bicycle", bike_speed, (8.0 / density, 60.0 / density), span, max_time)
    kerbs = (LANE_WIDTH_M * (same_lanes - 0.5) + (PARKING_WIDTH_M if parking else BIKE_LANE_WIDTH_M),
             -LANE_WIDTH_M * (oncoming_lanes + 0.5))
    for kerb, outward in zip(kerbs, (1.0, -1.0)):
        for offset, direction in ((0.9, 1.0), (2.1, -1.0)):
            _walkers(extras, rng, kerb + outward * offset, "pedestrian", direction * rng.uniform(1.0, 1.6),
                     (1.5 / density, 20.0 / density), span, max_time)
    # monitor.synthetic's street: same lanes at y = 0, -3.5 (its y is left, highway-env's right)
    street = StreetSection(same_lanes=same_lanes, oncoming_lanes=oncoming_lanes, parking=parking)
    structure: Structure = make_structure(np.random.default_rng(structure_seq), street,
                                          (-BEHIND_M, speed * max_time + SCENE_RADIUS_M))
    return World(spec, road, ego, hazard, speed, regime, route, max_time, extras, structure)


def _stream(road, rng, y, heading, speed, gaps, span, skip) -> None:
    """IDM vehicles along a lane at ``y`` over x in ``span``, gaps U(``gaps``) metres."""
    x = span[0] + rng.uniform(0.0, gaps[1])
    while x < span[1]:
        name = _pick(rng, _VEHICLE_MIX)
        size = _size(rng, name)
        vehicle = IDMVehicle(road, [x + 0.5 * size[1], y], heading, speed, target_speed=speed,
                             enable_lane_change=False)
        if skip is None or not _overlaps(vehicle, size, skip.actor):
            road.vehicles.append(_tag(vehicle, name, size))
        x += size[1] + rng.uniform(*gaps)


def _overlaps(vehicle, size, other, clearance: float = 3.0) -> bool:
    """Would a vehicle of ``size`` at ``vehicle``'s position come within ``clearance`` of ``other``?"""
    dx = abs(vehicle.position[0] - other.position[0]) - 0.5 * (size[1] + other.LENGTH)
    dy = abs(vehicle.position[1] - other.position[1]) - 0.5 * (size[0] + other.WIDTH)
    return dx < clearance and dy < clearance


def _parked(road, rng, y, gaps, span, keep_clear) -> None:
    """A row of parked cars (static obstacles) at ``y``; none over ``keep_clear`` (x interval)."""
    x = span[0] + rng.uniform(0.0, gaps[1])
    while x < span[1]:
        name = _pick(rng, (("car", 0.9), ("truck", 0.1)))
        size = _size(rng, name)
        lo, hi = x, x + size[1]
        if keep_clear is not None and hi > keep_clear[0] and lo < keep_clear[1]:
            x = keep_clear[1]  # the pedestrian's gap between two parked cars
            continue
        road.objects.append(_tag(Obstacle(road, [x + 0.5 * size[1], y], 0.0), name, size))
        x += size[1] + rng.uniform(*gaps)


def _walkers(extras, rng, y, name, speed, gaps, span, duration) -> None:
    """A line of walkers (pedestrians, cyclists) at ``y`` moving at ``speed`` (signed) along x."""
    drift = speed * duration
    lo, hi = span[0] - max(drift, 0.0), span[1] - min(drift, 0.0)
    x = lo + rng.uniform(0.0, gaps[1])
    heading = 0.0 if speed > 0 else np.pi
    while x < hi:
        size = _size(rng, name)
        extras.append(_tag(Walker(None, [x + 0.5 * size[1], y], heading, abs(speed), 0.0, np.inf), name, size))
        x += size[1] + rng.uniform(*gaps)
