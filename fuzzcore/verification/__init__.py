"""fuzzcore.verification: what a rule base does over its whole input box, before it drives anything.

>>> report = fuzzcore.verify(fis, monotone={"rdd": +1})
>>> print(report)            # readable; report.to_dict() for JSON; report.ok for scripts

One call reports:

- **coverage** (:mod:`.coverage`): the regions where no rule fires (or none reaches a
  threshold), exactly for piecewise-linear terms;
- **monotonicity** (:mod:`.surface`) along declared inputs: the worst violation found;
- the **output range** reached and the **largest slope or jump**;
- **rules** (:mod:`.rules`): never firing, redundant, conflicting, duplicated; unused terms;
- **term partitions** (:mod:`.partitions`): order, coverage of the range, distance from a
  Ruspini partition, distinguishability.
"""
from __future__ import annotations

import math
import numbers
from typing import Mapping

import numpy as np

from ..system import FuzzySystem
from .coverage import Coverage, Region, coverage, decompose
from .partitions import Partition, partition
from .report import OutputRange, Report
from .rules import RuleFindings, check_rules
from .surface import Monotonicity, Steepest, monotonicity, sample_lines, steepest

__all__ = ["Coverage", "Monotonicity", "OutputRange", "Partition", "Region", "Report", "RuleFindings", "Steepest",
           "parse_monotone", "parse_monotone_specs", "verify"]

DIRECTIONS = {"+": 1, "-": -1, "+1": 1, "-1": -1, "up": 1, "down": -1}


def parse_monotone(spec: str) -> tuple[str, int]:
    """``"rdd:+"`` -> ``("rdd", 1)``; directions ``+``/``-`` (or ``+1``/``-1``, ``up``/``down``)."""
    name, sep, direction = str(spec).rpartition(":")
    if not sep or not name or direction not in DIRECTIONS:
        raise ValueError(f"monotone property {spec!r}: expected INPUT:+ or INPUT:- (e.g. rdd:+)")
    return name, DIRECTIONS[direction]


def parse_monotone_specs(specs) -> dict[str, int]:
    """``["iou:-", "rdd:+"]`` -> ``{"iou": -1, "rdd": 1}`` (the command line's ``--monotone``);
    an input named twice is refused."""
    monotone = {}
    for spec in specs:
        name, direction = parse_monotone(spec)
        if name in monotone:
            raise ValueError(f"--monotone names {name!r} twice")
        monotone[name] = direction
    return monotone


def _check_count(name: str, value, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < low:
        raise ValueError(f"{name} = {value!r}: expected an integer >= {low}")
    return int(value)


def _check_fraction(name: str, value, high: float = 1.0) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0.0 <= value <= high:
        raise ValueError(f"{name} = {value!r}: expected a number in [0, {high:g}]")
    return float(value)


def verify(fis: FuzzySystem, monotone: Mapping[str, int] | None = None, *, threshold: float = 0.0,
           tol: float = 1e-9, budget: int = 50_000, refine: int = 5, monotone_tol: float = 1e-6,
           redundancy_tol: float = 1e-6, redundancy_samples: int = 20_000, max_cells: int = 10_000_000,
           max_regions: int = 20, seed: int | None = 0) -> Report:
    """Verify a rule base over its input box (module docstring).

    Parameters
    ----------
    fis : FuzzySystem
    monotone : mapping of str to {+1, -1}, optional
        Inputs along which every output must not decrease (+1) or not increase (-1).
    threshold : float in [0, 1]
        Coverage asks for the strongest rule to fire at least this much (0: at all).
    tol : float
        Bisection tolerance of the cell boundaries of smooth terms, as a fraction of the range.
    budget : int
        System evaluations for the line samples along each input.
    refine : int
        Worst lines refined locally per monotonicity property.
    monotone_tol, redundancy_tol : float
        Output changes at most this fraction of the output's range count as none.
    redundancy_samples : int
        Samples the redundancy check evaluates (drawn from the line samples).
    max_cells : int
        Refuse input boxes cut into more cells than this.
    max_regions : int
        Uncovered regions listed at most.
    seed : int or None
        Seeds the choice of lines and samples when the budget does not cover them all.

    Returns
    -------
    Report
    """
    if not isinstance(fis, FuzzySystem):
        raise TypeError(f"fis: expected a fuzzcore.FuzzySystem, got {type(fis).__name__}")
    monotone = dict(monotone or {})
    for name, direction in monotone.items():
        if name not in fis.input_names:
            raise ValueError(f"monotone: {name!r} is not an input of {fis.name!r}; its inputs are "
                             f"{', '.join(fis.input_names)}")
        if isinstance(direction, bool) or direction not in (1, -1):
            raise ValueError(f"monotone[{name!r}] = {direction!r}: expected +1 (increasing) or -1 (decreasing)")
    threshold = _check_fraction("threshold", threshold)
    tol = _check_fraction("tol", tol, 0.5)
    monotone_tol = _check_fraction("monotone_tol", monotone_tol)
    redundancy_tol = _check_fraction("redundancy_tol", redundancy_tol)
    budget = _check_count("budget", budget, 2)
    refine = _check_count("refine", refine, 0)
    redundancy_samples = _check_count("redundancy_samples", redundancy_samples, 1)
    max_cells = _check_count("max_cells", max_cells, 1)
    max_regions = _check_count("max_regions", max_regions, 0)
    if seed is not None and not isinstance(seed, numbers.Integral):
        raise ValueError(f"seed = {seed!r}: expected an integer or None")
    rng = np.random.default_rng(seed)

    cells = decompose(fis, threshold, tol, max_cells)
    axes = cells.axes
    lines = [sample_lines(fis, axes, a, budget, rng) for a in range(len(axes))]
    n_eval = sum(line.X.shape[0] * line.X.shape[1] for line in lines)
    mono = []
    for name, direction in monotone.items():
        found = monotonicity(fis, axes, lines[fis.input_names.index(name)], direction, monotone_tol, refine)
        line = lines[fis.input_names.index(name)]
        n_eval += sum(m.n_evaluations - line.X.shape[0] * line.X.shape[1] for m in found)
        mono += found
    steep = []
    for line in lines:
        steep += steepest(fis, axes, line, monotone_tol)
    best = {}
    for s in steep:  # the steepest per output over every input: jumps first, then by slope
        key = (s.jump, s.rise if s.jump else s.slope)
        if s.output not in best or key > best[s.output][0]:
            best[s.output] = (key, s)

    X = np.concatenate([line.X.reshape(-1, len(axes)) for line in lines])
    Y = np.concatenate([line.Y.reshape(-1, len(fis.outputs)) for line in lines])
    ranges = []
    for o, var in enumerate(fis.outputs):
        y = Y[:, o]
        if np.isnan(y).all():
            ranges.append(OutputRange(var.name, var.range, math.nan, math.nan, {}, {}))
            continue
        lo, hi = int(np.nanargmin(y)), int(np.nanargmax(y))
        ranges.append(OutputRange(var.name, var.range, float(y[lo]), float(y[hi]),
                                  dict(zip(fis.input_names, X[lo].tolist())),
                                  dict(zip(fis.input_names, X[hi].tolist()))))
    if X.shape[0] > redundancy_samples:
        pick = np.sort(rng.choice(X.shape[0], redundancy_samples, replace=False))
        X, Y = X[pick], Y[pick]
    findings = check_rules(fis, cells.rule_max, X, Y, redundancy_tol)
    parts = [partition(v, "input") for v in fis.inputs]
    if fis.type == "mamdani":
        parts += [partition(v, "output") for v in fis.outputs]
    return Report(
        system=fis.name, inputs={v.name: v.range for v in fis.inputs},
        outputs={v.name: v.range for v in fis.outputs}, n_rules=len(fis.rules),
        coverage=coverage(cells, threshold, max_regions), monotonicity=tuple(mono),
        output_range=tuple(ranges), steepest=tuple(s for _, s in best.values()), rules=findings,
        partitions=tuple(parts), n_evaluations=int(n_eval), seed=seed)
