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
            Per walking track: ``x`` now (ego frame, the median of its positions in the
            window), ``y`` now (the fitted line's), lateral speed (m/s, positive leftwards).

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
            best, nearest = None, ASSOCIATION_M
            for i, track in enumerate(live):
                if i in extended:
                    continue
                d = math.hypot(track[-1][1] - (x + odometer), track[-1][2] - y)
                if d <= nearest:
                    best, nearest = i, d
            if best is None:
                live.append([(time, x + odometer, y)])
                extended.add(len(live) - 1)
            else:
                live[best].append((time, x + odometer, y))
                extended.add(best)
        self._tracks = [[p for p in t if time - p[0] <= TRACK_WINDOW_S] for t in live]
        moving = []
        for track in self._tracks:
            if len(track) < MIN_POINTS:
                continue
            t, x, y = np.array(track).T
            if np.ptp(t) < MIN_SPAN_S:
                continue
            speed, now = np.polyfit(t - time, y, 1)
            if WALKING_SPEED[0] <= abs(speed) <= WALKING_SPEED[1]:
                moving.append((float(np.median(x)) - odometer, now, speed))
        return np.array(moving, dtype=np.float64).reshape(-1, 3)


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

