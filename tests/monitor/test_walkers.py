"""The detector's walkers and the depth view's sightings, tracked on the road: positions,
association, the bearings put at one depth and the fitted lateral speed by hand, and which
tracks step into the path."""
import numpy as np
import pytest

from monitor.walkers import SightingTracks, WalkerTracks, entering, walker_positions


def test_walker_positions_keep_the_walkers_scoring_enough_ahead():
    boxes = np.arange(35, dtype=np.float64).reshape(5, 7) + 1.0
    boxes[4, 0] = 0.0  # at the ego origin, beside the car
    classes = np.array(["pedestrian", "car", "pedestrian", "pedestrian", "pedestrian"])
    scores = np.array([0.9, 0.9, 0.2, 0.3, 0.9])
    assert walker_positions(boxes, classes, scores, 0.3).tolist() == [[1.0, 2.0], [22.0, 23.0]]
    assert walker_positions(np.zeros((0, 7)), np.array([], dtype=str), np.zeros(0), 0.3).shape == (0, 2)


def _walk(tracks, points, speed=10.0, dt=0.1):
    """Feed one walker's ego-frame ``(x, y)`` per frame, the ego at ``speed``; the last output."""
    out = None
    for k, (x, y) in enumerate(points):
        out = tracks.update([[x, y]], time=dt * k, odometer=speed * dt * k)
    return out


def test_the_lateral_speed_is_the_least_squares_slope_by_hand():
    # on the road x = 20 throughout (odometer 0, 1, 2, 3: ego-frame x 20, 19, 18, 17, so each
    # bearing is put at the depth it was seen at);
    # y = 4.0, 3.95, 3.75, 3.7 at t = 0, 0.1, 0.2, 0.3: mean t 0.15, mean y 3.85,
    # sum (t - 0.15)(y - 3.85) = -0.0225 - 0.005 - 0.005 - 0.0225 = -0.055, sum (t - 0.15)^2 =
    # 0.05: slope -1.1 m/s; the line at t = 0.3: 3.85 - 1.1 * 0.15 = 3.685; x now: the road
    # place, 20.0, minus the odometer, 3
    tracks = WalkerTracks()
    out = _walk(tracks, [(20.0, 4.0), (19.0, 3.95), (18.0, 3.75), (17.0, 3.7)])
    assert out.shape == (1, 3)
    assert out[0] == pytest.approx([17.0, 3.685, -1.1])


def test_a_track_needs_three_positions_and_a_walking_speed():
    tracks = WalkerTracks()
    assert _walk(tracks, [(20.0, 4.0), (19.0, 3.9)]).shape == (0, 3)
    assert _walk(WalkerTracks(), [(20.0 - k, 4.0) for k in range(5)]).shape == (0, 3)  # standing
    assert _walk(WalkerTracks(), [(20.0 - k, 4.0 - 0.02 * k) for k in range(5)]).shape == (0, 3)  # 0.2 m/s
    # 0.9 m per frame is within the association's 1 m but 9 m/s: no walker's
    assert _walk(WalkerTracks(), [(20.0 - k, 4.0 - 0.9 * k) for k in range(5)]).shape == (0, 3)


def test_two_people_joined_into_one_track_are_no_walker():
    # on a sidewalk 10 m ahead (the ego at rest), positions 0.9 m apart in turn, each within a
    # metre of the last: y = 4.0, 3.1, 3.9, 3.0 at t = 0 .. 0.3 fit the line 3.5 - 2.2 (t -
    # 0.15), a walking speed (sum (t - 0.15)(y - 3.5) = -0.075 + 0.02 + 0.02 - 0.075 = -0.11,
    # over 0.05), but stray from it by 0.17, -0.51, 0.51, -0.17: 0.38 m root mean square, more
    # than half a walker's width (0.3 m)
    assert _walk(WalkerTracks(), [(10.0, 4.0), (10.0, 3.1), (10.0, 3.9), (10.0, 3.0)], speed=0.0).shape == (0, 3)
    # one walker, y = 3.88, 3.56, 3.44, 3.12: the line 3.5 - 2.4 (t - 0.15), her positions
    # within 0.06 m of it: followed
    out = _walk(WalkerTracks(), [(10.0, 3.88), (10.0, 3.56), (10.0, 3.44), (10.0, 3.12)], speed=0.0)
    assert out[0, 2] == pytest.approx(-2.4)


def test_the_fit_keeps_the_last_second():
    # standing until t = 0.4, then walking right at 1.2 m/s: at t = 1.6 the window holds
    # t = 0.6 .. 1.6, all walking
    ys = [4.0] * 5 + [4.0 - 1.2 * 0.1 * k for k in range(1, 13)]
    out = _walk(WalkerTracks(), [(30.0 - k, y) for k, y in enumerate(ys)])
    assert out[0, 2] == pytest.approx(-1.2)
    assert out[0, 1] == pytest.approx(ys[-1])


def test_a_track_not_extended_for_half_a_second_is_dropped():
    tracks = WalkerTracks()
    for k in range(3):
        tracks.update([[20.0, 4.0 - 0.1 * k]], time=0.1 * k, odometer=0.0)
    # no detection: the track walks on, its line given where it puts her now
    assert tracks.update(np.zeros((0, 2)), time=0.3, odometer=0.0)[0] == pytest.approx([20.0, 3.7, -1.0])
    assert tracks.update([[20.0, 3.6]], time=0.4, odometer=0.0)[0, 2] == pytest.approx(-1.0)
    # seen again 0.6 s later where the line puts her: a new track, one position
    assert tracks.update([[20.0, 3.0]], time=1.0, odometer=0.0).shape == (0, 3)


def test_association_one_position_per_track_the_nearest_within_a_metre():
    tracks = WalkerTracks()
    for k in range(3):  # two walkers 3 m apart, crossing towards each other
        out = tracks.update([[20.0, 4.0 - 0.1 * k], [20.0, 1.0 + 0.1 * k]], time=0.1 * k, odometer=0.0)
    assert sorted(out[:, 2].round(9).tolist()) == [-1.0, 1.0]
    # two positions near one track's last (0.4 m and 0.6 m across): the nearer extends it, the
    # other starts a track; a position 1.5 m across from every track starts one too
    tracks = WalkerTracks()
    for k in range(2):
        tracks.update([[20.0, 4.0 - 0.1 * k]], time=0.1 * k, odometer=0.0)
    out = tracks.update([[20.0, 3.5], [20.0, 4.5], [20.0, 5.4]], time=0.2, odometer=0.0)
    # y 4.0, 3.9, 3.5 at t 0, 0.1, 0.2: (-0.1 * 0.2 + 0.1 * -0.3) / 0.02
    assert out.shape == (1, 3) and out[0, 2] == pytest.approx(-2.5)


@pytest.mark.parametrize("tracks", [WalkerTracks, SightingTracks])
def test_positions_must_be_finite_rows_of_two_ahead(tracks):
    with pytest.raises(ValueError, match=r"walkers has shape \(1, 3\): expected finite \(k, 2\) rows"):
        tracks().update([[1.0, 2.0, 3.0]], time=0.0, odometer=0.0)
    with pytest.raises(ValueError, match="expected finite"):
        tracks().update([[np.nan, 2.0]], time=0.0, odometer=0.0)
    with pytest.raises(ValueError, match=r"walkers x = \[0.0\]: positions must lie ahead of the ego origin"):
        tracks().update([[0.0, 2.0]], time=0.0, odometer=0.0)


# ---------------------------------------- both: the distance's error, a cyclist, the association

def _sighted(points, odometer=None, dt=0.1, tracks=SightingTracks):
    """Feed ``tracks`` (a new one of that class) one object's ego-frame ``(x, y)`` per frame
    (the ego at rest unless ``odometer`` gives its travel per frame); the last output."""
    tracks, out = tracks(), None
    for k, (x, y) in enumerate(points):
        out = tracks.update([[x, y]], time=dt * k, odometer=0.0 if odometer is None else odometer[k])
    return out


@pytest.mark.parametrize("tracks", [WalkerTracks, SightingTracks])
def test_the_bearings_are_put_at_one_depth_by_hand(tracks):
    # a walker 10 m ahead (the ego at rest) crossing from y = 2.0 at 1 m/s, t = 0 .. 0.4; the
    # camera reads her at 9.9, 10.2, 9.8, 10.2, 9.9 m: each position's x and y scaled alike
    # (scale 0.99, 1.02, 0.98, 1.02, 0.99). The road places' mean is 10.0 (the deviations
    # -0.1, 0.2, -0.2, 0.2, -0.1 sum to 0), so every bearing (2 - t) / 10 is put at 10 m:
    # y = 2 - t, exactly her line: now (t = 0.4) 1.6 m, -1 m/s
    t = np.arange(5) * 0.1
    scale = np.array([0.99, 1.02, 0.98, 1.02, 0.99])
    points = np.stack([10.0 * scale, (2.0 - t) * scale], axis=1)
    assert _sighted(points, tracks=tracks)[0] == pytest.approx([10.0, 1.6, -1.0])
    # the ego driving at 10 m/s, no error: x 20, 19, ... on a fixed road place, y as before
    ahead = np.stack([20.0 - 10.0 * t, 2.0 - t], axis=1)
    assert _sighted(ahead, odometer=10.0 * t, tracks=tracks)[0] == pytest.approx([16.0, 1.6, -1.0])


@pytest.mark.parametrize("tracks, cyclist", [(SightingTracks, False), (WalkerTracks, True)])
def test_a_sighting_riding_along_the_road_is_no_walker_a_detected_one_is(tracks, cyclist):
    # the ego at 10 m/s, the object moving along at 4 m/s (its road place 20 + 4 t), drifting
    # towards the path at 1 m/s: a cyclist, not a walker, unless the detector says so; at
    # 1.5 m/s along, a walker
    t = np.arange(5) * 0.1
    for along, walks in ((4.0, cyclist), (1.5, True)):
        points = np.stack([20.0 + (along - 10.0) * t, 2.5 - t], axis=1)
        assert (_sighted(points, odometer=10.0 * t, tracks=tracks).shape[0] == 1) is walks, along


@pytest.mark.parametrize("tracks", [WalkerTracks, SightingTracks])
def test_positions_join_within_the_distance_s_error_along_and_a_metre_across(tracks):
    # the last position 20 m ahead, 2 m to the left (bearing 0.1), the ego at rest: along the
    # road a position joins within 1 m + 0.15 of its x; across within 1 m of 2 m, its bearing
    # put at the track's depth, 20 m ((23.5, 2.0) lies at 1.70 m there, (17.5, 2.0) at 2.29 m)
    for x, y, joins in ((23.5, 2.0, True),    # 3.5 m farther: within 1 + 0.15 * 23.5 = 4.5 m
                        (17.5, 2.0, True),    # 2.5 m nearer: within 1 + 0.15 * 17.5 = 3.6 m
                        (16.0, 2.0, False),   # 4 m nearer: beyond 1 + 0.15 * 16 = 3.4 m
                        (20.0, 2.9, True),    # 0.9 m across
                        (20.0, 3.1, False)):  # 1.1 m across
        followed = tracks()
        followed.update([[20.0, 2.0]], time=0.0, odometer=0.0)
        followed.update([[x, y]], time=0.1, odometer=0.0)
        assert len(followed._tracks) == (1 if joins else 2), (x, y)


@pytest.mark.parametrize("tracks", [WalkerTracks, SightingTracks])
def test_across_the_road_both_bearings_are_put_at_the_track_s_depth(tracks):
    # a walker standing 7 m to the left of the path, 20 m ahead (the ego at rest), read 15 %
    # too far: (23.0, 8.05), 1.05 m farther out where it was read, but its bearing
    # 8.05 / 23 = 0.35 at the track's 20 m is 7 m again: the same track
    followed = tracks()
    followed.update([[20.0, 7.0]], time=0.0, odometer=0.0)
    followed.update([[23.0, 8.05]], time=0.1, odometer=0.0)
    assert len(followed._tracks) == 1
    # two people standing 1.2 m apart across, 12 m along the road (road place 12), the ego
    # coming at 5 m/s: the outer one read at t = 0, 0.1 (y -5.4), then only the inner one
    # at t = 0.4, 0.5, 0.6 (y -4.2). At the track's depth they stay 1.2 m apart: two tracks,
    # each standing, no walker. (Her last bearing seen at the car's new place, -5.4 / 11.5 *
    # 10 = -4.7 m, lay within a metre of the inner one: a track walking 2.4 m/s towards the path.)
    followed, out = tracks(), None
    for t, y in ((0.0, -5.4), (0.1, -5.4), (0.4, -4.2), (0.5, -4.2), (0.6, -4.2)):
        out = followed.update([[12.0 - 5.0 * t, y]], time=t, odometer=5.0 * t)
    assert len(followed._tracks) == 2 and out.shape == (0, 3)


# ------------------------------------------------------------------- the depth view's sightings

def test_a_sighting_track_needs_five_positions_over_0_4_s_and_a_walking_speed():
    t = np.arange(5) * 0.1
    crossing = np.stack([10.0 + 0.0 * t, 2.0 - t], axis=1)
    assert _sighted(crossing[:4]).shape == (0, 3)  # 0.3 s
    assert _sighted(crossing, dt=0.09).shape == (0, 3)  # five over 0.36 s
    assert _sighted(crossing).shape == (1, 3)
    assert _sighted(np.stack([10.0 + 0.0 * t, 2.0 + 0.0 * t], axis=1)).shape == (0, 3)  # standing


@pytest.mark.parametrize("x, y, vy, speed, expected", [
    # path half width 1.25, her half width 0.3: her edge is |y| - 1.55 from the path's
    (23.8, 2.5, -1.0, 10.0, True),    # 20 m ahead, 2 s away: within the 1 s horizon, 0.95 m <= 1.0 m
    (23.8, 3.0, -1.0, 10.0, False),   # 1.45 m to go, 1.0 m in the horizon
    (13.8, 2.5, -1.0, 20.0, False),   # 10 m ahead at 20 m/s: 0.5 s, the car is past first
    (13.8, 2.5, -2.0, 20.0, True),    # ... unless she walks 2 m/s
    (23.8, 2.5, 1.0, 10.0, False),    # walking away
    (23.8, -2.5, 1.0, 10.0, True),    # from the right
    (23.8, 1.5, -1.0, 10.0, False),   # in the path already (1.5 - 0.3 < 1.25): the view's to see
    (3.0, 2.5, -1.0, 10.0, False),    # behind the bumper
    (4.0, 1.9, -1.0, 0.0, True),      # a car at rest: 0.2 m ahead at 0.5 m/s, 0.4 s; 0.35 m to go
])
def test_entering_by_hand(x, y, vy, speed, expected):
    assert entering(np.array([[x, y, vy]]), 1.25, 3.8, speed, 1.0).tolist() == [expected]
