"""Numba kernels of the geometric depth view (private; see :mod:`monitor.depth.geometric`).

The kernels trust their inputs (the public class validates them: C-contiguous arrays of the
stated dtypes and shapes) and never raise. A depth is valid when it is finite and > 0; a
block whose depth reads 0 has no valid pixel. The per-block arrays are (rows, cols) grids of
``stride x stride`` pixel blocks, or their flat (rows * cols,) views. Compiled with
:mod:`fuzzcore.jit`'s options: a division follows IEEE rules instead of testing for zero, and
no fastmath, so NaN and inf keep their meaning.
"""
from __future__ import annotations

import math

import numpy as np

from fuzzcore.jit import kernel

_INF = np.float32(np.inf)


@kernel
def block_points(depth, stride, edge_spread, M, origin, xs, ys, zs, ds, invalid_px):
    """One depth per block, back-projected through the block's centre.

    A block's depth is the mean of its valid depths, or, at an edge (the largest exceeds
    the smallest by more than ``edge_spread`` times the smallest), its smallest: the nearer
    surface, never a point floating between two. ``depth`` is float32 (H, W) metres;
    ``M`` float64 (3, 3) maps a pixel ``(u, v, 1)`` to its ego-frame ray scaled to camera
    z = 1 (``R K^-1``); ``origin`` float64 (3,) is the camera centre in the ego frame. The
    blocks cover rows ``r stride .. (r + 1) stride - 1`` and columns likewise (partial at
    the last row and column); the centre of a block spanning pixels ``[j0, j1) x [i0, i1)``
    is ``((j0 + j1) / 2, (i0 + i1) / 2)``. Outputs, float32 (rows, cols): ``xs, ys, zs``
    the ego-frame point (metres) and ``ds`` the camera depth; a block without a valid pixel
    gets 0 in all four. ``invalid_px`` int32 (rows, cols): the block's invalid pixels.
    Returns the number of invalid pixels.

    Each band of ``stride`` rows is summed down its columns (sum, count, smallest and largest
    valid depth per pixel column), then across each block's columns, then back-projected.
    Bands and blocks four pixels wide, the default stride's, take loops written out for four
    (LLVM vectorises them); they add in the same order as the general loops, so the bits do
    not depend on which loop ran.
    """
    height, width = depth.shape
    rows, cols = ds.shape
    zero = np.float32(0.0)
    sums = np.empty(width, dtype=np.float32)  # per pixel column of the band
    counts = np.empty(width, dtype=np.float32)  # whole numbers, exact in float32
    lows = np.empty(width, dtype=np.float32)
    highs = np.empty(width, dtype=np.float32)
    totals = np.empty(cols, dtype=np.float32)  # per block of the band
    numbers = np.empty(cols, dtype=np.float32)
    least = np.empty(cols, dtype=np.float32)
    most = np.empty(cols, dtype=np.float32)
    widths = np.empty(cols, dtype=np.int64)
    centres = np.empty(cols)
    for c in range(cols):
        j0 = c * stride
        j1 = min(j0 + stride, width)
        widths[c] = j1 - j0
        centres[c] = 0.5 * (j0 + j1)
    whole = width // 4 if stride == 4 else 0  # blocks of four columns
    spread = np.float32(1.0 + edge_spread)
    ox, oy, oz = origin[0], origin[1], origin[2]
    n_invalid = 0
    for r in range(rows):
        i0 = r * stride
        i1 = min(i0 + stride, height)
        if i1 - i0 == 4:
            row0, row1, row2, row3 = depth[i0], depth[i0 + 1], depth[i0 + 2], depth[i0 + 3]
            for j in range(width):
                d0, d1, d2, d3 = row0[j], row1[j], row2[j], row3[j]
                ok0, ok1 = (d0 > zero) & (d0 < _INF), (d1 > zero) & (d1 < _INF)
                ok2, ok3 = (d2 > zero) & (d2 < _INF), (d3 > zero) & (d3 < _INF)
                sums[j] = (((d0 if ok0 else zero) + (d1 if ok1 else zero)) + (d2 if ok2 else zero)) \
                    + (d3 if ok3 else zero)
                counts[j] = ((np.float32(ok0) + np.float32(ok1)) + np.float32(ok2)) + np.float32(ok3)
                lows[j] = min(min(min(d0 if ok0 else _INF, d1 if ok1 else _INF), d2 if ok2 else _INF),
                              d3 if ok3 else _INF)
                highs[j] = max(max(max(d0 if ok0 else zero, d1 if ok1 else zero), d2 if ok2 else zero),
                               d3 if ok3 else zero)
        else:
            sums[:] = zero
            counts[:] = zero
            lows[:] = _INF
            highs[:] = zero
            for i in range(i0, i1):
                row = depth[i]
                for j in range(width):
                    d = row[j]
                    valid = (d > zero) & (d < _INF)
                    sums[j] += d if valid else zero
                    counts[j] += np.float32(valid)
                    lows[j] = min(lows[j], d if valid else _INF)
                    highs[j] = max(highs[j], d if valid else zero)
        for c in range(whole):
            j = 4 * c
            totals[c] = ((sums[j] + sums[j + 1]) + sums[j + 2]) + sums[j + 3]
            numbers[c] = ((counts[j] + counts[j + 1]) + counts[j + 2]) + counts[j + 3]
            least[c] = min(min(min(lows[j], lows[j + 1]), lows[j + 2]), lows[j + 3])
            most[c] = max(max(max(highs[j], highs[j + 1]), highs[j + 2]), highs[j + 3])
        for c in range(whole, cols):
            total, n, low, high = zero, zero, _INF, zero
            for j in range(c * stride, c * stride + widths[c]):
                total += sums[j]
                n += counts[j]
                low = min(low, lows[j])
                high = max(high, highs[j])
            totals[c], numbers[c], least[c], most[c] = total, n, low, high
        v = 0.5 * (i0 + i1)
        rx, ry, rz = M[0, 1] * v, M[1, 1] * v, M[2, 1] * v
        mx, my, mz = M[0, 0], M[1, 0], M[2, 0]
        kx, ky, kz = M[0, 2], M[1, 2], M[2, 2]
        xr, yr, zr, dr, missing = xs[r], ys[r], zs[r], ds[r], invalid_px[r]
        band_invalid = 0
        for c in range(cols):
            n = numbers[c]
            gone = (i1 - i0) * widths[c] - int(n)
            missing[c] = gone
            band_invalid += gone
            some = n > zero
            d = totals[c] / n if most[c] <= spread * least[c] else least[c]
            u = centres[c]
            xr[c] = ox + d * (mx * u + rx + kx) if some else zero
            yr[c] = oy + d * (my * u + ry + ky) if some else zero
            zr[c] = oz + d * (mz * u + rz + kz) if some else zero
            dr[c] = d if some else zero
        n_invalid += band_invalid
    return n_invalid


@kernel(inline=True)
def _lateral(x, y, centre_y, tan_heading, step):
    """Lateral offset of ``(x, y)`` from the corridor's centreline (its tangent line at the
    middle of the point's table row, see :meth:`monitor.geometry.corridor.Corridor.table`),
    NaN outside its reach."""
    if not x >= 0.0:
        return np.nan
    k = int(x / step)
    if k >= centre_y.shape[0]:
        return np.nan
    t = tan_heading[k]
    return abs(y - centre_y[k] - t * (x - (k + 0.5) * step)) / math.sqrt(1.0 + t * t)


@kernel
def footprint_blocks(ground_x, ground_y, ground_d, max_range, centre_y, tan_heading, step,
                     half_width, out):
    """The blocks that look at the corridor's ground.

    ``ground_x, ground_y, ground_d`` (flat float64) are where each block's centre ray meets
    the nominal ground plane (ego x, y, camera depth; ``ground_d`` inf where it does not).
    A block looks at the corridor when ``ground_d <= max_range`` and the lateral offset of
    its ground point is at most ``half_width``. Their flat indices are written to the start
    of ``out`` (int64); returns how many.
    """
    n = 0
    for k in range(ground_d.shape[0]):
        if ground_d[k] <= max_range and \
                _lateral(ground_x[k], ground_y[k], centre_y, tan_heading, step) <= half_width:
            out[n] = k
            n += 1
    return n


@kernel
def ground_candidates(xs, ys, zs, ds, x_max, band0, band_slope, out):
    """Flat indices of the blocks that may be road: valid, ``0 <= x <= x_max`` and
    ``|z| <= band0 + band_slope * sqrt(x^2 + y^2)`` (the nominal plane's band that every
    plane within the sanity bounds stays in). Written to the start of ``out`` (int64);
    returns how many."""
    n = 0
    for k in range(ds.shape[0]):
        x, y, z = xs[k], ys[k], zs[k]
        if ds[k] > 0.0 and x >= 0.0 and x <= x_max and \
                abs(z) <= band0 + band_slope * math.sqrt(x * x + y * y):
            out[n] = k
            n += 1
    return n


@kernel
def ransac_plane(xs, ys, zs, idx, n, uniforms, n_score, tol, max_slope, max_offset):
    """The plane ``z = a x + b y + c`` through three candidates with the most inliers
    (float64 arithmetic on the float32 points).

    Hypothesis i goes through candidates ``idx[floor(uniforms[i, m] * n)]``, m = 0, 1, 2
    (``uniforms`` float64 (iterations, 3) in [0, 1)). Planes with ``a^2 + b^2 >
    max_slope^2`` or ``|c| > max_offset`` are skipped, as are degenerate triples. A
    hypothesis scores the candidates ``idx[0], idx[s], idx[2 s], ...`` (``s = max(1, n //
    n_score)``) within ``tol`` of it vertically; ties keep the earlier hypothesis. Returns
    ``(a, b, c, score)``; score 0 and a zero plane when no hypothesis passed.
    """
    best_a, best_b, best_c, best = 0.0, 0.0, 0.0, 0
    if n < 3:
        return best_a, best_b, best_c, best
    s = max(1, n // n_score)
    for it in range(uniforms.shape[0]):
        i = idx[min(int(uniforms[it, 0] * n), n - 1)]
        j = idx[min(int(uniforms[it, 1] * n), n - 1)]
        k = idx[min(int(uniforms[it, 2] * n), n - 1)]
        xi, yi, zi = float(xs[i]), float(ys[i]), float(zs[i])
        ux, uy, uz = xs[j] - xi, ys[j] - yi, zs[j] - zi
        vx, vy, vz = xs[k] - xi, ys[k] - yi, zs[k] - zi
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        norm = math.sqrt(nx * nx + ny * ny + nz * nz)
        if not abs(nz) > 1e-6 * norm:  # degenerate triple or a vertical plane
            continue
        a, b = -nx / nz, -ny / nz
        c = zi - a * xi - b * yi
        if a * a + b * b > max_slope * max_slope or abs(c) > max_offset:
            continue
        score = 0
        for m in range(0, n, s):
            q = idx[m]
            score += abs(zs[q] - (a * xs[q] + b * ys[q] + c)) <= tol
        if score > best:
            best_a, best_b, best_c, best = a, b, c, score
    return best_a, best_b, best_c, best


@kernel
def refine_plane(xs, ys, zs, idx, n, a, b, c, tol):
    """Least-squares ``z = a x + b y + c`` over the candidates within ``tol`` of the plane
    given. Returns ``(a, b, c, inliers)``: the refit (the plane given if the inliers do not
    determine one) and how many candidates were within ``tol`` of the plane given."""
    sxx = sxy = sx = syy = sy = sxz = syz = sz = 0.0
    count = 0
    for m in range(n):
        q = idx[m]
        x, y, z = float(xs[q]), float(ys[q]), float(zs[q])
        if abs(z - (a * x + b * y + c)) <= tol:
            sxx += x * x
            sxy += x * y
            sx += x
            syy += y * y
            sy += y
            sxz += x * z
            syz += y * z
            sz += z
            count += 1
    w = float(count)
    # normal equations [[sxx sxy sx] [sxy syy sy] [sx sy w]] p = [sxz syz sz], Cramer's rule
    det = sxx * (syy * w - sy * sy) - sxy * (sxy * w - sy * sx) + sx * (sxy * sy - syy * sx)
    scale = (sxx + syy + w) ** 3
    if count < 3 or not abs(det) > 1e-12 * scale:
        return a, b, c, count
    da = sxz * (syy * w - sy * sy) - sxy * (syz * w - sy * sz) + sx * (syz * sy - syy * sz)
    db = sxx * (syz * w - sz * sy) - sxz * (sxy * w - sy * sx) + sx * (sxy * sz - syz * sx)
    dc = sxx * (syy * sz - sy * syz) - sxy * (sxy * sz - sy * sxz) + sx * (sxy * syz - syy * sxz)
    return da / det, db / det, dc / det, count


@kernel
def classify(xs, ys, zs, ds, a, b, c, min_height, max_height, max_range, below_margin,
             centre_y, tan_heading, step, half_width, tall_height, obstacle, corridor, tall, road):
    """Which blocks stand above the road, which of those are inside the corridor, which
    blocks are taller than traffic, and which are the road.

    A valid block's height above the plane is ``h = z - (a x + b y + c)``. ``obstacle``
    (flat uint8) gets 1 where ``min_height <= h <= max_height`` and ``d <= max_range``;
    ``corridor`` gets 1 where a block is an obstacle and its lateral offset from the
    centreline is at most ``half_width``; ``tall`` gets 1 where ``h > tall_height`` (inf:
    never); ``road`` (flat float32) the depth ``d`` where ``-below_margin <= h < min_height``,
    0 for the other valid blocks and NaN for the invalid ones. Returns ``(valid blocks,
    blocks with h < -below_margin)``.
    """
    n_valid = 0
    n_below = 0
    for k in range(ds.shape[0]):
        d = ds[k]
        obstacle[k] = 0
        corridor[k] = 0
        tall[k] = 0
        road[k] = np.nan
        if not d > 0.0:
            continue
        n_valid += 1
        x, y = xs[k], ys[k]
        h = zs[k] - (a * x + b * y + c)
        n_below += h < -below_margin
        road[k] = d if h >= -below_margin and h < min_height else 0.0
        tall[k] = h > tall_height
        if h >= min_height and h <= max_height and d <= max_range:
            obstacle[k] = 1
            corridor[k] = _lateral(x, y, centre_y, tan_heading, step) <= half_width
    return n_valid, n_below


@kernel(inline=True)
def _find(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]  # path halving
        i = parent[i]
    return i


@kernel(inline=True)
def _union(parent, i, j):
    ri, rj = _find(parent, i), _find(parent, j)
    if ri < rj:
        parent[rj] = ri
    elif rj < ri:
        parent[ri] = rj


@kernel
def label_objects(xs, ys, obstacle, x0, y0, cell, parent, ids, labels):
    """Objects as connected components of an occupancy grid on the ground.

    Each obstacle block occupies the grid cell of its ground position: column
    ``floor((x - x0) / cell)``, row ``floor((y - y0) / cell)`` of an (nx, ny) grid (indices
    clamped to the grid). Occupied cells are 8-connected; a gap of a free cell between two
    things on the ground splits them, so an object in front of another, or beside it, is
    its own. ``xs, ys`` float32 and ``obstacle`` uint8 are (rows, cols); ``parent`` and
    ``ids`` are int32 (nx, ny) scratch; ``labels`` int32 (rows, cols) gets each obstacle
    block's component, numbered 0, 1, ... in the order of their first block (row-major),
    and -1 elsewhere. Returns the number of components.
    """
    rows, cols = obstacle.shape
    nx, ny = parent.shape
    flat = parent.ravel()
    flat[:] = -1
    for r in range(rows):
        for col in range(cols):
            if obstacle[r, col]:
                gi = min(max(int(math.floor((xs[r, col] - x0) / cell)), 0), nx - 1)
                gj = min(max(int(math.floor((ys[r, col] - y0) / cell)), 0), ny - 1)
                flat[gi * ny + gj] = gi * ny + gj
    for gi in range(nx):
        for gj in range(ny):
            k = gi * ny + gj
            if flat[k] < 0:
                continue
            if gj + 1 < ny and flat[k + 1] >= 0:
                _union(flat, k, k + 1)
            if gi + 1 < nx:
                for dj in range(-1, 2):
                    if 0 <= gj + dj < ny and flat[k + ny + dj] >= 0:
                        _union(flat, k, k + ny + dj)
    ids_flat = ids.ravel()
    ids_flat[:] = -1
    n = 0
    for r in range(rows):
        for col in range(cols):
            if not obstacle[r, col]:
                labels[r, col] = -1
                continue
            gi = min(max(int(math.floor((xs[r, col] - x0) / cell)), 0), nx - 1)
            gj = min(max(int(math.floor((ys[r, col] - y0) / cell)), 0), ny - 1)
            root = _find(flat, gi * ny + gj)
            if ids_flat[root] < 0:
                ids_flat[root] = n
                n += 1
            labels[r, col] = ids_flat[root]
    return n


@kernel
def clear_structure(xs, ys, tall, x0, y0, cell, marks, obstacle, corridor):
    """Take the obstacle blocks standing where something tall rises from the ground.

    A block with ``tall`` set marks the cell of its ground position (``xs, ys``) on the
    (nx, ny) grid of :func:`label_objects`, and the cell's 8 neighbours (the scatter of a
    depth estimate's error; ``marks`` int32 scratch; blocks off the grid mark nothing).
    Every obstacle block in a marked cell is cleared from ``obstacle`` and ``corridor``
    (uint8, like ``tall`` (rows, cols)). Returns the number cleared.
    """
    rows, cols = tall.shape
    nx, ny = marks.shape
    flat = marks.ravel()
    flat[:] = 0
    for r in range(rows):
        for col in range(cols):
            if tall[r, col]:
                fi = math.floor((xs[r, col] - x0) / cell)
                fj = math.floor((ys[r, col] - y0) / cell)
                if 0 <= fi < nx and 0 <= fj < ny:  # the cell and its 8 neighbours
                    for i in range(max(int(fi) - 1, 0), min(int(fi) + 2, nx)):
                        for j in range(max(int(fj) - 1, 0), min(int(fj) + 2, ny)):
                            flat[i * ny + j] = 1
    n = 0
    for r in range(rows):
        for col in range(cols):
            if obstacle[r, col]:
                fi = math.floor((xs[r, col] - x0) / cell)
                fj = math.floor((ys[r, col] - y0) / cell)
                if 0 <= fi < nx and 0 <= fj < ny and flat[int(fi) * ny + int(fj)]:
                    obstacle[r, col] = 0
                    corridor[r, col] = 0
                    n += 1
    return n


@kernel
def standing(labels, index, corridor, xs, ys, zs, ds, plane, floor, top, x0, y0, cell, low, high,
             min_rise, side_percentile, row0, row1):
    """Per chosen component: where its part that rises from the road stands.

    Every valid block (``ds`` > 0) whose height above the road ``plane`` (float64 (3,),
    ``z = a x + b y + c``) is within ``[floor, top]`` widens the height range of the cell
    of its ground position on the (nx, ny) grid of :func:`label_objects` (``low`` and
    ``high`` float32 (nx, ny) scratch; blocks off the grid are left out). A block of a
    component *rises* when the cell of its ground position or one of its 8 neighbours (the
    scatter of a depth estimate's error) holds heights ``min_rise`` or more apart.
    ``labels`` int32, ``corridor`` uint8 and ``xs, ys, zs, ds`` float32 (rows, cols);
    ``index`` int64 (n,) maps a component to its row of the result (-1: not wanted), whose
    blocks all lie in the block rows ``row0`` to ``row1`` (inclusive).

    Returns float64 (k, 4), k = ``index.max() + 1``, rows ``x, y_low, y_high, rising``:
    the smallest ego x of the component's rising blocks inside the corridor, the
    ``side_percentile`` and ``100 - side_percentile`` of its rising blocks' ego y, and the
    number of its rising blocks. A component with no rising block inside the corridor takes
    ``x`` over all its blocks inside it (inf if none), one with no rising block ``y_low,
    y_high`` over all its blocks, as :func:`object_stats` gives them; NaN rows for
    components without blocks.
    """
    rows, cols = ds.shape
    nx, ny = low.shape
    a, b, c = plane[0], plane[1], plane[2]
    low[:, :] = np.inf
    high[:, :] = -np.inf
    for r in range(rows):
        for col in range(cols):
            if not ds[r, col] > 0.0:
                continue
            h = zs[r, col] - (a * xs[r, col] + b * ys[r, col] + c)
            fi = math.floor((xs[r, col] - x0) / cell)
            fj = math.floor((ys[r, col] - y0) / cell)
            if floor <= h <= top and 0 <= fi < nx and 0 <= fj < ny:
                i, j = int(fi), int(fj)
                low[i, j] = min(low[i, j], h)
                high[i, j] = max(high[i, j], h)
    # high: 1 where a cell's heights span min_rise; low: 1 where one of the 3 x 3 cells does
    for i in range(nx):
        for j in range(ny):
            high[i, j] = 1.0 if high[i, j] - low[i, j] >= min_rise else 0.0
    for i in range(nx):
        for j in range(ny):
            low[i, j] = 0.0
            for ii in range(max(i - 1, 0), min(i + 2, nx)):
                for jj in range(max(j - 1, 0), min(j + 2, ny)):
                    if high[ii, jj] > 0.0:
                        low[i, j] = 1.0
    k = 0
    for m in range(index.shape[0]):
        k = max(k, index[m] + 1)
    counts = np.zeros((k, 2), dtype=np.int64)  # blocks, rising blocks
    x_all = np.full(k, np.inf)
    x_up = np.full(k, np.inf)
    band = max(row1 - row0 + 1, 0)
    up = np.zeros((band, cols), dtype=np.uint8)
    for r in range(row0, row0 + band):
        for col in range(cols):
            m = labels[r, col]
            if m < 0 or index[m] < 0:
                continue
            j = index[m]
            fi = math.floor((xs[r, col] - x0) / cell)
            fj = math.floor((ys[r, col] - y0) / cell)
            if 0 <= fi < nx and 0 <= fj < ny and low[int(fi), int(fj)] > 0.0:
                up[r - row0, col] = 1
            counts[j, 0] += 1
            counts[j, 1] += up[r - row0, col]
            if corridor[r, col]:
                x_all[j] = min(x_all[j], float(xs[r, col]))
                if up[r - row0, col]:
                    x_up[j] = min(x_up[j], float(xs[r, col]))
    # the lateral positions of each component's rising blocks, or of all of them if none rise
    start = np.zeros(k + 1, dtype=np.int64)
    for j in range(k):
        start[j + 1] = start[j] + (counts[j, 1] if counts[j, 1] > 0 else counts[j, 0])
    sides = np.empty(start[k], dtype=np.float64)
    fill = start[:k].copy()
    for r in range(row0, row0 + band):
        for col in range(cols):
            m = labels[r, col]
            if m < 0 or index[m] < 0:
                continue
            j = index[m]
            if up[r - row0, col] or counts[j, 1] == 0:
                sides[fill[j]] = ys[r, col]
                fill[j] += 1
    out = np.full((k, 4), np.nan)
    for j in range(k):
        if counts[j, 0] == 0:
            continue
        out[j, 0] = x_up[j] if x_up[j] < np.inf else x_all[j]
        out[j, 1] = _percentile(sides[start[j]:start[j + 1]], side_percentile)
        out[j, 2] = _percentile(sides[start[j]:start[j + 1]], 100.0 - side_percentile)
        out[j, 3] = counts[j, 1]
    return out


@kernel
def _percentile(values, percentile):
    """The ``percentile`` (0..100, linear interpolation as numpy's default) of a non-empty
    1-D array, by selection (O(size)); reorders ``values``."""
    size = values.size
    pos = percentile / 100.0 * (size - 1)
    lo = int(math.floor(pos))
    segment = np.partition(values, lo)
    low = segment[lo]
    high = segment[lo + 1:].min() if lo + 1 < size else low  # the smallest above it
    return low + (high - low) * (pos - lo)


@kernel
def object_stats(labels, n, corridor, ds, xs, ys, min_points, percentile, side_percentile):
    """Per component: its extent, sizes, nearest corridor point, a robust depth and a
    robust lateral span.

    ``labels`` int32 (rows, cols) from :func:`label_objects` with ``n`` components;
    ``corridor`` uint8, ``ds``, ``xs`` and ``ys`` float32 (rows, cols). Returns float64
    (n, 10) rows ``r0, r1, c0, c1, blocks, corridor_blocks, corridor_x_min, depth, y_low,
    y_high``: the first and last block row and column, the number of blocks and of those
    inside the corridor, the smallest ego x of those (inf if none), and, for components
    with at least ``min_points`` blocks inside the corridor, the ``percentile`` (0..100,
    linear interpolation as numpy's default) of the blocks' depths and the
    ``side_percentile`` and ``100 - side_percentile`` of their ego y; NaN for the others.
    """
    rows, cols = ds.shape
    stats = np.empty((n, 10))
    for m in range(n):
        stats[m, 0] = rows
        stats[m, 1] = -1.0
        stats[m, 2] = cols
        stats[m, 3] = -1.0
        stats[m, 4] = 0.0
        stats[m, 5] = 0.0
        stats[m, 6] = np.inf
        stats[m, 7] = np.nan
        stats[m, 8] = np.nan
        stats[m, 9] = np.nan
    for r in range(rows):
        for col in range(cols):
            m = labels[r, col]
            if m < 0:
                continue
            stats[m, 0] = min(stats[m, 0], r)
            stats[m, 1] = max(stats[m, 1], r)
            stats[m, 2] = min(stats[m, 2], col)
            stats[m, 3] = max(stats[m, 3], col)
            stats[m, 4] += 1.0
            if corridor[r, col]:
                stats[m, 5] += 1.0
                stats[m, 6] = min(stats[m, 6], float(xs[r, col]))
    # the kept components' depths, gathered per component (counting sort)
    start = np.zeros(n + 1, dtype=np.int64)
    for m in range(n):
        kept = stats[m, 5] >= min_points
        start[m + 1] = start[m] + (int(stats[m, 4]) if kept else 0)
    depths = np.empty(start[n], dtype=np.float64)
    sides = np.empty(start[n], dtype=np.float64)
    fill = start[:n].copy()
    for r in range(rows):
        for col in range(cols):
            m = labels[r, col]
            if m >= 0 and stats[m, 5] >= min_points:
                depths[fill[m]] = ds[r, col]
                sides[fill[m]] = ys[r, col]
                fill[m] += 1
    for m in range(n):
        if start[m + 1] == start[m]:
            continue
        stats[m, 7] = _percentile(depths[start[m]:start[m + 1]], percentile)
        side = sides[start[m]:start[m + 1]]
        stats[m, 8] = _percentile(side, side_percentile)
        stats[m, 9] = _percentile(side, 100.0 - side_percentile)
    return stats


@kernel
def ledge_shape(labels, index, xs, ys, zs, plane, side_percentile, top_percentile):
    """Per chosen component: how high it rises and how far it reaches along x.

    ``labels`` int32 (rows, cols) from :func:`label_objects`; ``index`` int64 (n,) maps a
    component to its row of the result (-1: not wanted); ``xs``, ``ys`` and ``zs`` float32
    (rows, cols); ``plane`` float64 (3,) the road ``z = a x + b y + c``. Returns float64
    (k, 2), k = ``index.max() + 1``, rows ``top, along``: the ``top_percentile`` (0..100,
    linear interpolation as numpy's default) of the component's blocks' heights above the
    road and the distance between the ``side_percentile`` and ``100 - side_percentile`` of
    their ego x, metres.
    """
    rows, cols = labels.shape
    k = 0
    for m in range(index.size):
        k = max(k, index[m] + 1)
    start = np.zeros(k + 1, dtype=np.int64)
    for r in range(rows):
        for col in range(cols):
            m = labels[r, col]
            if m >= 0 and index[m] >= 0:
                start[index[m] + 1] += 1
    for j in range(k):
        start[j + 1] += start[j]
    heights = np.empty(start[k], dtype=np.float64)
    alongs = np.empty(start[k], dtype=np.float64)
    fill = start[:k].copy()
    a, b, c = plane[0], plane[1], plane[2]
    for r in range(rows):
        for col in range(cols):
            m = labels[r, col]
            if m >= 0 and index[m] >= 0:
                j = index[m]
                heights[fill[j]] = zs[r, col] - (a * xs[r, col] + b * ys[r, col] + c)
                alongs[fill[j]] = xs[r, col]
                fill[j] += 1
    out = np.empty((k, 2))
    for j in range(k):
        along = alongs[start[j]:start[j + 1]]
        out[j, 0] = _percentile(heights[start[j]:start[j + 1]], top_percentile)
        out[j, 1] = _percentile(along, 100.0 - side_percentile) - _percentile(along, side_percentile)
    return out


@kernel
def surface_shape(labels, index, ds, stride, road_slope, contact_ratio, contact_blocks):
    """Per chosen component: does it stand, or lie along the road with the road seen beneath?

    ``labels`` int32 (rows, cols) from :func:`label_objects`; ``index`` int64 (n,) maps a
    component to its row of the result (-1: not wanted); ``ds`` float32 (rows, cols)
    camera depths (<= 0 or NaN: no point); a block's image row is ``(r + 0.5) * stride``
    pixels; ``road_slope`` > 0 is the road plane's inverse depth gained per pixel down the
    image (1 / m per px). Returns float64 (k, 2), k = ``index.max() + 1``, rows
    ``incline, contact``:

    - ``incline``: the least-squares slope of the component's inverse depths over its rows,
      as a share of ``road_slope``: 0 for a face standing upright (one depth down its
      rows), 1 for a patch of road, above 1 for a surface parallel to the road above it.
      NaN when all its blocks lie in one row.
    - ``contact``: over its columns, the share whose lowest block has road or another thing
      right beneath it, no farther than ``contact_ratio`` times its depth: the largest
      depth ratio among the first ``contact_blocks`` valid blocks below it. A column without
      a valid block below is not counted (the image's edge, invalid pixels); NaN when no
      column is counted.
    """
    rows, cols = ds.shape
    k = 0
    for m in range(index.shape[0]):
        k = max(k, index[m] + 1)
    sums = np.zeros((k, 5))  # blocks, sum v, sum v^2, sum q, sum v q
    bottom = np.full((k, cols), -1, dtype=np.int64)
    for r in range(rows):
        v = (r + 0.5) * stride
        for col in range(cols):
            m = labels[r, col]
            if m < 0 or index[m] < 0:
                continue
            j = index[m]
            q = 1.0 / ds[r, col]
            sums[j, 0] += 1.0
            sums[j, 1] += v
            sums[j, 2] += v * v
            sums[j, 3] += q
            sums[j, 4] += v * q
            bottom[j, col] = r
    out = np.full((k, 2), np.nan)
    for m in range(index.shape[0]):
        j = index[m]
        if j < 0:
            continue
        n, sv, svv, sq, svq = sums[j, 0], sums[j, 1], sums[j, 2], sums[j, 3], sums[j, 4]
        spread = n * svv - sv * sv
        if spread > 1e-9 * n * svv:
            out[j, 0] = (n * svq - sv * sq) / spread / road_slope
        counted = 0
        touching = 0
        for col in range(cols):
            r0 = bottom[j, col]
            if r0 < 0:
                continue
            worst = -1.0
            seen = 0
            r = r0 + 1
            while r < rows and seen < contact_blocks:
                d = ds[r, col]
                if d > 0.0:
                    worst = max(worst, d / ds[r0, col])
                    seen += 1
                r += 1
            if seen > 0:
                counted += 1
                touching += worst <= contact_ratio
        if counted > 0:
            out[j, 1] = touching / counted
    return out


@kernel
def occlusion(labels, index, ds, xs, ys, zs, plane, road_q, stride, min_height, edge_ratio,
              edge_blocks):
    """Per chosen component: the share of its columns in which it hides what is behind it.

    ``labels``, ``index``, ``ds`` and ``stride`` as in :func:`surface_shape`; ``xs, ys,
    zs`` float32 (rows, cols) the blocks' ego-frame points; ``plane`` float64 (3,) the road
    ``z = a x + b y + c``; ``road_q`` float64 (3,) the road's inverse camera depth at pixel
    ``(u, v)``, ``q0 + qu u + qv v`` as ``(q0, qu, qv)`` (1 / m). Returns float64 (k, 2), k
    = ``index.max() + 1``, rows ``either, by_depth``: over the component's columns, the
    share whose top block has, among the first ``edge_blocks`` valid blocks above it, one
    that stands ``min_height`` or more above the road (something behind it, or above it) or
    one farther than ``edge_ratio`` times what the road would be there given the top
    block's depth (its depth times the road's depth ratio between the two rows; above the
    horizon, its depth); and the share with one so much farther (the depth alone). A column
    without a valid block above is not counted (the image's top edge, invalid pixels); NaN
    when no column is counted.
    """
    rows, cols = ds.shape
    k = 0
    for m in range(index.shape[0]):
        k = max(k, index[m] + 1)
    top = np.full((k, cols), -1, dtype=np.int64)
    for r in range(rows):
        for col in range(cols):
            m = labels[r, col]
            if m >= 0 and index[m] >= 0 and top[index[m], col] < 0:
                top[index[m], col] = r
    a, b, c = plane[0], plane[1], plane[2]
    q0, qu, qv = road_q[0], road_q[1], road_q[2]
    out = np.full((k, 2), np.nan)
    for j in range(k):
        counted = 0
        hiding = 0
        by_depth = 0
        for col in range(cols):
            r0 = top[j, col]
            if r0 < 0:
                continue
            u = (col + 0.5) * stride
            q_top = q0 + qu * u + qv * (r0 + 0.5) * stride
            seen = 0
            stands_behind = False
            farther = False
            r = r0 - 1
            while r >= 0 and seen < edge_blocks:
                d = ds[r, col]
                if d > 0.0:
                    seen += 1
                    if zs[r, col] - (a * xs[r, col] + b * ys[r, col] + c) >= min_height:
                        stands_behind = True
                    q = q0 + qu * u + qv * (r + 0.5) * stride
                    road_ratio = q_top / q if q > 0.0 and q_top > q else 1.0
                    if d > edge_ratio * road_ratio * ds[r0, col]:
                        farther = True
                r -= 1
            if seen > 0:
                counted += 1
                hiding += stands_behind or farther
                by_depth += farther
        if counted > 0:
            out[j, 0] = hiding / counted
            out[j, 1] = by_depth / counted
    return out


@kernel
def object_points(labels, row_of, xs, ys, zs, m, points, offsets):
    """Each object's blocks in the ego frame, object by object.

    ``labels`` int32 (rows, cols): each block's component, -1 for none; ``row_of`` int64
    (n + 1,): each component's object row, -1 for a dropped one (its last entry, for label
    -1, too); ``m`` objects. ``points`` float64 (>= member blocks, 3) gets ``x, y, z`` of
    object 0's blocks (in row-major order), then object 1's, ...; ``offsets`` int64
    (m + 1,) where each object's rows start (``offsets[m]``: their number).
    """
    rows, cols = labels.shape
    for k in range(m + 1):
        offsets[k] = 0
    for i in range(rows):
        for j in range(cols):
            r = row_of[labels[i, j]]
            if r >= 0:
                offsets[r + 1] += 1
    for k in range(m):
        offsets[k + 1] += offsets[k]
    fill = offsets[:m].copy()
    for i in range(rows):
        for j in range(cols):
            r = row_of[labels[i, j]]
            if r >= 0:
                n = fill[r]
                points[n, 0] = xs[i, j]
                points[n, 1] = ys[i, j]
                points[n, 2] = zs[i, j]
                fill[r] = n + 1
