"""The simulated driver's tracker: the Kalman filter against a batch least-squares fit, its
noise ellipse by hand, walkers, parked cars under depth noise, coasting, false positives."""
import numpy as np
import pytest

from monitor.offline import tracking
from monitor.offline.tracking import Tracker

SENSOR = np.array([1.7, 0.0])


def _noisy(rng, centre, depth_rel, bearing_rad):
    """A monocular detector's reading: the distance off by a log-normal factor, the bearing
    by a normal angle (the synthetic detector's model)."""
    sight = centre - SENSOR
    d = np.hypot(*sight)
    along, across = sight / d, np.array([-sight[1], sight[0]]) / d
    return SENSOR + along * d * np.exp(rng.normal(0.0, depth_rel)) + across * d * rng.normal(0.0, bearing_rad)


def test_measurement_noise_is_the_line_of_sight_ellipse_by_hand():
    tracker = Tracker(SENSOR)
    ahead, side = tracker._measurement_noise(np.array([[21.7, 0.0], [1.7, -10.0]]))
    # 20 m straight ahead: 2 m along x, 0.3 m across; 10 m to the right: 1 m along y, 0.2 m across
    assert ahead == pytest.approx(np.diag([2.0 ** 2, 0.3 ** 2]))
    assert side == pytest.approx(np.diag([0.2 ** 2, 1.0 ** 2]))


def test_without_process_noise_the_filter_is_the_batch_least_squares_fit(monkeypatch):
    # with no acceleration noise, the filter's last state is the weighted least-squares fit of
    # a straight constant-speed path to all the measurements, with the new track's velocity
    # prior (zero mean) as one more observation
    monkeypatch.setattr(tracking, "ACCEL", 0.0)
    rng = np.random.default_rng(3)
    tracker = Tracker(SENSOR)
    times = 0.1 * np.arange(8)
    odometer = 6.0 * times
    path = np.column_stack([15.0 - 6.0 * times, 3.0 - 1.2 * times])  # ego frame, the ego at 6 m/s
    seen = np.array([_noisy(rng, c, 0.05, 0.004) for c in path])
    for z, t, o in zip(seen, times, odometer):
        tracker.update(z[None], t, o)
    noise = tracker._measurement_noise(seen)
    normal, right = np.zeros((4, 4)), np.zeros(4)
    for z, t, o, R in zip(seen, times, odometer, noise):
        H = np.hstack([np.eye(2), (t - times[-1]) * np.eye(2)])  # position then from the last state
        W = np.linalg.inv(R)
        normal += H.T @ W @ H
        right += H.T @ W @ (z + [o, 0.0])
    normal[2:, 2:] += np.diag([1 / tracking.INIT_SPEED_ALONG ** 2, 1 / tracking.INIT_SPEED_ACROSS ** 2])
    fit = np.linalg.solve(normal, right)
    assert tracker._state[0] == pytest.approx(fit, abs=1e-9)
    assert tracker._cov[0] == pytest.approx(np.linalg.inv(normal), abs=1e-12)


def test_a_walker_crossing_gets_its_speed_and_a_parked_car_none():
    # the synthetic detector's noise under Gaussian image noise (6 % + 0.4 % per metre of the
    # distance, 0.004 rad): a walker setting off across the path 14 m ahead of the bumper,
    # detected in 70 % of the frames, and cars parked 3 m to the left or 3.5 m to the right
    # passing from 30 m, the ego at 10 m/s
    rng = np.random.default_rng(0)
    delays, parked_frames, frames = [], 0, 0
    for run in range(100):
        walker, car = Tracker(SENSOR), Tracker(SENSOR)
        first = None
        for k in range(30):
            t = 0.1 * k
            centre = np.array([17.8 - 10.0 * t, 3.2 - 1.5 * max(t - 0.3, 0.0)])
            rel = 0.06 + 0.004 * np.hypot(*(centre - SENSOR))
            seen = _noisy(rng, centre, rel, 0.004)[None] if rng.random() < 0.7 else np.zeros((0, 2))
            speed = walker.update(seen, t, 10.0 * t)
            if first is None and len(speed) and speed[0] < 0:
                first = t - 0.3
            centre = np.array([30.0 - 10.0 * t, 3.0 if run % 2 else -3.5])
            rel = 0.06 + 0.004 * np.hypot(*(centre - SENSOR))
            parked_frames += car.update(_noisy(rng, centre, rel, 0.004)[None], t, 10.0 * t)[0] != 0
            frames += 1
        delays.append(first)
    assert None not in delays and np.median(delays) <= 1.0  # seconds after it set off
    assert parked_frames / frames < 0.01


def test_tracks_coast_through_missed_frames_and_keep_apart():
    # two walkers 3 m apart along the road crossing opposite ways, exactly measured; the
    # detector misses both in frames 3 and 6 (one missed frame keeps a run going)
    tracker = Tracker(SENSOR)
    speeds = []
    for k in range(14):
        t = 0.1 * k
        walkers = np.array([[12.0, 2.0 - 1.5 * t], [15.0, -2.0 + 1.5 * t]])
        centres = walkers if k not in (3, 6) else np.zeros((0, 2))
        speeds.append(tracker.update(centres - [5.0 * t, 0.0], t, 5.0 * t))
    assert len(speeds[3]) == 0 and len(tracker._state) == 2
    assert speeds[-1] == pytest.approx([-1.5, 1.5], abs=0.05)
    # two missed frames in a row end the run: the speed waits for a new one
    for k in range(14, 16):
        tracker.update(np.zeros((0, 2)), 0.1 * k, 5.0 * 0.1 * k)
    t = 1.6
    again = tracker.update(np.array([[12.0, 2.0 - 1.5 * t], [15.0, -2.0 + 1.5 * t]]) - [5.0 * t, 0.0], t, 5.0 * t)
    assert list(again) == [0.0, 0.0] and len(tracker._state) == 2


def test_a_walker_the_detector_misses_coasts_where_it_goes_a_parked_car_does_not():
    # a walker 12 m ahead crossing at 1.5 m/s to the right and a car parked 4 m to the left,
    # measured exactly, the ego at 5 m/s; both missed from frame 10 on
    tracker = Tracker(SENSOR)
    for k in range(10):
        speeds = tracker.update(np.array([[12.0 - 0.5 * k, 3.0 - 0.15 * k], [20.0 - 0.5 * k, 4.0]]),
                                0.1 * k, 0.5 * k)
        assert len(tracker.coasting()[0]) == 0  # nothing missed
    walker_speed = speeds[0]
    assert walker_speed < -1.4 and speeds[1] == 0.0
    for k in range(10, 11 + tracking.MAX_MISSES):
        tracker.update(np.zeros((0, 2)), 0.1 * k, 0.5 * k)
        centres, coasting = tracker.coasting()
        if k - 9 <= tracking.MAX_MISSES:
            # the walker alone, where it walks (within the filter's lag), at its last speed
            assert coasting.tolist() == [walker_speed]
            np.testing.assert_allclose(centres, [[12.0 - 0.5 * k, 3.0 - 0.15 * k]], atol=0.1)
        else:  # dropped
            assert len(centres) == 0


def test_a_track_is_dropped_after_max_misses_and_false_positives_get_no_speed():
    tracker = Tracker(SENSOR)
    tracker.update(np.array([[10.0, 0.0]]), 0.0, 0.0)
    for k in range(1, tracking.MAX_MISSES + 1):
        tracker.update(np.zeros((0, 2)), 0.1 * k, 0.0)
    assert len(tracker._state) == 1  # coasting
    tracker.update(np.zeros((0, 2)), 0.1 * (tracking.MAX_MISSES + 1), 0.0)
    assert len(tracker._state) == 0
    # one false positive a frame, each somewhere else: hardly a frame gives one a speed
    rng = np.random.default_rng(1)
    moving = 0
    for run in range(100):
        tracker = Tracker(SENSOR)
        for k in range(50):
            box = np.array([[rng.uniform(5.0, 30.0), rng.uniform(-8.0, 8.0)]])
            moving += tracker.update(box, 0.1 * k, 0.5 * k)[0] != 0.0
    assert moving / 5000 < 0.005


@pytest.mark.parametrize("call, message", [
    (lambda tr: Tracker([1.0, 2.0, 3.0]), "sensor"),
    (lambda tr: tr.update(np.array([[np.nan, 0.0]]), 0.2, 0.0), "finite"),
    (lambda tr: tr.update(np.zeros((0, 2)), 0.1, 0.0), "later than the last frame's 0.1"),
])
def test_bad_input_is_refused_by_name(call, message):
    tracker = Tracker(SENSOR)
    tracker.update(np.zeros((0, 2)), 0.1, 0.0)
    with pytest.raises(ValueError, match=message):
        call(tracker)
