"""Hostile dataset files and boxes: errors name the file, field or argument (issue 13, item 17)."""
import numpy as np
import pytest

from monitor.alignment import align, assign_by_centre
from monitor.datasets.scene_folder import SCENE_FILE, read_scene


@pytest.mark.parametrize("content, message", [
    (b"\xff\xfe{}", r"not UTF-8 text \(byte 0"),
    (b"[" * 100_000 + b"]" * 100_000, "JSON nested too deeply to read"),
    (b"", "not valid JSON"),
])
def test_scene_file_errors_name_the_file(tmp_path, content, message):
    (tmp_path / SCENE_FILE).write_bytes(content)
    with pytest.raises(ValueError, match=message) as info:
        read_scene(tmp_path)
    assert str(tmp_path / SCENE_FILE) in str(info.value)


@pytest.mark.parametrize("value", [1e200, -1e300, 1.7e308, 1e16])
def test_huge_box_coordinates_are_refused_by_name(value):
    S = np.array([[10.0, 10.0, 4.0, 4.0, 5.0]])
    P = np.array([[value, 10.0, 4.0, 4.0, 5.0]])
    # before: scipy's "cost matrix is infeasible" (the centre distance overflows to inf)
    with pytest.raises(ValueError, match=r"P\[0, 0\] \(cx\) = .*: must be within \+-1e\+15"):
        align(S, P)
    with pytest.raises(ValueError, match=r"b\[0, 0\] \(cx\)"):
        assign_by_centre(S, P)


def test_large_but_sane_coordinates_still_align():
    # 1e15 at most: the squared distance 2e30 is far from overflowing
    S = np.array([[1e15, -1e15, 4.0, 4.0, 5.0], [10.0, 10.0, 4.0, 4.0, 5.0]])
    P = np.array([[10.0, 10.0, 4.0, 4.0, 5.0]])
    result = align(S, P)
    assert result.partner.tolist() == [-1, 0] and result.matched.tolist() == [False, True]
