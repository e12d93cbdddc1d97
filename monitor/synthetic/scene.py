"""Actors, road and motion of a synthetic driving scene.

The world is a straight, flat road along the world x axis. The ego car drives in lane 0
(centre ``y = 0``) at a constant speed in +x; its ego frame is the world shifted by the
ego's position (x forward, y left, z up, origin on the ground at the rear axle, as in
nuScenes). Right-hand traffic: same-direction lanes are at ``y = 0, -3.5``, oncoming ones
at ``y = 3.5, 7``. Right of the lanes runs a shoulder (a bike lane or a row of parked
cars), then a sidewalk; left of the oncoming lanes another sidewalk.

Static structure lines both sides, as on real streets (:class:`Structure`; not ground
truth, never detected): a curb at each kerb (a low box), poles and trees on the sidewalk
near the kerb, and beyond each sidewalk a frontage of buildings, fences and hedges with
gaps between them.

Actors (upright 3D boxes, sizes from nuScenes' class means) come in

* *streams*: vehicles in each lane, parked cars, cyclists in the bike lane, two lines of
  pedestrians on each sidewalk. All actors of a stream move at the stream's speed with
  gaps between them, so they never overlap. Ego-lane traffic moves at the ego's speed,
  ahead and behind the ego with a safe gap.
* *crossers*: pedestrians and cyclists crossing the road, timed so that they are in
  front of the ego but leave its lane before it arrives;
* *rare* actors (animals crossing or standing at the road side, wheelchairs crossing or
  on the sidewalk, debris lying at the ego lane's edge), placed where the ego will see
  them; how many depends on the condition.

Each actor moves on a segment: ``p(t) = p_a + (p_b - p_a) * clip((t - t_a) / (t_b - t_a), 0, 1)``.
A scene's layout depends only on its seed (``rare_per_scene`` adds rare actors from a
separate stream of random numbers, the structure comes from a third), so the same seed
gives the same traffic and the same street in every condition.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from monitor.datasets.frames import LABEL_MARKING, LABEL_ROAD, LABEL_SIDEWALK, LABEL_STRUCTURE

LANE_WIDTH_M = 3.5
SIDEWALK_WIDTH_M = 3.0
PARKING_WIDTH_M = 2.2
BIKE_LANE_WIDTH_M = 1.5
MARKING_WIDTH_M = 0.15
#: dashed lane lines: painted for DASH_ON_M out of every DASH_PERIOD_M
DASH_ON_M, DASH_PERIOD_M = 3.0, 9.0
#: the ego car's extent in its own frame (nuScenes: origin at the rear axle)
EGO_FRONT_M, EGO_REAR_M, EGO_HALF_WIDTH_M = 3.8, -1.0, 0.95
#: actors whose centre is within this distance of the ego are in a frame's ground truth
SCENE_RADIUS_M = 80.0


@dataclass(frozen=True)
class ActorClass:
    """Sizes of one ground-truth class.

    Attributes
    ----------
    name : str
    size : tuple of float
        Mean ``w, l, h`` in metres (nuScenes' class means where it has the class).
    size_log_std : float
        Log-normal spread of an actor's overall scale (each dimension further varies by 5 %).
    rare : bool
        A corner-case class (not in nuScenes' detection vocabulary).
    """

    name: str
    size: tuple[float, float, float]
    size_log_std: float
    rare: bool = False


#: class name -> ActorClass (barriers and traffic cones are not placed in scenes; their
#: sizes serve the detector's false positives)
ACTOR_CLASSES = {c.name: c for c in (
    ActorClass("car", (1.95, 4.62, 1.73), 0.06),
    ActorClass("truck", (2.51, 6.93, 2.84), 0.15),
    ActorClass("bus", (2.94, 11.19, 3.47), 0.06),
    ActorClass("motorcycle", (0.77, 2.11, 1.47), 0.06),
    ActorClass("bicycle", (0.61, 1.70, 1.29), 0.06),
    ActorClass("pedestrian", (0.67, 0.73, 1.77), 0.07),
    ActorClass("barrier", (2.53, 0.50, 0.98), 0.1),
    ActorClass("traffic_cone", (0.41, 0.41, 1.07), 0.1),
    ActorClass("wheelchair", (0.70, 1.10, 1.30), 0.05, rare=True),
    ActorClass("animal", (0.45, 1.10, 0.80), 0.35, rare=True),
    ActorClass("debris", (0.60, 0.60, 0.30), 0.35, rare=True),
)}

_LANE_MIX = (("car", 0.78), ("truck", 0.1), ("bus", 0.05), ("motorcycle", 0.07))
_PARKED_MIX = (("car", 0.9), ("truck", 0.1))


@dataclass(frozen=True)
class Road:
    """Cross-section of the road (constant along x).

    Attributes
    ----------
    same_lanes, oncoming_lanes : int
        Lanes in the ego's direction (the ego's included) and against it.
    parking : bool
        The right shoulder is a row of parked cars (else a bike lane).
    """

    same_lanes: int
    oncoming_lanes: int
    parking: bool

    @property
    def right_lane_edge(self) -> float:
        """y of the right edge of the rightmost lane, metres."""
        return -LANE_WIDTH_M * (self.same_lanes - 0.5)

    @property
    def right_kerb(self) -> float:
        """y where the right sidewalk begins, metres."""
        return self.right_lane_edge - (PARKING_WIDTH_M if self.parking else BIKE_LANE_WIDTH_M)

    @property
    def left_kerb(self) -> float:
        """y where the left sidewalk begins, metres."""
        return LANE_WIDTH_M * (self.oncoming_lanes + 0.5)

    def lane_centres(self) -> tuple[np.ndarray, np.ndarray]:
        """y of the same-direction and of the oncoming lane centres, metres."""
        return (-LANE_WIDTH_M * np.arange(self.same_lanes),
                LANE_WIDTH_M * np.arange(1, self.oncoming_lanes + 1))

    def markings(self) -> tuple[np.ndarray, np.ndarray]:
        """y of the solid and of the dashed painted lines, metres."""
        solid = [self.right_lane_edge, LANE_WIDTH_M / 2, self.left_kerb]
        dashed = [-LANE_WIDTH_M * (k + 0.5) for k in range(self.same_lanes - 1)]
        dashed += [LANE_WIDTH_M * (k + 1.5) for k in range(self.oncoming_lanes - 1)]
        return np.array(solid), np.array(dashed)


@dataclass(frozen=True, eq=False)
class Actors:
    """Every actor of a scene and its motion (world frame).

    Attributes
    ----------
    classes : ndarray of shape (n,), str
    sizes : ndarray of shape (n, 3), float64
        ``w, l, h`` metres.
    yaws : ndarray of shape (n,), float64
        Heading, radians.
    p_a, p_b : ndarray of shape (n, 2), float64
        World ``x, y`` at times ``t_a`` and ``t_b``; the actor moves on the segment
        between and stands at its ends before and after.
    t_a, t_b : ndarray of shape (n,), float64
        Seconds, ``t_b > t_a``.
    """

    classes: np.ndarray
    sizes: np.ndarray
    yaws: np.ndarray
    p_a: np.ndarray
    p_b: np.ndarray
    t_a: np.ndarray
    t_b: np.ndarray

    def boxes_at(self, t: float) -> np.ndarray:
        """(n, 7) world boxes ``x, y, z, w, l, h, yaw`` at time ``t`` (on the ground)."""
        s = np.clip((t - self.t_a) / (self.t_b - self.t_a), 0.0, 1.0)[:, None]
        xy = self.p_a + (self.p_b - self.p_a) * s
        return np.column_stack([xy, 0.5 * self.sizes[:, 2], self.sizes, self.yaws])


#: structure kind -> label code in the label map (curbs belong to the sidewalk)
STRUCTURE_LABELS = {"curb": LABEL_SIDEWALK, "building": LABEL_STRUCTURE, "fence": LABEL_STRUCTURE,
                    "hedge": LABEL_STRUCTURE, "pole": LABEL_STRUCTURE, "trunk": LABEL_STRUCTURE,
                    "crown": LABEL_STRUCTURE}
CURB_HEIGHT_M, CURB_WIDTH_M = 0.15, 0.3
#: poles and trees stand this far outward of the kerb (between the curb and the pedestrians)
KERB_SETBACK_M = 0.45
#: frontage beyond the sidewalk: (kind, probability, length range m)
_FRONTAGE = (("building", 0.55, (8.0, 30.0)), ("fence", 0.2, (5.0, 25.0)),
             ("hedge", 0.15, (3.0, 15.0)), ("gap", 0.1, (3.0, 15.0)))


@dataclass(frozen=True, eq=False)
class Structure:
    """Static structure beside the road (world frame): rendered, never ground truth.

    Attributes
    ----------
    kinds : ndarray of shape (m,), str
        Keys of :data:`STRUCTURE_LABELS`.
    boxes : ndarray of shape (m, 7), float64
        ``x, y, z, w, l, h, yaw`` (l along the road).
    """

    kinds: np.ndarray
    boxes: np.ndarray

    @property
    def labels(self) -> np.ndarray:
        """(m,) int16 label codes (:data:`STRUCTURE_LABELS`)."""
        return np.array([STRUCTURE_LABELS[k] for k in self.kinds.tolist()], dtype=np.int16)


@dataclass(frozen=True, eq=False)
class Layout:
    """A scene before rendering: the road, the ego's speed, the actors and the structure.

    The instance id of actor ``k`` is ``k``.
    """

    road: Road
    ego_speed: float
    duration: float
    actors: Actors
    structure: Structure

    def ego_x(self, t: float) -> float:
        """World x of the ego's origin at time ``t``, metres."""
        return self.ego_speed * t

    def frame_boxes(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The ground truth at time ``t``: actors within :data:`SCENE_RADIUS_M`, ego frame.

        Returns
        -------
        boxes3d : ndarray of shape (m, 7), float64
        classes : ndarray of shape (m,), str
        ids : ndarray of shape (m,), int64
        """
        boxes = self.actors.boxes_at(t)
        boxes[:, 0] -= self.ego_x(t)
        ids = np.flatnonzero(np.hypot(boxes[:, 0], boxes[:, 1]) <= SCENE_RADIUS_M)
        return boxes[ids], self.actors.classes[ids], ids.astype(np.int64)

    def frame_structure(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The structure that reaches within :data:`SCENE_RADIUS_M` along x of the ego at
        time ``t``: ego-frame boxes (m, 7) and their label codes (m,) int16."""
        boxes = self.structure.boxes.copy()
        boxes[:, 0] -= self.ego_x(t)
        keep = np.abs(boxes[:, 0]) - 0.5 * boxes[:, 4] <= SCENE_RADIUS_M
        return boxes[keep], self.structure.labels[keep]


class _Builder:
    """Collects actors while a layout is drawn."""

    def __init__(self, rng: np.random.Generator, duration: float):
        self.rng, self.duration = rng, duration
        self.rows: list[tuple] = []

    def size(self, name: str) -> np.ndarray:
        cls = ACTOR_CLASSES[name]
        scale = np.exp(cls.size_log_std * self.rng.standard_normal())
        return np.array(cls.size) * scale * np.exp(0.05 * self.rng.standard_normal(3))

    def pick(self, mix) -> str:
        names, weights = zip(*mix)
        return names[self.rng.choice(len(names), p=np.array(weights) / sum(weights))]

    def add(self, name, size, yaw, p_a, p_b, t_a, t_b):
        self.rows.append((name, size, yaw, p_a, p_b, t_a, t_b))

    def add_moving(self, name, size, yaw, x0, y, speed):
        """An actor at world (x0, y) at t = 0 moving along x at ``speed`` (signed)."""
        t_end = max(self.duration, 1.0)  # > 0 even for a single frame
        self.add(name, size, yaw, (x0, y), (x0 + speed * t_end, y), 0.0, t_end)

    def stream(self, mix, y, speed, yaw, gap, lo, hi, yaw_std=0.02):
        """Actors along x in [lo, hi] at t = 0, gaps U(gap) metres, all at ``speed``."""
        x = lo + self.rng.uniform(0.0, gap[0])
        while True:
            name = self.pick(mix)
            size = self.size(name)
            if x + size[1] > hi:
                return
            self.add_moving(name, size, yaw + yaw_std * self.rng.standard_normal(),
                            x + 0.5 * size[1], y, speed)
            x += size[1] + self.rng.uniform(*gap)

    def actors(self) -> Actors:
        if not self.rows:
            empty = np.zeros((0, 2))
            return Actors(np.zeros(0, dtype=str), np.zeros((0, 3)), np.zeros(0), empty, empty,
                          np.zeros(0), np.ones(0))
        names, sizes, yaws, p_a, p_b, t_a, t_b = zip(*self.rows)
        return Actors(np.array(names, dtype=str), np.array(sizes, dtype=np.float64),
                      np.array(yaws, dtype=np.float64), np.array(p_a, dtype=np.float64),
                      np.array(p_b, dtype=np.float64), np.array(t_a, dtype=np.float64),
                      np.array(t_b, dtype=np.float64))


def _window(speed: float, ego_speed: float, duration: float) -> tuple[float, float]:
    """x range at t = 0 of a stream moving at ``speed`` that covers the ego's surroundings
    (within SCENE_RADIUS_M ahead and behind) at some time of the scene."""
    drift = (speed - ego_speed) * duration
    return -SCENE_RADIUS_M - max(drift, 0.0), SCENE_RADIUS_M - min(drift, 0.0)


def make_layout(seed: int | np.random.SeedSequence, duration: float,
                rare_per_scene: float) -> Layout:
    """Draw a scene's road, ego speed and actors.

    Parameters
    ----------
    seed : int or numpy.random.SeedSequence
        Seeds everything; the ordinary traffic depends on nothing else.
    duration : float
        Seconds covered by the frames (the last frame's time).
    rare_per_scene : float
        Expected number of rare actors per 10 s.

    Returns
    -------
    Layout
    """
    if not isinstance(seed, np.random.SeedSequence):
        seed = np.random.SeedSequence(seed)
    traffic_seq, rare_seq, structure_seq = seed.spawn(3)
    rng = np.random.default_rng(traffic_seq)
    road = Road(same_lanes=int(rng.integers(1, 3)), oncoming_lanes=int(rng.integers(1, 3)),
                parking=bool(rng.random() < 0.5))
    ego_speed = 0.0 if rng.random() < 0.15 else float(rng.uniform(2.0, 10.0))
    density = rng.uniform(0.7, 1.4)  # > 1: denser traffic
    build = _Builder(rng, duration)
    same, oncoming = road.lane_centres()

    # ego lane: traffic at the ego's speed, a safe gap ahead of and behind the ego
    gap = (4.0 / density, 25.0 / density)
    build.stream(_LANE_MIX, 0.0, ego_speed, 0.0, gap,
                 EGO_FRONT_M + rng.uniform(3.0, 12.0), SCENE_RADIUS_M)
    build.stream(_LANE_MIX, 0.0, ego_speed, 0.0, gap,
                 -SCENE_RADIUS_M, EGO_REAR_M - rng.uniform(3.0, 8.0))
    ego_lane = np.array([(row[3][0], row[1][1]) for row in build.rows]).reshape(-1, 2)
    for y in same[1:]:
        speed = max(ego_speed + rng.uniform(-2.0, 2.0), 0.0)
        build.stream(_LANE_MIX, y, speed, 0.0, gap, *_window(speed, ego_speed, duration))
    for y in oncoming:
        speed = -rng.uniform(4.0, 12.0)
        build.stream(_LANE_MIX, y, speed, np.pi, gap, *_window(speed, ego_speed, duration))

    shoulder = 0.5 * (road.right_lane_edge + road.right_kerb)
    if road.parking:
        build.stream(_PARKED_MIX, shoulder, 0.0, 0.0, (0.8, 8.0 / density),
                     *_window(0.0, ego_speed, duration))
    else:
        speed = rng.uniform(3.0, 6.0)
        build.stream((("bicycle", 1.0),), shoulder, speed, 0.0, (8.0 / density, 60.0 / density),
                     *_window(speed, ego_speed, duration))

    sidewalk_gap = (1.5 / density, 20.0 / density)
    for kerb, outward in ((road.right_kerb, -1.0), (road.left_kerb, 1.0)):
        for offset, direction in ((0.9, 1.0), (2.1, -1.0)):
            speed = direction * rng.uniform(1.0, 1.6)
            build.stream((("pedestrian", 1.0),), kerb + outward * offset, speed,
                         0.0 if direction > 0 else np.pi, sidewalk_gap,
                         *_window(speed, ego_speed, duration), yaw_std=0.1)

    for _ in range(rng.poisson(1.5 * duration / 10.0)):
        name = "pedestrian" if rng.random() < 0.8 else "bicycle"
        speed = rng.uniform(1.0, 1.7) if name == "pedestrian" else rng.uniform(2.5, 4.5)
        _add_crosser(build, road, ego_speed, ego_lane, name, speed)

    rare = _Builder(np.random.default_rng(rare_seq), duration)
    for _ in range(rare.rng.poisson(rare_per_scene * duration / 10.0)):
        _add_rare(rare, road, ego_speed, ego_lane)
    build.rows += rare.rows
    x_range = (min(0.0, ego_speed * duration) - SCENE_RADIUS_M - 10.0,
               max(0.0, ego_speed * duration) + SCENE_RADIUS_M + 10.0)
    structure = make_structure(np.random.default_rng(structure_seq), road, x_range)
    return Layout(road, ego_speed, duration, build.actors(), structure)


def make_structure(rng: np.random.Generator, road: Road, x_range: tuple[float, float]) -> Structure:
    """Curbs, poles, trees and a frontage of buildings, fences and hedges on both sides.

    Parameters
    ----------
    rng : numpy.random.Generator
    road : Road
    x_range : (float, float)
        World x the street must cover, metres.

    Returns
    -------
    Structure
    """
    lo, hi = x_range
    rows: list[tuple[str, tuple]] = []

    def box(kind, x0, x1, y_inner, outward, width, height, z0=0.0):
        """A box along x from x0 to x1 whose side nearest the road is at y_inner."""
        y = y_inner + outward * 0.5 * width
        rows.append((kind, (0.5 * (x0 + x1), y, z0 + 0.5 * height, width, x1 - x0, height, 0.0)))

    for kerb, outward in ((road.right_kerb, -1.0), (road.left_kerb, 1.0)):
        box("curb", lo, hi, kerb, outward, CURB_WIDTH_M, CURB_HEIGHT_M)
        x = lo + rng.uniform(0.0, 20.0)  # poles and trees near the kerb
        while x < hi:
            y = kerb + outward * KERB_SETBACK_M
            if rng.random() < 0.65:
                size = rng.uniform(0.15, 0.3)
                box("pole", x - 0.5 * size, x + 0.5 * size, y, outward, size, rng.uniform(4.0, 9.0))
            else:
                trunk_h, crown = rng.uniform(2.2, 3.0), rng.uniform(1.8, 2.6)
                box("trunk", x - 0.15, x + 0.15, y, outward, 0.3, trunk_h)
                box("crown", x - 0.5 * crown, x + 0.5 * crown, y + 0.15 * outward - 0.5 * crown * outward,
                    outward, crown, rng.uniform(2.0, 3.5), z0=trunk_h)
            x += rng.uniform(12.0, 40.0)
        frontage = kerb + outward * SIDEWALK_WIDTH_M
        kinds, weights, lengths = zip(*_FRONTAGE)
        x = lo
        while x < hi:
            k = int(rng.choice(len(kinds), p=np.array(weights) / sum(weights)))
            length = rng.uniform(*lengths[k])
            if kinds[k] == "building":
                box("building", x, x + length, frontage + outward * rng.uniform(0.0, 3.0), outward,
                    12.0, rng.uniform(5.0, 18.0))
            elif kinds[k] == "fence":
                box("fence", x, x + length, frontage + outward * 0.1, outward, 0.1, rng.uniform(1.0, 2.0))
            elif kinds[k] == "hedge":
                box("hedge", x, x + length, frontage + outward * 0.1, outward, rng.uniform(0.6, 1.5),
                    rng.uniform(0.8, 2.0))
            x += length + rng.uniform(0.0, 6.0)
    kinds = np.array([k for k, _ in rows], dtype=str)
    return Structure(kinds, np.array([b for _, b in rows], dtype=np.float64).reshape(-1, 7))


def _add_crosser(build: _Builder, road: Road, ego_speed: float, ego_lane: np.ndarray,
                 name: str, speed: float) -> None:
    """An actor walking across the road, in front of the ego but out of its lane in time.

    ``ego_lane`` holds the ego-lane vehicles' ``x`` (relative to the ego, constant) and
    length, shape (k, 2).

    It is at the ego lane's centre at a random time t_c, at a distance ahead such that it
    has left the ego's path (plus a margin) before the ego gets there; positions on an
    ego-lane vehicle are redrawn (up to 10 times, then the crosser is left out).
    """
    rng = build.rng
    size = build.size(name)
    t_clear = (EGO_HALF_WIDTH_M + 0.5 * size[0] + 0.5) / speed
    for _ in range(10):
        ahead = EGO_FRONT_M + ego_speed * t_clear + 2.0 + rng.uniform(0.0, 20.0) + 0.5 * size[1]
        on_vehicle = np.abs(ego_lane[:, 0] - ahead) < 0.5 * (ego_lane[:, 1] + size[1]) + 1.0
        if not on_vehicle.any():
            break
    else:
        return
    t_c = rng.uniform(0.0, build.duration)
    x = ego_speed * t_c + ahead
    y_right = road.right_kerb - 0.5 * SIDEWALK_WIDTH_M
    y_left = road.left_kerb + 0.5 * SIDEWALK_WIDTH_M
    y_from, y_to = (y_right, y_left) if rng.random() < 0.5 else (y_left, y_right)
    t_a = t_c - abs(y_from) / speed
    t_b = t_c + abs(y_to) / speed
    yaw = np.sign(y_to - y_from) * np.pi / 2 + 0.1 * rng.standard_normal()
    build.add(name, size, yaw, (x, y_from), (x, y_to), t_a, t_b)


def _add_rare(build: _Builder, road: Road, ego_speed: float, ego_lane: np.ndarray) -> None:
    """One rare actor where the ego will see it (kinds and behaviours in the module doc)."""
    rng = build.rng
    kind = build.pick((("animal", 0.4), ("wheelchair", 0.3), ("debris", 0.3)))
    if kind == "animal" and rng.random() < 0.7:
        _add_crosser(build, road, ego_speed, ego_lane, kind, rng.uniform(0.5, 2.5))
        return
    if kind == "wheelchair" and rng.random() < 0.5:
        _add_crosser(build, road, ego_speed, ego_lane, kind, rng.uniform(0.6, 1.2))
        return
    size = build.size(kind)
    t_seen = rng.uniform(0.0, build.duration)
    x = ego_speed * t_seen + rng.uniform(6.0, 30.0)  # ahead of the ego at t_seen
    if kind == "animal":  # standing at the right road side
        y = road.right_kerb + rng.uniform(-1.0, 0.5)
        build.add(kind, size, rng.uniform(-np.pi, np.pi), (x, y), (x, y), 0.0, 1.0)
    elif kind == "wheelchair":  # on the right sidewalk, along it
        speed = rng.choice([-1.0, 1.0]) * rng.uniform(0.6, 1.2)
        y = road.right_kerb - 0.5 * SIDEWALK_WIDTH_M
        build.add_moving(kind, size, 0.0 if speed > 0 else np.pi, x - speed * t_seen, y, speed)
    else:  # debris on a line at the ego lane's edge, clear of the ego's path
        y = rng.choice([-1.0, 1.0]) * (EGO_HALF_WIDTH_M + 0.5 * size[0] + rng.uniform(0.1, 0.5))
        build.add(kind, size, rng.uniform(-np.pi, np.pi), (x, y), (x, y), 0.0, 1.0)


class GroundPainter:
    """Splits the ground pixels of a label map into road, lane markings and sidewalk.

    The ground point under each pixel is fixed for a camera, so the classes are worked out
    once; per frame only the dashes move with the ego.

    Parameters
    ----------
    road : Road
    ground_x, ground_y : ndarray of shape (H, W), float64
        Ego-frame ground point of each pixel, inf where there is none
        (:func:`~monitor.synthetic.raycast.ground_points`).
    """

    def __init__(self, road: Road, ground_x: np.ndarray, ground_y: np.ndarray):
        solid, dashed = road.markings()
        half = 0.5 * MARKING_WIDTH_M
        codes = np.full(ground_y.shape, LABEL_ROAD, dtype=np.int16)
        codes[(ground_y < road.right_kerb) | (ground_y > road.left_kerb)] = LABEL_SIDEWALK
        for y in solid:
            codes[np.abs(ground_y - y) <= half] = LABEL_MARKING
        on_dashed = np.zeros(ground_y.shape, dtype=bool)
        for y in dashed:
            on_dashed |= np.abs(ground_y - y) <= half
        self._codes = codes
        self._dashed = np.flatnonzero(on_dashed)
        self._dashed_x = ground_x.ravel()[self._dashed]

    def paint(self, labels: np.ndarray, ego_x: float) -> np.ndarray:
        """A new label map in which the ground pixels (LABEL_ROAD) got their class.

        Parameters
        ----------
        labels : ndarray of shape (H, W), int16
            From the ray cast.
        ego_x : float
            World x of the ego (places the dashes), metres.
        """
        codes = self._codes.copy()
        on = np.mod(self._dashed_x + ego_x, DASH_PERIOD_M) < DASH_ON_M
        codes.ravel()[self._dashed[on]] = LABEL_MARKING
        return np.where(labels == LABEL_ROAD, codes, labels)
