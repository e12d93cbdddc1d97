"""Packing a fuzzy system into the two flat arrays the Numba kernels read.

Two arrays cross into compiled code, so a call costs two argument conversions, not twenty.
Kernels index them at offsets kept in ``iblob``'s header (names in :mod:`fuzzcore._kernels`):
making a view per part would cost reference counting on every call.

``iblob`` (int64)::

    [0] system  [1] and  [2] or  [3] implication  [4] aggregation  [5] defuzzifier
    [6] no-rule policy  [7] n_in  [8] n_out  [9] T (input terms)  [10] R (rules)
    [11] K (most terms of one output)  [12] P (output parameter width)  [13] resolution
    [14:21] where each iblob part starts, [21:27] where each fblob part starts,
    [27:35] the work array's lane rows, [35:45] its per-sample scratch (see below), then
    in_kind (T) | in_var (T) | antecedent (R*n_in) | consequent (R*n_out) |
    rule_or (R) | out_kind (n_out*K, -1 where an output has fewer terms) |
    support (n_out*K*2: first and one-past-last grid index where the term is > 0)

``fblob`` (float64)::

    [0] no-rule value, then in_params (T*4) | rule weights (R) | out_range (n_out*2) |
    out_params (n_out*K*P) | grid (n_out*res) | term table on the grid (n_out*K*res)

Work array (float64, one per thread): rows of B lanes, one lane per sample of a block --
inputs (n_in rows) | memberships (T) | rule strengths (R) | max-aggregation levels (2K: a
term, then its NOT) | one aggregated grid row | centroid numerator | denominator |
outputs (n_out) -- then per-sample scratch: the fired sets' level rows, codes and grid
stretches (S each), one sample's aggregated set (res), one sample's set codes and levels
(S each), exact-centroid breakpoints and sub-breakpoints. Scratch is sized by what the
system's methods use: S = 2K sets with max aggregation (rules sharing a term merge), R
otherwise, none for Sugeno; the exact centroid's lists (S^2 / 2 crossing points) only for
``centroid_exact``. A system whose work array would exceed :data:`MAX_WORK` floats is
refused (:func:`pack`), naming what needs the room.

Antecedent entries are 0 (don't care) or +-(flat input-term index + 1); consequent
entries are 0 or +-(term index within the output + 1); negative means NOT.
:class:`Layout` gives the slices of each part so the tuners can write candidate
parameters straight into copies of ``fblob`` / ``iblob``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _kernels as K
from .errors import RuleBaseError
from .membership import MAX_PARAMS, resolve_kind

SYSTEMS = {"mamdani": K.MAMDANI, "sugeno": K.SUGENO}
AND_METHODS = {"min": K.AND_MIN, "prod": K.AND_PROD}
OR_METHODS = {"max": K.OR_MAX, "probor": K.OR_PROBOR}
IMPLICATIONS = {"min": K.IMP_MIN, "prod": K.IMP_PROD}
AGGREGATIONS = {"max": K.AGG_MAX, "sum": K.AGG_SUM, "probor": K.AGG_PROBOR}
MAMDANI_DEFUZZIFIERS = {
    "centroid": K.D_CENTROID, "bisector": K.D_BISECTOR, "mom": K.D_MOM,
    "som": K.D_SOM, "lom": K.D_LOM, "centroid_exact": K.D_EXACT,
}
SUGENO_DEFUZZIFIERS = {"wtaver": K.D_WTAVER, "wtsum": K.D_WTSUM}
POLICIES = {"midpoint": K.P_MIDPOINT, "nan": K.P_NAN}  # a number means P_VALUE
#: most floats one work array may hold (one per thread and call; 2**26 floats = 512 MiB)
MAX_WORK = 2**26

@dataclass(frozen=True)
class Layout:
    """Where each part lives in the packed arrays (slices into ``fblob`` / ``iblob``)."""

    n_in: int
    n_out: int
    n_terms_in: int
    n_rules: int
    max_terms_out: int
    out_param_width: int
    resolution: int
    in_params: slice      # fblob, reshape (T, 4)
    rule_weights: slice   # fblob, (R,)
    out_range: slice      # fblob, reshape (n_out, 2)
    out_params: slice     # fblob, reshape (n_out, K, P)
    consequent: slice     # iblob, reshape (R, n_out)
    antecedent: slice     # iblob, reshape (R, n_in)


def _check_size(system, work: int, crossings: int) -> None:
    """Refuse a system whose work array (``work`` floats, of which ``crossings`` for the exact
    centroid) would not fit in :data:`MAX_WORK`, saying what needs the room."""
    if work <= MAX_WORK:
        return
    need = f"{work:,} floats ({work * 8 / 2**30:.1f} GiB) of scratch per call and thread"
    if crossings > MAX_WORK // 2:
        cause = (f"centroid_exact with {system.aggregation} aggregation over {len(system.rules):,} rules keeps "
                 f"{crossings:,} crossing points; use max aggregation (sets merge per output term), fewer rules "
                 "or the centroid defuzzifier")
        place = "defuzzifier"
    else:
        cause = (f"{len(system.rules):,} rules and {sum(len(v.terms) for v in system.inputs):,} input terms "
                 f"over blocks of {K.BLOCK} samples; split the rule base")
        place = "rules"
    raise RuleBaseError(f"this system needs {need}, more than the limit of {MAX_WORK:,} floats: {cause}",
                        place=place)


def pack(system) -> tuple[np.ndarray, np.ndarray, Layout]:
    """Pack a validated :class:`~fuzzcore.system.FuzzySystem` into ``(fblob, iblob, layout)``.

    Raises :class:`~fuzzcore.errors.RuleBaseError` when the work array would exceed
    :data:`MAX_WORK` floats.
    """
    n_in, n_out = len(system.inputs), len(system.outputs)
    in_terms = [(i, t) for i, v in enumerate(system.inputs) for t in v.terms]
    T, R = len(in_terms), len(system.rules)
    Kmax = max(len(v.terms) for v in system.outputs)
    P = max(MAX_PARAMS, n_in + 1)
    mamdani = system.type == "mamdani"
    res = system.resolution if mamdani else 0
    flat_start = np.cumsum([0] + [len(v.terms) for v in system.inputs])

    policy = system.no_rule_fired
    policy_code = K.P_VALUE if isinstance(policy, float) else POLICIES[policy]
    defuzz = (MAMDANI_DEFUZZIFIERS if mamdani else SUGENO_DEFUZZIFIERS)[system.defuzzifier]
    header = [SYSTEMS[system.type], AND_METHODS[system.and_method], OR_METHODS[system.or_method],
              IMPLICATIONS[system.implication], AGGREGATIONS[system.aggregation], defuzz,
              policy_code, n_in, n_out, T, R, Kmax, P, res]

    in_kind = [resolve_kind(t.kind).code for _, t in in_terms]
    in_var = [i for i, _ in in_terms]
    ante = np.zeros((R, n_in), dtype=np.int64)
    cons = np.zeros((R, n_out), dtype=np.int64)
    for r, rule in enumerate(system.rules):
        for i, code in enumerate(rule.antecedent):
            if code:
                ante[r, i] = np.sign(code) * (flat_start[i] + abs(code))
        cons[r] = rule.consequent
    rule_or = [1 if rule.connective == "or" else 0 for rule in system.rules]
    out_kind = np.full((n_out, Kmax), -1, dtype=np.int64)
    out_params = np.zeros((n_out, Kmax, P))
    for o, var in enumerate(system.outputs):
        for k, term in enumerate(var.terms):
            out_kind[o, k] = resolve_kind(term.kind).code
            out_params[o, k, :len(term.params)] = term.params

    in_params = np.zeros((T, MAX_PARAMS))
    for t, (_, term) in enumerate(in_terms):
        in_params[t, :len(term.params)] = term.params
    parts_f = [
        np.array([policy if isinstance(policy, float) else 0.0]),
        in_params.ravel(),
        np.array([rule.weight for rule in system.rules], dtype=float),
        np.array([v.range for v in system.outputs], dtype=float).ravel(),
        out_params.ravel(),
        np.zeros(n_out * res),
        np.zeros(n_out * Kmax * res),
    ]
    parts_i = [np.array(in_kind), np.array(in_var), ante.ravel(), cons.ravel(),
               np.array(rule_or), out_kind.ravel(), np.zeros(n_out * Kmax * 2)]
    i_starts = K.HEADER + np.cumsum([0] + [len(p) for p in parts_i])
    f_starts = np.cumsum([0] + [len(p) for p in parts_f])
    n_sets = 0 if not mamdani else (2 * Kmax if system.aggregation == "max" else R)
    exact = [n_sets, n_sets, 2 + 6 * n_sets, n_sets * (n_sets - 1) // 2 + 2]
    if system.defuzzifier != "centroid_exact":
        exact = [0, 0, 0, 0]
    rows = [n_in, T, R, 2 * Kmax, 1, 1, 1, n_out]  # inputs | mu | fire | level | row | num | den | y
    tail = [n_sets] * 4 + [max(res, 1)] + exact
    _check_size(system, sum(rows) * K.BLOCK + sum(tail), exact[-1])
    header = np.concatenate([header, i_starts[:-1], f_starts[1:-1], np.cumsum(rows),
                             np.cumsum([0] + tail)])  # K.HEADER long
    fblob = np.concatenate(parts_f).astype(np.float64)
    iblob = np.concatenate([p.astype(np.int64) for p in [header] + parts_i])
    K.refresh_tables(fblob, iblob)

    layout = Layout(
        n_in=n_in, n_out=n_out, n_terms_in=T, n_rules=R, max_terms_out=Kmax, out_param_width=P,
        resolution=res,
        in_params=slice(int(f_starts[1]), int(f_starts[2])),
        rule_weights=slice(int(f_starts[2]), int(f_starts[3])),
        out_range=slice(int(f_starts[3]), int(f_starts[4])),
        out_params=slice(int(f_starts[4]), int(f_starts[5])),
        antecedent=slice(int(i_starts[2]), int(i_starts[3])),
        consequent=slice(int(i_starts[3]), int(i_starts[4])),
    )
    return fblob, iblob, layout
