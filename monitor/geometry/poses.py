"""Quaternions, rigid poses and frame changes of points.

Conventions (nuScenes):

- ego frame: x forward, y left, z up, metres, origin at the ego vehicle's reference point;
- camera frame: z forward (optical axis), x right, y down, metres;
- quaternions are ``(w, x, y, z)``; a pose ``(rotation, translation)`` takes points of the
  child frame to the parent frame, ``p_parent = R p_child + t`` (nuScenes' calibrated
  sensors are camera -> ego, its ego poses are ego -> global). A pose is a (4, 4) float64
  matrix ``[[R, t], [0, 0, 0, 1]]``.
"""
from __future__ import annotations

import numpy as np

from monitor.geometry.arrays import finite_array

_UNIT_TOLERANCE = 1e-3  # |norm - 1| accepted for a quaternion (then normalised)
_RIGID_TOLERANCE = 1e-6  # max |R^T R - I| and |det R - 1| of a pose's rotation


def _unit_quaternions(q_wxyz, name: str) -> np.ndarray:
    q = finite_array(q_wxyz, name, "(..., 4) quaternions (w, x, y, z)", last=4)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    bad = np.abs(norm[..., 0] - 1.0) > _UNIT_TOLERANCE
    if bad.any():
        where = tuple(int(x) for x in np.argwhere(np.atleast_1d(bad))[0])[:bad.ndim]
        raise ValueError(f"{name}{list(where) if where else ''} has norm "
                         f"{float(norm[where][0])!r}, expected a unit quaternion "
                         f"(w, x, y, z) within {_UNIT_TOLERANCE}")
    return q / norm


def _rotation_matrices(q_wxyz, name: str) -> np.ndarray:
    w, x, y, z = np.moveaxis(_unit_quaternions(q_wxyz, name), -1, 0)
    rows = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def yaw_of_rotation(R: np.ndarray) -> np.ndarray:
    """(...) heading of (..., 3, 3) rotations: the angle of the rotated x axis in the xy
    plane, radians in ``[-pi, pi]``."""
    return np.arctan2(R[..., 1, 0], R[..., 0, 0])


def quaternion_to_rotation(q_wxyz) -> np.ndarray:
    """Rotation matrices of unit quaternions.

    Parameters
    ----------
    q_wxyz : array_like of shape (..., 4)
        ``(w, x, y, z)``; norms within 1e-3 of 1 are accepted and normalised.

    Returns
    -------
    ndarray of shape (..., 3, 3)
    """
    return _rotation_matrices(q_wxyz, "q_wxyz")


def yaw_from_quaternion(q_wxyz, name: str = "q_wxyz"):
    """Heading about the z axis of a rotation: the angle of the rotated x axis in the xy plane.

    The same as the nuScenes devkit's ``quaternion_yaw``.

    Parameters
    ----------
    q_wxyz : array_like of shape (..., 4)
        Unit quaternions ``(w, x, y, z)``.
    name : str
        The argument's name, for messages.

    Returns
    -------
    float or ndarray of shape (...)
        Radians in ``[-pi, pi]``.
    """
    yaw = yaw_of_rotation(_rotation_matrices(q_wxyz, name))
    return float(yaw) if yaw.ndim == 0 else yaw


def as_pose(T, name: str) -> np.ndarray:
    """Validate a (4, 4) rigid transform (rotation within 1e-6, last row ``0 0 0 1``)."""
    T = finite_array(T, name, "(4, 4) rigid transform", ndim=2)
    if T.shape != (4, 4):
        raise ValueError(f"{name} has shape {T.shape}, expected (4, 4) rigid transform")
    if not np.array_equal(T[3], [0.0, 0.0, 0.0, 1.0]):
        raise ValueError(f"{name} has last row {T[3].tolist()}, expected [0, 0, 0, 1]")
    R = T[:3, :3]
    err = max(np.abs(R.T @ R - np.eye(3)).max(), abs(np.linalg.det(R) - 1.0))
    if err > _RIGID_TOLERANCE:
        raise ValueError(f"{name}[:3, :3] is not a rotation (deviation {err:.3g} from "
                         f"orthonormal with determinant 1; tolerance {_RIGID_TOLERANCE})")
    return T


def pose_matrix(rotation_wxyz, translation) -> np.ndarray:
    """4x4 rigid transform ``p_parent = R p_child + t`` from a quaternion and a translation.

    Parameters
    ----------
    rotation_wxyz : array_like of shape (4,)
        Unit quaternion ``(w, x, y, z)``.
    translation : array_like of shape (3,)
        Metres.

    Returns
    -------
    ndarray of shape (4, 4)
    """
    q = finite_array(rotation_wxyz, "rotation_wxyz", "(4,) quaternion (w, x, y, z)",
                     ndim=1, last=4)
    t = finite_array(translation, "translation", "(3,) metres", ndim=1, last=3)
    T = np.eye(4)
    T[:3, :3] = _rotation_matrices(q, "rotation_wxyz")
    T[:3, 3] = t
    return T


def invert_pose(T) -> np.ndarray:
    """The inverse of a rigid transform, ``[R^T, -R^T t]``.

    Parameters
    ----------
    T : array_like of shape (4, 4)

    Returns
    -------
    ndarray of shape (4, 4)
    """
    T = as_pose(T, "T")
    inv = np.eye(4)
    inv[:3, :3] = T[:3, :3].T
    inv[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return inv


def transform_points(points, T) -> np.ndarray:
    """Apply a rigid transform to points.

    Parameters
    ----------
    points : array_like of shape (n, 3)
        Metres.
    T : array_like of shape (4, 4)

    Returns
    -------
    ndarray of shape (n, 3)
    """
    p = finite_array(points, "points", "(n, 3) metres", ndim=2, last=3)
    T = as_pose(T, "T")
    return p @ T[:3, :3].T + T[:3, 3]
