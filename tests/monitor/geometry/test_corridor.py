"""The driving corridor's centreline table against exact geometry, and its validation."""
import math

import numpy as np
import pytest

from monitor.geometry.corridor import Corridor


def _lateral(corridor, x, y, step=0.1):
    """Distance from the centreline's tangent line at the middle of each point's row."""
    centre, tan = corridor.table(40.0, step)
    k = (np.asarray(x) / step).astype(int)
    return np.abs(y - centre[k] - tan[k] * (x - (k + 0.5) * step)) / np.hypot(1.0, tan[k])


def test_straight_corridor_offsets_are_y():
    x = np.array([0.0, 5.05, 19.99, 39.9])
    y = np.array([0.3, -1.2, 2.0, -0.01])
    np.testing.assert_allclose(_lateral(Corridor(1.75), x, y), np.abs(y))


@pytest.mark.parametrize("curvature", [1 / 30.0, -1 / 50.0])
def test_arc_offsets_match_the_distance_to_the_circle(curvature):
    corridor = Corridor(1.75, curvature=curvature)
    radius = 1 / curvature
    rng = np.random.default_rng(0)
    x = rng.uniform(0.0, 0.5 * abs(radius), 500)  # heading up to 30 degrees
    arc_y = radius - np.sign(radius) * np.sqrt(radius**2 - x**2)
    for offset in (2.0, 0.3):
        y = arc_y + rng.uniform(-offset, offset, 500)
        exact = np.abs(np.hypot(x, y - radius) - abs(radius))  # distance to the circle
        # the tangent line departs from the arc by s^2 / (2 R) at arc length s from where it
        # touches; the foot of the perpendicular is within step / (2 cos) + l sin(heading)
        s = 0.05 / math.cos(math.pi / 6) + offset * 0.5
        np.testing.assert_allclose(_lateral(corridor, x, y), exact, atol=s**2 / (2 * abs(radius)))


def test_arc_ends_where_it_turns_back_and_polyline_where_it_ends():
    centre, tan = Corridor(1.0, curvature=0.1).table(20.0, 0.1)  # R = 10 m
    assert np.all(np.isfinite(centre[:100])) and np.all(np.isnan(centre[100:]))
    assert np.all(np.isnan(tan[100:]))
    # x = 6.05 m: y = 10 - sqrt(100 - 6.05^2), dy/dx = 6.05 / sqrt(100 - 6.05^2)
    root = math.sqrt(100 - 6.05**2)
    assert (centre[60], tan[60]) == (pytest.approx(10 - root), pytest.approx(6.05 / root))
    centre, _ = Corridor(1.0, polyline=[[-1.0, 0.0], [5.0, 0.0], [12.0, 1.4]]).table(20.0, 0.1)
    assert np.all(np.isfinite(centre[:120])) and np.all(np.isnan(centre[120:]))
    # on the second segment, slope 0.2: x = 8.05 m -> y = 0.2 * 3.05
    assert centre[80] == pytest.approx(0.61)


def test_polyline_of_an_arc_agrees_with_the_arc():
    xs = np.linspace(0.0, 25.0, 101)
    radius = 40.0
    line = Corridor(1.5, polyline=np.column_stack([xs, radius - np.sqrt(radius**2 - xs**2)]))
    arc = Corridor(1.5, curvature=1 / radius)
    # chords spanning 0.25 m of x, up to L = 0.25 / cos(heading) long at x = 25 m: y within
    # the sag L^2 / (8 R) / cos (measured along y), slope within L / (2 R) / cos^2
    cos = math.sqrt(1 - (25.0 / radius) ** 2)
    chord = 0.25 / cos
    (y_line, t_line), (y_arc, t_arc) = line.table(25.0, 0.1), arc.table(25.0, 0.1)
    np.testing.assert_allclose(y_line, y_arc, atol=chord**2 / (8 * radius) / cos)
    np.testing.assert_allclose(t_line, t_arc, atol=chord / (2 * radius) / cos**2)


@pytest.mark.parametrize("kwargs, text", [
    (dict(half_width=0.0), "half_width = 0.0"),
    (dict(half_width=1.0, curvature=math.nan), "curvature = nan"),
    (dict(half_width=1.0, curvature=0.1, polyline=[[0, 0], [1, 0]]), "one or the other"),
    (dict(half_width=1.0, polyline=[[0, 0]]), "1 vertex"),
    (dict(half_width=1.0, polyline=[[0, 0], [2, 0], [2, 1]]), r"x\[2\] = 2.0 after x\[1\] = 2.0"),
    (dict(half_width=1.0, polyline=[[0.5, 0], [2, 0]]), "starts at x = 0.5"),
    (dict(half_width=1.0, polyline=[[0, 0], [2, np.inf]]), "must be finite"),
])
def test_bad_corridors_are_refused(kwargs, text):
    with pytest.raises(ValueError, match=text):
        Corridor(**kwargs)
