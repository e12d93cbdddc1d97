"""The pinhole camera on the ego vehicle, and the projection of 3D boxes to 2D boxes.

Pixels: ``u`` right, ``v`` down, continuous coordinates; the image spans
``[0, width] x [0, height]`` (pixel ``(i, j)`` covers ``[i, i + 1) x [j, j + 1)``). Frames
and poses follow :mod:`monitor.geometry.poses`, 3D boxes :mod:`monitor.geometry.boxes3d`.

:func:`project_boxes` turns 3D boxes into the monitor's 2D box arrays (rows
``cx, cy, w, h, d``, see :mod:`monitor.geometry.boxes`) from the part of each box the camera
sees: the box cut by the near plane and by the four planes through the image borders.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from monitor.geometry import _camera_kernels as _ck
from monitor.geometry.arrays import finite_array
from monitor.geometry.boxes3d import as_boxes3d, box_axes
from monitor.geometry.poses import as_pose, invert_pose, pose_matrix, transform_points

#: Visible 2D boxes narrower or lower than this (pixels) are dropped: such a box only
#: touches the view (e.g. lies exactly on an image border), and the threshold absorbs the
#: floating-point round-off of the clipping.
MIN_EXTENT_PX = 1e-3

#: Distances :func:`project_boxes` can give each 2D box.
DISTANCES = ("camera_depth", "ego_closest")


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
        K = finite_array(self.K, "K", "(3, 3) intrinsics", ndim=2)
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
        cam_to_ego = as_pose(self.cam_to_ego, "cam_to_ego").copy()
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
        p = finite_array(points_cam, "points_cam", "(n, 3) metres", ndim=2, last=3)
        behind = np.flatnonzero(p[:, 2] <= 0.0)
        if behind.size:
            i = int(behind[0])
            raise ValueError(f"points_cam[{i}] = {p[i].tolist()}: z must be > 0 (in front "
                             f"of the camera) to project")
        return (p @ self.K[:2].T) / p[:, 2:3]

    def ground_extents(self, boxes) -> np.ndarray:
        """Where image boxes stand in the ego frame: their bottom edge back-projected at their depth.

        Parameters
        ----------
        boxes : ndarray of shape (m, 5)
            Image boxes ``cx, cy, w, h, d`` (pixels, metres), ``d`` the camera depth (z) of
            the box's nearest part, as the depth views and ``project_boxes`` give it.

        Returns
        -------
        ndarray of shape (m, 3)
            Per box ``x, y_min, y_max``, metres in the ego frame: the forward distance of the
            nearer of its two bottom corners, and the lateral span between them.
        """
        b = np.asarray(boxes, dtype=np.float64).reshape(-1, 5)
        v = b[:, 1] + 0.5 * b[:, 3]
        left, right = (self.camera_to_ego(np.column_stack([
            (b[:, 0] + sign * 0.5 * b[:, 2] - self.K[0, 2]) / self.K[0, 0],
            (v - self.K[1, 2]) / self.K[1, 1], np.ones(len(b))]) * b[:, 4:5]) for sign in (-1.0, 1.0))
        return np.column_stack([np.minimum(left[:, 0], right[:, 0]),
                                np.minimum(left[:, 1], right[:, 1]),
                                np.maximum(left[:, 1], right[:, 1])])

    def same_as(self, other: "Camera") -> bool:
        """True when ``other`` has the same image size, near plane, intrinsics and mounting."""
        return (self.width == other.width and self.height == other.height
                and self.near == other.near and np.array_equal(self.K, other.K)
                and np.array_equal(self.cam_to_ego, other.cam_to_ego))


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
    axes = np.ascontiguousarray(np.einsum("ij,njk->nik", R, box_axes(boxes)))
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
    local = np.einsum("nji,nj->ni", box_axes(boxes), -boxes[:, :3])  # R^T (0 - c)
    outside = np.maximum(np.abs(local) - 0.5 * boxes[:, [4, 3, 5]], 0.0)
    return np.linalg.norm(outside, axis=1)
