"""Coverage: where in the input box no rule fires, or the strongest rule fires below a threshold.

The box is cut into cells (:mod:`fuzzcore.verification.cells`); the strongest weighted firing
strength is computed at one representative point per cell, which decides the whole cell:

- threshold 0 ("does any rule fire?"): exact for piecewise-linear terms, whatever the
  ``and``/``or`` methods (a product or probor of clauses is positive exactly when a min or max
  of them is); for smooth terms the cell boundaries are bisected to ``tol`` of the range;
- threshold > 0 with ``and = min`` and ``or = max``: the same (the level crossings are cell
  boundaries too);
- threshold > 0 with ``prod`` or ``probor``: a product of clauses can cross the threshold
  inside a cell, so every axis is also cut at :data:`SUBDIVISIONS` uniform points and the
  answer is sampled at cell centres (the report says so).

Uncovered cells are merged into boxes (:class:`Region`), their share of the box volume
summed exactly; lower-dimensional regions (a point or line where nothing fires between two
terms that only touch) have share 0 but are reported too.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._kernels import strongest_per_cell
from .cells import Axis, build_axis, level_tests

#: uniform cuts per axis when a threshold meets prod/probor (coverage is then sampled)
SUBDIVISIONS = 64


@dataclass(frozen=True)
class Cells:
    """The cell decomposition of a system's input box and the firing strengths on it.

    Attributes
    ----------
    axes : tuple of Axis
    strongest : ndarray, shape (n_elements of each axis)
        The strongest weighted firing strength at each cell's representative point.
    rule_max : ndarray (n_rules,)
        Each rule's largest strength over the cells (0: it fires nowhere in the box).
    method : str
        How exact the decomposition is, in words.
    exact : bool
        No bisection tolerance and no sampling involved.
    """

    axes: tuple[Axis, ...]
    strongest: np.ndarray
    rule_max: np.ndarray
    method: str
    exact: bool

    @property
    def n_cells(self) -> int:
        return int(self.strongest.size)

    def volumes(self) -> np.ndarray:
        """Each cell's share of the box volume (0 for a lower-dimensional cell)."""
        share = np.ones(())
        for axis in self.axes:
            share = np.multiply.outer(share, axis.lengths / (axis.hi - axis.lo))
        return share


def decompose(fis, threshold: float, tol: float, max_cells: int) -> Cells:
    """Cut ``fis``'s input box into cells and compute the strongest firing strength on each.

    Parameters
    ----------
    fis : FuzzySystem
    threshold : float in [0, 1]
        Strength levels below which a point counts as uncovered (0: no rule fires).
    tol : float
        Bisection tolerance for smooth terms, as a fraction of each input's range.
    max_cells : int
        Refuse (``ValueError``) a decomposition with more cells.
    """
    weights = np.array([r.weight for r in fis.rules])
    tests = level_tests(weights, threshold)
    axes = [build_axis(var, tests, tol) for var in fis.inputs]
    exact_levels = threshold == 0 or (fis.and_method == "min" and fis.or_method == "max")
    if not exact_levels:
        axes = [Axis(a.name, a.lo, a.hi, np.unique(np.concatenate([a.points, np.linspace(a.lo, a.hi,
                                                                                         SUBDIVISIONS + 1)])),
                     a.exact) for a in axes]
    shape = tuple(a.n_elements for a in axes)
    n_cells = math.prod(shape)
    if n_cells > max_cells:
        raise ValueError(f"the input box of {fis.name!r} has {n_cells} cells ({' x '.join(map(str, shape))} "
                         f"elements per input), more than max_cells = {max_cells}; raise max_cells "
                         "(memory: 8 bytes a cell)")
    tables, offsets = [], []
    for axis, var in zip(axes, fis.inputs):
        offsets.append(sum(t.size for t in tables))
        reps = axis.representatives
        table = np.stack([term.membership(reps) for term in var.terms], axis=1) if var.terms \
            else np.zeros((reps.shape[0], 0))
        tables.append(table.ravel())
    ante = np.array([r.antecedent for r in fis.rules], dtype=np.int64).reshape(len(fis.rules), len(fis.inputs))
    strongest = np.empty(n_cells)
    rule_max = np.empty(len(fis.rules))
    strongest_per_cell(np.concatenate(tables), np.array(offsets, dtype=np.int64),
                       np.array([len(v.terms) for v in fis.inputs], dtype=np.int64),
                       np.array(shape, dtype=np.int64), ante, weights,
                       np.array([r.connective == "or" for r in fis.rules], dtype=np.int64),
                       fis.and_method == "prod", fis.or_method == "probor", strongest, rule_max)
    smooth = not all(a.exact for a in axes)
    if not exact_levels:
        method = (f"sampled: and = {fis.and_method}, or = {fis.or_method} with a threshold; cell centres after "
                  f"cutting each input at {SUBDIVISIONS + 1} uniform points as well")
    elif smooth:
        method = f"cell boundaries of smooth terms bisected to {tol:g} of each range"
    else:
        method = "exact (piecewise-linear terms)"
    return Cells(tuple(axes), strongest.reshape(shape), rule_max, method, bool(exact_levels and not smooth))


@dataclass(frozen=True)
class Region:
    """A box of the input space where no rule fires (or none reaches the threshold).

    Attributes
    ----------
    bounds : dict
        input name -> ``(lo, hi, lo_closed, hi_closed)``.
    share : float
        Share of the input box's volume (0 for a point, line, ... of lower dimension).
    example : dict
        input name -> value of a point inside the region.
    """

    bounds: dict
    share: float
    example: dict

    @property
    def dimension(self) -> int:
        return sum(1 for lo, hi, *_ in self.bounds.values() if hi > lo)

    def describe(self) -> str:
        parts = []
        for name, (lo, hi, lc, hc) in self.bounds.items():
            parts.append(f"{name} = {lo:.6g}" if lo == hi else
                         f"{name} in {'[' if lc else '('}{lo:.6g}, {hi:.6g}{']' if hc else ')'}")
        return ", ".join(parts)

    def to_dict(self) -> dict:
        return {"bounds": {k: {"lo": lo, "hi": hi, "lo_closed": lc, "hi_closed": hc}
                           for k, (lo, hi, lc, hc) in self.bounds.items()},
                "share": self.share, "dimension": self.dimension, "example": self.example}


@dataclass(frozen=True)
class Coverage:
    """Where the strongest rule fires at most/below ``threshold`` (see the module docstring).

    Attributes
    ----------
    threshold : float
    method : str
    exact : bool
    uncovered_share : float
        Share of the box volume that is uncovered (exact up to the method).
    n_uncovered_cells : int
        Cells uncovered, including lower-dimensional ones.
    regions : tuple of Region
        The uncovered cells merged into boxes, largest share first (at most ``max_regions``).
    complete : bool
        ``regions`` lists every uncovered cell.
    n_cells : int
    """

    threshold: float
    method: str
    exact: bool
    uncovered_share: float
    n_uncovered_cells: int
    regions: tuple[Region, ...]
    complete: bool
    n_cells: int

    @property
    def covered(self) -> bool:
        return self.n_uncovered_cells == 0

    def to_dict(self) -> dict:
        return {"threshold": self.threshold, "method": self.method, "exact": self.exact,
                "covered": self.covered, "uncovered_share": self.uncovered_share,
                "n_uncovered_cells": self.n_uncovered_cells, "n_cells": self.n_cells,
                "regions": [r.to_dict() for r in self.regions], "regions_complete": self.complete}


def uncovered_mask(cells: Cells, threshold: float) -> np.ndarray:
    """Cells whose strongest strength is 0 (threshold 0) or below ``threshold``."""
    s = cells.strongest
    return ~(s > 0.0) if threshold == 0 else ~(s >= threshold)


def coverage(cells: Cells, threshold: float, max_regions: int = 20) -> Coverage:
    """The :class:`Coverage` of a decomposition at ``threshold``."""
    mask = uncovered_mask(cells, threshold)
    volumes = cells.volumes()
    regions, remaining = [], mask.copy()
    while remaining.any() and len(regions) < max_regions:
        start = np.unravel_index(int(np.argmax(remaining)), remaining.shape)
        lo, hi = list(start), list(start)
        for axis in range(remaining.ndim):
            while hi[axis] + 1 < remaining.shape[axis]:
                slab = tuple(slice(hi[a] + 1, hi[a] + 2) if a == axis else slice(lo[a], hi[a] + 1)
                             for a in range(remaining.ndim))
                if not remaining[slab].all():
                    break
                hi[axis] += 1
        box = tuple(slice(l, h + 1) for l, h in zip(lo, hi))
        remaining[box] = False
        bounds, example = {}, {}
        for a, axis in enumerate(cells.axes):
            b = axis.element_bounds(lo[a], hi[a])
            bounds[axis.name] = b
            example[axis.name] = 0.5 * (b[0] + b[1])
        regions.append(Region(bounds, float(volumes[box].sum()), example))
    regions.sort(key=lambda r: (-r.share, -r.dimension))
    return Coverage(threshold=threshold, method=cells.method, exact=cells.exact,
                    uncovered_share=float(volumes[mask].sum()), n_uncovered_cells=int(mask.sum()),
                    regions=tuple(regions), complete=bool(not remaining.any()), n_cells=cells.n_cells)
