"""Numba kernels of the inference engine. Private: callers go through :class:`FuzzySystem`.

Kernels never validate and never raise. :mod:`fuzzcore.compiled` packs a validated system
into two flat arrays (``fblob`` float64, ``iblob`` int64) whose layout is documented there;
kernels index them at the offsets in ``iblob``'s header (the names below), never through
views: making a view costs reference counting, which a scalar call cannot afford.

Samples are evaluated in blocks of up to ``BLOCK``, one lane per sample: every intermediate
result (memberships, rule strengths, aggregated sets, ...) is a row of lanes in one work
array, so each step is a loop over the lanes that the compiler vectorises, and every sample
still sees exactly the operations, in exactly the order, it would see alone. A block of one
sample is the scalar path. The aggregation and centroid have two loop orders: over the lanes
grid point by grid point (:func:`_centroid_lanes`, blocks of LANES_MIN samples or more) and
over the grid for one sample (:func:`_aggregate_sample`); both apply the same operations in
the same order to each sample and give the same bits (the tests check batch against one by
one). Lane loops index with unsigned integers: a signed index carries a negative-index
check that stops vectorisation.

NaN semantics: a sample with any NaN input gets NaN for every output. Infinite inputs take
the membership functions' limits (trimf(+inf) = 0, sigmf(+inf) = 1 for a > 0, ...), which
MATLAB's formulas also give.

Arithmetic: plain IEEE, no fastmath anywhere, in MATLAB's operation order: exact ties (mom,
som, lom, bisector) and probor's ``a + b - a*b`` must round as MATLAB's do, and a result must
not depend on how the compiler reorders a sum (with ``reassoc`` the centroid differed between
a freshly compiled and a cached kernel). The centroid's two sums run over the grid in order,
as MATLAB's do, on every path and every CPU: this reproduces MATLAB's reference outputs
(../shared/conformance) bit for bit four times in ten, the rest within a few ulps, against
one time in seven with vectorised, reordered sums.

Every membership, rule strength and aggregated value is >= +0.0 (or NaN, for a NaN input):
the kernels rely on it where they write ``max``/``min`` updates as ``... + 0.0`` (see
:func:`_keep`).

No rule fired, and other NaNs: the ``no_rule_fired`` policy answers only where an output's
set is empty (Mamdani: nothing aggregated on the grid; Sugeno: total weight 0), which the
defuzzifiers see directly (:func:`_mamdani`, :func:`_sugeno`). Any other NaN propagates: a
NaN membership gives a NaN rule strength (:func:`_and`, :func:`_or`), a NaN strength makes
every output its rule concludes NaN, a Sugeno rule output that is NaN (``0 * inf``) gives a
NaN output (:func:`_infer`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from .jit import kernel

# codes (kept in step with fuzzcore.compiled and fuzzcore.membership)
MAMDANI, SUGENO = 0, 1
AND_MIN, AND_PROD = 0, 1
OR_MAX, OR_PROBOR = 0, 1
IMP_MIN, IMP_PROD = 0, 1
AGG_MAX, AGG_SUM, AGG_PROBOR = 0, 1, 2
D_CENTROID, D_BISECTOR, D_MOM, D_SOM, D_LOM, D_EXACT, D_WTAVER, D_WTSUM = 0, 1, 2, 3, 4, 5, 6, 7
P_MIDPOINT, P_NAN, P_VALUE = 0, 1, 2
K_TRIMF, K_TRAPMF, K_CONSTANT, K_LINEAR = 0, 1, 20, 21

# iblob header (written by fuzzcore.compiled.pack): settings and sizes; where each part
# starts in iblob (I_) and in fblob (F_); the work array's lane rows (R_, in rows of B lanes;
# the inputs are rows 0 .. n_in-1) and, after N_ROWS * B lanes, its per-sample scratch (T_).
(SYSTEM, AND, OR, IMP, AGG, DEFUZZ, POLICY, N_IN, N_OUT, N_TERMS, N_RULES, N_K, N_P, RES,
 I_IN_KIND, I_IN_VAR, I_ANTE, I_CONS, I_RULE_OR, I_OUT_KIND, I_SUPPORT,
 F_IN_PARAMS, F_RULE_W, F_OUT_RANGE, F_OUT_PARAMS, F_GRID, F_TABLE,
 R_MU, R_FIRE, R_LEVEL, R_ROW, R_NUM, R_DEN, R_Y, N_ROWS,
 T_SET_ROW, T_SET_CODE, T_SET_J0, T_SET_J1, T_AGG, T_CODE, T_LEVEL, T_PTS, T_SUB, N_TAIL) = range(45)
HEADER = 45

#: samples per block (lanes of the work rows); a block's rows stay in the L1 cache
BLOCK = 128
#: blocks of fewer samples take the centroid one sample at a time (see _mamdani)
LANES_MIN = 8
#: samples per work chunk of the parallel batch kernel (each chunk allocates its work once)
CHUNK = 4 * BLOCK

_GAUSS = 0.5 / math.sqrt(3.0)  # 2-point Gauss-Legendre node offset, in units of the interval

_OFF = (np.uint64(0), np.uint64(1))  # unsigned constants: an index stays unsigned


# --------------------------------------------------------------------------- memberships
@kernel(inline=True)
def _trimf(a, b, c, x):
    # both slopes first, then a choice without branches, so a loop over lanes vectorises;
    # the value chosen is the one trimf.m computes (a slope with a zero width is never chosen)
    rise = (x - a) / (b - a)
    fall = (c - x) / (c - b)
    y = rise if x < b else fall
    y = 0.0 if (x <= a) | (x >= c) else y
    return 1.0 if x == b else y


@kernel(inline=True)
def _trapmf(a, b, c, d, x):
    rise = (x - a) / (b - a)  # as in _trimf: computed first, chosen without branches
    fall = (d - x) / (d - c)
    y1 = 1.0 if x >= b else (rise if x >= a else 0.0)
    y2 = 1.0 if x <= c else (fall if x <= d else 0.0)
    return min(y1, y2)


@kernel
def _sig(a, c, x):
    if a == 0.0:
        return 0.5
    return 1.0 / (1.0 + math.exp(-a * (x - c)))


@kernel
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


@kernel
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


@kernel
def mf(kind, p0, p1, p2, p3, x):
    """Membership of ``x`` in the term ``kind`` with parameters p0..p3 (MATLAB's formulas).

    Parameters come as scalars, not an array view: a view per call costs reference counting
    in the innermost loop. NaN in, NaN out (comparisons alone would turn it into 0 or 1).
    """
    if x != x:
        return math.nan
    if kind == K_TRIMF:
        return _trimf(p0, p1, p2, x)
    if kind == K_TRAPMF:
        return _trapmf(p0, p1, p2, p3, x)
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


@kernel
def mf_array(kind, p, x, out):
    """``out[i] = mf(kind, *p, x[i])`` for 1-D ``x`` and ``p`` of length 4 (zero-padded)."""
    for i in range(x.shape[0]):
        out[i] = mf(kind, p[0], p[1], p[2], p[3], x[i])


# --------------------------------------------------------------------------- packed tables
@kernel
def refresh_tables(fblob, iblob):
    """Recompute the output grids, term tables and term supports from the output parameters.

    Call after changing output ranges or parameters in place (the tuners do).
    """
    res, n_out, K, P = iblob[RES], iblob[N_OUT], iblob[N_K], iblob[N_P]
    if iblob[SYSTEM] != MAMDANI or res == 0:
        return
    for o in range(n_out):
        lo, hi = fblob[iblob[F_OUT_RANGE] + 2 * o], fblob[iblob[F_OUT_RANGE] + 2 * o + 1]
        g = iblob[F_GRID] + o * res
        for j in range(res):  # MATLAB's linspace: lo + (j * (hi - lo)) / (res - 1), last = hi
            fblob[g + j] = lo + (j * (hi - lo)) / (res - 1)
        fblob[g + res - 1] = hi
        for k in range(K):
            kind = iblob[iblob[I_OUT_KIND] + o * K + k]
            if kind < 0:
                continue
            p = iblob[F_OUT_PARAMS] + (o * K + k) * P
            row = iblob[F_TABLE] + (o * K + k) * res
            s = iblob[I_SUPPORT] + 2 * (o * K + k)
            iblob[s], iblob[s + 1] = res, 0
            for j in range(res):
                m = mf(kind, fblob[p], fblob[p + 1], fblob[p + 2], fblob[p + 3], fblob[g + j])
                fblob[row + j] = m
                if m > 0.0:
                    iblob[s] = min(iblob[s], j)
                    iblob[s + 1] = j + 1


# --------------------------------------------------------------------------- lane steps
@kernel(inline=True)
def _and(a, b):
    """``min(a, b)``, NaN if either is NaN (the builtin ``min`` drops a NaN second argument)."""
    return a if a != a else (a if a < b else b)


@kernel(inline=True)
def _or(a, b):
    """``max(a, b)``, NaN if either is NaN."""
    return a if a != a else (a if a > b else b)


@kernel(inline=True)
def _keep(v):
    """``v + 0.0`` for a ``max``/``min`` update ``w[i] = keep(op(w[i], x))``.

    The same value for every v the kernels store (never -0.0, see the module notes), but the
    store no longer reads "keep the old value unless ...", which the compiler turns into a
    masked store (slow on AMD CPUs) instead of a vector max and a plain store.
    """
    return v + 0.0


@kernel
def _memberships(w, fblob, iblob, m, B):
    """Row R_MU + t = membership of the input lanes in input term t."""
    m, B = np.uint64(m), np.uint64(B)
    kinds, var, par = iblob[I_IN_KIND], iblob[I_IN_VAR], iblob[F_IN_PARAMS]
    for t in range(iblob[N_TERMS]):
        kind = iblob[kinds + t]
        p = par + 4 * t
        p0, p1, p2, p3 = fblob[p], fblob[p + 1], fblob[p + 2], fblob[p + 3]
        src = np.uint64(iblob[var + t]) * B
        dst = np.uint64(iblob[R_MU] + t) * B
        if kind == K_TRIMF:  # the common kinds get a loop of their own, which vectorises
            for s in range(m):
                w[dst + s] = _trimf(p0, p1, p2, w[src + s])
        elif kind == K_TRAPMF:
            for s in range(m):
                w[dst + s] = _trapmf(p0, p1, p2, p3, w[src + s])
        else:
            for s in range(m):
                w[dst + s] = mf(kind, p0, p1, p2, p3, w[src + s])


@kernel
def _fire(w, fblob, iblob, m, B):
    """Row R_FIRE + r = weighted firing strength of rule r."""
    m, B = np.uint64(m), np.uint64(B)
    n_in, and_m, or_m = iblob[N_IN], iblob[AND], iblob[OR]
    ante, rule_w = iblob[I_ANTE], iblob[F_RULE_W]
    for r in range(iblob[N_RULES]):
        is_or = iblob[iblob[I_RULE_OR] + r] == 1
        dst = np.uint64(iblob[R_FIRE] + r) * B
        start = 0.0 if is_or else 1.0
        for s in range(m):
            w[dst + s] = start
        for v in range(n_in):
            code = iblob[ante + r * n_in + v]
            if code == 0:
                continue
            src = np.uint64(iblob[R_MU] + abs(code) - 1) * B
            for s in range(m):
                x = w[src + s]
                if code < 0:
                    x = 1.0 - x
                f = w[dst + s]
                if is_or:
                    f = _or(f, x) if or_m == OR_MAX else f + x - f * x
                else:
                    f = _and(f, x) if and_m == AND_MIN else f * x
                w[dst + s] = _keep(f)
        weight = fblob[rule_w + r]
        for s in range(m):
            w[dst + s] = w[dst + s] * weight


@kernel
def _active_sets(w, iblob, o, m, B):
    """List the implied sets of output ``o`` that some lane fires; returns their count.

    Max aggregation: rules sharing a consequent merge into one set at their largest strength
    (max_r imp(a_r, mu) = imp(max_r a_r, mu) for min and prod implication), one per (term,
    NOT) slot, in rows R_LEVEL. Sum and probor aggregation: every rule is its own set (rows
    R_FIRE), in rule order. Each listed set gets its level row, signed term code and the grid
    stretch it can be nonzero on: the term's support, or the whole grid for a NOT set.
    """
    m, B = np.uint64(m), np.uint64(B)
    R, n_out, K, res = iblob[N_RULES], iblob[N_OUT], iblob[N_K], iblob[RES]
    cons = iblob[I_CONS]
    tail = np.uint64(iblob[N_ROWS]) * B
    n = np.int64(0)  # not a literal 0: the callers pass n on, and Numba would compile a version for 0
    if iblob[AGG] == AGG_MAX:
        for slot in range(2 * K):
            dst = np.uint64(iblob[R_LEVEL] + slot) * B
            for s in range(m):
                w[dst + s] = 0.0
        for r in range(R):
            code = iblob[cons + r * n_out + o]
            if code == 0:
                continue
            src = np.uint64(iblob[R_FIRE] + r) * B
            dst = np.uint64(iblob[R_LEVEL] + (abs(code) - 1) * 2 + (1 if code < 0 else 0)) * B
            for s in range(m):
                f, level = w[src + s], w[dst + s]
                w[dst + s] = _keep(f if f > level else level)
    for q in range(2 * K if iblob[AGG] == AGG_MAX else R):
        if iblob[AGG] == AGG_MAX:
            row = iblob[R_LEVEL] + q
            code = (q // 2 + 1) * (-1 if q % 2 == 1 else 1)
        else:
            row = iblob[R_FIRE] + q
            code = iblob[cons + q * n_out + o]
        if code == 0:
            continue
        fired = 0
        src = np.uint64(row) * B
        for s in range(m):
            if w[src + s] > 0.0:
                fired += 1
        if fired == 0:
            continue
        support = iblob[I_SUPPORT] + 2 * (o * K + abs(code) - 1)
        w[tail + np.uint64(iblob[T_SET_ROW] + n)] = row
        w[tail + np.uint64(iblob[T_SET_CODE] + n)] = code
        w[tail + np.uint64(iblob[T_SET_J0] + n)] = 0 if code < 0 else iblob[support]
        w[tail + np.uint64(iblob[T_SET_J1] + n)] = res if code < 0 else iblob[support + 1]
        n += 1
    return n


@kernel(inline=True)
def _aggregate(a, v, agg_m):
    """Aggregate the implied value ``v`` into ``a`` (MATLAB's max, sum or probor)."""
    if agg_m == AGG_MAX:
        return v if v > a else a
    return a + v if agg_m == AGG_SUM else a + v - a * v


@kernel(inline=True)
def _implied(level, mu, imp_m):
    """MATLAB's implication of a set's level on a membership value: min or prod."""
    return (level if level < mu else mu) if imp_m == IMP_MIN else level * mu


@kernel
def _centroid_lanes(w, fblob, iblob, o, n_sets, m, B, imp_m, agg_m):
    """Rows R_Y + o = centroid of output ``o``'s aggregated set, every lane of the block.

    Grid point by grid point: the sets reaching ``j`` are aggregated over the lanes, in list
    order onto 0, and the result ``a`` is added to the sums: ``den += a``, ``num += y_j a``
    (the last set adds instead of storing). A grid point no set reaches would add exact
    zeros: it is skipped. :func:`_centroid_sample` gives the same bits one sample at a time.
    ``imp_m`` and ``agg_m`` come as literal constants for the usual methods, so that version
    compiles with lane loops free of branches.
    """
    res, K = iblob[RES], iblob[N_K]
    tail = np.uint64(iblob[N_ROWS]) * B
    set_row, set_code = tail + np.uint64(iblob[T_SET_ROW]), tail + np.uint64(iblob[T_SET_CODE])
    set_j0, set_j1 = tail + np.uint64(iblob[T_SET_J0]), tail + np.uint64(iblob[T_SET_J1])
    row = np.uint64(iblob[R_ROW]) * B
    den, num = np.uint64(iblob[R_DEN]) * B, np.uint64(iblob[R_NUM]) * B
    for s in range(m):
        w[den + s] = 0.0
        w[num + s] = 0.0
    table, grid = iblob[F_TABLE] + o * K * res, iblob[F_GRID] + o * res
    for j in range(res):
        n_here = 0
        for q in range(np.uint64(n_sets)):
            if w[set_j0 + q] <= j < w[set_j1 + q]:
                n_here += 1
        if n_here == 0:
            continue
        yj = fblob[grid + j]
        n = 0
        for q in range(np.uint64(n_sets)):
            if not w[set_j0 + q] <= j < w[set_j1 + q]:
                continue
            code = int(w[set_code + q])
            mu = fblob[table + (abs(code) - 1) * res + j]
            if code < 0:
                mu = 1.0 - mu
            src = np.uint64(int(w[set_row + q])) * B
            if n == n_here - 1 and n == 0:  # the only set: straight into the sums
                for s in range(m):
                    a = _aggregate(0.0, _implied(w[src + s], mu, imp_m), agg_m)
                    w[den + s] = w[den + s] + a
                    w[num + s] = w[num + s] + yj * a
            elif n == n_here - 1:  # the last set: into the sums
                for s in range(m):
                    a = _aggregate(w[row + s], _implied(w[src + s], mu, imp_m), agg_m)
                    w[den + s] = w[den + s] + a
                    w[num + s] = w[num + s] + yj * a
            elif n == 0:  # the first set, onto 0
                for s in range(m):
                    w[row + s] = _aggregate(0.0, _implied(w[src + s], mu, imp_m), agg_m)
            else:
                for s in range(m):
                    w[row + s] = _keep(_aggregate(w[row + s], _implied(w[src + s], mu, imp_m), agg_m))
            n += 1
    y = np.uint64(iblob[R_Y] + o) * B
    for s in range(m):
        w[y + s] = w[num + s] / w[den + s] if w[den + s] > 0.0 else math.nan


@kernel
def _aggregate_sample(w, fblob, iblob, o, n_sets, s, B, imp_m, agg_m):
    """Output ``o``'s aggregated set of lane ``s`` on the whole grid, into the sample's
    scratch at T_AGG (res floats): the sets in list order onto 0, each over its stretch only
    (it is 0 elsewhere), a set this lane does not fire skipped (it would aggregate exact
    zeros). Vectorised over the grid; ``imp_m``, ``agg_m`` as in :func:`_centroid_lanes`.
    Returns ``(lo, hi)``: the set is 0 outside grid points lo .. hi - 1 (lo = res, hi = 0
    when no set fires).
    """
    B = np.uint64(B)
    res, K = iblob[RES], iblob[N_K]
    tail = np.uint64(iblob[N_ROWS]) * B
    agg = tail + np.uint64(iblob[T_AGG])
    for j in range(np.uint64(res)):
        w[agg + j] = 0.0
    lo, hi = np.uint64(res), _OFF[0]
    for q in range(np.uint64(n_sets)):
        level = w[np.uint64(int(w[tail + np.uint64(iblob[T_SET_ROW]) + q])) * B + s]
        if not level > 0.0:
            continue
        code = int(w[tail + np.uint64(iblob[T_SET_CODE]) + q])
        j0 = np.uint64(int(w[tail + np.uint64(iblob[T_SET_J0]) + q]))
        j1 = np.uint64(int(w[tail + np.uint64(iblob[T_SET_J1]) + q]))
        lo, hi = min(lo, j0), max(hi, j1)
        table = np.uint64(iblob[F_TABLE] + (o * K + abs(code) - 1) * res)
        if code < 0:
            for j in range(j0, j1):
                v = _implied(level, 1.0 - fblob[table + j], imp_m)
                w[agg + j] = _keep(_aggregate(w[agg + j], v, agg_m))
        else:
            for j in range(j0, j1):
                v = _implied(level, fblob[table + j], imp_m)
                w[agg + j] = _keep(_aggregate(w[agg + j], v, agg_m))
    return lo, hi


@kernel
def _centroid_sample(w, fblob, iblob, o, agg, lo, hi):
    """Centroid of one sample's aggregated set ``w[agg: agg + res]``, which is 0 outside grid
    points lo .. hi - 1: the sums of :func:`_centroid_lanes`, in the same order, so the same
    bits (the zeros left out would add exact zeros). NaN when the set is empty."""
    y = np.uint64(iblob[F_GRID] + o * iblob[RES])
    num, den = 0.0, 0.0
    for j in range(lo, hi):
        a = w[agg + j]
        den += a
        num += fblob[y + j] * a
    return num / den if den > 0.0 else math.nan


@kernel
def _grid_scan(w, fblob, iblob, o, agg):
    """MATLAB's discrete bisector, mom, som or lom of one sample's aggregated set
    ``w[agg: agg + res]`` on output ``o``'s grid; NaN when the set is empty. The bisector
    overwrites the set with its running sums.
    """
    method, n = iblob[DEFUZZ], iblob[RES]
    y = iblob[F_GRID] + o * n
    total = 0.0
    for j in range(n):
        total += w[agg + j]
    if not total > 0.0:
        return math.nan
    if method == D_BISECTOR:
        # the first grid point where the running sum reaches half the total; both sums run
        # strictly in order, as in MATLAB's loop, so exact ties resolve as MATLAB's do
        for j in range(1, n):
            w[agg + j] += w[agg + j - 1]
        half = 0.5 * w[agg + n - 1]
        for j in range(n):
            if w[agg + j] >= half:
                return fblob[y + j]
        return fblob[y + n - 1]
    top = w[agg]
    for j in range(n):
        top = max(top, w[agg + j])
    if method == D_MOM:
        total, count = 0.0, 0
        for j in range(n):
            if w[agg + j] == top:
                total += fblob[y + j]
                count += 1
        return total / count
    best = math.nan  # som: smallest |y| among maxima; lom: largest |y| (MATLAB; first on ties)
    for j in range(n):
        if w[agg + j] == top:
            yj = fblob[y + j]
            if best != best:
                best = yj
            elif method == D_SOM and abs(yj) < abs(best):
                best = yj
            elif method == D_LOM and abs(yj) > abs(best):
                best = yj
    return best


@kernel
def _set_at(w, fblob, iblob, o, t, q, yv):
    """Value at ``yv`` of implied set ``q`` of one sample (scratch lists at ``t``)."""
    code, level = int(w[t + iblob[T_CODE] + q]), w[t + iblob[T_LEVEL] + q]
    k = o * iblob[N_K] + abs(code) - 1
    p = iblob[F_OUT_PARAMS] + k * iblob[N_P]
    m = mf(iblob[iblob[I_OUT_KIND] + k], fblob[p], fblob[p + 1], fblob[p + 2], fblob[p + 3], yv)
    if code < 0:
        m = 1.0 - m
    return min(level, m) if iblob[IMP] == IMP_MIN else level * m


@kernel
def _agg_at(w, fblob, iblob, o, t, n_sets, yv):
    acc = 0.0
    for q in range(n_sets):
        v = _set_at(w, fblob, iblob, o, t, q, yv)
        acc = max(acc, v) if iblob[AGG] == AGG_MAX else acc + v
    return acc


@kernel
def _exact_centroid(w, fblob, iblob, o, t, n_sets):
    """Exact centroid of a piecewise-linear aggregated set on output ``o``'s range, for one
    sample whose implied sets are listed at ``w[t + T_CODE]`` / ``w[t + T_LEVEL]``.

    Breakpoints: the terms' vertices, where each slope meets its clip level, and (for max
    aggregation) where two implied sets cross. Between breakpoints the aggregate is linear,
    so 2-point Gauss-Legendre integrates both f and y*f exactly, and never evaluates on a
    breakpoint (where a vertical edge would make the value ambiguous).
    """
    lo, hi = fblob[iblob[F_OUT_RANGE] + 2 * o], fblob[iblob[F_OUT_RANGE] + 2 * o + 1]
    pts, sub = t + iblob[T_PTS], t + iblob[T_SUB]
    n = 0
    w[pts + n] = lo; n += 1
    w[pts + n] = hi; n += 1
    for q in range(n_sets):
        code = int(w[t + iblob[T_CODE] + q])
        k = o * iblob[N_K] + abs(code) - 1
        kind = iblob[iblob[I_OUT_KIND] + k]
        p = iblob[F_OUT_PARAMS] + k * iblob[N_P]
        p0, p1, p2, p3 = fblob[p], fblob[p + 1], fblob[p + 2], fblob[p + 3]
        nv = 3 if kind == K_TRIMF else (4 if kind == K_TRAPMF else 2)
        level = w[t + iblob[T_LEVEL] + q] if code > 0 else 1.0 - w[t + iblob[T_LEVEL] + q]
        for v in range(nv):
            w[pts + n] = fblob[p + v]; n += 1
        if kind == K_TRIMF:
            w[pts + n] = p0 + level * (p1 - p0); n += 1
            w[pts + n] = p2 - level * (p2 - p1); n += 1
        elif kind == K_TRAPMF:
            w[pts + n] = p0 + level * (p1 - p0); n += 1
            w[pts + n] = p3 - level * (p3 - p2); n += 1
        elif kind == 11:
            w[pts + n] = p0 + level * (p1 - p0); n += 1
        else:
            w[pts + n] = p1 - level * (p1 - p0); n += 1
    w[pts:pts + n].sort()
    num, den = 0.0, 0.0
    prev = lo
    for c in range(n):
        q = min(w[pts + c], hi)
        if not q > prev:
            continue
        m = 1
        w[sub] = prev
        if iblob[AGG] == AGG_MAX:  # crossings of two sets inside (prev, q)
            h = q - prev
            ya, yb = prev + (0.5 - _GAUSS) * h, prev + (0.5 + _GAUSS) * h
            for s1 in range(n_sets):
                for s2 in range(s1 + 1, n_sets):
                    da = _set_at(w, fblob, iblob, o, t, s1, ya) - _set_at(w, fblob, iblob, o, t, s2, ya)
                    db = _set_at(w, fblob, iblob, o, t, s1, yb) - _set_at(w, fblob, iblob, o, t, s2, yb)
                    slope = (db - da) / (yb - ya)
                    d0 = da - slope * (ya - prev)
                    d1 = db + slope * (q - yb)
                    if (d0 > 0.0 and d1 < 0.0) or (d0 < 0.0 and d1 > 0.0):
                        w[sub + m] = prev + h * d0 / (d0 - d1)
                        m += 1
        w[sub + m] = q
        m += 1
        w[sub:sub + m].sort()
        for u in range(m - 1):
            a, b = w[sub + u], w[sub + u + 1]
            h = b - a
            if not h > 0.0:
                continue
            y1, y2 = a + (0.5 - _GAUSS) * h, a + (0.5 + _GAUSS) * h
            f1 = _agg_at(w, fblob, iblob, o, t, n_sets, y1)
            f2 = _agg_at(w, fblob, iblob, o, t, n_sets, y2)
            den += 0.5 * h * (f1 + f2)
            num += 0.5 * h * (y1 * f1 + y2 * f2)
        prev = q
    if not den > 0.0:
        return math.nan
    return num / den


@kernel(inline=True)
def _fallback(fblob, iblob, o):
    """Output ``o``'s value when its set is empty: the ``no_rule_fired`` policy."""
    policy, rng = iblob[POLICY], iblob[F_OUT_RANGE] + 2 * o
    if policy == P_MIDPOINT:
        return 0.5 * (fblob[rng] + fblob[rng + 1])
    return fblob[0] if policy == P_VALUE else math.nan


@kernel
def _empty_to_policy(w, fblob, iblob, o, y, m):
    """Lanes of row ``y`` (output ``o``) that a Mamdani defuzzifier left NaN get the policy.

    With finite rule strengths a Mamdani defuzzifier gives NaN only for an empty set (the
    aggregated values are finite and >= 0); a NaN strength is dealt with in :func:`_infer`.
    """
    fallback = _fallback(fblob, iblob, o)
    for s in range(m):
        v = w[y + s]
        w[y + s] = fallback if v != v else v


@kernel
def _mamdani(w, fblob, iblob, o, m, B):
    """Row R_Y + o = defuzzified output ``o`` (the ``no_rule_fired`` policy where its set is empty).

    The centroid of a block of LANES_MIN samples or more runs over the lanes; anything else
    runs one sample at a time.
    """
    lanes, stride = np.uint64(m), np.uint64(B)  # m, B go on as given: maybe literals
    method, imp_m, agg_m = iblob[DEFUZZ], iblob[IMP], iblob[AGG]
    usual = imp_m == IMP_MIN and agg_m == AGG_MAX
    n_sets = _active_sets(w, iblob, o, m, B)
    y = np.uint64(iblob[R_Y] + o) * stride
    if method == D_CENTROID and lanes >= LANES_MIN:
        if usual:  # literal constants: a version of the loops without branches
            _centroid_lanes(w, fblob, iblob, o, n_sets, lanes, stride, IMP_MIN, AGG_MAX)
        else:
            _centroid_lanes(w, fblob, iblob, o, n_sets, lanes, stride, imp_m, agg_m)
        _empty_to_policy(w, fblob, iblob, o, y, lanes)
        return
    tail = np.uint64(iblob[N_ROWS]) * stride
    agg, t = tail + np.uint64(iblob[T_AGG]), int(tail)
    for s in range(lanes):
        if method == D_EXACT:  # from the sets this sample fires, in list order
            n = np.int64(0)  # (as in _active_sets)
            for q in range(n_sets):
                level = w[np.uint64(int(w[tail + np.uint64(iblob[T_SET_ROW] + q)])) * stride + s]
                if level > 0.0:
                    w[t + iblob[T_CODE] + n] = w[tail + np.uint64(iblob[T_SET_CODE] + q)]
                    w[t + iblob[T_LEVEL] + n] = level
                    n += 1
            w[y + s] = _exact_centroid(w, fblob, iblob, o, t, n) if n > 0 else math.nan
            continue
        if usual:
            lo, hi = _aggregate_sample(w, fblob, iblob, o, n_sets, s, B, IMP_MIN, AGG_MAX)
        else:
            lo, hi = _aggregate_sample(w, fblob, iblob, o, n_sets, s, B, imp_m, agg_m)
        if method == D_CENTROID:
            w[y + s] = _centroid_sample(w, fblob, iblob, o, agg, lo, hi)
        else:
            w[y + s] = _grid_scan(w, fblob, iblob, o, agg)
    _empty_to_policy(w, fblob, iblob, o, y, lanes)


@kernel
def _sugeno(w, fblob, iblob, o, m, B):
    """Row R_Y + o = weighted average (or sum) of the rule outputs of Sugeno output ``o``; the
    ``no_rule_fired`` policy where the total weight is 0. A NaN rule output (``0 * inf``) gives NaN."""
    m, B = np.uint64(m), np.uint64(B)
    n_in, n_out, K, P = iblob[N_IN], iblob[N_OUT], iblob[N_K], iblob[N_P]
    num, den = np.uint64(iblob[R_NUM]) * B, np.uint64(iblob[R_DEN]) * B
    for s in range(m):
        w[num + s] = 0.0
        w[den + s] = 0.0
    for r in range(iblob[N_RULES]):
        code = iblob[iblob[I_CONS] + r * n_out + o]
        if code == 0:
            continue
        k = o * K + code - 1
        p = iblob[F_OUT_PARAMS] + k * P
        linear = iblob[iblob[I_OUT_KIND] + k] == K_LINEAR
        fire = np.uint64(iblob[R_FIRE] + r) * B
        for s in range(m):
            f = w[fire + s]
            if f == 0.0:
                continue
            if linear:
                z = fblob[p + n_in]
                for v in range(n_in):
                    z += fblob[p + v] * w[np.uint64(v) * B + s]
            else:
                z = fblob[p]
            w[num + s] += f * z
            w[den + s] += f
    y = np.uint64(iblob[R_Y] + o) * B
    wtaver = iblob[DEFUZZ] == D_WTAVER
    fallback = _fallback(fblob, iblob, o)
    for s in range(m):
        d = w[den + s]
        w[y + s] = (w[num + s] / d if wtaver else w[num + s]) if d > 0.0 else fallback


@kernel
def _infer(w, fblob, iblob, m, B):
    """Evaluate the ``m`` samples in the input rows of work array ``w`` (lanes 0..m-1 of
    rows 0..n_in-1, B lanes per row) into rows R_Y .. R_Y + n_out - 1.

    ``w`` holds ``N_ROWS * B + N_TAIL`` floats (header offsets). ``m`` and ``B`` are
    integers; the scalar path passes the literals 1, 1, and Numba then compiles a version
    for them in which every lane loop is one step (each step function takes them as given
    and converts them to unsigned itself, so the literals reach it).
    """
    n_in, n_out = iblob[N_IN], iblob[N_OUT]
    _memberships(w, fblob, iblob, m, B)
    _fire(w, fblob, iblob, m, B)
    for o in range(n_out):
        if iblob[SYSTEM] == SUGENO:
            _sugeno(w, fblob, iblob, o, m, B)
        else:
            _mamdani(w, fblob, iblob, o, m, B)
    # any NaN input makes every output NaN; a NaN rule strength, every output its rule concludes
    m, B = np.uint64(m), np.uint64(B)
    nan_in = np.uint64(iblob[R_ROW]) * B
    for s in range(m):
        w[nan_in + s] = 0.0
    for v in range(n_in):
        x = np.uint64(v) * B
        for s in range(m):
            w[nan_in + s] = _keep(w[x + s] if w[x + s] != w[x + s] else w[nan_in + s])
    cons = iblob[I_CONS]
    for o in range(n_out):
        y = np.uint64(iblob[R_Y] + o) * B
        for s in range(m):
            w[y + s] = w[nan_in + s] if w[nan_in + s] != w[nan_in + s] else w[y + s]
        for r in range(iblob[N_RULES]):
            if iblob[cons + r * n_out + o] == 0:
                continue
            f = np.uint64(iblob[R_FIRE] + r) * B
            for s in range(m):
                w[y + s] = w[f + s] if w[f + s] != w[f + s] else w[y + s]


@kernel
def _run(X, start, stop, fblob, iblob, out, lanes):
    """``out[i] = system(X[i])`` for ``start <= i < stop``, in blocks of ``lanes`` samples."""
    n_in, n_out, B = X.shape[1], out.shape[1], np.uint64(lanes)
    w = np.empty(iblob[N_ROWS] * lanes + iblob[N_TAIL])
    for i0 in range(start, stop, lanes):
        m = min(lanes, stop - i0)
        for s in range(m):
            for v in range(n_in):
                w[np.uint64(v) * B + np.uint64(s)] = X[i0 + s, v]
        _infer(w, fblob, iblob, np.uint64(m), B)
        for s in range(m):
            for o in range(n_out):
                out[i0 + s, o] = w[np.uint64(iblob[R_Y] + o) * B + np.uint64(s)]


# --------------------------------------------------------------------------- entry points
@kernel
def infer_one(xs, fblob, iblob):
    """One sample given as a tuple of floats; returns the first output (single-output fast path)."""
    w = np.empty(iblob[N_ROWS] + iblob[N_TAIL])
    for v in range(len(xs)):
        w[v] = xs[v]
    _infer(w, fblob, iblob, 1, 1)
    return w[iblob[R_Y]]


@kernel(parallel=True)
def evaluate_batch(X, fblob, iblob, out):
    """``out[i] = system(X[i])`` for X (n, n_in) and out (n, n_out), parallel over chunks of samples."""
    n = X.shape[0]
    n_chunks = (n + CHUNK - 1) // CHUNK
    for c in prange(n_chunks):
        _run(X, c * CHUNK, min(n, (c + 1) * CHUNK), fblob, iblob, out, BLOCK)


@kernel
def evaluate_serial(X, fblob, iblob, out):
    """As :func:`evaluate_batch`, on the calling thread only (small batches, no thread start-up;
    the tuners call it per candidate from their own threads)."""
    n = X.shape[0]
    _run(X, 0, n, fblob, iblob, out, max(1, min(BLOCK, n)))


@kernel
def explain_one(X, fblob, iblob, mu_out, fire_out, agg_out, out):
    """One sample ``X`` (1, n_in) with its intermediate results.

    Fills ``mu_out`` (T,) input-term memberships, ``fire_out`` (R,) weighted firing
    strengths, ``agg_out`` (n_out, res) the aggregated output sets on the grid (Mamdani;
    left as given for a NaN input), and ``out`` (1, n_out) the outputs. Memberships and
    strengths are NaN for a NaN input.
    """
    w = np.empty(iblob[N_ROWS] + iblob[N_TAIL])
    for v in range(X.shape[1]):
        w[v] = X[0, v]
    _infer(w, fblob, iblob, np.uint64(1), np.uint64(1))
    for o in range(out.shape[1]):
        out[0, o] = w[iblob[R_Y] + o]
    if np.isnan(X).any():
        mu_out[:] = math.nan
        fire_out[:] = math.nan
        return
    T, R, res = iblob[N_TERMS], iblob[N_RULES], iblob[RES]
    mu_out[:] = w[iblob[R_MU]:iblob[R_MU] + T]
    fire_out[:] = w[iblob[R_FIRE]:iblob[R_FIRE] + R]
    if iblob[SYSTEM] == MAMDANI:
        agg = iblob[N_ROWS] + iblob[T_AGG]
        for o in range(agg_out.shape[0]):
            n_sets = _active_sets(w, iblob, o, _OFF[1], _OFF[1])
            _aggregate_sample(w, fblob, iblob, o, n_sets, _OFF[0], _OFF[1], iblob[IMP], iblob[AGG])
            agg_out[o] = w[agg:agg + res]
