"""The driving corridor: the band of the ground the ego vehicle will sweep.

A corridor is a centreline on the ground plane of the ego frame (x forward, y left, see
:mod:`monitor.geometry.poses`) and a half width: a point belongs to it when its lateral
offset from the centreline is at most ``half_width``. The centreline is the ego's path:

- straight ahead (``curvature = 0``, the default),
- a circular arc of constant ``curvature`` (1/m, positive turning left) tangent to the x axis
  at the ego origin: ``y = R - sqrt(R^2 - x^2)`` with ``R = 1 / curvature``, or
- a polyline of ego-frame vertices ``(x, y)`` with strictly increasing x, starting at or
  behind the ego origin (``x[0] <= 0``), e.g. the planner's path.

A path is a function of x here: where it turns back (an arc beyond a quarter turn, at
``x = |R|``) or ends (the polyline's last vertex), the corridor ends; beyond it nothing is
inside.

:meth:`Corridor.table` samples the centreline along x for the per-pixel kernels: row k holds
the centreline's y and the tangent of its heading at ``x_k = (k + 1/2) step``, and a point
with ``k step <= x < (k + 1) step`` is ``|y - y_k - t_k (x - x_k)| / sqrt(1 + t_k^2)`` from
the tangent line there: exact for a straight path and a polyline, and for an arc of radius
R within ``s^2 / (2 R)``, ``s = step / (2 cos(heading)) + l sin(heading)``, of a point's
distance l from the circle (1 mm for l = 0.3 m on a 30 m arc, 2 cm for l = 2 m).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from monitor.geometry.arrays import finite_array


@dataclass(frozen=True, eq=False)
class Corridor:
    """The band of ground within ``half_width`` of the ego's path.

    Attributes
    ----------
    half_width : float
        Metres, > 0: the ego's half width plus a margin.
    curvature : float
        1/m of a circular path tangent to the x axis at the ego origin (positive turns
        left); 0 is straight ahead. Must be 0 when ``polyline`` is given.
    polyline : ndarray of shape (n, 2) or None
        Ego-frame path vertices ``x, y`` in metres, n >= 2, strictly increasing x,
        ``x[0] <= 0``; None for the arc of ``curvature``.
    """

    half_width: float
    curvature: float = 0.0
    polyline: np.ndarray | None = None

    def __post_init__(self):
        half_width = float(self.half_width)
        if not (math.isfinite(half_width) and half_width > 0):
            raise ValueError(f"half_width = {self.half_width!r}, must be a finite distance > 0 m")
        curvature = float(self.curvature)
        if not math.isfinite(curvature):
            raise ValueError(f"curvature = {self.curvature!r}, must be finite (1/m, 0 = straight)")
        object.__setattr__(self, "half_width", half_width)
        object.__setattr__(self, "curvature", curvature)
        if self.polyline is None:
            return
        if curvature != 0.0:
            raise ValueError(f"curvature = {curvature} and a polyline given: a path is one or "
                             "the other (curvature 0 with a polyline)")
        points = finite_array(self.polyline, "polyline", "(n, 2) ego-frame x, y metres, n >= 2",
                              ndim=2, last=2).copy()
        if points.shape[0] < 2:
            raise ValueError(f"polyline has {points.shape[0]} vertex, expected n >= 2 (x, y) rows")
        steps = np.diff(points[:, 0])
        if not np.all(steps > 0):
            i = int(np.argmax(steps <= 0))
            raise ValueError(f"polyline x must increase strictly: x[{i + 1}] = {points[i + 1, 0]} "
                             f"after x[{i}] = {points[i, 0]}")
        if points[0, 0] > 0:
            raise ValueError(f"polyline starts at x = {points[0, 0]} m, ahead of the ego origin; "
                             "it must start at x <= 0 so that the corridor covers everything ahead")
        points.flags.writeable = False
        object.__setattr__(self, "polyline", points)

    def table(self, x_end: float, step: float) -> tuple[np.ndarray, np.ndarray]:
        """The centreline sampled at ``x = 0, step, 2 step, ...`` up to ``x_end``.

        Row k describes the points with ``k step <= x < (k + 1) step`` by the centreline's
        tangent at the middle of that interval, ``x_k = (k + 1/2) step``.

        Parameters
        ----------
        x_end : float
            Metres > 0: points farther ahead than this are outside.
        step : float
            Metres > 0.

        Returns
        -------
        centre_y : ndarray of shape (n,), float64
            Centreline y at ``x_k``, metres; NaN where the path does not reach (outside).
        tan_heading : ndarray of shape (n,), float64
            dy/dx of the centreline at ``x_k``; NaN where the path does not reach.
        """
        if not (math.isfinite(x_end) and x_end > 0 and math.isfinite(step) and step > 0):
            raise ValueError(f"x_end = {x_end!r}, step = {step!r}: both must be finite and > 0 m")
        x = (np.arange(math.ceil(x_end / step)) + 0.5) * step
        if self.polyline is not None:
            px, py = self.polyline[:, 0], self.polyline[:, 1]
            segment = np.clip(np.searchsorted(px, x, side="right") - 1, 0, px.size - 2)
            slope = (py[segment + 1] - py[segment]) / (px[segment + 1] - px[segment])
            centre = py[segment] + slope * (x - px[segment])
            outside = x > px[-1]
        elif self.curvature == 0.0:
            centre, slope, outside = np.zeros_like(x), np.zeros_like(x), np.zeros(x.size, bool)
        else:
            radius = 1.0 / self.curvature
            outside = x >= abs(radius)
            root = np.sqrt(np.maximum(radius * radius - x * x, 0.0))
            centre = radius - np.sign(radius) * root
            with np.errstate(divide="ignore", invalid="ignore"):
                slope = np.sign(radius) * x / root
        centre = np.where(outside, np.nan, centre)
        slope = np.where(outside, np.nan, slope)
        return centre, slope
