"""Membership-function parameters as one vector, with the constraints that keep every term valid.

:class:`TermSpace` lists the parameters of the tuned variables' terms (inputs, and
Mamdani/Sugeno-constant outputs), in variable, term and parameter order, and says where
each lives in the packed arrays (:mod:`fuzzcore.compiled`), so a candidate vector is
written straight into a copy of ``fblob``.

Every parameter has a role, from its membership-function kind:

=======  ==============================================  =======================  ========
role     meaning                                         constraint               scale
=======  ==============================================  =======================  ========
point    a place on the variable's axis (vertex, centre) inside the range          span
width    a spread in the variable's units (sigma, a)     > 0, not degenerate (1)  span
slope    a steepness (sigmf's a), units^-1               none                     1 / span
shape    a unitless exponent (gbellmf's b)               > 0                      1
=======  ==============================================  =======================  ========

(1) inside (:data:`~fuzzcore.membership.WIDTH_MIN`, :data:`~fuzzcore.membership.WIDTH_MAX`]:
``2 w^2`` stays a positive normal float64.

The vertex kinds (trimf, trapmf, pimf, smf, zmf, linsmf, linzmf) keep their points
in non-decreasing order with a positive width (first point < last point). With
``keep_order`` (the default), the terms of a variable also keep their order: each
corner of a vertex term (left foot, left shoulder, right shoulder, right foot; a
triangle's peak is both shoulders) stays on the side of the next term's same corner that
it starts on, so "low" stays left of "medium" and the labels keep their meaning (the
paper's tuned terms move but stay in order; without it a search may swap them). A point that
starts outside its variable's range (MATLAB allows feet beyond the range) may stay
anywhere between that start and the range. ``scale`` is what one unit of a tuner's step
is worth: a pattern-search mesh of 0.01 moves a vertex by 1 % of its variable's range.

With ``partition`` (the tuners' default; :class:`~fuzzcore.tune.patternsearch.PatternSearch`),
the terms of every tuned variable whose terms are all piecewise linear (trimf, trapmf,
linsmf, linzmf) also stay a readable partition of its range, in declared order. With a
term's corners (left foot a, left shoulder b, right shoulder c, right foot d) and
``h =`` :data:`COVER`:

- covering the range: the first term is at least h at the range's low end
  (``(1-h) a + h b <= lo``), the last at its high end (``(1-h) d + h c >= hi``), and
  neighbours cross at h or above (``(1-h) a' + h b' <= (1-h) d + h c`` for a term and the
  next), so some term is at least h everywhere and every rule grid covers the whole box;
- bounded overlap: neighbours cross at :data:`SEPARATION` or below (the same inequality
  the other way at that level: neither is nearly 1 where the other is), a term rises only
  after the previous one's core begins (``a' >= b``)
  and falls before the next one's core ends (``d <= c'``), and no point is in three
  terms (``d <= a''`` for a term and the one after next);
- bounded width: a term's support within the range is at most :data:`MAX_WIDTH` of it.

All but the last are linear inequalities on the parameters, so they are an extreme
barrier like the others: a candidate that breaks one is never scored.
"""
from __future__ import annotations

import dataclasses
from typing import Sequence

import numpy as np

from ..membership import WIDTH_MAX, WIDTH_MIN, resolve_kind
from ..variables import Term

ROLES: dict[str, tuple[str, ...]] = {
    "trimf": ("point",) * 3,
    "trapmf": ("point",) * 4,
    "linsmf": ("point",) * 2,
    "linzmf": ("point",) * 2,
    "smf": ("point",) * 2,
    "zmf": ("point",) * 2,
    "pimf": ("point",) * 4,
    "gaussmf": ("width", "point"),
    "gauss2mf": ("width", "point", "width", "point"),
    "gbellmf": ("width", "shape", "point"),
    "sigmf": ("slope", "point"),
    "dsigmf": ("slope", "point", "slope", "point"),
    "psigmf": ("slope", "point", "slope", "point"),
    "constant": ("point",),
}
#: kinds whose parameters are vertices: non-decreasing, first < last
ORDERED = frozenset({"trimf", "trapmf", "linsmf", "linzmf", "smf", "zmf", "pimf"})
#: the trapezoid corners (left foot, left shoulder, right shoulder, right foot) of the vertex
#: kinds, as parameter indices; None where the corner is at -inf/+inf
CORNERS = {
    "trimf": (0, 1, 1, 2), "trapmf": (0, 1, 2, 3), "pimf": (0, 1, 2, 3),
    "linsmf": (0, 1, None, None), "smf": (0, 1, None, None),
    "linzmf": (None, None, 0, 1), "zmf": (None, None, 0, 1),
}


#: the level neighbouring terms must cross at or above, and the edges be covered at (partition)
COVER = 0.5
#: the level neighbouring terms must cross at or below (partition: they stay distinguishable)
SEPARATION = 0.75
#: the largest support of a term within its variable's range, as a fraction of it (partition)
MAX_WIDTH = 0.75
#: kinds the partition constraints apply to (a variable with another kind keeps only its order)
PARTITION_KINDS = frozenset({"trimf", "trapmf", "linsmf", "linzmf"})


class TermSpace:
    """The membership-function parameters of a system's variables as one vector.

    Parameters
    ----------
    system : FuzzySystem
    variables : sequence of str, optional
        Names of the variables whose terms are tuned; default every input and output.
    keep_order : bool
        Keep each variable's terms in the order they start in (module docstring).
    partition : bool
        Keep each variable's piecewise-linear terms a readable partition of its range
        (module docstring); the starting terms must be one (``ValueError`` says why not).

    Attributes
    ----------
    system : FuzzySystem
        The starting system (its values are :attr:`x0`).
    names : tuple of str
        ``"variable.term[k]"`` for each parameter (``k`` 0-based, MATLAB's order).
    x0 : ndarray (n_params,)
        The starting values.
    scale : ndarray (n_params,)
        A tuner's unit step for each parameter (table in the module docstring).
    lower, upper : ndarray (n_params,)
        Bounds (``-inf`` / ``inf`` where none); strict for widths and shapes.
    f_positions : ndarray (n_params,), int64
        Index of each parameter in ``fblob``.
    i_positions : ndarray (0,), int64
        None: a term space writes nothing into ``iblob``.
    refresh : bool
        Whether a candidate changes output terms (the output tables need recomputing).
    """

    def __init__(self, system, variables: Sequence[str] | None = None, keep_order: bool = True,
                 partition: bool = False):
        all_vars = [("inputs", i, v) for i, v in enumerate(system.inputs)] + \
                   [("outputs", o, v) for o, v in enumerate(system.outputs)]
        known = [v.name for _, _, v in all_vars]
        if variables is None:
            chosen = known
        else:
            if isinstance(variables, str):
                raise TypeError(f"variables={variables!r}: expected a sequence of names, e.g. [{variables!r}]")
            chosen = list(variables)
            unknown = [n for n in chosen if n not in known]
            if unknown or not chosen:
                raise ValueError(f"variables {chosen!r}: expected names among {', '.join(known)}"
                                 + (f"; unknown: {', '.join(unknown)}" if unknown else "; got none"))
        _, _, layout = system.packed
        in_start, out_start = layout.in_params.start, layout.out_params.start
        K, P = layout.max_terms_out, layout.out_param_width

        names, x0, scale, lower, upper, strict, positions = [], [], [], [], [], [], []
        chains = []  # parameter index lists that must be non-decreasing with first < last
        pairs = []   # (i, j): P[:, i] <= P[:, j]
        terms = []  # (first, end, "inputs"/"outputs", variable index, term index k, ordered kind?)
        refresh = False
        flat = 0  # flat input-term index
        partitioned = []  # (variable, [(first parameter index, kind, term name)]) of tuned variables
        for kind_of_var, index, var in all_vars:
            tuned = var.name in chosen
            if tuned:
                partitioned.append((var, []))
            previous = None  # (first parameter index, kind) of the previous term of this variable
            for k, term in enumerate(var.terms):
                if kind_of_var == "inputs":
                    base = in_start + flat * 4
                    flat += 1
                else:
                    base = out_start + (index * K + k) * P
                if not tuned:
                    continue
                kind = resolve_kind(term.kind).name
                if kind not in ROLES:
                    raise ValueError(f"term {term.name!r} of {var.name!r} is {kind}: its parameters are not "
                                     f"tunable here (tunable kinds: {', '.join(ROLES)})")
                lo, hi = var.range
                span = hi - lo
                first = len(names)
                for j, (role, value) in enumerate(zip(ROLES[kind], term.params)):
                    names.append(f"{var.name}.{term.name}[{j}]")
                    x0.append(value)
                    positions.append(base + j)
                    if role == "point":
                        scale.append(span)
                        lower.append(min(lo, value))
                        upper.append(max(hi, value))
                        strict.append(False)
                    elif role == "slope":
                        scale.append(1.0 / span)
                        lower.append(-np.inf)
                        upper.append(np.inf)
                        strict.append(False)
                    else:  # width, shape: positive (a width also not degenerate: fuzzcore.membership)
                        scale.append(span if role == "width" else 1.0)
                        lower.append(WIDTH_MIN if role == "width" else 0.0)
                        upper.append(WIDTH_MAX if role == "width" else np.inf)
                        strict.append(True)
                        if not value > 0:
                            raise ValueError(f"term {term.name!r} of {var.name!r} ({kind} {list(term.params)}): "
                                             f"parameter {j + 1} ({role}) is {value:g}; tuning keeps it > 0, "
                                             "so it must start > 0")
                terms.append((first, len(names), kind_of_var, index, k, kind in ORDERED))
                partitioned[-1][1].append((first, kind, term.name))
                if keep_order and previous is not None and kind in ORDERED and previous[1] in ORDERED:
                    for a, b in zip(CORNERS[previous[1]], CORNERS[kind]):
                        if a is not None and b is not None:
                            i, j = previous[0] + a, first + b
                            pairs.append((i, j) if x0[i] <= x0[j] else (j, i))
                previous = (first, kind)
                if kind in ORDERED:
                    chain = list(range(first, len(names)))
                    if not term.params[0] < term.params[-1]:
                        raise ValueError(f"term {term.name!r} of {var.name!r} ({kind} {list(term.params)}) "
                                         "has zero width; tuning keeps first < last, so it must start so")
                    chains.append(chain)
                if kind_of_var == "outputs":
                    refresh = True
        if not names:
            raise ValueError(f"variables {chosen!r} have no terms to tune")
        self.system = system
        self.variables = tuple(chosen)
        self.names = tuple(names)
        self.x0 = np.array(x0, dtype=np.float64)
        self.scale = np.array(scale, dtype=np.float64)
        self.lower = np.array(lower, dtype=np.float64)
        self.upper = np.array(upper, dtype=np.float64)
        self._strict = np.array(strict, dtype=bool)
        pairs += [(a, b) for chain in chains for a, b in zip(chain, chain[1:])]
        self.keep_order = bool(keep_order)
        self._left = np.array([a for a, _ in pairs], dtype=np.int64)   # P[:, left] <= P[:, right]
        self._right = np.array([b for _, b in pairs], dtype=np.int64)
        self._first = np.array([c[0] for c in chains], dtype=np.int64)  # P[:, first] < P[:, last]
        self._last = np.array([c[-1] for c in chains], dtype=np.int64)
        self._terms = terms
        self._term_of = np.repeat(np.arange(len(terms)), [end - first for first, end, *_ in terms])
        self.partition = bool(partition)
        self._linear, self._widths, self._texts = [], [], ([], [])  # see _partition_constraints
        if partition:
            for var, listed in partitioned:
                if listed and all(kind in PARTITION_KINDS for _, kind, _ in listed):
                    self._partition_constraints(var, listed)
        n = len(names)
        self._A = np.zeros((len(self._linear), n))  # partition: P @ A.T <= b
        for row, (coefficients, _) in enumerate(self._linear):
            for j, c in coefficients:
                self._A[row, j] += c
        self._b = np.array([b for _, b in self._linear], dtype=np.float64)
        self._slack = 1e-12 * np.array([1.0 + abs(b) for b in self._b])
        self.f_positions = np.array(positions, dtype=np.int64)
        self.i_positions = np.empty(0, dtype=np.int64)
        self.refresh = refresh
        if partition:
            broken = self.broken_constraints(self.x0)
            if broken:
                raise ValueError("the starting terms are not a readable partition, which partition=True keeps: "
                                 + "; ".join(broken) + " (start from terms that are, or pass partition=False)")

    def _partition_constraints(self, var, listed) -> None:
        """Add the partition constraints of one variable (module docstring) to the lists:
        ``_linear`` ([(index, coefficient)], rhs) for ``sum c P[:, i] <= rhs``, ``_widths``
        (left foot index or None, right foot index or None, lo, hi, limit), and ``_texts``
        (the descriptions of the linear ones and of the widths, in order)."""
        lo, hi = var.range
        h = COVER
        corners = [tuple(None if c is None else first + c for c in CORNERS[kind]) for first, kind, _ in listed]
        label = [f"{var.name}.{name}" for _, _, name in listed]

        def add(terms, rhs, text):
            self._linear.append(([(i, c) for i, c in terms if i is not None], rhs))
            self._texts[0].append(text)

        a0, b0, _, _ = corners[0]
        if a0 is not None:
            add([(a0, 1 - h), (b0, h)], lo, f"{label[0]} is at least {h:g} at {var.name}'s low end {lo:g}")
        _, _, c1, d1 = corners[-1]
        if d1 is not None:
            add([(d1, -(1 - h)), (c1, -h)], -hi, f"{label[-1]} is at least {h:g} at {var.name}'s high end {hi:g}")
        for k in range(len(corners) - 1):
            (a, b, c, d), (a2, b2, c2, _) = corners[k], corners[k + 1]
            if d is not None and a2 is not None:
                add([(a2, 1 - h), (b2, h), (d, -(1 - h)), (c, -h)], 0.0,
                    f"{label[k]} and {label[k + 1]} cross at {h:g} or above")
                g = SEPARATION
                add([(d, 1 - g), (c, g), (a2, -(1 - g)), (b2, -g)], 0.0,
                    f"{label[k]} and {label[k + 1]} cross at {g:g} or below")
            if a2 is not None and b is not None:
                add([(b, 1.0), (a2, -1.0)], 0.0, f"{label[k + 1]} rises only after {label[k]}'s core begins")
            if d is not None and c2 is not None:
                add([(d, 1.0), (c2, -1.0)], 0.0, f"{label[k]} falls before {label[k + 1]}'s core ends")
            if k + 2 < len(corners) and d is not None and corners[k + 2][0] is not None:
                add([(d, 1.0), (corners[k + 2][0], -1.0)], 0.0,
                    f"{label[k]} ends before {label[k + 2]} begins (no point in three terms)")
        for (a, _, _, d), text in zip(corners, label):
            self._widths.append((a, d, lo, hi, MAX_WIDTH * (hi - lo)))
        self._texts[1].extend([f"{text} is at most {MAX_WIDTH:g} of {var.name}'s range wide" for text in label])

    def _partition_each(self, P: np.ndarray) -> np.ndarray:
        """(n, n_constraints) bool: which partition constraints each row of ``P`` keeps."""
        ok = [P @ self._A.T <= self._b + self._slack]
        for a, d, lo, hi, limit in self._widths:
            left = np.maximum(P[:, a], lo) if a is not None else np.full(P.shape[0], lo)
            right = np.minimum(P[:, d], hi) if d is not None else np.full(P.shape[0], hi)
            ok.append((right - left <= limit * (1 + 1e-12))[:, None])
        return np.concatenate(ok, axis=1)

    def broken_constraints(self, p: np.ndarray) -> list[str]:
        """The partition constraints the parameter vector ``p`` (n_params,) breaks, in words."""
        if not self.partition:
            return []
        each = self._partition_each(np.asarray(p, dtype=np.float64)[None])[0]
        return [text for text, ok in zip(self._texts[0] + self._texts[1], each) if not ok]

    @property
    def n_params(self) -> int:
        return self.x0.shape[0]

    def feasible(self, P: np.ndarray) -> np.ndarray:
        """Which candidates give valid terms.

        Parameters
        ----------
        P : ndarray (n_candidates, n_params)

        Returns
        -------
        ndarray (n_candidates,), bool
        """
        ok = np.isfinite(P).all(axis=1)
        with np.errstate(invalid="ignore"):
            ok &= (P <= self.upper).all(axis=1)
            ok &= np.where(self._strict, P > self.lower, P >= self.lower).all(axis=1)
            ok &= (P[:, self._left] <= P[:, self._right]).all(axis=1)
            ok &= (P[:, self._first] < P[:, self._last]).all(axis=1)
            if self.partition:
                ok &= self._partition_each(np.where(np.isfinite(P), P, 0.0)).all(axis=1)
        return ok

    def changes(self, base: np.ndarray, p: np.ndarray) -> list[tuple]:
        """What moving from ``base`` to ``p`` can change, for :class:`~fuzzcore.tune.objective.Objective`.

        One entry per changed term: ``("interval", v, lo, hi)`` (memberships of input v can
        change only for inputs in [lo, hi]), ``("input", v)`` (anywhere on input v) or
        ``("output_term", o, k)`` (term k of output o: only samples whose rules conclude it).

        A vertex kind's membership depends on its vertices piecewise: moving the single
        vertex j changes it only between vertices j - 1 and j + 1 (or, for the first/last
        vertex, from its lower/higher position); moving several, only inside the hull of
        the old and new vertices. Other kinds are smooth everywhere.
        """
        out = []
        for t in np.unique(self._term_of[np.flatnonzero(p != base)]):
            first, end, role, var, k, ordered = self._terms[t]
            if role == "outputs":
                out.append(("output_term", var, k))
            elif not ordered:
                out.append(("input", var))
            else:
                old, new = base[first:end], p[first:end]
                moved = np.flatnonzero(old != new)
                if moved.shape[0] == 1:
                    j, last = int(moved[0]), end - first - 1
                    lo = min(old[j], new[j]) if j == 0 else old[j - 1]
                    hi = max(old[j], new[j]) if j == last else old[j + 1]
                else:
                    lo, hi = min(old.min(), new.min()), max(old.max(), new.max())
                out.append(("interval", var, float(lo), float(hi)))
        return out

    def blob_values(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(fblob values (n, n_params), iblob values (n, 0))`` to write at the positions."""
        return np.ascontiguousarray(P, dtype=np.float64), np.empty((P.shape[0], 0), dtype=np.int64)

    def to_system(self, p: np.ndarray):
        """The system with the parameters ``p`` (n_params,) written into its terms.

        Raises ``ValueError`` if ``p`` violates the constraints.
        """
        p = np.asarray(p, dtype=np.float64)
        if p.shape != self.x0.shape:
            raise ValueError(f"parameter vector has shape {p.shape}, expected {self.x0.shape}")
        if not self.feasible(p[None])[0]:
            raise ValueError("parameter vector violates the term constraints (order, range, positive widths"
                             + (", partition" if self.partition else "") + ")")
        values = iter(p.tolist())
        system = self.system

        def rebuilt(var):
            if var.name not in self.variables:
                return var
            terms = tuple(Term(t.name, t.kind, [next(values) for _ in t.params]) for t in var.terms)
            return dataclasses.replace(var, terms=terms)

        inputs = tuple(rebuilt(v) for v in system.inputs)
        outputs = tuple(rebuilt(v) for v in system.outputs)
        return dataclasses.replace(system, inputs=inputs, outputs=outputs)
