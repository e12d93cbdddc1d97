"""The trade-off figure's labels: settings named by what differs between them, grouped by point."""
import math

from monitor.report.closed_loop_figures import point_labels


def _point(driver, fb, avoided, trip):
    return {"driver": driver, "false_brake_rate": fb, "avoidance_rate_avoidable": avoided,
            "added_trip_time": trip}


def test_settings_on_one_point_share_a_label_naming_what_differs():
    points = [_point("t0.50 r0.50 h5 p1.25 m1", 0.42, 0.94, 0.14),
              _point("t0.30 r0.30 h5 p1.25 m1", 0.42, 0.94, 0.14),
              _point("t0.30 r0.30 h0 p1.25 m1", 0.42, 0.88, 0.001),
              _point("t0.80 r0.70 h0 p1.25 m1", 0.25, 0.75, math.nan)]
    # the last two words (p1.25, m1) are shared by all four: left out
    assert point_labels(points) == {
        (0.42, 0.94): "t0.50 r0.50 h5 (+14% trip)\nt0.30 r0.30 h5 (+14% trip)",
        (0.42, 0.88): "t0.30 r0.30 h0 (+0% trip)",
        (0.25, 0.75): "t0.80 r0.70 h0",
    }


def test_a_single_setting_keeps_its_whole_name():
    assert point_labels([_point("t0.50 h5", 0.1, 1.0, -0.02)]) == {(0.1, 1.0): "t0.50 h5 (-2% trip)"}
    assert point_labels([]) == {}
