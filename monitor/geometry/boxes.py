"""2D boxes with a distance, the paper's measures on them, and the range limit.

A box array is float64 of shape ``(n, 5)``, rows ``cx, cy, w, h, d``: centre, width and
height in pixels, distance in metres (FuzzRisk, Sec. III-A). An empty frame is ``(0, 5)``.
Pixel coordinates are continuous: a box spans ``[cx - w/2, cx + w/2] x [cy - h/2, cy + h/2]``.

Measures (elementwise, broadcasting over leading axes; a scalar for single boxes):

- :func:`iou` -- intersection over union;
- :func:`iog` -- intersection over the ground truth's area;
- :func:`rdd` -- relative depth discrepancy ``min(1, (d_p - d_s) / d_s)``, in ``[-1, 1]``;
- :func:`depth_ratio` -- DR ``min(1, d_g / d_p)``, in ``[0, 1]``;
- :func:`usc` -- ``iog * depth_ratio``.

Degenerate input has a fixed answer or a clear error, never a NaN:

- a box of zero width or height overlaps nothing: its IoU with anything is 0 (also with
  itself), and its IoG as a prediction is 0;
- IoG (and USC) of a ground truth with zero area is undefined: ``ValueError`` naming ``g``;
- RDD needs ``d_s > 0`` (``ValueError`` naming ``d_s``); ``d_p = 0`` gives RDD = -1;
- DR is defined for all ``d >= 0``: ``d_p <= d_g`` gives 1 (so ``d_p = 0`` gives 1), and
  ``d_g = 0 < d_p`` gives 0;
- any negative depth or size, NaN or infinity is a ``ValueError`` naming the argument.

The range limit lives here and only here: :data:`DEFAULT_RANGE_M`, :func:`range_mask`,
:func:`within_range`.
"""
from __future__ import annotations

import numpy as np

from monitor.geometry import _box_kernels as _k

#: Objects farther than this (metres, the box's ``d``) are outside the monitor's concern
#: (FuzzRisk, Sec. III-A: "we focus on those situated within 20 meters").
DEFAULT_RANGE_M = 20.0

#: Column names of a box array, for messages.
COLUMNS = ("cx", "cy", "w", "h", "d")

_PROBLEMS = {
    _k.NOT_FINITE: "must be finite",
    _k.NEGATIVE_SIZE: "box widths and heights must be >= 0 pixels",
    _k.NEGATIVE_DEPTH: "distances must be >= 0 metres",
    _k.NONPOSITIVE_DEPTH: "distances must be > 0 metres here",
    _k.ZERO_AREA: "the box must have a positive area here (w > 0 and h > 0)",
    _k.TOO_LARGE: f"must be within +-{_k.MAX_MAGNITUDE:g} (pixels or metres; beyond, distances and areas overflow)",
}


def _as_float_array(a, name: str) -> np.ndarray:
    arr = np.asarray(a)
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"{name} has dtype {arr.dtype}, expected real numbers (float64)")
    return np.asarray(arr, dtype=np.float64, order="C")


def _check_rows(rows: np.ndarray, name: str, shape: tuple, positive_depth: bool,
                positive_area: bool) -> None:
    i, j, code = _k.invalid_entry(rows, positive_depth, positive_area)
    if code != _k.OK:
        index = np.unravel_index(i, shape[:-1]) + (j,) if shape[:-1] else (j,)
        where = ", ".join(str(int(x)) for x in index)
        raise ValueError(f"{name}[{where}] ({COLUMNS[j]}) = {float(rows[i, j])!r}: "
                         f"{_PROBLEMS[code]}")


def _box_values(a, name: str, positive_depth: bool = False,
                positive_area: bool = False) -> np.ndarray:
    """Validated float64 array of shape ``(..., 5)`` (the elementwise measures' input)."""
    arr = _as_float_array(a, name)
    if arr.ndim == 0 or arr.shape[-1] != 5:
        raise ValueError(f"{name} has shape {arr.shape}, expected (..., 5) with columns "
                         f"{', '.join(COLUMNS)}")
    _check_rows(arr.reshape(-1, 5), name, arr.shape, positive_depth, positive_area)
    return arr


def as_boxes(a, name: str = "boxes", *, positive_depth: bool = False,
             positive_area: bool = False) -> np.ndarray:
    """Validate a box array and return it as float64 of shape ``(n, 5)``.

    Parameters
    ----------
    a : array_like of shape (n, 5)
        Rows ``cx, cy, w, h, d`` (pixels, pixels, pixels, pixels, metres). Integers are
        converted; no copy is made when ``a`` already is C-contiguous float64.
    name : str
        The argument's name, used in error messages.
    positive_depth : bool
        Require ``d > 0`` (instead of ``d >= 0``), e.g. where ``d`` divides.
    positive_area : bool
        Require ``w > 0`` and ``h > 0``, e.g. where the box's area divides.

    Returns
    -------
    ndarray of shape (n, 5), float64

    Raises
    ------
    ValueError
        Wrong dtype or shape, a non-finite entry or one beyond +-1e15, a negative size or
        distance (or one the flags exclude); the message names ``name``, the row, the
        column and the value.
    """
    arr = _as_float_array(a, name)
    if arr.ndim != 2 or arr.shape[1] != 5:
        raise ValueError(f"{name} has shape {arr.shape}, expected (n, 5) with columns "
                         f"{', '.join(COLUMNS)} (an empty frame is (0, 5))")
    _check_rows(arr, name, arr.shape, positive_depth, positive_area)
    return arr


def _depth_values(d, name: str, positive: bool) -> np.ndarray:
    arr = _as_float_array(d, name)
    bad = ~np.isfinite(arr) | ((arr <= 0.0) if positive else (arr < 0.0))
    if bad.any():
        where = tuple(int(x) for x in np.argwhere(np.atleast_1d(bad))[0])[:arr.ndim]
        label = f"{name}[{', '.join(map(str, where))}]" if where else name
        rule = "> 0" if positive else ">= 0"
        raise ValueError(f"{label} = {float(arr[where])!r}: distances must be finite and "
                         f"{rule} metres")
    return arr


def _elementwise(kernel, a: np.ndarray, b: np.ndarray, row_shape: tuple):
    """Broadcast ``a`` and ``b``, run a row kernel, return an array (or a float)."""
    a, b = np.broadcast_arrays(a, b)
    shape = a.shape[:a.ndim - len(row_shape)]
    a = np.asarray(a, order="C").reshape((-1,) + row_shape)
    b = np.asarray(b, order="C").reshape((-1,) + row_shape)
    out = np.empty(a.shape[0])
    kernel(a, b, out)
    out = out.reshape(shape)
    return float(out) if out.ndim == 0 else out


def iou(a, b):
    """Intersection over union of boxes, elementwise.

    Parameters
    ----------
    a, b : array_like of shape (..., 5)
        Boxes (rows ``cx, cy, w, h, d``; ``d`` is checked but not used), broadcast together.

    Returns
    -------
    float or ndarray of shape (...)
        In ``[0, 1]``; 0 for a box with zero width or height.
    """
    return _elementwise(_k.iou_rows, _box_values(a, "a"), _box_values(b, "b"), (5,))


def iog(p, g):
    """Intersection over the ground truth's area, ``area(p & g) / area(g)``, elementwise.

    Parameters
    ----------
    p : array_like of shape (..., 5)
        Predicted boxes.
    g : array_like of shape (..., 5)
        Ground-truth boxes, each with ``w > 0`` and ``h > 0``.

    Returns
    -------
    float or ndarray of shape (...)
        In ``[0, 1]``.
    """
    return _elementwise(_k.iog_rows, _box_values(p, "p"),
                        _box_values(g, "g", positive_area=True), (5,))


def rdd(d_p, d_s):
    """Relative depth discrepancy ``min(1, (d_p - d_s) / d_s)``, elementwise (paper eq. 3).

    Parameters
    ----------
    d_p : array_like
        Distances of the predictions, metres, ``>= 0``.
    d_s : array_like
        Distances of the safety-critical objects, metres, ``> 0``.

    Returns
    -------
    float or ndarray
        In ``[-1, 1]``: negative when the prediction is closer than the object.
    """
    return _elementwise(_k.rdd_rows, _depth_values(d_p, "d_p", positive=False),
                        _depth_values(d_s, "d_s", positive=True), ())


def depth_ratio(d_p, d_g):
    """Depth ratio DR ``min(1, d_g / d_p)``, elementwise; 1 when ``d_p <= d_g``.

    Parameters
    ----------
    d_p, d_g : array_like
        Distances of the predictions and of the ground truths, metres, ``>= 0``.

    Returns
    -------
    float or ndarray
        In ``[0, 1]``: below 1 only when the prediction is farther than the ground truth.
    """
    return _elementwise(_k.depth_ratio_rows, _depth_values(d_p, "d_p", positive=False),
                        _depth_values(d_g, "d_g", positive=False), ())


def usc(p, g):
    """USC ``iog(p, g) * depth_ratio(d_p, d_g)``, elementwise.

    Parameters
    ----------
    p : array_like of shape (..., 5)
        Predicted boxes.
    g : array_like of shape (..., 5)
        Ground-truth boxes, each with ``w > 0`` and ``h > 0``.

    Returns
    -------
    float or ndarray of shape (...)
        In ``[0, 1]``.
    """
    p = _box_values(p, "p")
    g = _box_values(g, "g", positive_area=True)
    return (_elementwise(_k.iog_rows, p, g, (5,))
            * _elementwise(_k.depth_ratio_rows, p[..., 4], g[..., 4], ()))


def centre_distances(a, b) -> np.ndarray:
    """Euclidean distances between box centres, pixels.

    Parameters
    ----------
    a : array_like of shape (n, 5)
    b : array_like of shape (m, 5)

    Returns
    -------
    ndarray of shape (n, m)
    """
    return _k.centre_distances(as_boxes(a, "a"), as_boxes(b, "b"))


def check_range(max_range) -> float:
    """Validate a range limit (the one rule for it): a number of metres > 0, ``np.inf`` for
    no limit. Returns it as a float; ValueError naming the value otherwise."""
    value = float(max_range)
    if not value > 0.0:  # also catches NaN
        raise ValueError(f"max_range = {max_range!r}, expected a distance > 0 metres "
                         f"(np.inf for no limit)")
    return value


def range_mask(boxes, max_range: float = DEFAULT_RANGE_M) -> np.ndarray:
    """Which rows lie within the range limit, ``d <= max_range``.

    Parameters
    ----------
    boxes : array_like of shape (n, 5)
    max_range : float
        Metres, ``> 0``; ``np.inf`` keeps every row.

    Returns
    -------
    ndarray of shape (n,), bool
    """
    return as_boxes(boxes, "boxes")[:, 4] <= check_range(max_range)


def within_range(boxes, max_range: float = DEFAULT_RANGE_M) -> np.ndarray:
    """The rows with ``d <= max_range`` (metres), as a new (k, 5) float64 array.

    Parameters
    ----------
    boxes : array_like of shape (n, 5)
    max_range : float
        Metres, ``> 0``; ``np.inf`` keeps every row.

    Returns
    -------
    ndarray of shape (k, 5), float64
    """
    boxes = as_boxes(boxes, "boxes")
    return boxes[range_mask(boxes, max_range)]
