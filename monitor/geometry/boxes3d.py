"""3D boxes: validation, construction from nuScenes records, frame changes, corners.

A 3D box array is float64 ``(n, 7)``, rows ``x, y, z, w, l, h, yaw``: the centre, the size
(``l`` along the heading, ``w`` across it, ``h`` up; nuScenes' ``wlh`` order) and the
heading angle about the frame's z axis, radians. Boxes are in the ego frame unless a
function says otherwise. Boxes stay upright: a frame change keeps only the rotation of the
heading about the up axis (exact for nuScenes' global <-> ego, which rotates about z up to
small tilts).
"""
from __future__ import annotations

import numpy as np

from monitor.geometry.arrays import finite_array
from monitor.geometry.poses import as_pose, yaw_from_quaternion

#: Column names of a 3D box array, for messages.
COLUMNS_3D = ("x", "y", "z", "w", "l", "h", "yaw")

#: Largest |x|, |y|, |z| of a box centre, metres (100 km: nuScenes' global frames span a
#: few km). Beyond it a box is a corrupt value, and the camera's clipping loses precision.
MAX_COORDINATE_M = 1e5
#: Largest box size w, l, h, metres: no road object is a kilometre long.
MAX_SIZE_M = 1e3

_MIN_UP = 0.9  # a frame change for upright boxes must keep z up: R[2, 2] > this


def as_boxes3d(a, name: str = "boxes3d") -> np.ndarray:
    """Validate a 3D box array and return it as float64 of shape ``(n, 7)``.

    Parameters
    ----------
    a : array_like of shape (n, 7)
        Rows ``x, y, z, w, l, h, yaw`` (metres, radians), finite real numbers; sizes in
        (0, :data:`MAX_SIZE_M`], centre coordinates within :data:`MAX_COORDINATE_M`.
    name : str
        The argument's name, used in error messages.

    Returns
    -------
    ndarray of shape (n, 7), float64
    """
    arr = finite_array(a, name, "(n, 7) with columns " + ", ".join(COLUMNS_3D)
                       + " (no boxes is (0, 7))", ndim=2, last=7)
    bad = np.argwhere(arr[:, 3:6] <= 0.0)
    if bad.size:
        i, j = int(bad[0, 0]), int(bad[0, 1]) + 3
        raise ValueError(f"{name}[{i}, {j}] ({COLUMNS_3D[j]}) = {float(arr[i, j])!r}: "
                         f"box sizes must be > 0 metres")
    for columns, limit, what in ((slice(0, 3), MAX_COORDINATE_M, "centre coordinates"),
                                 (slice(3, 6), MAX_SIZE_M, "box sizes")):
        bad = np.argwhere(np.abs(arr[:, columns]) > limit)
        if bad.size:
            i, j = int(bad[0, 0]), int(bad[0, 1]) + columns.start
            raise ValueError(f"{name}[{i}, {j}] ({COLUMNS_3D[j]}) = {float(arr[i, j])!r}: "
                             f"{what} must be within {limit:g} metres")
    return arr


def boxes3d_from_quaternions(centres, sizes_wlh, rotations_wxyz) -> np.ndarray:
    """3D box array from nuScenes-style records (centre, ``wlh`` size, quaternion).

    Parameters
    ----------
    centres : array_like of shape (n, 3)
        Metres.
    sizes_wlh : array_like of shape (n, 3)
        Width, length, height, metres.
    rotations_wxyz : array_like of shape (n, 4)
        Orientation quaternions; only their heading about z is kept.

    Returns
    -------
    ndarray of shape (n, 7)
    """
    c = finite_array(centres, "centres", "(n, 3) metres", ndim=2, last=3)
    s = finite_array(sizes_wlh, "sizes_wlh", "(n, 3) metres", ndim=2, last=3)
    q = finite_array(rotations_wxyz, "rotations_wxyz", "(n, 4) quaternions", ndim=2, last=4)
    if not c.shape[0] == s.shape[0] == q.shape[0]:
        raise ValueError(f"centres, sizes_wlh and rotations_wxyz have {c.shape[0]}, "
                         f"{s.shape[0]} and {q.shape[0]} rows, expected the same number")
    bad = np.argwhere(s <= 0.0)
    if bad.size:
        i, j = (int(x) for x in bad[0])
        raise ValueError(f"sizes_wlh[{i}, {j}] ({'wlh'[j]}) = {float(s[i, j])!r}: box sizes "
                         f"must be > 0 metres")
    return np.column_stack([c, s, yaw_from_quaternion(q, "rotations_wxyz")])


def transform_boxes(boxes3d, T) -> np.ndarray:
    """Move 3D boxes to another frame.

    Centres are transformed; the heading becomes the direction of the transformed heading
    vector in the new xy plane (nuScenes' ``Box.rotate`` followed by its yaw). Example,
    nuScenes global -> ego: ``transform_boxes(b, invert_pose(pose_matrix(ego_rotation,
    ego_translation)))``.

    Parameters
    ----------
    boxes3d : array_like of shape (n, 7)
    T : array_like of shape (4, 4)
        Rigid transform from the boxes' frame to the new one; it must keep z up
        (``T[2, 2] > 0.9``), as upright boxes cannot be tilted.

    Returns
    -------
    ndarray of shape (n, 7)
    """
    boxes = as_boxes3d(boxes3d)
    T = as_pose(T, "T")
    if not T[2, 2] > _MIN_UP:
        raise ValueError(f"T[2, 2] = {T[2, 2]!r}: the transform tilts the up axis by "
                         f"more than {np.degrees(np.arccos(_MIN_UP)):.0f} degrees; "
                         f"upright 3D boxes cannot follow it")
    out = boxes.copy()
    out[:, :3] = boxes[:, :3] @ T[:3, :3].T + T[:3, 3]
    heading = T[:2, :2] @ np.stack([np.cos(boxes[:, 6]), np.sin(boxes[:, 6])])  # z part 0
    out[:, 6] = np.arctan2(heading[1], heading[0])
    return out


def box_axes(boxes: np.ndarray) -> np.ndarray:
    """(n, 3, 3) unit axes of validated boxes, columns: heading (l), lateral (w), up (h)."""
    c, s = np.cos(boxes[:, 6]), np.sin(boxes[:, 6])
    axes = np.zeros((boxes.shape[0], 3, 3))
    axes[:, 0, 0], axes[:, 1, 0] = c, s
    axes[:, 0, 1], axes[:, 1, 1] = -s, c
    axes[:, 2, 2] = 1.0
    return axes


#: Corner signs along (heading, lateral, up), in the nuScenes devkit's order: the first
#: four corners face forward, the last four backward.
_CORNER_SIGNS = np.array([[1, 1, 1], [1, -1, 1], [1, -1, -1], [1, 1, -1],
                          [-1, 1, 1], [-1, -1, 1], [-1, -1, -1], [-1, 1, -1]], dtype=float)


def box_corners(boxes3d) -> np.ndarray:
    """The eight corners of each 3D box, in the boxes' frame.

    Parameters
    ----------
    boxes3d : array_like of shape (n, 7)

    Returns
    -------
    ndarray of shape (n, 8, 3)
        Corner ``k`` is ``centre + R (signs[k] * (l, w, h) / 2)``, nuScenes' order: corners
        0-3 face forward (0: left top, 1: right top, 2: right bottom, 3: left bottom),
        4-7 are the same behind.
    """
    boxes = as_boxes3d(boxes3d)
    local = _CORNER_SIGNS[None] * (0.5 * boxes[:, None, [4, 3, 5]])
    return boxes[:, None, :3] + np.einsum("nij,nkj->nki", box_axes(boxes), local)


def footprints(boxes: np.ndarray) -> np.ndarray:
    """Where validated upright boxes stand on the ground, seen from the ego: per box ``x``
    its nearest extent along the frame's x axis, ``y_min, y_max`` its extent across it.

    Parameters
    ----------
    boxes : ndarray of shape (n, 7)
        Validated boxes (:func:`as_boxes3d`), metres and radians.

    Returns
    -------
    ndarray of shape (n, 3), float64
        ``x - half_x, y - half_y, y + half_y``, metres, where ``half_x`` and ``half_y`` are
        the half extents of the box's ground rectangle along x and y
        (``(|cos yaw| l + |sin yaw| w) / 2`` and ``(|sin yaw| l + |cos yaw| w) / 2``).
    """
    c, s = np.abs(np.cos(boxes[:, 6])), np.abs(np.sin(boxes[:, 6]))
    half_x = 0.5 * (c * boxes[:, 4] + s * boxes[:, 3])
    half_y = 0.5 * (s * boxes[:, 4] + c * boxes[:, 3])
    return np.column_stack([boxes[:, 0] - half_x, boxes[:, 1] - half_y, boxes[:, 1] + half_y])
