"""Walkers the detector reports, tracked on the road, for the shield's walker gate.

A pedestrian stepping out into the road is seen beside the path before she is in it: the
detector reports her there, and what the car does about it is the planner's (the closed
loop's baseline predicts a track's path only once its Kalman filter is sure of the lateral
speed, :mod:`monitor.offline.tracking`: for a walker at 1 m/s when she is nearly in the
path). :class:`WalkerTracks` follows the
detector's pedestrians from frame to frame where they stand on the road (the ego's travel
added to their distance), and gives, for each one it followed long enough, where she is now
and how fast she walks across the car's heading; :meth:`monitor.shield.Shield.update` engages
the shield for one walking into the path within its reach (``shield.walker_horizon``).

Tracking is nearest-neighbour, as simple as a walker's motion over a second allows: a
position joins the track whose last position (on the road) lies nearest within
:data:`ASSOCIATION_M`, if that was seen within :data:`TRACK_GAP_S`; else it starts a track.
A track's lateral speed is the least-squares slope of its lateral positions over the last
:data:`TRACK_WINDOW_S` seconds, given once it holds :data:`MIN_POINTS` positions spanning
:data:`MIN_SPAN_S` there; a speed outside :data:`WALKING_SPEED` is no walker's (standing
still within the detector's noise, or two people joined into one track). The frames must
come at 10 Hz or so (the closed loop's rate): at nuScenes' 2 Hz keyframes three positions
span a whole second and a walker moves 0.5-1 m between them; hardly a track forms.

:class:`SightingTracks` follows the depth view's unseen objects that could be walkers in
the same way (``shield.unseen_walkers``): a walker the detector misses is still seen by the
depth view once she is in its corridor. Their positions need two things more. A monocular
depth's scale error changes from frame to frame and moves an object's ``x`` and ``y``
together along its line of sight (a post 2.5 m beside the path jumps 0.15 m across with a
6 % error), so a track keeps each sighting's bearing ``y / x`` and puts all of them at one
depth: a straight line fitted to the track's road positions over time. And an object riding
along the road (a cyclist the detector missed) turns its bearing too, as a walker would, so
a track whose fitted speed along the road exceeds :data:`MAX_ALONG_SPEED` is nobody walking
across; the line needs more sightings over a longer time to tell
(:data:`SIGHTING_MIN_POINTS`, :data:`SIGHTING_MIN_SPAN_S`).
"""
from __future__ import annotations

import math

import numpy as np

#: the detector class names that are walkers (nuScenes' detection name, the generator's)
WALKER_CLASSES = ("pedestrian",)
#: metres: the farthest a walker's position joins a track, on the road, from its last one
ASSOCIATION_M = 1.0
#: seconds: a track not extended for longer is dropped
TRACK_GAP_S = 0.5
#: seconds of positions a track's lateral speed is fitted to
TRACK_WINDOW_S = 1.0
#: positions (in the window) a track needs before it has a speed
MIN_POINTS = 3
#: seconds those positions must span
MIN_SPAN_S = 0.15
#: m/s: the lateral speeds that are a walker's (min, max)
WALKING_SPEED = (0.3, 3.0)
#: metres: half a walker's width, beyond her box's centre
BODY_HALF_WIDTH = 0.3
#: the share of an unseen object's columns that must stand on the road
#: (:attr:`monitor.RiskReport.unseen_contact`) for the depth view's sighting to be a walker's
#: (``shield.unseen_walkers``): a walker meets the road at her feet; a blob of the depth floats
STANDING_CONTACT = 0.5
#: :class:`SightingTracks`: the share of its ``x`` by which a sighting's road position may
#: lie from its track's last one (the depth's error, on top of :data:`ASSOCIATION_M`) ...
DEPTH_TOLERANCE = 0.15
#: ... the positions a track needs in its window, the seconds they must span ...
SIGHTING_MIN_POINTS = 5
SIGHTING_MIN_SPAN_S = 0.4
#: ... and the fastest it may move along the road, m/s (a cyclist rides faster)
MAX_ALONG_SPEED = 2.0


def walker_positions(boxes3d: np.ndarray, classes: np.ndarray, scores: np.ndarray,
                     min_score: float) -> np.ndarray:
    """Where the detector's walkers stand: the ``x, y`` (ego frame, metres) of the boxes of
    a class in :data:`WALKER_CLASSES` scoring ``min_score`` or more.

    Parameters
    ----------
    boxes3d : ndarray of shape (m, 7)
        The detector's boxes, ego frame (``x, y, z, w, l, h, yaw``).
    classes : ndarray of shape (m,), str
    scores : ndarray of shape (m,)
    min_score : float

    Returns
    -------
    ndarray of shape (k, 2), float64
    """
    walking = np.isin(np.asarray(classes), WALKER_CLASSES) & (np.asarray(scores) >= min_score)
    return np.asarray(boxes3d, dtype=np.float64).reshape(-1, 7)[walking, :2]


class WalkerTracks:
    """The detector's walkers, followed on the road from frame to frame.

    Examples
    --------
    >>> tracks = WalkerTracks()  # 20 m ahead, 4 m to the left, walking right at 1 m/s
    >>> for k in range(4):  # the ego at 10 m/s: she comes 1 m nearer each 0.1 s
    ...     moving = tracks.update([[20.0 - k, 4.0 - 0.1 * k]], time=0.1 * k, odometer=float(k))
    >>> moving.round(6).tolist()
    [[17.0, 3.7, -1.0]]
    """

    def __init__(self):
        self._tracks = []  # per track: a list of (time, x on the road, y)

    def update(self, walkers, time: float, odometer: float) -> np.ndarray:
        """Add one frame's walkers; the tracks that walk, as they are now.

        Parameters
        ----------
        walkers : array_like of shape (k, 2)
            ``x, y`` of the frame's walkers (ego frame, metres; :func:`walker_positions`).
        time : float
            The frame's time, seconds, increasing.
        odometer : float
            Metres the ego has travelled: a walker's place on the road is her ``x`` plus it.

        Returns
        -------
        ndarray of shape (n, 3), float64
            Per walking track: ``x`` now (ego frame: the median of its road places here,
            their fitted line's for :class:`SightingTracks`), ``y`` now (the fitted line's),
            lateral speed (m/s, positive leftwards).

        Raises
        ------
        ValueError
            ``walkers`` not finite (k, 2) rows.
        """
        walkers = np.asarray(walkers, dtype=np.float64)
        if walkers.size == 0:
            walkers = walkers.reshape(0, 2)
        if walkers.ndim != 2 or walkers.shape[1] != 2 or not np.isfinite(walkers).all():
            raise ValueError(f"walkers has shape {walkers.shape}: expected finite (k, 2) rows x, y "
                             "(ego frame, metres; monitor.walkers.walker_positions)")
        live = [t for t in self._tracks if time - t[-1][0] <= TRACK_GAP_S]
        extended = set()
        for x, y in walkers.tolist():
            best, nearest = None, math.inf
            for i, track in enumerate(live):
                if i in extended:
                    continue
                d = self._distance(track[-1], x, y, odometer)
                if math.isfinite(d) and d <= nearest:
                    best, nearest = i, d
            if best is None:
                live.append([self._row(time, x, y, odometer)])
                extended.add(len(live) - 1)
            else:
                live[best].append(self._row(time, x, y, odometer))
                extended.add(best)
        self._tracks = [[p for p in t if time - p[0] <= TRACK_WINDOW_S] for t in live]
        moving = []
        for track in self._tracks:
            rows = np.array(track)
            if len(rows) < self.min_points or np.ptp(rows[:, 0]) < self.min_span:
                continue
            now = self._motion(rows, time, odometer)
            if now is not None:
                moving.append(now)
        return np.array(moving, dtype=np.float64).reshape(-1, 3)

    #: positions (in the window) a track needs before it has a speed, and the seconds they span
    min_points, min_span = MIN_POINTS, MIN_SPAN_S

    @staticmethod
    def _row(time: float, x: float, y: float, odometer: float) -> tuple:
        """What a track keeps of a position: ``time``, its place along the road, ``y``."""
        return time, x + odometer, y

    @staticmethod
    def _distance(last: tuple, x: float, y: float, odometer: float) -> float:
        """How far a position lies from a track's ``last`` row, metres (inf: too far to join)."""
        d = math.hypot(last[1] - (x + odometer), last[2] - y)
        return d if d <= ASSOCIATION_M else math.inf

    @staticmethod
    def _motion(rows: np.ndarray, time: float, odometer: float) -> tuple | None:
        """A track's ``x, y, lateral speed`` now from its rows (n, 3), None if it does not
        walk: the least-squares line of ``y`` over time; ``x``, the median road place."""
        t, x, y = rows.T
        speed, now = np.polyfit(t - time, y, 1)
        if WALKING_SPEED[0] <= abs(speed) <= WALKING_SPEED[1]:
            return float(np.median(x)) - odometer, float(now), float(speed)
        return None


class SightingTracks(WalkerTracks):
    """The depth view's sightings of what could be a walker, followed on the road.

    As :class:`WalkerTracks`, but a sighting joins a track whose last road position lies
    within :data:`ASSOCIATION_M` plus :data:`DEPTH_TOLERANCE` of its ``x`` along the road
    and within :data:`ASSOCIATION_M` across it (its last bearing at this sighting's depth),
    and a track's positions are its bearings put at one depth, a line fitted to its road
    positions over time; a track moving along the road faster than
    :data:`MAX_ALONG_SPEED` does not walk (module docstring). ``update`` takes sightings
    ahead of the ego origin (``x > 0``).

    Examples
    --------
    >>> tracks = SightingTracks()  # 20 m ahead, 2.5 m to the left, walking right at 1 m/s
    >>> scale = [1.03, 0.98, 1.01, 0.99, 1.02, 0.98]  # the depth's error, frame by frame
    >>> for k, s in enumerate(scale):  # the ego at 10 m/s
    ...     moving = tracks.update([[s * (20.0 - k), s * (2.5 - 0.1 * k)]], time=0.1 * k,
    ...                            odometer=float(k))
    >>> moving.round(2).tolist()
    [[14.85, 1.98, -1.1]]
    """

    min_points, min_span = SIGHTING_MIN_POINTS, SIGHTING_MIN_SPAN_S

    def update(self, walkers, time: float, odometer: float) -> np.ndarray:
        """As :meth:`WalkerTracks.update`, for the sightings ``walkers`` (k, 2) ``x, y``;
        ValueError for one at ``x <= 0`` too."""
        walkers = np.asarray(walkers, dtype=np.float64)
        if walkers.ndim == 2 and walkers.shape[1] == 2 and np.isfinite(walkers).all() \
                and not (walkers[:, 0] > 0).all():
            raise ValueError(f"walkers x = {walkers[:, 0].tolist()}: sightings must lie ahead of the ego "
                             "origin, x > 0 metres")
        return super().update(walkers, time, odometer)

    @staticmethod
    def _row(time: float, x: float, y: float, odometer: float) -> tuple:
        """``time``, the road place, the bearing ``y / x`` and ``x``."""
        return time, x + odometer, y / x, x

    @staticmethod
    def _distance(last: tuple, x: float, y: float, odometer: float) -> float:
        """How far a sighting lies from a track's ``last`` row, in tolerances (inf: too far):
        along the road in units of :data:`ASSOCIATION_M` plus :data:`DEPTH_TOLERANCE` of
        ``x``, across it (the last bearing at the last road place, seen from here) in
        :data:`ASSOCIATION_M`."""
        along = abs(last[1] - (x + odometer)) / (ASSOCIATION_M + DEPTH_TOLERANCE * x)
        across = abs(last[2] * (last[1] - odometer) - y) / ASSOCIATION_M
        return math.hypot(along, across) if along <= 1.0 and across <= 1.0 else math.inf

    @staticmethod
    def _motion(rows: np.ndarray, time: float, odometer: float) -> tuple | None:
        """``x, y, lateral speed`` now from rows (n, 4), None if it does not walk: the road
        place's least-squares line over time gives each sighting's depth, and the bearings
        put at those depths the line of ``y``."""
        t, road, bearing, x = rows.T
        along, place = np.polyfit(t - time, road, 1)
        depth = along * (t - time) + place - (road - x)  # road - x: the odometer then
        speed, now = np.polyfit(t - time, bearing * depth, 1)
        if WALKING_SPEED[0] <= abs(speed) <= WALKING_SPEED[1] and abs(along) <= MAX_ALONG_SPEED:
            return float(place) - odometer, float(now), float(speed)
        return None


def entering(tracks: np.ndarray, half_width: float, front: float, speed: float, horizon: float) -> np.ndarray:
    """Which walking tracks step into the path before the car is past them.

    A track counts when it walks towards the centreline, stands beside the path now (her
    body, :data:`BODY_HALF_WIDTH` each side of her centre, outside ``half_width``) and ahead
    of the front bumper, and at its lateral speed reaches the path's edge within the time
    the car needs to reach her (at ``speed``, at least 0.5 m/s) or ``horizon`` seconds,
    whichever is sooner.

    Parameters
    ----------
    tracks : ndarray of shape (n, 3)
        :meth:`WalkerTracks.update`'s ``x, y, lateral speed``.
    half_width, front : float
        Metres: the path's half width, the front bumper's x (ego frame).
    speed : float
        The ego's speed, m/s.
    horizon : float
        Seconds.

    Returns
    -------
    ndarray of shape (n,), bool
    """
    x, y, vy = tracks.T
    ahead = x - front
    beside = np.abs(y) - BODY_HALF_WIDTH - half_width
    soon = np.minimum(ahead / max(speed, 0.5), horizon)
    return (y * vy < 0) & (beside > 0) & (ahead >= 0) & (beside <= np.abs(vy) * soon)

