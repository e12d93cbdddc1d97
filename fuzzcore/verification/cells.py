"""The cell structure of an input box: per axis, the points where some rule clause can change.

A rule's firing strength is built from clauses ``mu(x_i)`` (or ``1 - mu(x_i)`` for NOT) of
one input each. Whether a clause is positive, or at least a level ``L``, changes only at
*critical points* of its input's axis:

- piecewise-linear terms (trimf, trapmf, linsmf, linzmf): their vertices (where the
  membership leaves 0 or reaches 1) and, on each sloped side, where a weighted clause
  reaches the threshold: the two adjacent floating-point numbers between which the test,
  evaluated as the strength is (``w * mu >= threshold``, ``w * (1 - mu) >= threshold`` for
  NOT), changes its answer, bisected from the side's ends (a side is linear, so the test
  changes once): exact to the last bit, where the level's crossing computed from the
  side's ends can lie an ulp or more from where the computed membership crosses it;
- smooth terms: the same points found numerically: each axis is sampled at
  :data:`SAMPLES` points plus the term's own characteristic points (centres, vertices,
  centre +- k widths), and every change of a clause's truth value between two samples is
  bisected to within ``tol`` of the axis span (the stated tolerance of a smooth system).

The critical points cut each axis into *elements*: the points themselves and the open
intervals between them, in order (``p0, (p0, p1), p1, ..., pn``; ``p0`` and ``pn`` are the
range ends). A *cell* is one element per axis. Inside a cell every clause's truth value is
constant, so whether a rule fires (strength > 0) is decided exactly by one representative
point per cell (an interval's midpoint); with ``and = min`` and ``or = max`` so is whether its
strength reaches the levels.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..membership import PIECEWISE_LINEAR

#: samples per axis for locating the critical points of smooth terms
SAMPLES = 4097
#: bisection steps for one critical point of a smooth term (2^-60 of a sampling step)
BISECTIONS = 60


def vertices(term) -> list[tuple[float, float]]:
    """The (x, membership) vertices of a piecewise-linear term, left to right."""
    p = term.params
    if term.kind == "trimf":
        return [(p[0], 0.0), (p[1], 1.0), (p[2], 0.0)]
    if term.kind == "trapmf":
        return [(p[0], 0.0), (p[1], 1.0), (p[2], 1.0), (p[3], 0.0)]
    if term.kind == "linsmf":
        return [(p[0], 0.0), (p[1], 1.0)]
    return [(p[0], 1.0), (p[1], 0.0)]  # linzmf


def level_tests(weights, threshold: float) -> list:
    """The clause tests whose answers decide whether a rule of weight ``w`` (each of
    ``weights`` > 0) reaches ``threshold`` > 0, computed as the verifier's kernel computes the
    strength: ``w * mu >= threshold`` (a clause) and ``w * (1 - mu) >= threshold`` (a NOT
    clause), each a function of a membership array; none for threshold 0."""
    if threshold <= 0:
        return []
    tests = []
    for w in sorted({float(w) for w in weights if w > 0}):
        tests += [lambda m, w=w: w * m >= threshold, lambda m, w=w: w * (1.0 - m) >= threshold]
    return tests


def _holds(term, test, x: float) -> bool:
    """``test``'s answer for the term's membership at ``x``."""
    return bool(test(term.membership(np.array([x])))[0])


def _pwl_points(term, tests) -> list[float]:
    """Vertices of a piecewise-linear term, and on each sloped side the adjacent pair of
    floats between which one of ``tests`` changes (exact)."""
    vs = vertices(term)
    out = [x for x, _ in vs]
    for (x0, y0), (x1, y1) in zip(vs, vs[1:]):
        if y0 == y1 or x0 == x1:
            continue
        for test in tests:
            a, b, first = x0, x1, _holds(term, test, x0)
            if _holds(term, test, x1) == first:
                continue
            while True:  # halves [a, b] until a and b are adjacent floats
                m = 0.5 * (a + b)
                if not a < m < b:
                    break
                a, b = (m, b) if _holds(term, test, m) == first else (a, m)
            out += [a, b]
    return out


def _characteristic(term) -> list[float]:
    """Places where a smooth term changes fast: centres, vertices, centre +- k widths."""
    p, kind = term.params, term.kind
    if kind in ("gaussmf", "gbellmf"):
        width, centre = (p[0], p[1]) if kind == "gaussmf" else (abs(p[0]), p[2])
        return [centre + k * width for k in (-8, -4, -2, -1, -0.5, 0, 0.5, 1, 2, 4, 8)]
    if kind == "gauss2mf":
        return [c + k * s for s, c in ((p[0], p[1]), (p[2], p[3])) for k in (-8, -4, -2, -1, 0, 1, 2, 4, 8)]
    if kind in ("sigmf", "dsigmf", "psigmf"):
        out = []
        for a, c in zip(p[0::2], p[1::2]):
            out += [c] if a == 0 else [c + k / abs(a) for k in (-40, -20, -8, -4, -2, -1, 0, 1, 2, 4, 8, 20, 40)]
        return out
    return list(p)  # smf, zmf, pimf: vertices


def _smooth_points(term, lo: float, hi: float, tests, tol: float) -> list[float]:
    """Where a smooth term's clause truth values change on [lo, hi], bisected to ``tol``."""
    grid = np.concatenate([np.linspace(lo, hi, SAMPLES),
                           [x for x in _characteristic(term) if lo < x < hi]])
    grid = np.unique(grid)
    mu = term.membership(grid)
    out = []
    for test in [lambda m: m > 0.0, lambda m: m < 1.0, *tests]:
        truth = test(mu)
        for j in np.flatnonzero(truth[1:] != truth[:-1]):
            a, b = grid[j], grid[j + 1]
            ta = truth[j]
            for _ in range(BISECTIONS):
                if b - a <= tol:
                    break
                m = 0.5 * (a + b)
                if test(term.membership(np.array([m])))[0] == ta:
                    a = m
                else:
                    b = m
            out += [a, b] if b > a else [a]
    return out


@dataclass(frozen=True)
class Axis:
    """One input's critical points and elements (module docstring).

    Attributes
    ----------
    name : str
    lo, hi : float
        The input's range.
    points : ndarray (n_points,)
        Sorted critical points, ``lo`` first and ``hi`` last.
    exact : bool
        Every point is exact (all the input's terms are piecewise linear).
    """

    name: str
    lo: float
    hi: float
    points: np.ndarray
    exact: bool

    @property
    def n_elements(self) -> int:
        return 2 * self.points.shape[0] - 1

    @property
    def representatives(self) -> np.ndarray:
        """(n_elements,) a point of each element: the point itself, or an interval's midpoint."""
        p = self.points
        reps = np.empty(self.n_elements)
        reps[0::2] = p
        reps[1::2] = 0.5 * (p[:-1] + p[1:])
        return reps

    @property
    def lengths(self) -> np.ndarray:
        """(n_elements,) 0 for a point, the length of an interval."""
        lengths = np.zeros(self.n_elements)
        lengths[1::2] = np.diff(self.points)
        return lengths

    def element_bounds(self, first: int, last: int) -> tuple[float, float, bool, bool]:
        """``(lo, hi, lo_closed, hi_closed)`` of the union of elements ``first..last``."""
        p = self.points
        lo = p[first // 2]
        hi = p[last // 2] if last % 2 == 0 else p[last // 2 + 1]
        return float(lo), float(hi), bool(first % 2 == 0), bool(last % 2 == 0)


def build_axis(var, tests, tol: float) -> Axis:
    """The :class:`Axis` of input ``var``.

    ``tests`` are the clause tests whose answers cut the axis besides ``mu > 0`` and
    ``mu < 1`` (:func:`level_tests`); ``tol`` is the bisection tolerance for smooth terms, as
    a fraction of the range.
    """
    lo, hi = var.range
    found = [lo, hi]
    exact = True
    for term in var.terms:
        if term.kind in PIECEWISE_LINEAR:
            found += _pwl_points(term, tests)
        else:
            exact = False
            found += _smooth_points(term, lo, hi, tests, tol * (hi - lo))
    points = np.unique(np.array([x for x in found if lo <= x <= hi and math.isfinite(x)], dtype=np.float64))
    return Axis(var.name, lo, hi, points, exact)
