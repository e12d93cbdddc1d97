"""Error models: a monocular depth network's estimate and a monocular 3D detector's boxes.

:func:`estimate_depth` turns a true depth map into what a network like ZoeDepth would
give; :func:`detect` turns ground-truth boxes into what a detector like PGD would give.
What they do, step by step, and every parameter are documented with the tables in
:mod:`monitor.synthetic.conditions` (:class:`~monitor.synthetic.conditions.DepthErrors`,
:class:`~monitor.synthetic.conditions.DetectorErrors`). Pixel parameters there are for a
1600 px wide image; ``px_scale`` (image width / 1600) adapts them to other sizes.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from monitor.geometry.boxes3d import as_boxes3d
from monitor.geometry.camera import Camera
from monitor.synthetic import _degrade_kernels as _k
from monitor.synthetic.conditions import (
    DETECTOR_CLASSES, FALSE_POSITIVE_CLASSES, DepthErrors, DetectorErrors,
)
from monitor.synthetic.scene import ACTOR_CLASSES

#: image width the pixel parameters of the tables are given for
REFERENCE_WIDTH_PX = 1600
#: the smooth error field is drawn on a grid this many times finer than its length
_FIELD_CELLS_PER_LENGTH = 4
#: false positives are placed this far ahead (metres)
FP_RANGE_M = (4.0, 50.0)
#: blob artefacts are centred below this fraction of the image height (not in the sky)
ARTIFACT_TOP = 0.3


def smooth_field(rng: np.random.Generator, shape: tuple[int, int], length_px: float) -> np.ndarray:
    """A smooth Gaussian random field with zero mean and unit variance at every pixel.

    White noise on a grid of spacing ``length_px / 4`` is filtered with a Gaussian of
    sigma ``length_px`` (4 cells), normalised by the kernel's norm so that its variance is
    exactly 1 on the grid, and interpolated bilinearly to the image (neighbouring cells are
    98 % correlated, so the variance stays at about 0.99 between them).

    Parameters
    ----------
    rng : numpy.random.Generator
    shape : (H, W)
    length_px : float
        Correlation length (the Gaussian's sigma), pixels, >= 1.

    Returns
    -------
    ndarray of shape (H, W), float32
    """
    height, width = shape
    cell = length_px / _FIELD_CELLS_PER_LENGTH
    pad = 3 * _FIELD_CELLS_PER_LENGTH
    grid_h = int(np.ceil(height / cell)) + 1
    grid_w = int(np.ceil(width / cell)) + 1
    kernel = cv2.getGaussianKernel(2 * pad + 1, _FIELD_CELLS_PER_LENGTH, cv2.CV_64F)
    noise = rng.standard_normal((grid_h + 2 * pad, grid_w + 2 * pad))
    smooth = cv2.sepFilter2D(noise, -1, kernel, kernel)[pad:-pad, pad:-pad]
    smooth /= float(np.sum(kernel ** 2))  # variance after the 2-D filter: (sum k^2)^2
    return cv2.resize(smooth.astype(np.float32), (width, height), interpolation=cv2.INTER_LINEAR)


def lognormal_blocks(rng: np.random.Generator, shape: tuple[int, int], block: int,
                     log_std: float) -> np.ndarray:
    """Multiplicative noise ``exp(log_std * n)``, n standard normal per ``block`` x ``block``
    pixel block (blocks from the top left).

    Parameters
    ----------
    rng : numpy.random.Generator
    shape : (H, W)
    block : int
        >= 1 pixels.
    log_std : float

    Returns
    -------
    ndarray of shape (H, W), float32
    """
    height, width = shape
    coarse = rng.standard_normal((-(-height // block), -(-width // block)), dtype=np.float32)
    factor = np.exp(np.float32(log_std) * coarse)
    size = (coarse.shape[1] * block, coarse.shape[0] * block)  # an exact integer upscale
    return cv2.resize(factor, size, interpolation=cv2.INTER_NEAREST_EXACT)[:height, :width]


def estimate_depth(depth_true: np.ndarray, labels: np.ndarray, background: np.ndarray,
                   errors: DepthErrors, rng: np.random.Generator, px_scale: float = 1.0
                   ) -> np.ndarray:
    """A monocular depth network's estimate of a true depth map.

    Parameters
    ----------
    depth_true : ndarray of shape (H, W), float32
        Metres, > 0, inf where nothing is hit (the ray cast's depth).
    labels : ndarray of shape (H, W), int16
        Box ``k`` is ``k + 1``; other values are background.
    background : ndarray of shape (H, W), float32
        The depth without any box (the empty road, inf above the horizon): where a faded
        object blends to.
    errors : DepthErrors
    rng : numpy.random.Generator
    px_scale : float
        Image width / 1600; scales the pixel parameters.

    Returns
    -------
    ndarray of shape (H, W), float32
        Metres, finite, in (0, ``errors.max_depth``].
    """
    shape = depth_true.shape
    if not (labels.shape == background.shape == shape and depth_true.ndim == 2):
        raise ValueError(
            f"depth_true, labels and background have shapes {depth_true.shape}, {labels.shape} "
            f"and {background.shape}; expected the same (H, W)"
        )
    for name, array, dtype in (("depth_true", depth_true, np.float32), ("labels", labels, np.int16),
                               ("background", background, np.float32)):
        if array.dtype != dtype:
            raise ValueError(f"{name} has dtype {array.dtype}, expected {np.dtype(dtype)}")
    for name, array in (("depth_true", depth_true), ("background", background)):
        if not np.all(array > 0):  # inf (no hit) is allowed, NaN is not
            raise ValueError(f"{name} has values that are not > 0 (or NaN); expected metres > 0 "
                             "with inf where nothing is hit")
    if not (np.isfinite(px_scale) and px_scale > 0):
        raise ValueError(f"px_scale = {px_scale!r}, must be > 0 (image width / 1600)")

    n_objects = int(labels.max(initial=0))
    alpha = np.zeros(n_objects + 1, dtype=np.float32)  # blend weight per label
    fade = rng.random(n_objects) < errors.fade_prob
    alpha[1:][fade] = rng.uniform(errors.fade_min, 1.0, int(fade.sum()))
    depth = np.empty(shape, dtype=np.float32)
    grain = lognormal_blocks(rng, shape, max(1, int(round(errors.grain_px * px_scale))),
                             errors.grain_log_std)
    _k.fade_clip_grain(depth_true, labels, background, alpha, errors.max_depth, grain, depth)
    for _ in range(rng.poisson(errors.artifact_rate)):
        _add_blob(depth, rng, errors, px_scale)
    if errors.edge_blur_px > 0:
        depth = cv2.GaussianBlur(depth, (0, 0), errors.edge_blur_px * px_scale)
    scale = rng.normal(errors.scale_log_bias, errors.scale_log_std)
    field = smooth_field(rng, shape, errors.field_px * px_scale)
    log_error = depth * np.float32(errors.field_rel_per_m)  # in place from here: r(D) F + g
    log_error += np.float32(errors.field_rel0)
    log_error *= field
    log_error += np.float32(scale)
    depth *= np.exp(log_error, out=log_error)
    return np.minimum(depth, np.float32(errors.max_depth), out=depth)


def _add_blob(depth: np.ndarray, rng: np.random.Generator, errors: DepthErrors,
              px_scale: float) -> None:
    """Multiply an elliptic blob of ``depth`` (in place) by a factor < 1."""
    height, width = depth.shape
    cu = rng.uniform(0, width)
    cv = rng.uniform(ARTIFACT_TOP * height, height)
    ru, rv = rng.uniform(*errors.artifact_px, size=2) * px_scale
    factor = np.float32(rng.uniform(*errors.artifact_factor))
    u0, u1 = max(int(cu - ru), 0), min(int(cu + ru) + 1, width)
    v0, v1 = max(int(cv - rv), 0), min(int(cv + rv) + 1, height)
    j, i = np.ogrid[v0:v1, u0:u1]
    inside = ((i + 0.5 - cu) / ru) ** 2 + ((j + 0.5 - cv) / rv) ** 2 <= 1.0
    depth[v0:v1, u0:u1][inside] *= factor


@dataclass(frozen=True, eq=False)
class Detections:
    """A detector's output for one frame.

    Attributes
    ----------
    boxes3d : ndarray of shape (m, 7), float64
        Ego frame, ``x, y, z, w, l, h, yaw``.
    classes : ndarray of shape (m,), str
        Detection names.
    scores : ndarray of shape (m,), float64
        In (0, 1); rows are sorted by decreasing score.
    source : ndarray of shape (m,), int64
        Row of the ground truth each detection comes from, -1 for a false positive.
    """

    boxes3d: np.ndarray
    classes: np.ndarray
    scores: np.ndarray
    source: np.ndarray


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-x))


def detection_probability(errors: DetectorErrors, classes: np.ndarray, distance: np.ndarray,
                          visibility: np.ndarray) -> np.ndarray:
    """The chance of each ground-truth box being detected (the formula of DetectorErrors).

    Parameters
    ----------
    errors : DetectorErrors
    classes : ndarray of shape (n,), str
        Ground-truth classes (keys of :data:`~monitor.synthetic.conditions.DETECTOR_CLASSES`).
    distance : ndarray of shape (n,)
        Box centre to camera, metres.
    visibility : ndarray of shape (n,)
        Visible fraction of the silhouette.

    Returns
    -------
    ndarray of shape (n,), float64
    """
    factor = np.array([DETECTOR_CLASSES[c].recall_factor for c in classes.tolist()])
    return (errors.recall_max * factor.reshape(-1) * visibility ** errors.occlusion_power
            / (1.0 + (distance / errors.recall_half_m) ** errors.recall_slope))


def detect(camera: Camera, gt_boxes3d: np.ndarray, gt_classes: np.ndarray,
           visibility: np.ndarray, visible_px: np.ndarray, errors: DetectorErrors,
           rng: np.random.Generator) -> Detections:
    """A monocular 3D detector's output for one frame.

    Parameters
    ----------
    camera : Camera
    gt_boxes3d : ndarray of shape (n, 7), float64
        Ground truth, ego frame.
    gt_classes : ndarray of shape (n,), str
    visibility : ndarray of shape (n,), float64
        Visible fraction of each box's silhouette in this image (0: not in view).
    visible_px : ndarray of shape (n,), int
        Visible pixels of each box.
    errors : DetectorErrors
    rng : numpy.random.Generator

    Returns
    -------
    Detections
    """
    gt_boxes3d = as_boxes3d(gt_boxes3d, "gt_boxes3d")
    n = gt_boxes3d.shape[0]
    if not (gt_classes.shape == visibility.shape == visible_px.shape == (n,)):
        raise ValueError(
            f"gt_classes, visibility and visible_px have shapes {gt_classes.shape}, "
            f"{visibility.shape} and {visible_px.shape}; expected ({n},), one per box"
        )
    unknown = sorted(set(gt_classes.tolist()) - set(DETECTOR_CLASSES))
    if unknown:
        raise ValueError(f"gt_classes has {unknown}, expected names in {sorted(DETECTOR_CLASSES)}")
    px_scale = camera.width / REFERENCE_WIDTH_PX
    origin = camera.cam_to_ego[:3, 3]
    offset = gt_boxes3d[:, :3] - origin
    distance = np.linalg.norm(offset, axis=1)
    p = detection_probability(errors, gt_classes, distance, visibility)
    p[visible_px < errors.min_visible_px * px_scale ** 2] = 0.0
    found = np.flatnonzero(rng.random(n) < p)

    d = distance[found]
    ray = offset[found] / d[:, None]
    across = np.cross(ray, [0.0, 0.0, 1.0])
    across /= np.maximum(np.linalg.norm(across, axis=1, keepdims=True), 1e-12)
    up = np.cross(across, ray)
    log_factor = rng.normal(errors.depth_bias, errors.depth_rel0 + errors.depth_rel_per_m * d)
    lateral = rng.normal(0.0, errors.lateral_rad, size=(found.size, 2)) * d[:, None]
    boxes = gt_boxes3d[found].copy()
    boxes[:, :3] = (origin + ray * (d * np.exp(log_factor))[:, None]
                    + across * lateral[:, :1] + up * lateral[:, 1:])
    boxes[:, 3:6] *= np.exp(rng.normal(0.0, errors.size_log_std, size=(found.size, 3)))
    yaw = boxes[:, 6] + rng.normal(0.0, errors.yaw_std, found.size)
    yaw += np.pi * (rng.random(found.size) < errors.yaw_flip_prob)
    boxes[:, 6] = np.mod(yaw + np.pi, 2 * np.pi) - np.pi

    confused = rng.random(found.size) < errors.confusion_prob
    names = []
    for gt_class, swap in zip(gt_classes[found].tolist(), confused.tolist()):
        behaviour = DETECTOR_CLASSES[gt_class]
        names.append(behaviour.confusions[rng.integers(len(behaviour.confusions))] if swap
                     else behaviour.detection_name)
    logits = errors.tp_logit - errors.score_per_m * d
    scores = _sigmoid(logits + rng.normal(0.0, errors.score_logit_std, found.size))

    fp_boxes, fp_names = _false_positives(camera, errors, rng)
    fp_scores = _sigmoid(errors.fp_logit + rng.normal(0.0, errors.score_logit_std, len(fp_names)))

    all_scores = np.concatenate([scores, fp_scores])
    order = np.argsort(-all_scores, kind="stable")
    return Detections(
        boxes3d=np.concatenate([boxes, fp_boxes])[order],
        classes=np.array(names + fp_names, dtype=str).reshape(-1)[order],
        scores=all_scores[order],
        source=np.concatenate([found, np.full(len(fp_names), -1)]).astype(np.int64)[order],
    )


def _false_positives(camera: Camera, errors: DetectorErrors, rng: np.random.Generator
                     ) -> tuple[np.ndarray, list[str]]:
    """Boxes of classes drawn from FALSE_POSITIVE_CLASSES, on the ground in the view."""
    count = rng.poisson(errors.fp_per_frame)
    names_, weights = zip(*FALSE_POSITIVE_CLASSES)
    picks = rng.choice(len(names_), size=count, p=np.array(weights) / sum(weights))
    names = [names_[k] for k in picks.tolist()]
    half_fov = np.arctan2(0.5 * camera.width, camera.K[0, 0])
    x = rng.uniform(*FP_RANGE_M, count)
    y = x * np.tan(half_fov) * rng.uniform(-0.9, 0.9, count)
    sizes = np.array([ACTOR_CLASSES[name].size for name in names]).reshape(count, 3)
    sizes = sizes * np.exp(rng.normal(0.0, 0.1, (count, 3)))
    yaw = rng.uniform(-np.pi, np.pi, count)
    return np.column_stack([x, y, 0.5 * sizes[:, 2], sizes, yaw]), names
