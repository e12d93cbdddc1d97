"""Pinhole camera, 3D boxes and their frames, and the projection of 3D boxes to 2D boxes.

Conventions (nuScenes):

- ego frame: x forward, y left, z up, metres, origin at the ego vehicle's reference point;
- camera frame: z forward (optical axis), x right, y down, metres;
- pixels: ``u`` right, ``v`` down, continuous coordinates; the image spans
  ``[0, width] x [0, height]`` (pixel ``(i, j)`` covers ``[i, i + 1) x [j, j + 1)``);
- quaternions are ``(w, x, y, z)``; a pose ``(rotation, translation)`` takes points of the
  child frame to the parent frame, ``p_parent = R p_child + t`` (nuScenes' calibrated
  sensors are camera -> ego, its ego poses are ego -> global).

A 3D box array is float64 ``(n, 7)``, rows ``x, y, z, w, l, h, yaw``: the centre, the size
(``l`` along the heading, ``w`` across it, ``h`` up; nuScenes' ``wlh`` order) and the
heading angle about the frame's z axis, radians. Boxes are in the ego frame unless a
function says otherwise. Boxes stay upright: a frame change keeps only the rotation of the
heading about the up axis (exact for nuScenes' global <-> ego, which rotates about z up to
small tilts).

:func:`project_boxes` turns 3D boxes into the monitor's 2D box arrays (rows
``cx, cy, w, h, d``, see :mod:`monitor.boxes`) from the part of each box the camera sees:
the box cut by the near plane and by the four planes through the image borders.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from monitor import _camera_kernels as _ck

#: Column names of a 3D box array, for messages.
COLUMNS_3D = ("x", "y", "z", "w", "l", "h", "yaw")

#: Visible 2D boxes narrower or lower than this (pixels) are dropped: such a box only
#: touches the view (e.g. lies exactly on an image border), and the threshold absorbs the
#: floating-point round-off of the clipping.
MIN_EXTENT_PX = 1e-3

#: Distances :func:`project_boxes` can give each 2D box.
DISTANCES = ("camera_depth", "ego_closest")

_UNIT_TOLERANCE = 1e-3  # |norm - 1| accepted for a quaternion (then normalised)
_RIGID_TOLERANCE = 1e-6  # max |R^T R - I| and |det R - 1| of a pose's rotation
_MIN_UP = 0.9  # a frame change for upright boxes must keep z up: R[2, 2] > this


def _float_array(a, name: str, shape_text: str, ndim: int | None = None,
                 last: int | None = None) -> np.ndarray:
    arr = np.asarray(a)
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"{name} has dtype {arr.dtype}, expected real numbers")
    arr = np.asarray(arr, dtype=np.float64, order="C")
    if (ndim is not None and arr.ndim != ndim) or (last is not None and (
            arr.ndim == 0 or arr.shape[-1] != last)):
        raise ValueError(f"{name} has shape {arr.shape}, expected {shape_text}")
    if not np.isfinite(arr).all():
        where = tuple(int(x) for x in np.argwhere(~np.isfinite(arr))[0])
        raise ValueError(f"{name}{list(where) if where else ''} = {float(arr[where])!r}: "
                         f"must be finite")
    return arr


def _unit_quaternions(q_wxyz, name: str) -> np.ndarray:
    q = _float_array(q_wxyz, name, "(..., 4) quaternions (w, x, y, z)", last=4)
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


def _yaw(R: np.ndarray) -> np.ndarray:
    """Angle of the rotated x axis in the xy plane, radians."""
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


def yaw_from_quaternion(q_wxyz):
    """Heading about the z axis of a rotation: the angle of the rotated x axis in the xy plane.

    The same as the nuScenes devkit's ``quaternion_yaw``.

    Parameters
    ----------
    q_wxyz : array_like of shape (..., 4)
        Unit quaternions ``(w, x, y, z)``.

    Returns
    -------
    float or ndarray of shape (...)
        Radians in ``[-pi, pi]``.
    """
    yaw = _yaw(_rotation_matrices(q_wxyz, "q_wxyz"))
    return float(yaw) if yaw.ndim == 0 else yaw


def _as_pose(T, name: str) -> np.ndarray:
    T = _float_array(T, name, "(4, 4) rigid transform", ndim=2)
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
    q = _float_array(rotation_wxyz, "rotation_wxyz", "(4,) quaternion (w, x, y, z)",
                     ndim=1, last=4)
    t = _float_array(translation, "translation", "(3,) metres", ndim=1, last=3)
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
    T = _as_pose(T, "T")
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
    p = _float_array(points, "points", "(n, 3) metres", ndim=2, last=3)
    T = _as_pose(T, "T")
    return p @ T[:3, :3].T + T[:3, 3]


def as_boxes3d(a, name: str = "boxes3d") -> np.ndarray:
    """Validate a 3D box array and return it as float64 of shape ``(n, 7)``.

    Parameters
    ----------
    a : array_like of shape (n, 7)
        Rows ``x, y, z, w, l, h, yaw`` (metres, radians); sizes must be > 0.
    name : str
        The argument's name, used in error messages.

    Returns
    -------
    ndarray of shape (n, 7), float64
    """
    arr = _float_array(a, name, "(n, 7) with columns " + ", ".join(COLUMNS_3D)
                       + " (no boxes is (0, 7))", ndim=2, last=7)
    bad = np.argwhere(arr[:, 3:6] <= 0.0)
    if bad.size:
        i, j = int(bad[0, 0]), int(bad[0, 1]) + 3
        raise ValueError(f"{name}[{i}, {j}] ({COLUMNS_3D[j]}) = {float(arr[i, j])!r}: "
                         f"box sizes must be > 0 metres")
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
    c = _float_array(centres, "centres", "(n, 3) metres", ndim=2, last=3)
    s = _float_array(sizes_wlh, "sizes_wlh", "(n, 3) metres", ndim=2, last=3)
    q = _float_array(rotations_wxyz, "rotations_wxyz", "(n, 4) quaternions", ndim=2, last=4)
    if not c.shape[0] == s.shape[0] == q.shape[0]:
        raise ValueError(f"centres, sizes_wlh and rotations_wxyz have {c.shape[0]}, "
                         f"{s.shape[0]} and {q.shape[0]} rows, expected the same number")
    bad = np.argwhere(s <= 0.0)
    if bad.size:
        i, j = (int(x) for x in bad[0])
        raise ValueError(f"sizes_wlh[{i}, {j}] ({'wlh'[j]}) = {float(s[i, j])!r}: box sizes "
                         f"must be > 0 metres")
    return np.column_stack([c, s, _yaw(_rotation_matrices(q, "rotations_wxyz"))])


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
    T = _as_pose(T, "T")
    if not T[2, 2] > _MIN_UP:
        raise ValueError(f"T[2, 2] = {T[2, 2]!r}: the transform tilts the up axis by "
                         f"more than {np.degrees(np.arccos(_MIN_UP)):.0f} degrees; "
                         f"upright 3D boxes cannot follow it")
    out = boxes.copy()
    out[:, :3] = boxes[:, :3] @ T[:3, :3].T + T[:3, 3]
    heading = T[:2, :2] @ np.stack([np.cos(boxes[:, 6]), np.sin(boxes[:, 6])])  # z part 0
    out[:, 6] = np.arctan2(heading[1], heading[0])
    return out


def _box_axes(boxes: np.ndarray) -> np.ndarray:
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
    return boxes[:, None, :3] + np.einsum("nij,nkj->nki", _box_axes(boxes), local)


@dataclass(frozen=True, eq=False)
class Camera:
    """A pinhole camera mounted on the ego vehicle.

    Attributes
    ----------
    K : ndarray of shape (3, 3)
        Intrinsics, pixels; last row ``(0, 0, 1)``, ``fx, fy > 0``.
    width, height : int
        Image size, pixels.
    cam_to_ego : ndarray of shape (4, 4)
        Rigid transform taking camera-frame points to ego-frame points.
    near : float
        Near plane, metres (camera z), ``>= 1e-3``.
    """

    K: np.ndarray
    width: int
    height: int
    cam_to_ego: np.ndarray
    near: float = 0.1

    def __post_init__(self):
        K = _float_array(self.K, "K", "(3, 3) intrinsics", ndim=2)
        if K.shape != (3, 3) or not np.array_equal(K[2], [0.0, 0.0, 1.0]) \
                or not (K[0, 0] > 0 and K[1, 1] > 0):
            raise ValueError(f"K = {K.tolist()}: expected (3, 3) intrinsics "
                             f"[[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0")
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
                    or value <= 0:
                raise ValueError(f"{name} = {value!r}, expected a positive integer (pixels)")
        near = float(self.near)
        if not (np.isfinite(near) and near >= 1e-3):
            raise ValueError(f"near = {self.near!r}, expected a finite distance >= 1e-3 m")
        cam_to_ego = _as_pose(self.cam_to_ego, "cam_to_ego").copy()
        K = K.copy()
        ego_to_cam = invert_pose(cam_to_ego)
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))
        object.__setattr__(self, "near", near)
        frustum = _frustum_planes(self)
        for arr in (K, cam_to_ego, ego_to_cam, frustum):
            arr.flags.writeable = False
        object.__setattr__(self, "cam_to_ego", cam_to_ego)
        object.__setattr__(self, "_ego_to_cam", ego_to_cam)
        object.__setattr__(self, "_frustum", frustum)

    @classmethod
    def from_nuscenes(cls, camera_intrinsic, rotation_wxyz, translation, width=1600,
                      height=900) -> "Camera":
        """A camera from a nuScenes ``calibrated_sensor`` record.

        Parameters
        ----------
        camera_intrinsic : array_like of shape (3, 3)
        rotation_wxyz : array_like of shape (4,)
            Camera -> ego rotation.
        translation : array_like of shape (3,)
            Camera position in the ego frame, metres.
        width, height : int
            Image size, pixels (nuScenes: 1600 x 900).
        """
        return cls(np.asarray(camera_intrinsic), width, height,
                   pose_matrix(rotation_wxyz, translation))

    @classmethod
    def nuscenes_front(cls) -> "Camera":
        """nuScenes' CAM_FRONT (its calibration in the v1.0 scenes), 1600 x 900."""
        return cls.from_nuscenes(
            [[1266.417203046554, 0.0, 816.2670197447984],
             [0.0, 1266.417203046554, 491.50706579294757],
             [0.0, 0.0, 1.0]],
            [0.4998015430569128, -0.5030316162024876, 0.4997798114386805,
             -0.49737083824542755],
            [1.70079118954, 0.0159456324149, 1.51095763913])

    @property
    def ego_to_cam(self) -> np.ndarray:
        """(4, 4) rigid transform taking ego-frame points to camera-frame points."""
        return self._ego_to_cam

    def ego_to_camera(self, points) -> np.ndarray:
        """(n, 3) ego-frame points -> (n, 3) camera-frame points, metres."""
        return transform_points(points, self._ego_to_cam)

    def camera_to_ego(self, points) -> np.ndarray:
        """(n, 3) camera-frame points -> (n, 3) ego-frame points, metres."""
        return transform_points(points, self.cam_to_ego)

    def project(self, points_cam) -> np.ndarray:
        """Pinhole projection ``u = (K p)_0 / z``, ``v = (K p)_1 / z``.

        Parameters
        ----------
        points_cam : array_like of shape (n, 3)
            Camera-frame points with ``z > 0``, metres.

        Returns
        -------
        ndarray of shape (n, 2)
            Pixels ``(u, v)``; not limited to the image.
        """
        p = _float_array(points_cam, "points_cam", "(n, 3) metres", ndim=2, last=3)
        behind = np.flatnonzero(p[:, 2] <= 0.0)
        if behind.size:
            i = int(behind[0])
            raise ValueError(f"points_cam[{i}] = {p[i].tolist()}: z must be > 0 (in front "
                             f"of the camera) to project")
        return (p @ self.K[:2].T) / p[:, 2:3]


def _frustum_planes(camera: Camera) -> np.ndarray:
    """(5, 4) half-spaces ``a . p <= b`` (unit ``a``) bounding the view, camera frame.

    Rows: near plane ``z >= near``, then ``u >= 0``, ``u <= width``, ``v >= 0``,
    ``v <= height`` (for ``z > 0``, ``u >= 0`` is ``(K p)_0 >= 0``, and so on).
    """
    K, e_z = camera.K, np.array([0.0, 0.0, 1.0])
    normals = np.stack([-e_z, -K[0], K[0] - camera.width * e_z,
                        -K[1], K[1] - camera.height * e_z])
    offsets = np.array([-camera.near, 0.0, 0.0, 0.0, 0.0])
    norm = np.linalg.norm(normals, axis=1)
    return np.column_stack([normals / norm[:, None], offsets / norm])


def project_boxes(boxes3d, camera: Camera, distance: str = "camera_depth"
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Project 3D boxes (ego frame) to 2D boxes with a distance, as the camera sees them.

    Each box is cut by the camera's view (near plane and the four planes through the image
    borders); the 2D box is the extent of that visible part's projection: exactly the
    projected outline of the box clipped at the near plane, intersected with the image.
    A box with no visible part (wholly behind the near plane or outside the image), or one
    whose visible extent is below :data:`MIN_EXTENT_PX`, is dropped.

    Parameters
    ----------
    boxes3d : array_like of shape (n, 7)
        Rows ``x, y, z, w, l, h, yaw`` in the ego frame.
    camera : Camera
    distance : {"camera_depth", "ego_closest"}
        ``"camera_depth"``: the smallest camera-frame depth (z) of the visible part, to
        compare like with like with a depth map. ``"ego_closest"``: the Euclidean distance
        from the ego origin to the closest point of the whole box (0 if it contains the
        origin), the paper's "closest distance to the AV's position".

    Returns
    -------
    boxes2d : ndarray of shape (m, 5)
        Rows ``cx, cy, w, h, d`` (pixels, metres), inside the image, ``w, h > 0``.
    kept : ndarray of shape (m,), int64
        Row of ``boxes3d`` each 2D box comes from, ascending.
    """
    if distance not in DISTANCES:
        raise ValueError(f"distance = {distance!r}, expected one of {DISTANCES}")
    if not isinstance(camera, Camera):
        raise ValueError(f"camera is a {type(camera).__name__}, expected a Camera")
    boxes = as_boxes3d(boxes3d)
    R, t = camera.ego_to_cam[:3, :3], camera.ego_to_cam[:3, 3]
    centres = boxes[:, :3] @ R.T + t
    axes = np.ascontiguousarray(np.einsum("ij,njk->nik", R, _box_axes(boxes)))
    half = np.ascontiguousarray(0.5 * boxes[:, [4, 3, 5]])
    extents = np.empty((boxes.shape[0], 5))
    visible = _ck.visible_extents(centres, axes, half, camera._frustum,
                                  camera.K, float(camera.width),
                                  float(camera.height), camera.near, MIN_EXTENT_PX, extents)
    kept = np.flatnonzero(visible)
    u0, u1, v0, v1, z_min = extents[kept].T
    if distance == "camera_depth":
        d = z_min
    else:
        d = _distance_to_origin(boxes[kept])
    boxes2d = np.column_stack([0.5 * (u0 + u1), 0.5 * (v0 + v1), u1 - u0, v1 - v0, d])
    return boxes2d, kept


def _distance_to_origin(boxes: np.ndarray) -> np.ndarray:
    """(n,) Euclidean distance from the frame's origin to each (validated) box, metres."""
    local = np.einsum("nji,nj->ni", _box_axes(boxes), -boxes[:, :3])  # R^T (0 - c)
    outside = np.maximum(np.abs(local) - 0.5 * boxes[:, [4, 3, 5]], 0.0)
    return np.linalg.norm(outside, axis=1)
