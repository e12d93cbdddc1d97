"""What the shield braked for, looked up in the closed loop's ground truth.

An unseen object that engages the shield is a span ``x, y_min, y_max`` in the ego frame
(:attr:`monitor.shield.ShieldDecision.objects`) that the depth view made of some of the
frame's pixels. Back-projected through the estimated depth, every pixel lands somewhere in
the ego frame; those that land on the object (along x within :data:`ALONG_M` of its near
edge ``x``, within its lateral span widened by :data:`SPAN_MARGIN_M`, between
:data:`HEIGHTS_M` above the road) are the pixels the view read there, and the ray cast's
label map says what each of them really shows. The object lay on what most of them show:
``road`` (a lane marking counts as road), ``sidewalk``, ``structure``, ``sky``, the class of a
road user (``car``, ``pedestrian``, ...), ``label <code>`` for another code of the map, or
``none`` when no pixel lands there.

A patch of road the depth reads too near lifts its pixels off the road onto the object, so
it reads ``road``; a car beside the path read at the path's edge reads ``car``. Only the
simulation knows this: it is a diagnostic of :func:`monitor.offline.closed_loop.run_scenario`,
not something the monitor could use.
"""
from __future__ import annotations

import numpy as np

from monitor.datasets.frames import LABEL_MARKING, LABEL_ROAD, LABEL_SIDEWALK, LABEL_SKY, LABEL_STRUCTURE
from monitor.geometry.camera import Camera
from monitor.synthetic.raycast import pixel_rays

#: Metres along x, from an object's near edge ``x``, whose pixels count as the object's (the
#: view's ``x`` is the object's nearest block; its other blocks lie farther).
ALONG_M = (-0.1, 1.5)
#: Metres either side of an object's lateral span whose pixels count as the object's.
SPAN_MARGIN_M = 0.05
#: Heights above the road (z = 0 in the closed loop's ego frame) of the pixels that count,
#: metres: the road's pixels read about right stay under the lower bound (a 10 % depth error
#: lifts them 0.15 m: the camera's height times it), what a car passes under lies above the upper.
HEIGHTS_M = (0.15, 3.0)
#: Names of the label map's codes other than road users'.
GROUND_NAMES = {LABEL_ROAD: "road", LABEL_MARKING: "road", LABEL_SIDEWALK: "sidewalk",
                LABEL_STRUCTURE: "structure", LABEL_SKY: "sky"}


def what_lies_there(objects, depth: np.ndarray, labels: np.ndarray, classes, camera: Camera) -> list[str]:
    """What each object's pixels really show.

    Parameters
    ----------
    objects : array_like of shape (k, 3)
        ``x, y_min, y_max`` per object, ego frame, metres.
    depth : ndarray of shape (H, W)
        The estimated depth the monitor saw, metres (non-finite or <= 0: no point).
    labels : ndarray of shape (H, W), int
        The ray cast's label map (:mod:`monitor.datasets.frames`: ground codes, or ``k + 1``
        for actor ``k``).
    classes : sequence of str, length n
        The class of each actor of the label map.
    camera : Camera
        The camera of ``depth``; the road is the ego frame's z = 0.

    Returns
    -------
    list of str, length k
        See the module docstring.
    """
    objects = np.asarray(objects, dtype=np.float64).reshape(-1, 3)
    if len(objects) == 0:
        return []
    a, b, c = pixel_rays(camera)
    j, i = np.mgrid[0:camera.height, 0:camera.width]
    d = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).astype(np.float64)
    points = camera.cam_to_ego[:3, 3] + d[..., None] * (i[..., None] * a + j[..., None] * b + c)
    x, y, z = points[..., 0], points[..., 1], points[..., 2]
    band = (z > HEIGHTS_M[0]) & (z < HEIGHTS_M[1])
    names = []
    for near, y_min, y_max in objects:
        on = band & (x >= near + ALONG_M[0]) & (x <= near + ALONG_M[1]) \
            & (y >= y_min - SPAN_MARGIN_M) & (y <= y_max + SPAN_MARGIN_M)
        if not on.any():
            names.append("none")
            continue
        codes, counts = np.unique(labels[on], return_counts=True)
        top = int(codes[np.argmax(counts)])
        names.append(str(classes[top - 1]) if top >= 1 else GROUND_NAMES.get(top, f"label {top}"))
    return names
