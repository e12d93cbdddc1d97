"""Numba kernels of :mod:`monitor.synthetic.raycast`. Private: no validation, never raise.

Rays are affine in the pixel: the ego-frame direction through pixel (u, v) is
``a * u + b * v + c``, scaled so that its camera-frame z component is 1. A hit at ray
parameter t therefore has camera-frame depth exactly t.
"""
from __future__ import annotations

import math

import numpy as np

from fuzzcore.jit import SYNTHETIC_IMAGE, kernel


@kernel(fastmath=SYNTHETIC_IMAGE)
def render(a, b, c, origin, near, boxes, box_labels, n_structure, rects, sky, ground, depth,
           labels, silhouette, depth32, visible, background32):
    """Ray-cast the ground plane z = 0 and oriented boxes into a z-buffer.

    The first ``n_structure`` boxes are static structure (walls, poles, curbs, ...): the
    z-buffer after them, ground and structure only, is the background.

    Parameters
    ----------
    a, b, c : ndarray of shape (3,), float64
        Ray direction per pixel: ``a * u + b * v + c`` (ego frame, camera-z component 1).
    origin : ndarray of shape (3,), float64
        Camera centre in the ego frame (``origin[2] > 0``).
    near : float
        Hits at t < near are clipped; a box the near plane cuts reads ``near`` there.
    boxes : ndarray of shape (n, 7), float64
        ``x, y, z, w, l, h, yaw`` in the ego frame (l along the heading), structure first.
    box_labels : ndarray of shape (n,), int16
        The label each box writes (structure: a code <= ground; actor k: k + 1).
    n_structure : int
        How many of the boxes are structure.
    rects : ndarray of shape (n, 4), int64
        Per box the pixels to test, half-open ``u0, u1, v0, v1`` (empty: skip the box).
    sky, ground : int
        Labels of no hit and of the ground.
    depth : ndarray of shape (H, W), float64, out
        Nearest hit's t (camera-frame depth, metres), inf for no hit.
    labels : ndarray of shape (H, W), int16, out
    silhouette : ndarray of shape (n,), int64, out
        Per box the number of pixels whose ray hits it (occluded or not).
    depth32 : ndarray of shape (H, W), float32, out
        ``depth`` rounded to float32.
    visible : ndarray of shape (n - n_structure,), int64, out
        Per actor the number of pixels where it is the nearest hit (label k + 1 -> k).
    background32 : ndarray of shape (H, W), float32, out
        The depth of the ground and the structure alone.
    """
    height, width = depth.shape
    oz = origin[2]
    for v in range(height):
        for u in range(width):
            rz = a[2] * u + b[2] * v + c[2]
            t = -oz / rz if rz < 0.0 else np.inf
            if t >= near and t < np.inf:
                depth[v, u] = t
                labels[v, u] = ground
            else:
                depth[v, u] = np.inf
                labels[v, u] = sky
    for k in range(boxes.shape[0]):
        if k == n_structure:
            _round(depth, background32)
        silhouette[k] = 0
        u0, u1, v0, v1 = rects[k, 0], rects[k, 1], rects[k, 2], rects[k, 3]
        if u0 >= u1 or v0 >= v1:
            continue
        cs = math.cos(boxes[k, 6])
        sn = math.sin(boxes[k, 6])
        # everything in the box frame: p_box = Rz(-yaw) (p - centre)
        dx = origin[0] - boxes[k, 0]
        dy = origin[1] - boxes[k, 1]
        ox = cs * dx + sn * dy
        oy = -sn * dx + cs * dy
        oz_box = origin[2] - boxes[k, 2]
        ax, ay, az = cs * a[0] + sn * a[1], -sn * a[0] + cs * a[1], a[2]
        bx, by, bz = cs * b[0] + sn * b[1], -sn * b[0] + cs * b[1], b[2]
        cx, cy, cz = cs * c[0] + sn * c[1], -sn * c[0] + cs * c[1], c[2]
        hx = 0.5 * boxes[k, 4]
        hy = 0.5 * boxes[k, 3]
        hz = 0.5 * boxes[k, 5]
        label = box_labels[k]
        count = 0
        for v in range(v0, v1):
            for u in range(u0, u1):
                t_in, t_out = _slab(ax * u + bx * v + cx, ox, hx, -np.inf, np.inf)
                t_in, t_out = _slab(ay * u + by * v + cy, oy, hy, t_in, t_out)
                t_in, t_out = _slab(az * u + bz * v + cz, oz_box, hz, t_in, t_out)
                if t_in > t_out or t_out < near:
                    continue
                count += 1
                t = max(t_in, near)
                if t < depth[v, u]:
                    depth[v, u] = t
                    labels[v, u] = label
        silhouette[k] = count
    if n_structure >= boxes.shape[0]:
        _round(depth, background32)
    visible[:] = 0
    for v in range(height):
        for u in range(width):
            depth32[v, u] = depth[v, u]
            if labels[v, u] > ground:
                visible[labels[v, u] - 1] += 1


@kernel(fastmath=SYNTHETIC_IMAGE)
def _round(depth, out):
    """``out = depth`` rounded to float32."""
    for v in range(depth.shape[0]):
        for u in range(depth.shape[1]):
            out[v, u] = depth[v, u]


@kernel(inline=True, fastmath=SYNTHETIC_IMAGE)
def _slab(r, o, half, t_in, t_out):
    """Narrow [t_in, t_out] to where o + t r lies in [-half, half] (empty: t_in > t_out)."""
    if r == 0.0:
        if abs(o) > half:
            return np.inf, -np.inf
        return t_in, t_out
    t1 = (-half - o) / r
    t2 = (half - o) / r
    if t1 > t2:
        t1, t2 = t2, t1
    return max(t_in, t1), min(t_out, t2)
