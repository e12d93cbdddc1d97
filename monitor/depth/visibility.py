"""Can the depth view see through this frame? A check that does not depend on the view.

The depth view finds objects by their edges against the prior. A depth map without edges
gives no objects, and "no objects" reads as "no risk", whatever the reason there were no
edges: something filling the view at 1 m (a uniform near surface has no edges), a map of
garbage depths (all 1e6 m, all 1e-30 m), or an object whose pixels are invalid (NaN) and
so are skipped. :func:`check_view` looks at the lower part of the image, where a forward
camera on a vehicle sees the road ahead, and says when the frame cannot be seen through:

* **blocked**: more than ``blocked_share`` of the band's pixels are nearer than
  ``blocked_range`` metres (something fills the view just ahead of the camera);
* **no ground**: of the band's valid pixels, fewer than ``min_in_range_share`` lie within
  ``max_range`` metres (the road just ahead is missing: depths in the wrong unit, or
  garbage); or the band does not come nearer towards the bottom of the image as the road
  ahead does: the mean inverse depth of its lowest tenth of rows is less than
  ``min_ground_ratio`` times that of its highest tenth (a wall or a uniform surface at any
  distance, which has no edges for the view to find);
* **hidden**: the band's invalid pixels hold a ``hidden_size`` x ``hidden_size`` square:
  a region large enough to hide an object the view would report (the smallest reported
  box is ``retrieval.min_size`` pixels a side; a pedestrian 0.67 m wide at 20 m is 42 px
  wide in the nuScenes front camera).

The defaults were measured on the synthetic benchmark (1600 x 900 nuScenes CAM_FRONT,
:mod:`monitor.synthetic.suite`, ``Benchmark(scenes_per_condition=3, n_frames=20,
prior_scenes=2)``, the street with structures): there the lower half of the image is at
most 14 % nearer than 3 m (a car close ahead in snow), at least 73 % within 20 m (noise),
its ground ratio is at least 1.25 (snow; medians 2.2-4.0 by condition) and it has no
invalid pixels; none of the 360 frames (6 conditions x 3 scenes x 20 frames) is flagged. A
ground ratio of 1.5 flagged 8 frames of the earlier street (3 % of nominal, 10 % of snow:
cars close ahead); a uniform surface gives 1.0.
The check costs one pass over the band (a Numba kernel), plus an erosion of the invalid
mask when the band has at least ``hidden_size**2`` invalid pixels.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from monitor.depth import _visibility_kernels as kernels
from monitor.geometry.boxes import DEFAULT_RANGE_M


@dataclass(frozen=True)
class VisibilityParams:
    """When a frame cannot be seen through (see the module docstring).

    Parameters
    ----------
    band : float in (0, 1]
        The checked band: this share of the image's rows, at the bottom.
    blocked_range : float
        Metres; a pixel nearer than this is "blocked".
    blocked_share : float in [0, 1]
        The frame is blocked when more than this share of the band's pixels is blocked
        (1 turns the rule off).
    max_range : float
        Metres; the monitor's range (the configuration's top-level ``max_range``).
    min_in_range_share : float in [0, 1]
        The frame has no ground when fewer than this share of the band's valid pixels lie
        within ``max_range`` (0 turns the rule off).
    min_ground_ratio : float >= 0
        The frame has no ground when the mean inverse depth of the band's lowest tenth of
        rows is less than this many times that of its highest tenth (0 turns the rule off).
    hidden_size : int or None
        Side in pixels of the smallest square of invalid pixels that could hide an object;
        None turns the rule off.
    """

    band: float = 0.5
    blocked_range: float = 3.0
    blocked_share: float = 0.5
    max_range: float = DEFAULT_RANGE_M
    min_in_range_share: float = 0.25
    min_ground_ratio: float = 1.1
    hidden_size: int | None = 40

    def __post_init__(self):
        if not 0 < self.band <= 1:
            raise ValueError(f"band = {self.band!r}, must be in (0, 1] (a share of the image's rows)")
        if not (math.isfinite(self.blocked_range) and self.blocked_range > 0):
            raise ValueError(f"blocked_range = {self.blocked_range!r}, must be a finite number of metres > 0")
        for name in ("blocked_share", "min_in_range_share"):
            if not 0 <= getattr(self, name) <= 1:
                raise ValueError(f"{name} = {getattr(self, name)!r}, must be in [0, 1]")
        if not (math.isfinite(self.min_ground_ratio) and self.min_ground_ratio >= 0):
            raise ValueError(f"min_ground_ratio = {self.min_ground_ratio!r}, must be a finite number >= 0")
        if not self.max_range > 0:
            raise ValueError(f"max_range = {self.max_range!r}, must be > 0 metres")
        if self.hidden_size is not None and (isinstance(self.hidden_size, bool)
                                             or not isinstance(self.hidden_size, int) or self.hidden_size < 1):
            raise ValueError(f"hidden_size = {self.hidden_size!r}, must be None (off) or an integer >= 1 (pixels)")


def check_view(depth: np.ndarray, params: VisibilityParams = VisibilityParams()) -> str:
    """Why the depth view cannot see through ``depth``, or "" when it can.

    Parameters
    ----------
    depth : ndarray of shape (H, W), float32, C-contiguous
        Metres, invalid pixels NaN, inf or <= 0 (as
        :func:`monitor.depth.retrieval.as_depth_map` returns it).
    params : VisibilityParams

    Returns
    -------
    str
        "" for a frame the view can see through; otherwise the rule that fired, with the
        measured value, the limit and the configuration key.
    """
    if not (isinstance(depth, np.ndarray) and depth.dtype == np.float32 and depth.ndim == 2
            and depth.flags.c_contiguous):
        raise ValueError("depth must be a C-contiguous float32 (H, W) array (monitor.depth.retrieval.as_depth_map)")
    height, width = depth.shape
    first = height - max(1, round(params.band * height))
    rows = height - first
    invalid = np.empty((rows, width), dtype=np.uint8)
    row_inverse, row_valid = np.empty(rows), np.empty(rows, dtype=np.int64)
    n_invalid, n_near, n_in_range = kernels.band_counts(
        depth, first, np.float32(params.blocked_range), np.float32(params.max_range), invalid,
        row_inverse, row_valid)
    n = invalid.size
    where = f"the lower {100 * params.band:g}% of the image"
    if n_near > params.blocked_share * n:
        return (f"view blocked: {100 * n_near / n:.1f}% of {where} is nearer than {params.blocked_range:g} m, "
                f"more than visibility.blocked_share = {100 * params.blocked_share:g}%")
    n_valid = n - n_invalid
    if n_valid and n_in_range < params.min_in_range_share * n_valid:
        return (f"no ground in view: {100 * n_in_range / n_valid:.1f}% of the valid depths in {where} lie within "
                f"{params.max_range:g} m, fewer than visibility.min_in_range_share = "
                f"{100 * params.min_in_range_share:g}% (depths in another unit, or not a depth map?)")
    tenth = max(1, rows // 10)
    top, bottom = row_valid[:tenth].sum(), row_valid[-tenth:].sum()
    if top and bottom:
        near_end = row_inverse[-tenth:].sum() / bottom
        far_end = row_inverse[:tenth].sum() / top
        if near_end < params.min_ground_ratio * far_end:
            return (f"no ground in view: the mean inverse depth of the lowest tenth of {where} is "
                    f"{near_end:.3g} 1/m, less than visibility.min_ground_ratio = {params.min_ground_ratio:g} "
                    f"times that of its highest tenth ({far_end:.3g} 1/m): nothing comes nearer towards the "
                    "bottom of the image as the road ahead does (a surface filling the view?)")
    size = params.hidden_size
    if size is not None and n_invalid >= size * size:
        cores = cv2.erode(invalid, np.ones((size, size), np.uint8), borderType=cv2.BORDER_CONSTANT, borderValue=0)
        inside = np.flatnonzero(cores)
        if inside.size:
            row, col = divmod(int(inside[0]), width)
            return (f"hidden region: the invalid pixels of {where} hold a {size} x {size} square (centre at row "
                    f"{first + row}, column {col}) that could hide an object; visibility.hidden_size = {size}")
    return ""


def warmup() -> None:
    """Compile (or load from the disk cache) the kernel on a tiny frame."""
    kernels.band_counts(np.ones((2, 2), np.float32), 1, np.float32(1.0), np.float32(2.0),
                        np.empty((1, 2), np.uint8), np.empty(1), np.empty(1, dtype=np.int64))
