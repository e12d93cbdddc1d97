"""Term partitions: is each variable's set of terms a readable partition of its range?

For each input and each Mamdani output:

- **order**: the terms' centres of gravity (over the range) run one way in declared order;
- **coverage of the range**: the intervals where every term is 0, and the smallest largest
  membership ``min_x max_k mu_k(x)`` (epsilon-completeness; 0.5 is the usual requirement);
- **distance from a Ruspini partition**: ``max_x |sum_k mu_k(x) - 1|`` (0: memberships sum
  to one everywhere, as in a strong fuzzy partition);
- **distinguishability**: the Jaccard similarity ``int min / int max`` of each pair of
  neighbouring terms (1: the same term twice); above :data:`SIMILARITY_LIMIT` is reported.

For piecewise-linear terms the minimum and maximum are exact: they are evaluated at every
breakpoint (and one ulp to each side, for jumps), and at every crossing of two terms'
linear pieces; smooth terms add a dense sample (:data:`~fuzzcore.verification.cells.SAMPLES`).
The integrals are trapezoid sums on the same points.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..membership import PIECEWISE_LINEAR
from .cells import SAMPLES, vertices

#: neighbouring terms more similar than this are reported as hard to tell apart
SIMILARITY_LIMIT = 0.5


@dataclass(frozen=True)
class Partition:
    """How one variable's terms partition its range (module docstring).

    Attributes
    ----------
    variable : str
    role : {"input", "output"}
    centres : dict
        term -> centre of gravity over the range (NaN for a term that is 0 on the whole range).
    ordered : bool
    uncovered : tuple of (lo, hi)
        Intervals (closed, possibly single points) of the range where every term is 0.
    min_cover : float
        ``min_x max_k mu_k(x)``, at ``min_cover_at``.
    ruspini : float
        ``max_x |sum_k mu_k(x) - 1|``, at ``ruspini_at``.
    similarity : tuple of (str, str, float)
        Each pair of neighbouring terms (by centre) and its Jaccard similarity.
    exact : bool
        All terms are piecewise linear.
    """

    variable: str
    role: str
    centres: dict
    ordered: bool
    uncovered: tuple
    min_cover: float
    min_cover_at: float
    ruspini: float
    ruspini_at: float
    similarity: tuple
    exact: bool

    @property
    def similar(self) -> tuple:
        return tuple(s for s in self.similarity if s[2] > SIMILARITY_LIMIT)

    @property
    def sound(self) -> bool:
        """Ordered, covering the whole range, no two neighbours alike."""
        return self.ordered and not self.uncovered and not self.similar

    def to_dict(self) -> dict:
        return {"variable": self.variable, "role": self.role, "centres": self.centres, "ordered": self.ordered,
                "uncovered": [list(u) for u in self.uncovered], "min_cover": self.min_cover,
                "min_cover_at": self.min_cover_at, "ruspini_distance": self.ruspini,
                "ruspini_at": self.ruspini_at,
                "similarity": [{"terms": [a, b], "jaccard": s} for a, b, s in self.similarity],
                "similarity_limit": SIMILARITY_LIMIT, "exact": self.exact}


def _points(var) -> np.ndarray:
    """Where to evaluate (module docstring)."""
    lo, hi = var.range
    pwl = [t for t in var.terms if t.kind in PIECEWISE_LINEAR]
    breaks = sorted({x for t in pwl for x, _ in vertices(t) if lo <= x <= hi} | {lo, hi})
    pts = list(breaks) + [np.nextafter(x, -np.inf) for x in breaks] + [np.nextafter(x, np.inf) for x in breaks]
    for u, v in zip(breaks, breaks[1:]):  # crossings of linear pieces inside (u, v)
        a = np.array([t.membership(np.array([np.nextafter(u, np.inf), np.nextafter(v, -np.inf)])) for t in pwl])
        for i in range(len(pwl)):
            for j in range(i + 1, len(pwl)):
                di, dj = a[i, 1] - a[i, 0], a[j, 1] - a[j, 0]
                if di != dj:
                    s = (a[j, 0] - a[i, 0]) / (di - dj)
                    if 0.0 < s < 1.0:
                        pts.append(u + s * (v - u))
    if len(pwl) < len(var.terms):
        pts += np.linspace(lo, hi, SAMPLES).tolist()
    x = np.unique(np.array(pts))
    return x[(x >= lo) & (x <= hi)]


def _integral(y: np.ndarray, x: np.ndarray) -> float:
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def partition(var, role: str) -> Partition:
    """The :class:`Partition` of variable ``var`` (an input or a Mamdani output)."""
    x = _points(var)
    names = [t.name for t in var.terms]
    mu = np.array([t.membership(x) for t in var.terms]) if var.terms else np.zeros((0, x.shape[0]))
    centres = {}
    for name, m in zip(names, mu):
        area = _integral(m, x)
        centres[name] = _integral(m * x, x) / area if area > 0 else math.nan
    c = np.array(list(centres.values()))
    steps = np.diff(c)
    ordered = bool(len(c) < 2 or (np.all(steps > 0) or np.all(steps < 0)))
    top = mu.max(axis=0) if len(names) else np.zeros_like(x)
    uncovered, start = [], None
    for xi, t in zip(x, top):  # runs of zero top membership (x holds every breakpoint)
        if not t > 0:
            start = xi if start is None else start
            end = xi
        elif start is not None:
            uncovered.append((float(start), float(end)))
            start = None
    if start is not None:
        uncovered.append((float(start), float(end)))
    total = np.abs(mu.sum(axis=0) - 1.0)
    order = [names[i] for i in np.argsort(np.where(np.isnan(c), np.inf, c), kind="stable")]
    similarity = []
    for a, b in zip(order, order[1:]):
        ma, mb = mu[names.index(a)], mu[names.index(b)]
        union = _integral(np.maximum(ma, mb), x)
        similarity.append((a, b, _integral(np.minimum(ma, mb), x) / union if union > 0 else 1.0))
    k, r = int(np.argmin(top)), int(np.argmax(total))
    return Partition(var.name, role, centres, ordered, tuple(uncovered), float(top[k]), float(x[k]),
                     float(total[r]), float(x[r]), tuple(similarity),
                     all(t.kind in PIECEWISE_LINEAR for t in var.terms))
