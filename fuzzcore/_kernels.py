"""Numba kernels of the inference engine. Private: callers go through :class:`FuzzySystem`.

Kernels never validate and never raise; :mod:`fuzzcore.compiled` packs a validated system
into two flat arrays (``fblob`` float64, ``iblob`` int64) whose layout is documented there,
and :func:`unpack` turns them back into named views inside compiled code.

NaN semantics: a sample with any NaN input gets NaN for every output, decided before any
arithmetic. Infinite inputs take the membership functions' limits (trimf(+inf) = 0,
sigmf(+inf) = 1 for a > 0, ...), which MATLAB's formulas also give.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

#: fastmath flags, for the centroid's two sums only: never nnan/ninf (NaN and inf keep their
#: meaning); reassoc lets the reductions vectorise. Everything else is plain IEEE arithmetic
#: in MATLAB's operation order, because exact ties (mom, som, lom, bisector) and probor's
#: ``a + b - a*b`` must round as MATLAB's do.
FASTMATH = {"nsz", "contract", "reassoc"}

# codes (kept in step with fuzzcore.compiled)
MAMDANI, SUGENO = 0, 1
AND_MIN, AND_PROD = 0, 1
OR_MAX, OR_PROBOR = 0, 1
IMP_MIN, IMP_PROD = 0, 1
AGG_MAX, AGG_SUM, AGG_PROBOR = 0, 1, 2
D_CENTROID, D_BISECTOR, D_MOM, D_SOM, D_LOM, D_EXACT, D_WTAVER, D_WTSUM = 0, 1, 2, 3, 4, 5, 6, 7
P_MIDPOINT, P_NAN, P_VALUE = 0, 1, 2
K_CONSTANT, K_LINEAR = 20, 21

#: samples per work chunk in the parallel batch kernel (each chunk allocates its work once)
CHUNK = 256

_GAUSS = 0.5 / math.sqrt(3.0)  # 2-point Gauss-Legendre node offset, in units of the interval

_jit = dict(cache=True, nogil=True)
_jit_fast = dict(cache=True, nogil=True, fastmath=FASTMATH)


# --------------------------------------------------------------------------- memberships
@njit(**_jit)
def _sig(a, c, x):
    if a == 0.0:
        return 0.5
    return 1.0 / (1.0 + math.exp(-a * (x - c)))


@njit(**_jit)
def _smf(a, b, x):
    if a >= b:
        return 1.0 if x >= 0.5 * (a + b) else 0.0
    if x <= a:
        return 0.0
    if x >= b:
        return 1.0
    if x <= 0.5 * (a + b):
        t = (x - a) / (b - a)
        return 2.0 * t * t
    t = (b - x) / (b - a)
    return 1.0 - 2.0 * t * t


@njit(**_jit)
def _zmf(a, b, x):
    if a >= b:
        return 1.0 if x <= 0.5 * (a + b) else 0.0
    if x <= a:
        return 1.0
    if x >= b:
        return 0.0
    if x <= 0.5 * (a + b):
        t = (x - a) / (b - a)
        return 1.0 - 2.0 * t * t
    t = (b - x) / (b - a)
    return 2.0 * t * t


@njit(**_jit)
def mf(kind, p0, p1, p2, p3, x):
    """Membership of ``x`` in the term ``kind`` with parameters p0..p3 (MATLAB's formulas).

    Parameters come as scalars, not an array view: a view per call costs reference counting
    in the innermost loop. NaN in, NaN out (comparisons alone would turn it into 0 or 1).
    """
    if x != x:
        return math.nan
    if kind == 0:  # trimf
        a, b, c = p0, p1, p2
        if x == b:
            return 1.0
        if x <= a or x >= c:
            return 0.0
        if x < b:
            return (x - a) / (b - a)
        return (c - x) / (c - b)
    if kind == 1:  # trapmf
        a, b, c, d = p0, p1, p2, p3
        y1 = 1.0 if x >= b else ((x - a) / (b - a) if x >= a else 0.0)
        y2 = 1.0 if x <= c else ((d - x) / (d - c) if x <= d else 0.0)
        return min(y1, y2)
    # Gaussians and the bell in MATLAB's operation order (gaussmf.m, gauss2mf.m, gbellmf.m),
    # so results round as MATLAB's do
    if kind == 2:  # gaussmf [sigma, c]
        d = x - p1
        return math.exp(-(d * d) / (2.0 * (p0 * p0)))
    if kind == 3:  # gauss2mf [sigma1, c1, sigma2, c2]
        y = 1.0
        if x <= p1:
            d = x - p1
            y = math.exp(-(d * d) / (2.0 * (p0 * p0)))
        if x >= p3:
            d = x - p3
            y *= math.exp(-(d * d) / (2.0 * (p2 * p2)))
        return y
    if kind == 4:  # gbellmf [a, b, c]
        t = (x - p2) / p0
        return 1.0 / (1.0 + (t * t) ** p1)
    if kind == 5:  # sigmf
        return _sig(p0, p1, x)
    if kind == 6:  # dsigmf
        return abs(_sig(p0, p1, x) - _sig(p2, p3, x))
    if kind == 7:  # psigmf
        return _sig(p0, p1, x) * _sig(p2, p3, x)
    if kind == 8:
        return _smf(p0, p1, x)
    if kind == 9:
        return _zmf(p0, p1, x)
    if kind == 10:  # pimf
        return _smf(p0, p1, x) * _zmf(p2, p3, x)
    if kind == 11:  # linsmf
        if x < p0:
            return 0.0
        if x >= p1:
            return 1.0
        return (x - p0) / (p1 - p0)
    if kind == 12:  # linzmf
        if x <= p0:
            return 1.0
        if x > p1:
            return 0.0
        return (p1 - x) / (p1 - p0)
    return math.nan


@njit(**_jit)
def mf_array(kind, p, x, out):
    """``out[i] = mf(kind, *p, x[i])`` for 1-D ``x`` and ``p`` of length 4 (zero-padded)."""
    for i in range(x.shape[0]):
        out[i] = mf(kind, p[0], p[1], p[2], p[3], x[i])


# --------------------------------------------------------------------------- packing
@njit(**_jit)
def unpack(fblob, iblob):
    """Named views into the packed system (layout: :mod:`fuzzcore.compiled`)."""
    n_in, n_out, T, R, K, P, res = iblob[7], iblob[8], iblob[9], iblob[10], iblob[11], iblob[12], iblob[13]
    i = 14
    in_kind = iblob[i:i + T]; i += T
    in_var = iblob[i:i + T]; i += T
    ante = iblob[i:i + R * n_in].reshape((R, n_in)); i += R * n_in
    cons = iblob[i:i + R * n_out].reshape((R, n_out)); i += R * n_out
    rule_or = iblob[i:i + R]; i += R
    out_kind = iblob[i:i + n_out * K].reshape((n_out, K)); i += n_out * K
    support = iblob[i:i + n_out * K * 2].reshape((n_out, K, 2))
    f = 1
    in_params = fblob[f:f + T * 4].reshape((T, 4)); f += T * 4
    rule_w = fblob[f:f + R]; f += R
    out_range = fblob[f:f + n_out * 2].reshape((n_out, 2)); f += n_out * 2
    out_params = fblob[f:f + n_out * K * P].reshape((n_out, K, P)); f += n_out * K * P
    grid = fblob[f:f + n_out * res].reshape((n_out, res)); f += n_out * res
    table = fblob[f:f + n_out * K * res].reshape((n_out, K, res))
    return (in_kind, in_var, ante, cons, rule_or, out_kind,
            in_params, rule_w, out_range, out_params, grid, table, support)


@njit(**_jit)
def refresh_tables(fblob, iblob):
    """Recompute the output grids and term tables in ``fblob`` from its output parameters.

    Call after changing output ranges or parameters in place (the tuners do).
    """
    (in_kind, in_var, ante, cons, rule_or, out_kind,
     in_params, rule_w, out_range, out_params, grid, table, support) = unpack(fblob, iblob)
    res = iblob[13]
    if iblob[0] != MAMDANI or res == 0:
        return
    for o in range(grid.shape[0]):
        lo, hi = out_range[o, 0], out_range[o, 1]
        for j in range(res):  # MATLAB's linspace: lo + (j * (hi - lo)) / (res - 1), last = hi
            grid[o, j] = lo + (j * (hi - lo)) / (res - 1)
        grid[o, res - 1] = hi
        for k in range(out_kind.shape[1]):
            if out_kind[o, k] < 0:
                continue
            support[o, k, 0], support[o, k, 1] = res, 0
            for j in range(res):
                m = mf(out_kind[o, k], out_params[o, k, 0], out_params[o, k, 1],
                       out_params[o, k, 2], out_params[o, k, 3], grid[o, j])
                table[o, k, j] = m
                if m > 0.0:
                    support[o, k, 0] = min(support[o, k, 0], j)
                    support[o, k, 1] = j + 1


# --------------------------------------------------------------------------- inference
@njit(inline="always", **_jit)
def _fire(X, i, in_kind, in_var, in_params, ante, rule_or, rule_w, and_m, or_m, mu, fire):
    """Memberships of every input term (``mu``) and every rule's weighted strength (``fire``)
    for sample ``X[i]``."""
    for t in range(in_kind.shape[0]):
        mu[t] = mf(in_kind[t], in_params[t, 0], in_params[t, 1], in_params[t, 2], in_params[t, 3],
                   X[i, in_var[t]])
    for r in range(ante.shape[0]):
        is_or = rule_or[r] == 1
        f = 0.0 if is_or else 1.0
        for v in range(ante.shape[1]):
            code = ante[r, v]
            if code == 0:
                continue
            m = mu[abs(code) - 1]
            if code < 0:
                m = 1.0 - m
            if is_or:
                f = max(f, m) if or_m == OR_MAX else f + m - f * m
            else:
                f = min(f, m) if and_m == AND_MIN else f * m
        fire[r] = f * rule_w[r]


@njit(inline="always", **_jit)
def _collect_sets(o, cons, fire, agg_m, K, set_code, set_level):
    """The implied sets feeding output ``o``: (signed term code, level) pairs; returns their count.

    For max aggregation, rules sharing a consequent merge into one set at their largest
    strength (max_r imp(a_r, mu) = imp(max_r a_r, mu) for min and prod implication).
    For sum and probor aggregation every firing rule is its own set.
    """
    n = 0
    if agg_m == AGG_MAX:
        for s in range(2 * K):
            set_level[s] = 0.0
        for r in range(cons.shape[0]):
            code = cons[r, o]
            if code != 0 and fire[r] > 0.0:
                s = (abs(code) - 1) * 2 + (1 if code < 0 else 0)
                if fire[r] > set_level[s]:
                    set_level[s] = fire[r]
        for s in range(2 * K):
            if set_level[s] > 0.0:
                set_code[n] = (s // 2 + 1) * (-1 if s % 2 == 1 else 1)
                set_level[n] = set_level[s]
                n += 1
    else:
        for r in range(cons.shape[0]):
            code = cons[r, o]
            if code != 0 and fire[r] > 0.0:
                set_code[n] = code
                set_level[n] = fire[r]
                n += 1
    return n


@njit(inline="always", **_jit)
def _aggregate_grid(o, imp_m, agg_m, set_code, set_level, n_sets, table, support, agg):
    """Aggregate the implied sets of output ``o`` on its grid into ``agg`` (res,).

    A set ``imp(level, mu_k)`` is zero outside term k's support (the grid points where
    mu_k > 0), so only that stretch is visited; a NOT set (1 - mu_k) covers the whole grid.
    The branches sit outside the loops over the grid so each loop vectorises.
    """
    res = agg.shape[0]
    for j in range(res):
        agg[j] = 0.0
    for s in range(n_sets):
        code, level = set_code[s], set_level[s]
        k = abs(code) - 1
        if code < 0:
            for j in range(res):
                m = 1.0 - table[o, k, j]
                v = (level if level < m else m) if imp_m == IMP_MIN else level * m
                if agg_m == AGG_MAX:
                    agg[j] = v if v > agg[j] else agg[j]
                else:
                    agg[j] = agg[j] + v if agg_m == AGG_SUM else agg[j] + v - agg[j] * v
            continue
        row = table[o, k]
        j0, j1 = support[o, k, 0], support[o, k, 1]
        if agg_m == AGG_MAX and imp_m == IMP_MIN:
            for j in range(j0, j1):
                m = row[j]
                v = level if level < m else m
                agg[j] = v if v > agg[j] else agg[j]
        elif agg_m == AGG_MAX:
            for j in range(j0, j1):
                v = level * row[j]
                agg[j] = v if v > agg[j] else agg[j]
        else:
            for j in range(j0, j1):
                m = row[j]
                v = (level if level < m else m) if imp_m == IMP_MIN else level * m
                agg[j] = agg[j] + v if agg_m == AGG_SUM else agg[j] + v - agg[j] * v


@njit(**_jit_fast)
def _centroid_sums(y, agg):
    """(sum(y * agg), sum(agg)), vectorised (fastmath; not inlined, so the flags stay here)."""
    num, total = 0.0, 0.0
    for j in range(y.shape[0]):
        total += agg[j]
        num += y[j] * agg[j]
    return num, total


@njit(**_jit)
def _bisector(y, agg):
    """The first grid point where the running sum of ``agg`` reaches half its total.

    Both sums run strictly in order, as in MATLAB's loop, so exact ties resolve as MATLAB's
    do. Overwrites ``agg``.
    """
    for j in range(1, y.shape[0]):
        agg[j] += agg[j - 1]
    half = 0.5 * agg[y.shape[0] - 1]
    for j in range(y.shape[0]):
        if agg[j] >= half:
            return y[j]
    return y[y.shape[0] - 1]


@njit(inline="always", **_jit)
def _defuzz_grid(method, grid, o, agg):
    """MATLAB's discrete defuzzifiers of ``agg`` on ``grid[o]``; NaN when the set is empty."""
    y = grid[o]
    if method == D_CENTROID:
        num, total = _centroid_sums(y, agg)
        return num / total if total > 0.0 else math.nan
    total = 0.0
    for j in range(y.shape[0]):
        total += agg[j]
    if not total > 0.0:
        return math.nan
    if method == D_BISECTOR:
        return _bisector(y, agg)
    top = agg[0]
    for j in range(y.shape[0]):
        top = max(top, agg[j])
    if method == D_MOM:
        s, n = 0.0, 0
        for j in range(y.shape[0]):
            if agg[j] == top:
                s += y[j]
                n += 1
        return s / n
    best = math.nan  # som: smallest |y| among maxima; lom: largest |y| (MATLAB; first on ties)
    for j in range(y.shape[0]):
        if agg[j] == top:
            if best != best:
                best = y[j]
            elif method == D_SOM and abs(y[j]) < abs(best):
                best = y[j]
            elif method == D_LOM and abs(y[j]) > abs(best):
                best = y[j]
    return best


@njit(**_jit)
def _set_at(yv, s, o, imp_m, set_code, set_level, out_kind, out_params):
    code = set_code[s]
    k = abs(code) - 1
    m = mf(out_kind[o, k], out_params[o, k, 0], out_params[o, k, 1], out_params[o, k, 2],
           out_params[o, k, 3], yv)
    if code < 0:
        m = 1.0 - m
    return min(set_level[s], m) if imp_m == IMP_MIN else set_level[s] * m


@njit(**_jit)
def _agg_at(yv, o, imp_m, agg_m, set_code, set_level, n_sets, out_kind, out_params):
    acc = 0.0
    for s in range(n_sets):
        v = _set_at(yv, s, o, imp_m, set_code, set_level, out_kind, out_params)
        acc = max(acc, v) if agg_m == AGG_MAX else acc + v
    return acc


@njit(**_jit)
def _exact_centroid(o, lo, hi, imp_m, agg_m, set_code, set_level, n_sets, out_kind, out_params, pts, sub):
    """Exact centroid of a piecewise-linear aggregated set on [lo, hi].

    Breakpoints: the terms' vertices, where each slope meets its clip level, and (for max
    aggregation) where two implied sets cross. Between breakpoints the aggregate is linear,
    so 2-point Gauss-Legendre integrates both f and y*f exactly, and never evaluates on a
    breakpoint (where a vertical edge would make the value ambiguous).
    """
    n = 0
    pts[n] = lo; n += 1
    pts[n] = hi; n += 1
    for s in range(n_sets):
        code = set_code[s]
        k = abs(code) - 1
        kind = out_kind[o, k]
        p = out_params[o, k, :4]
        nv = 3 if kind == 0 else (4 if kind == 1 else 2)
        level = set_level[s] if code > 0 else 1.0 - set_level[s]
        for v in range(nv):
            pts[n] = p[v]; n += 1
        if kind == 0:
            pts[n] = p[0] + level * (p[1] - p[0]); n += 1
            pts[n] = p[2] - level * (p[2] - p[1]); n += 1
        elif kind == 1:
            pts[n] = p[0] + level * (p[1] - p[0]); n += 1
            pts[n] = p[3] - level * (p[3] - p[2]); n += 1
        elif kind == 11:
            pts[n] = p[0] + level * (p[1] - p[0]); n += 1
        else:
            pts[n] = p[1] - level * (p[1] - p[0]); n += 1
    cand = np.sort(pts[:n])
    num, den = 0.0, 0.0
    prev = lo
    for c in range(n):
        q = min(cand[c], hi)
        if not q > prev:
            continue
        m = 1
        sub[0] = prev
        if agg_m == AGG_MAX:  # crossings of two sets inside (prev, q)
            h = q - prev
            ya, yb = prev + (0.5 - _GAUSS) * h, prev + (0.5 + _GAUSS) * h
            for s1 in range(n_sets):
                for s2 in range(s1 + 1, n_sets):
                    da = (_set_at(ya, s1, o, imp_m, set_code, set_level, out_kind, out_params)
                          - _set_at(ya, s2, o, imp_m, set_code, set_level, out_kind, out_params))
                    db = (_set_at(yb, s1, o, imp_m, set_code, set_level, out_kind, out_params)
                          - _set_at(yb, s2, o, imp_m, set_code, set_level, out_kind, out_params))
                    slope = (db - da) / (yb - ya)
                    d0 = da - slope * (ya - prev)
                    d1 = db + slope * (q - yb)
                    if (d0 > 0.0 and d1 < 0.0) or (d0 < 0.0 and d1 > 0.0):
                        sub[m] = prev + h * d0 / (d0 - d1)
                        m += 1
        sub[m] = q
        m += 1
        sub[:m].sort()
        for u in range(m - 1):
            a, b = sub[u], sub[u + 1]
            h = b - a
            if not h > 0.0:
                continue
            y1, y2 = a + (0.5 - _GAUSS) * h, a + (0.5 + _GAUSS) * h
            f1 = _agg_at(y1, o, imp_m, agg_m, set_code, set_level, n_sets, out_kind, out_params)
            f2 = _agg_at(y2, o, imp_m, agg_m, set_code, set_level, n_sets, out_kind, out_params)
            den += 0.5 * h * (f1 + f2)
            num += 0.5 * h * (y1 * f1 + y2 * f2)
        prev = q
    if not den > 0.0:
        return math.nan
    return num / den


@njit(inline="always", **_jit)
def _sugeno(o, X, i, cons, fire, out_kind, out_params, defuzz_m):
    num, den = 0.0, 0.0
    n_in = X.shape[1]
    for r in range(cons.shape[0]):
        code = cons[r, o]
        if code == 0 or fire[r] == 0.0:
            continue
        k = code - 1
        if out_kind[o, k] == K_LINEAR:
            z = out_params[o, k, n_in]
            for v in range(n_in):
                z += out_params[o, k, v] * X[i, v]
        else:
            z = out_params[o, k, 0]
        num += fire[r] * z
        den += fire[r]
    if not den > 0.0:
        return math.nan
    return num / den if defuzz_m == D_WTAVER else num


@njit(**_jit)
def _scratch(iblob):
    T, R, K, res, n_out = iblob[9], iblob[10], iblob[11], iblob[13], iblob[8]
    n_sets = max(2 * K, R)
    n_pts = 2 + 6 * n_sets
    n_sub = n_sets * (n_sets - 1) // 2 + 2
    work = np.empty(T + R + n_sets + max(res, 1) + n_pts + n_sub + n_out)
    set_code = np.empty(n_sets, dtype=np.int64)
    i = 0
    mu = work[i:i + T]; i += T
    fire = work[i:i + R]; i += R
    set_level = work[i:i + n_sets]; i += n_sets
    agg = work[i:i + max(res, 1)]; i += max(res, 1)
    pts = work[i:i + n_pts]; i += n_pts
    sub = work[i:i + n_sub]; i += n_sub
    out = work[i:i + n_out]
    return mu, fire, set_code, set_level, agg, pts, sub, out


@njit(inline="always", **_jit)
def infer_sample(X, i, fblob, iblob, views, mu, fire, set_code, set_level, agg, pts, sub, out):
    """Evaluate sample ``X[i]`` (X: (n, n_in)) into ``out[i]`` (out: (n, n_out)).

    ``mu`` .. ``sub`` are scratch space from :func:`_scratch`.
    """
    (in_kind, in_var, ante, cons, rule_or, out_kind,
     in_params, rule_w, out_range, out_params, grid, table, support) = views
    n_out = out.shape[1]
    for v in range(X.shape[1]):
        if X[i, v] != X[i, v]:
            for o in range(n_out):
                out[i, o] = math.nan
            return
    system, and_m, or_m, imp_m, agg_m, defuzz_m, policy = (
        iblob[0], iblob[1], iblob[2], iblob[3], iblob[4], iblob[5], iblob[6])
    _fire(X, i, in_kind, in_var, in_params, ante, rule_or, rule_w, and_m, or_m, mu, fire)
    K = out_kind.shape[1]
    for o in range(n_out):
        if system == SUGENO:
            y = _sugeno(o, X, i, cons, fire, out_kind, out_params, defuzz_m)
        else:
            n_sets = _collect_sets(o, cons, fire, agg_m, K, set_code, set_level)
            if n_sets == 0:
                y = math.nan
            elif defuzz_m == D_EXACT:
                y = _exact_centroid(o, out_range[o, 0], out_range[o, 1], imp_m, agg_m, set_code,
                                    set_level, n_sets, out_kind, out_params, pts, sub)
            else:
                _aggregate_grid(o, imp_m, agg_m, set_code, set_level, n_sets, table, support, agg)
                y = _defuzz_grid(defuzz_m, grid, o, agg)
        if y != y:  # nothing fired (the input was not NaN): the declared policy
            if policy == P_MIDPOINT:
                y = 0.5 * (out_range[o, 0] + out_range[o, 1])
            elif policy == P_VALUE:
                y = fblob[0]
        out[i, o] = y


# --------------------------------------------------------------------------- entry points
@njit(**_jit)
def infer_one(xs, fblob, iblob):
    """One sample given as a tuple of floats; returns the first output (single-output fast path)."""
    views = unpack(fblob, iblob)
    mu, fire, set_code, set_level, agg, pts, sub, out = _scratch(iblob)
    X = np.empty((1, len(xs)))
    for v in range(len(xs)):
        X[0, v] = xs[v]
    out2 = out.reshape((1, out.shape[0]))
    infer_sample(X, 0, fblob, iblob, views, mu, fire, set_code, set_level, agg, pts, sub, out2)
    return out2[0, 0]


@njit(parallel=True, **_jit)
def evaluate_batch(X, fblob, iblob, out):
    """``out[i] = system(X[i])`` for X (n, n_in) and out (n, n_out), parallel over chunks of samples."""
    n = X.shape[0]
    views = unpack(fblob, iblob)
    n_chunks = (n + CHUNK - 1) // CHUNK
    for c in prange(n_chunks):
        mu, fire, set_code, set_level, agg, pts, sub, _ = _scratch(iblob)
        for i in range(c * CHUNK, min(n, (c + 1) * CHUNK)):
            infer_sample(X, i, fblob, iblob, views, mu, fire, set_code, set_level, agg, pts, sub, out)


@njit(**_jit)
def evaluate_serial(X, fblob, iblob, out):
    """As :func:`evaluate_batch`, on the calling thread only (small batches, no thread start-up)."""
    views = unpack(fblob, iblob)
    mu, fire, set_code, set_level, agg, pts, sub, _ = _scratch(iblob)
    for i in range(X.shape[0]):
        infer_sample(X, i, fblob, iblob, views, mu, fire, set_code, set_level, agg, pts, sub, out)


@njit(**_jit)
def explain_one(X, fblob, iblob, mu_out, fire_out, agg_out, out):
    """One sample ``X`` (1, n_in) with its intermediate results.

    Fills ``mu_out`` (T,) input-term memberships, ``fire_out`` (R,) weighted firing
    strengths, ``agg_out`` (n_out, res) the aggregated output sets on the grid (Mamdani;
    left as given for a NaN input), and ``out`` (1, n_out) the outputs.
    """
    views = unpack(fblob, iblob)
    mu, fire, set_code, set_level, agg, pts, sub, _ = _scratch(iblob)
    mu[:] = math.nan
    fire[:] = math.nan
    infer_sample(X, 0, fblob, iblob, views, mu, fire, set_code, set_level, agg, pts, sub, out)
    mu_out[:] = mu
    fire_out[:] = fire
    if iblob[0] == MAMDANI and not np.isnan(X).any():
        for o in range(agg_out.shape[0]):
            n_sets = _collect_sets(o, views[3], fire, iblob[4], views[5].shape[1], set_code, set_level)
            _aggregate_grid(o, iblob[3], iblob[4], set_code, set_level, n_sets, views[11], views[12],
                            agg_out[o])
