"""Numba kernel behind :func:`monitor.geometry.camera.project_boxes`.

Private: the public function validates its input and builds the planes; this kernel never
validates and never raises.

The visible part of a 3D box is the convex polytope ``box & frustum``: the box's six
half-spaces and the camera's five (near plane, four image borders; the far side is open).
Its vertices are the feasible intersection points of three of the eleven planes, so they
are found by trying every triple (165 small linear solves). The 2D box is the extent of
their projections and the distance their smallest depth. This is exact: it equals clipping
the box's edges and faces at the near plane, projecting, and intersecting the projected
outline with the image rectangle.
"""
from __future__ import annotations

import numpy as np

from fuzzcore.jit import kernel

N_PLANES = 11  # 6 box faces + near plane + 4 image borders


@kernel
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])


@kernel
def visible_extents(centres, axes, half, frustum, K, width, height, near, min_extent, out):
    """Extent of each box's visible part.

    Parameters
    ----------
    centres : (n, 3) box centres, camera frame, metres.
    axes : (n, 3, 3) box axes in the camera frame, one per column, unit length.
    half : (n, 3) half extents along those axes, metres, > 0.
    frustum : (5, 4) rows ``a0, a1, a2, b``: unit normal ``a`` and offset ``b`` of the
        camera's half-spaces ``a . p <= b``.
    K : (3, 3) intrinsics with last row (0, 0, 1).
    width, height : image size, pixels.
    near : near plane, metres.
    min_extent : smallest width and height, pixels, of a box counted as visible.
    out : (n, 5) output rows ``u0, u1, v0, v1, z_min`` (written only for visible boxes).

    Returns
    -------
    (n,) bool, visible.
    """
    n = centres.shape[0]
    visible = np.zeros(n, dtype=np.bool_)
    planes = np.empty((N_PLANES, 4))
    planes[6:, :] = frustum
    for b in range(n):
        c = centres[b]
        scale = 1.0 + abs(c[0]) + abs(c[1]) + abs(c[2])
        for k in range(3):
            ax = axes[b, :, k]
            ac = ax[0] * c[0] + ax[1] * c[1] + ax[2] * c[2]
            planes[2 * k, 0:3] = ax
            planes[2 * k, 3] = ac + half[b, k]
            planes[2 * k + 1, 0:3] = -ax
            planes[2 * k + 1, 3] = -ac + half[b, k]
            scale += half[b, k]
        eps = 1e-9 * scale
        u0 = np.inf
        u1 = -np.inf
        v0 = np.inf
        v1 = -np.inf
        z_min = np.inf
        for i in range(N_PLANES - 2):
            for j in range(i + 1, N_PLANES - 1):
                cjx, cjy, cjz = _cross(planes[i, 0:3], planes[j, 0:3])
                for k in range(j + 1, N_PLANES):
                    ck = planes[k, 0:3]
                    det = cjx * ck[0] + cjy * ck[1] + cjz * ck[2]  # a_i . (a_j x a_k)
                    if abs(det) < 1e-12:
                        continue
                    jk = _cross(planes[j, 0:3], ck)
                    ki = _cross(ck, planes[i, 0:3])
                    bi = planes[i, 3]
                    bj = planes[j, 3]
                    bk = planes[k, 3]
                    px = (bi * jk[0] + bj * ki[0] + bk * cjx) / det
                    py = (bi * jk[1] + bj * ki[1] + bk * cjy) / det
                    pz = (bi * jk[2] + bj * ki[2] + bk * cjz) / det
                    feasible = True
                    for q in range(N_PLANES):
                        if (planes[q, 0] * px + planes[q, 1] * py + planes[q, 2] * pz
                                > planes[q, 3] + eps):
                            feasible = False
                            break
                    if not feasible:
                        continue
                    u = (K[0, 0] * px + K[0, 1] * py + K[0, 2] * pz) / pz
                    v = (K[1, 0] * px + K[1, 1] * py + K[1, 2] * pz) / pz
                    u0 = min(u0, u)
                    u1 = max(u1, u)
                    v0 = min(v0, v)
                    v1 = max(v1, v)
                    z_min = min(z_min, pz)
        if z_min == np.inf:
            continue
        # the vertices satisfy the frustum up to eps: clamp that round-off, nothing more
        u0 = max(u0, 0.0)
        u1 = min(u1, width)
        v0 = max(v0, 0.0)
        v1 = min(v1, height)
        if u1 - u0 > min_extent and v1 - v0 > min_extent:
            visible[b] = True
            out[b, 0] = u0
            out[b, 1] = u1
            out[b, 2] = v0
            out[b, 3] = v1
            out[b, 4] = max(z_min, near)
    return visible
