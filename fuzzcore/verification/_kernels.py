"""Numba kernels of the verifier. Private: :mod:`fuzzcore.verification.coverage` calls them with
validated, packed input; they never raise."""
from __future__ import annotations

import numpy as np

from ..jit import kernel


@kernel
def strongest_per_cell(tables, offsets, n_terms, n_elements, ante, weights, is_or, and_prod, or_probor,
                       strongest, rule_max):
    """Strongest weighted firing strength in every cell, and each rule's largest strength.

    Parameters
    ----------
    tables : (sum_i n_elements[i] * n_terms[i],) float64
        Axis ``i``'s table at ``offsets[i]``, row-major (element, term): the membership of
        the element's representative point in each of the input's terms.
    offsets, n_terms, n_elements : (n_in,) int64
    ante : (R, n_in) int64
        MATLAB's antecedent form: 0 don't care, k term k (1-based), -k NOT term k.
    weights : (R,) float64
    is_or : (R,) int64
        1 where the rule's clauses are joined by ``or``.
    and_prod, or_probor : bool
        ``and`` is the product (else min); ``or`` is probor (else max).
    strongest : (n_cells,) float64, out
        Cells in C order over ``n_elements`` (the last input varies fastest).
    rule_max : (R,) float64, out
    """
    n_in = n_elements.shape[0]
    R = ante.shape[0]
    index = np.zeros(n_in, dtype=np.int64)
    rule_max[:] = 0.0
    for cell in range(strongest.shape[0]):
        best = 0.0
        for r in range(R):
            orr = is_or[r] == 1
            f = 0.0 if orr else 1.0
            for v in range(n_in):
                code = ante[r, v]
                if code == 0:
                    continue
                x = tables[offsets[v] + index[v] * n_terms[v] + abs(code) - 1]
                if code < 0:
                    x = 1.0 - x
                if orr:
                    f = f + x - f * x if or_probor else max(f, x)
                else:
                    f = f * x if and_prod else min(f, x)
            f *= weights[r]
            if f > best:
                best = f
            if f > rule_max[r]:
                rule_max[r] = f
        strongest[cell] = best
        v = n_in - 1  # next cell: C order
        while v >= 0:
            index[v] += 1
            if index[v] < n_elements[v]:
                break
            index[v] = 0
            v -= 1
