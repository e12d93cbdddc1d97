"""The simulated driver's tracker: how each detection moves, for its planner to predict.

A driver that brakes only for what stands in its corridor meets a pedestrian stepping out
from between parked cars too late, however well its detector sees the pedestrian: an
automated driver's tracker follows each detection over frames, and its planner predicts
where the detection will be. :class:`Tracker` gives the closed loop's driver
(:mod:`monitor.offline.closed_loop`) that tracker: one constant-velocity Kalman filter per
track on the road plane; each frame's detections assigned to the tracks by the least total
Mahalanobis distance inside a gate (global nearest neighbour); a new track for each
detection left over; a track dropped after ``MAX_MISSES`` frames without a detection. A
track's lateral speed is used once a run of detections close to its predictions confirms
it; a track that had one at its last detection and misses a frame still tells where it
goes (:meth:`Tracker.coasting`), as a walker the detector loses for a frame or two goes
on walking.

A monocular 3D detector places an object well in bearing and poorly in distance, so the
measurement's covariance is an ellipse along the line of sight from the camera:
``DEPTH_REL * d`` along it, ``BEARING_RAD * d + CENTRE_M`` across it (one standard
deviation, ``d`` the distance). A parked car 20 m ahead and 3 m to the side, whose distance
error also moves it across the path, is thus not taken for one walking across it.

The closed loop's roads are straight and the ego drives along its frame's x axis, so the
filters' frame is the ego frame shifted along x by the ego's odometer.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linear_sum_assignment

#: Measurement noise of a monocular 3D detector, one standard deviation: along the line of
#: sight a share of the distance; across it radians times the distance plus metres of box
#: centre. (Published monocular detectors on nuScenes, FCOS3D and PGD, have mean translation
#: errors of 0.6-0.7 m, mostly in depth.)
DEPTH_REL = 0.1
BEARING_RAD = 0.01
CENTRE_M = 0.1
#: Standard deviation of the constant-velocity model's white-noise acceleration, m/s^2 (a
#: walker setting off, traffic braking gently).
ACCEL = 3.0
#: A new track's velocity standard deviation, m/s: along the road (traffic either way) and
#: across it.
INIT_SPEED_ALONG, INIT_SPEED_ACROSS = 15.0, 2.0
#: The gate: the largest squared Mahalanobis distance of a detection from a track's
#: prediction (chi-square with 2 degrees of freedom, 0.999).
GATE = 13.8
#: A detection at most this far from the prediction (chi-square, 2 degrees of freedom, 0.95)
#: lengthens the track's run of close detections; one farther starts the run again, as do
#: two frames in a row without any (one missed frame does not end it).
CLOSE = 5.99
#: Frames a track coasts without a detection before it is dropped.
MAX_MISSES = 5
#: A track's lateral speed counts once its run of close detections is ``MIN_RUN`` long and
#: the speed is at least ``MIN_LATERAL_SPEED`` m/s and ``SIGNIFICANCE`` standard deviations
#: from 0. (A false positive here and there does not make a run.)
MIN_RUN = 3
MIN_LATERAL_SPEED = 0.5
SIGNIFICANCE = 2.0


class Tracker:
    """Kalman tracks of detections on the road plane; their lateral speeds, frame by frame.

    Parameters
    ----------
    sensor : sequence of 2 floats
        The camera's ``x, y`` in the ego frame, metres: where the lines of sight start.

    Examples
    --------
    >>> tracker = Tracker((1.7, 0.0))  # a walker 12 m ahead crossing at 1.5 m/s to the right
    >>> speeds = [tracker.update(np.array([[12.0 - 0.5 * k, 3.0 - 0.15 * k]]), 0.1 * k, 0.5 * k)
    ...           for k in range(9)]  # the ego drives at 5 m/s and measures it exactly
    >>> [round(float(s[0]), 1) for s in speeds]  # no speed until it is sure of one
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.5, -1.5]
    """

    def __init__(self, sensor):
        sensor = np.asarray(sensor, dtype=np.float64)
        if sensor.shape != (2,) or not np.isfinite(sensor).all():
            raise ValueError(f"sensor = {sensor!r}, expected the camera's finite x, y in the ego frame")
        self._sensor = sensor
        self._state = np.zeros((0, 4))  # x, y, vx, vy per track (road frame)
        self._cov = np.zeros((0, 4, 4))
        self._run = np.zeros(0, dtype=np.int64)
        self._misses = np.zeros(0, dtype=np.int64)
        self._speed = np.zeros(0)  # the lateral speed reported at each track's last detection
        self._odometer = 0.0
        self._time = None

    def update(self, centres: np.ndarray, time: float, odometer: float) -> np.ndarray:
        """Assign this frame's detections to the tracks, update them, and say how fast each
        detection moves across the ego's path.

        Parameters
        ----------
        centres : ndarray of shape (k, 2)
            Box centres ``x, y`` in the ego frame, metres.
        time : float
            The frame's time, seconds, increasing.
        odometer : float
            Metres the ego has travelled along x, at this frame.

        Returns
        -------
        ndarray of shape (k,), float64
            Each detection's track's speed along y, m/s (positive: to the ego's left); 0
            where the track is not sure of a lateral speed (``MIN_RUN``,
            ``MIN_LATERAL_SPEED``, ``SIGNIFICANCE``).
        """
        centres = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
        if not (np.isfinite(centres).all() and math.isfinite(time) and math.isfinite(odometer)):
            raise ValueError("centres, time and odometer must be finite")
        if self._time is not None:
            if not time > self._time:
                raise ValueError(f"time = {time!r}, expected later than the last frame's {self._time!r}")
            self._predict(time - self._time)
        self._time = float(time)
        z = centres + np.array([odometer, 0.0])
        noise = self._measurement_noise(centres)
        track_of = self._assign(z, noise)
        assigned = np.zeros(len(self._state), dtype=bool)
        speeds = np.zeros(len(z))
        for c, t in enumerate(track_of):
            if t < 0:
                continue
            close = self._correct(t, z[c], noise[c]) <= CLOSE
            assigned[t] = True
            self._run[t] = self._run[t] + 1 if close else 1
            vy, sd = self._state[t, 3], math.sqrt(self._cov[t, 3, 3])
            if self._run[t] >= MIN_RUN and abs(vy) >= max(MIN_LATERAL_SPEED, SIGNIFICANCE * sd):
                speeds[c] = vy
            self._speed[t] = speeds[c]
        self._misses[assigned] = 0
        self._misses[~assigned] += 1
        self._run[self._misses >= 2] = 0  # two frames in a row without a detection end a run

        keep = self._misses <= MAX_MISSES
        new = track_of < 0
        init = np.zeros((int(new.sum()), 4, 4))
        init[:, :2, :2] = noise[new]
        init[:, 2, 2], init[:, 3, 3] = INIT_SPEED_ALONG ** 2, INIT_SPEED_ACROSS ** 2
        self._state = np.concatenate([self._state[keep], np.column_stack([z[new], np.zeros((len(init), 2))])])
        self._cov = np.concatenate([self._cov[keep], init])
        self._run = np.concatenate([self._run[keep], np.ones(len(init), dtype=np.int64)])
        self._misses = np.concatenate([self._misses[keep], np.zeros(len(init), dtype=np.int64)])
        self._speed = np.concatenate([self._speed[keep], np.zeros(len(init))])
        self._odometer = float(odometer)
        return speeds

    def coasting(self) -> tuple[np.ndarray, np.ndarray]:
        """The tracks that got no detection in the last :meth:`update` but had a lateral
        speed at their last one (for up to ``MAX_MISSES`` frames, until they are dropped).

        Returns
        -------
        centres : ndarray of shape (k, 2), float64
            Their predicted centres ``x, y`` in the ego frame of that update, metres.
        speeds : ndarray of shape (k,), float64
            The lateral speeds reported at their last detections, m/s.
        """
        coast = (self._misses >= 1) & (self._speed != 0.0)
        return self._state[coast, :2] - np.array([self._odometer, 0.0]), self._speed[coast].copy()

    def _predict(self, dt: float) -> None:
        F = np.eye(4)
        F[0, 2] = F[1, 3] = dt
        q = ACCEL ** 2 * np.array([[dt ** 4 / 4, dt ** 3 / 2], [dt ** 3 / 2, dt ** 2]])
        Q = np.zeros((4, 4))
        Q[np.ix_([0, 2], [0, 2])] = Q[np.ix_([1, 3], [1, 3])] = q
        self._state = self._state @ F.T
        self._cov = F @ self._cov @ F.T + Q

    def _measurement_noise(self, centres: np.ndarray) -> np.ndarray:
        """(k, 2, 2) covariances: the line of sight's ellipse at each centre."""
        sight = centres - self._sensor
        d = np.maximum(np.hypot(sight[:, 0], sight[:, 1]), 1e-6)
        along = sight / d[:, None]
        across = np.column_stack([-along[:, 1], along[:, 0]])
        s_along, s_across = DEPTH_REL * d, BEARING_RAD * d + CENTRE_M
        return (s_along[:, None, None] ** 2 * along[:, :, None] * along[:, None, :]
                + s_across[:, None, None] ** 2 * across[:, :, None] * across[:, None, :])

    def _assign(self, z: np.ndarray, noise: np.ndarray) -> np.ndarray:
        """Each detection's track (index), -1 for none: least total squared Mahalanobis
        distance over the pairs inside the gate."""
        track_of = np.full(len(z), -1, dtype=np.int64)
        if len(z) == 0 or len(self._state) == 0:
            return track_of
        innovation = z[None, :, :] - self._state[:, None, :2]  # (n, k, 2)
        S = self._cov[:, None, :2, :2] + noise[None]
        m2 = np.einsum("nki,nkij,nkj->nk", innovation, np.linalg.inv(S), innovation)
        inside = m2 <= GATE
        rows, cols = linear_sum_assignment(np.where(inside, m2, GATE * 1e3))
        ok = inside[rows, cols]
        track_of[cols[ok]] = rows[ok]
        return track_of

    def _correct(self, t: int, z: np.ndarray, noise: np.ndarray) -> float:
        """Update track ``t`` with measurement ``z``; the innovation's squared Mahalanobis
        distance."""
        P = self._cov[t]
        S_inv = np.linalg.inv(P[:2, :2] + noise)
        innovation = z - self._state[t, :2]
        K = P[:, :2] @ S_inv
        self._state[t] = self._state[t] + K @ innovation
        P = P - K @ P[:2, :]
        self._cov[t] = 0.5 * (P + P.T)
        return float(innovation @ S_inv @ innovation)
