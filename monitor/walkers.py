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
position joins the track whose last position (on the road) lies nearest within the
tolerances below, if that was seen within :data:`TRACK_GAP_S`; else it starts a track. A
track's lateral speed is the least-squares slope of its lateral positions over the last
:data:`TRACK_WINDOW_S` seconds, given once it holds :data:`MIN_POINTS` positions spanning
:data:`MIN_SPAN_S` there; a speed outside :data:`WALKING_SPEED` is no walker's (standing
still within the detector's noise), and neither is a track whose positions stray from its
line by more than :data:`MAX_SPREAD_M` (two people joined into one track: on a sidewalk
they walk in lines a metre apart, in both directions). The frames must come at 10 Hz or so
(the closed loop's rate): at nuScenes' 2 Hz keyframes three positions span a whole second
and a walker moves 0.5-1 m between them; hardly a track forms.

A camera's distances err more than its bearings. A monocular 3D detector's distance is off
by some per cent from frame to frame, a monocular depth's scale error changes from frame to
frame, and either moves a position's ``x`` and ``y`` together along its line of sight: a
walker 5 m beside the path, read 10 % too far, jumps 0.5 m across. So a track keeps each
position's bearing ``y / x`` and puts all of them at one depth, the mean of its places
along the road (a walker crossing the road stays at one place along it; over a few frames
the mean errs less than any one reading, and less than a line fitted to them). A position
joins a track within :data:`ASSOCIATION_M` plus :data:`DEPTH_TOLERANCE` of its ``x`` along
the road, and within :data:`ASSOCIATION_M` across it, its bearing and the track's last one
both put at the track's depth: a walker's place across the road does not move as the car
comes nearer, nor with a reading's distance error.

:class:`SightingTracks` follows the depth view's unseen objects that could be walkers in
the same way (``shield.unseen_walkers``): a walker the detector misses is still seen by the
depth view once she is in its corridor. What it sees has no class to tell a walker by. The
end of a parked car or a post beside the path stands still, so a sighting track needs more
positions over a longer time (:data:`SIGHTING_MIN_POINTS`, :data:`SIGHTING_MIN_SPAN_S`); and
an object riding along the road (a cyclist the detector missed) turns its bearing too, as a
walker would, so a sighting track whose speed along the road (the least-squares slope of
its places over time) exceeds :data:`MAX_ALONG_SPEED` is nobody walking across.
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
#: metres: the most a track's lateral positions may stray from their fitted line (root mean
#: square): half a walker's width; more is two people joined into one track
MAX_SPREAD_M = BODY_HALF_WIDTH
#: the share of an unseen object's columns that must stand on the road
#: (:attr:`monitor.RiskReport.unseen_contact`) for the depth view's sighting to be a walker's
#: (``shield.unseen_walkers``): a walker meets the road at her feet; a blob of the depth floats
STANDING_CONTACT = 0.5
#: the share of its ``x`` by which a position's place along the road may lie from its
#: track's last one (the distance's error, on top of :data:`ASSOCIATION_M`)
DEPTH_TOLERANCE = 0.15
#: :class:`SightingTracks`: the positions a track needs in its window, the seconds they span ...
SIGHTING_MIN_POINTS = 5
SIGHTING_MIN_SPAN_S = 0.4
#: ... and the fastest it may move along the road, m/s (a cyclist rides faster)
MAX_ALONG_SPEED = 2.0


def walker_positions(boxes3d: np.ndarray, classes: np.ndarray, scores: np.ndarray,
                     min_score: float) -> np.ndarray:
    """Where the detector's walkers stand: the ``x, y`` (ego frame, metres) of the boxes of
    a class in :data:`WALKER_CLASSES` scoring ``min_score`` or more, ahead of the ego origin
    (``x > 0``; one beside or behind the car steps into no path ahead of it).

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
    boxes3d = np.asarray(boxes3d, dtype=np.float64).reshape(-1, 7)
    walking = np.isin(np.asarray(classes), WALKER_CLASSES) & (np.asarray(scores) >= min_score) & (boxes3d[:, 0] > 0)
    return boxes3d[walking, :2]


class WalkerTracks:
    """The detector's walkers, followed on the road from frame to frame (module docstring):
    their bearings put at one depth, the mean of their places along the road.

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
            ``x, y`` of the frame's walkers (ego frame, metres, ``x > 0``;
            :func:`walker_positions`).
        time : float
            The frame's time, seconds, increasing.
        odometer : float
            Metres the ego has travelled: a walker's place on the road is her ``x`` plus it.

        Returns
        -------
        ndarray of shape (n, 3), float64
            Per walking track: ``x`` now (ego frame: the mean of its road places), ``y`` now
            (the fitted line's), lateral speed (m/s, positive leftwards).

        Raises
        ------
        ValueError
            ``walkers`` not finite (k, 2) rows, or one at ``x <= 0``.
        """
        walkers = np.asarray(walkers, dtype=np.float64)
        if walkers.size == 0:
            walkers = walkers.reshape(0, 2)
        if walkers.ndim != 2 or walkers.shape[1] != 2 or not np.isfinite(walkers).all():
            raise ValueError(f"walkers has shape {walkers.shape}: expected finite (k, 2) rows x, y "
                             "(ego frame, metres; monitor.walkers.walker_positions)")
        if not (walkers[:, 0] > 0).all():
            raise ValueError(f"walkers x = {walkers[:, 0].tolist()}: positions must lie ahead of the ego "
                             "origin, x > 0 metres")
        live = [t for t in self._tracks if time - t[-1][0] <= TRACK_GAP_S]
        extended = set()
        for x, y in walkers.tolist():
            best, nearest = None, math.inf
            for i, track in enumerate(live):
                if i in extended:
                    continue
                d = self._distance(track, x, y, odometer)
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
    #: m/s: the fastest a walking track may move along the road (the detector's class says
    #: who walks)
    max_along = math.inf

    @staticmethod
    def _row(time: float, x: float, y: float, odometer: float) -> tuple:
        """What a track keeps of a position: ``time``, its place along the road, its bearing
        ``y / x`` and ``x``."""
        return time, x + odometer, y / x, x

    @staticmethod
    def _distance(track: list, x: float, y: float, odometer: float) -> float:
        """How far a position lies from a ``track`` (its rows), in tolerances (inf: too far):
        along the road from its last place, in units of :data:`ASSOCIATION_M` plus
        :data:`DEPTH_TOLERANCE` of ``x``; across it in :data:`ASSOCIATION_M`, the position's
        bearing and the track's last one both put at the track's depth (the mean of its road
        places), as :meth:`_motion` puts them."""
        last = track[-1]
        place = sum(row[1] for row in track) / len(track)
        along = abs(last[1] - (x + odometer)) / (ASSOCIATION_M + DEPTH_TOLERANCE * x)
        # last[1] - last[3]: the odometer when the last position was read
        across = abs(last[2] * (place - (last[1] - last[3])) - y / x * (place - odometer)) / ASSOCIATION_M
        return math.hypot(along, across) if along <= 1.0 and across <= 1.0 else math.inf

    @classmethod
    def _motion(cls, rows: np.ndarray, time: float, odometer: float) -> tuple | None:
        """``x, y, lateral speed`` now from rows (n, 4), None if it does not walk: each
        position's depth is the mean road place less the odometer then, and its bearing put
        at that depth gives its ``y``; the least-squares line of ``y`` over time gives ``y``
        now and the lateral speed, and the ``y`` must lie near it (:data:`MAX_SPREAD_M`)."""
        t, road, bearing, x = rows.T
        place = road.mean()
        y = bearing * (place - (road - x))  # road - x: the odometer then
        speed, now = np.polyfit(t - time, y, 1)
        spread = math.sqrt(np.mean((y - now - speed * (t - time)) ** 2))
        if spread > MAX_SPREAD_M or not WALKING_SPEED[0] <= abs(speed) <= WALKING_SPEED[1]:
            return None
        if math.isfinite(cls.max_along) and abs(np.polyfit(t - time, road, 1)[0]) > cls.max_along:
            return None  # riding along the road
        return float(place) - odometer, float(now), float(speed)


class SightingTracks(WalkerTracks):
    """The depth view's sightings of what could be a walker, followed on the road as
    :class:`WalkerTracks` follows the detector's walkers; a track needs
    :data:`SIGHTING_MIN_POINTS` sightings over :data:`SIGHTING_MIN_SPAN_S` and moves along
    the road no faster than :data:`MAX_ALONG_SPEED` (module docstring).

    Examples
    --------
    >>> tracks = SightingTracks()  # 20 m ahead, 2.5 m to the left, walking right at 1 m/s
    >>> scale = [1.03, 0.98, 1.01, 0.99, 1.02, 0.98]  # the depth's error, frame by frame
    >>> for k, s in enumerate(scale):  # the ego at 10 m/s
    ...     moving = tracks.update([[s * (20.0 - k), s * (2.5 - 0.1 * k)]], time=0.1 * k,
    ...                            odometer=float(k))
    >>> moving.round(2).tolist()
    [[15.04, 2.01, -1.0]]
    """

    min_points, min_span = SIGHTING_MIN_POINTS, SIGHTING_MIN_SPAN_S
    max_along = MAX_ALONG_SPEED


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

