"""A cheap shaded picture of a synthetic frame, for figures to draw boxes on.

Not an image any network saw: it is made from the true depth and the label map. Each
surface gets its class colour, lit by a fixed sun through normals taken from the depth
map (so box faces differ), faded into haze with distance; the sky is a gradient.
"""
from __future__ import annotations

import numpy as np

from monitor.datasets.frames import (
    Frame, LABEL_MARKING, LABEL_ROAD, LABEL_SIDEWALK, LABEL_SKY, LABEL_STRUCTURE,
)

#: RGB colour of each ground-truth class (unknown classes are grey)
CLASS_COLOURS = {
    "car": (40, 90, 190), "truck": (200, 120, 30), "bus": (210, 170, 40),
    "motorcycle": (120, 60, 160), "bicycle": (30, 150, 140), "pedestrian": (210, 60, 60),
    "barrier": (230, 230, 230), "traffic_cone": (240, 110, 20),
    "wheelchair": (230, 80, 170), "animal": (140, 100, 60), "debris": (110, 110, 80),
}
_OTHER = (150, 150, 150)
_GROUND = {LABEL_ROAD: (85, 85, 90), LABEL_MARKING: (235, 235, 225),
           LABEL_SIDEWALK: (160, 155, 145), LABEL_STRUCTURE: (150, 120, 100)}
_SKY_TOP, _SKY_HORIZON = np.array([110, 160, 225.0]), np.array([215, 225, 235.0])
_HAZE = np.array([200, 210, 220.0])
_HAZE_M = 120.0  # distance of 1/e visibility
_LIGHT = np.array([-0.35, -0.8, -0.5]) / np.linalg.norm([-0.35, -0.8, -0.5])  # camera frame


def shade(frame: Frame) -> np.ndarray:
    """An RGB picture of a frame with a true depth and a label map (synthetic frames).

    Parameters
    ----------
    frame : Frame
        ``depth_true`` and ``labels`` must be present.

    Returns
    -------
    ndarray of shape (H, W, 3), uint8
    """
    if frame.depth_true is None or frame.labels is None:
        raise ValueError(
            f"frame {frame.index} has no true depth or label map; a shaded picture can only "
            "be made of synthetic frames"
        )
    camera, labels = frame.camera, frame.labels
    height, width = labels.shape
    palette = {LABEL_SKY: _OTHER, **_GROUND}
    palette.update({k + 1: CLASS_COLOURS.get(c, _OTHER)
                    for k, c in enumerate(frame.gt_classes.tolist())})
    codes = np.array(sorted(palette))
    colours = np.array([palette[c] for c in codes], dtype=np.float32)
    rgb = colours[np.searchsorted(codes, labels)]

    # back-projected points (camera frame) and their normals, facing the camera
    solid = labels != LABEL_SKY
    depth = np.where(solid, frame.depth_true, np.float32(0.0))
    k_inv = np.linalg.inv(camera.K).astype(np.float32)
    u = (np.arange(width, dtype=np.float32) + 0.5)[None, :]
    v = (np.arange(height, dtype=np.float32) + 0.5)[:, None]
    points = np.stack([depth * (k_inv[0, 0] * u + k_inv[0, 1] * v + k_inv[0, 2]),
                       depth * (k_inv[1, 0] * u + k_inv[1, 1] * v + k_inv[1, 2]), depth], axis=-1)
    normal = np.cross(np.gradient(points, axis=1), np.gradient(points, axis=0))
    facing = -np.sign(np.einsum("hwc,hwc->hw", normal, points))
    length = np.linalg.norm(normal, axis=-1)
    cosine = np.divide(facing * (normal @ -_LIGHT.astype(np.float32)), length,
                       out=np.zeros_like(length), where=length > 0)
    rgb *= (0.45 + 0.55 * np.clip(cosine, 0.0, 1.0))[..., None]
    haze = (1.0 - np.exp(-depth / np.float32(_HAZE_M)))[..., None]
    rgb = rgb * (1.0 - haze) + _HAZE.astype(np.float32) * haze

    row = (np.arange(height, dtype=np.float32) / max(height - 1, 1))[:, None, None]
    sky = _SKY_TOP * (1.0 - row) + _SKY_HORIZON * row
    rgb = np.where(solid[..., None], rgb, sky.astype(np.float32))
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8)
