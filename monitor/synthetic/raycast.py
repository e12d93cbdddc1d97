"""True depth by ray casting a flat road and oriented 3D boxes.

The scene is the ground plane ``z = 0`` of the ego frame (nuScenes' ego origin is on the
ground), static structure (buildings, fences, poles, vegetation, curbs: upright boxes that
are not ground truth) and the actors (upright 3D boxes); boxes are rows
``x, y, z, w, l, h, yaw``, see :mod:`monitor.geometry.camera`. One ray per pixel centre (pixel ``(i, j)`` is the point
``(i + 0.5, j + 0.5)``, the camera module's convention) finds the nearest hit at or beyond
the near plane. The depth is the hit's camera-frame z in metres, ``inf`` where the ray hits
nothing (sky). A box the near plane cuts reads ``near`` where it blocks the view.

:func:`render_depth` is the Numba renderer. It tests each box only on the pixels of its
projected extent (:func:`monitor.geometry.camera.project_boxes`, plus a pixel of margin).
:func:`render_depth_reference` is the same computation in plain vectorised NumPy over every
pixel and every box, slow and obviously complete; it exists to check and to benchmark the
renderer.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from monitor.geometry.boxes3d import as_boxes3d
from monitor.geometry.camera import Camera, project_boxes
from monitor.datasets.frames import LABEL_ROAD, LABEL_SKY, LABEL_STRUCTURE
from monitor.synthetic import _raycast_kernels as _k

#: most boxes an int16 label map can name (box k is k + 1)
MAX_BOXES = int(np.iinfo(np.int16).max) - 1


@dataclass(frozen=True, eq=False)
class DepthRender:
    """The result of a ray cast.

    Attributes
    ----------
    depth : ndarray of shape (H, W), float32
        Camera-frame depth of the nearest hit, metres; ``inf`` for no hit.
    labels : ndarray of shape (H, W), int16
        :data:`~monitor.datasets.frames.LABEL_SKY` (no hit), :data:`~monitor.datasets.frames.LABEL_ROAD`
        (ground), a structure box's label, or ``k + 1`` for box ``k``.
    silhouette_px : ndarray of shape (n,), int64
        Per box, the pixels whose ray hits it, occluded or not.
    visible_px : ndarray of shape (n,), int64
        Per box, the pixels where it is the nearest hit.
    background : ndarray of shape (H, W), float32
        The depth of the ground and the structure without the boxes, metres.
    """

    depth: np.ndarray
    labels: np.ndarray
    silhouette_px: np.ndarray
    visible_px: np.ndarray
    background: np.ndarray

    @property
    def visibility(self) -> np.ndarray:
        """(n,) float64 visible fraction of each box's silhouette, 0 where it has none."""
        return np.divide(self.visible_px, self.silhouette_px, out=np.zeros(self.visible_px.size),
                         where=self.silhouette_px > 0)


def _checked_structure(structure, structure_labels) -> tuple[np.ndarray, np.ndarray]:
    boxes = as_boxes3d(np.zeros((0, 7)) if structure is None else structure, "structure")
    if structure_labels is None:
        return boxes, np.full(boxes.shape[0], LABEL_STRUCTURE, dtype=np.int16)
    codes = np.asarray(structure_labels)
    if codes.shape != (boxes.shape[0],) or codes.dtype.kind not in "iu":
        raise ValueError(f"structure_labels has shape {codes.shape} and dtype {codes.dtype}; expected "
                         f"({boxes.shape[0]},) integers, one per structure box")
    bad = codes[(codes >= LABEL_ROAD) | (codes == LABEL_SKY)]
    if bad.size:
        raise ValueError(f"structure_labels has {sorted(set(bad.tolist()))}; structure labels must be "
                         f"negative codes other than LABEL_SKY ({LABEL_SKY}), e.g. LABEL_STRUCTURE")
    return boxes, codes.astype(np.int16)


def _checked(camera: Camera, boxes3d) -> np.ndarray:
    if not isinstance(camera, Camera):
        raise ValueError(f"camera is a {type(camera).__name__}, expected a Camera")
    height = camera.cam_to_ego[2, 3]
    if not height > 0.0:
        raise ValueError(
            f"the camera centre is at z = {height!r} m in the ego frame; it must be above "
            "the ground plane z = 0"
        )
    boxes = as_boxes3d(boxes3d)
    if boxes.shape[0] > MAX_BOXES:
        raise ValueError(f"{boxes.shape[0]} boxes, at most {MAX_BOXES} fit an int16 label map")
    return boxes


def pixel_rays(camera: Camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ego-frame ray through pixel centre ``(i, j)`` is ``a * i + b * j + c``.

    Rays are scaled to a camera-frame z component of 1, so a point ``origin + t * ray``
    has camera depth ``t`` (``origin = camera.cam_to_ego[:3, 3]``).

    Returns
    -------
    a, b, c : ndarray of shape (3,), float64
    """
    M = camera.cam_to_ego[:3, :3] @ np.linalg.inv(camera.K)
    return M[:, 0].copy(), M[:, 1].copy(), M @ np.array([0.5, 0.5, 1.0])


def _pixel_rects(camera: Camera, boxes: np.ndarray) -> np.ndarray:
    """(n, 4) int64 half-open pixel ranges ``i0, i1, j0, j1`` that hold each box's pixels."""
    rects = np.zeros((boxes.shape[0], 4), dtype=np.int64)
    boxes2d, kept = project_boxes(boxes, camera)
    cx, cy, w, h = boxes2d[:, :4].T
    # pixel i is the point i + 0.5: those within [u0, u1] lie in floor(u0) .. ceil(u1) - 1;
    # one pixel of margin either way absorbs round-off
    rects[kept, 0] = np.maximum(np.floor(cx - 0.5 * w) - 1, 0)
    rects[kept, 1] = np.minimum(np.ceil(cx + 0.5 * w) + 1, camera.width)
    rects[kept, 2] = np.maximum(np.floor(cy - 0.5 * h) - 1, 0)
    rects[kept, 3] = np.minimum(np.ceil(cy + 0.5 * h) + 1, camera.height)
    return rects


def render_depth(camera: Camera, boxes3d, structure=None, structure_labels=None) -> DepthRender:
    """Ray-cast the true depth of the ground, the structure and the boxes.

    Parameters
    ----------
    camera : Camera
        Its centre must be above the ground (``cam_to_ego[2, 3] > 0``).
    boxes3d : array_like of shape (n, 7)
        The actors: rows ``x, y, z, w, l, h, yaw`` in the ego frame; at most :data:`MAX_BOXES`.
    structure : array_like of shape (m, 7), optional
        Static structure, same rows: rendered like the boxes, labelled ``structure_labels``,
        not counted in ``silhouette_px`` / ``visible_px``.
    structure_labels : array_like of shape (m,), int, optional
        Negative label codes (not LABEL_SKY); default :data:`~monitor.datasets.frames.LABEL_STRUCTURE`.

    Returns
    -------
    DepthRender
    """
    boxes = _checked(camera, boxes3d)
    walls, codes = _checked_structure(structure, structure_labels)
    everything = np.ascontiguousarray(np.concatenate([walls, boxes]))
    box_labels = np.concatenate([codes, np.arange(1, boxes.shape[0] + 1)]).astype(np.int16)
    a, b, c = pixel_rays(camera)
    depth = np.empty((camera.height, camera.width), dtype=np.float64)
    labels = np.empty((camera.height, camera.width), dtype=np.int16)
    depth32 = np.empty((camera.height, camera.width), dtype=np.float32)
    background = np.empty((camera.height, camera.width), dtype=np.float32)
    silhouette = np.zeros(everything.shape[0], dtype=np.int64)
    visible = np.zeros(boxes.shape[0], dtype=np.int64)
    _k.render(a, b, c, np.ascontiguousarray(camera.cam_to_ego[:3, 3]), camera.near, everything,
              box_labels, walls.shape[0], _pixel_rects(camera, everything), LABEL_SKY, LABEL_ROAD,
              depth, labels, silhouette, depth32, visible, background)
    return DepthRender(depth32, labels, silhouette[walls.shape[0]:], visible, background)


def render_depth_reference(camera: Camera, boxes3d, structure=None, structure_labels=None) -> DepthRender:
    """:func:`render_depth` in vectorised NumPy, every box against every pixel (slow).

    Same parameters and result. Rays are built here from ``K`` and ``cam_to_ego`` directly
    and boxes are intersected with the textbook slab method.
    """
    boxes = _checked(camera, boxes3d)
    walls, codes = _checked_structure(structure, structure_labels)
    n_walls = walls.shape[0]
    H, W = camera.height, camera.width
    j, i = np.mgrid[0:H, 0:W]
    pixels = np.stack([i + 0.5, j + 0.5, np.ones((H, W))], axis=-1).reshape(-1, 3)
    rays_cam = pixels @ np.linalg.inv(camera.K).T  # camera z component 1
    rays = rays_cam @ camera.cam_to_ego[:3, :3].T
    origin = camera.cam_to_ego[:3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ground = np.where(rays[:, 2] < 0.0, -origin[2] / rays[:, 2], np.inf)
    hit_ground = (t_ground >= camera.near) & np.isfinite(t_ground)
    depth = np.where(hit_ground, t_ground, np.inf)
    labels = np.where(hit_ground, LABEL_ROAD, LABEL_SKY).astype(np.int16)
    silhouette = np.zeros(boxes.shape[0], dtype=np.int64)
    background = depth
    for k, (x, y, z, w, l, h, yaw) in enumerate(np.concatenate([walls, boxes])):
        to_box = np.array([[np.cos(yaw), np.sin(yaw), 0.0],
                           [-np.sin(yaw), np.cos(yaw), 0.0],
                           [0.0, 0.0, 1.0]])
        o = to_box @ (origin - [x, y, z])
        r = rays @ to_box.T
        half = np.array([l, w, h]) / 2
        t_in = np.full(r.shape[0], -np.inf)
        t_out = np.full(r.shape[0], np.inf)
        for axis in range(3):
            parallel = r[:, axis] == 0.0
            with np.errstate(divide="ignore", invalid="ignore"):
                t1 = (-half[axis] - o[axis]) / r[:, axis]
                t2 = (half[axis] - o[axis]) / r[:, axis]
            t_in = np.where(parallel, t_in, np.maximum(t_in, np.minimum(t1, t2)))
            t_out = np.where(parallel, t_out, np.minimum(t_out, np.maximum(t1, t2)))
            if abs(o[axis]) > half[axis]:  # a parallel ray outside the slab misses
                t_in = np.where(parallel, np.inf, t_in)
        hit = (t_in <= t_out) & (t_out >= camera.near)
        if k >= n_walls:
            silhouette[k - n_walls] = np.count_nonzero(hit)
        t = np.maximum(t_in, camera.near)
        nearer = hit & (t < depth)
        depth = np.where(nearer, t, depth)
        labels = np.where(nearer, codes[k] if k < n_walls else k - n_walls + 1, labels).astype(np.int16)
        if k == n_walls - 1:
            background = depth
    labels = labels.reshape(H, W)
    visible = np.array([np.count_nonzero(labels == k + 1) for k in range(boxes.shape[0])],
                       dtype=np.int64)
    return DepthRender(depth.reshape(H, W).astype(np.float32), labels, silhouette, visible,
                       background.reshape(H, W).astype(np.float32))


def ground_points(camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Where each pixel's ray meets the ground: ego-frame ``x, y`` maps, metres.

    Returns
    -------
    x, y : ndarray of shape (H, W), float64
        ``inf`` where the ray does not reach the ground at or beyond the near plane.
    """
    _checked(camera, np.zeros((0, 7)))
    a, b, c = pixel_rays(camera)
    i = np.arange(camera.width, dtype=np.float64)[None, :]
    j = np.arange(camera.height, dtype=np.float64)[:, None]
    origin = camera.cam_to_ego[:3, 3]
    rz = a[2] * i + b[2] * j + c[2]
    with np.errstate(divide="ignore"):
        t = -origin[2] / rz
    hit = (rz < 0.0) & (t >= camera.near)
    x = np.where(hit, origin[0] + t * (a[0] * i + b[0] * j + c[0]), np.inf)
    y = np.where(hit, origin[1] + t * (a[1] * i + b[1] * j + c[1]), np.inf)
    return x, y
