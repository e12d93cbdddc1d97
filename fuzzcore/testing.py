"""fuzzcore.testing: property-based testing of your own rule bases.

Needs hypothesis (``pip install 'fuzzrisk[test]'``); ``import fuzzcore`` alone never imports it.

Strategies:

- :func:`inputs` -- input tuples of a given system: inside its box, on its terms'
  breakpoints, at and beyond the edges, with NaN and infinities;
- :func:`systems` -- random valid Mamdani systems (:func:`variables`, :func:`term_params`
  build their parts), drawn without filtering.

Assertions (plain functions; an ``AssertionError`` says what failed and where):
:func:`assert_in_range`, :func:`assert_monotone`, :func:`assert_covered`,
:func:`assert_nan_propagates`, :func:`assert_matches_reference`.

Example (a test file of your own)::

    import fuzzcore
    from fuzzcore.testing import assert_covered, assert_in_range, assert_nan_propagates, inputs
    from hypothesis import given

    FIS = fuzzcore.load("rules/mine.yaml")

    def test_every_input_fires_a_rule():
        assert_covered(FIS)

    @given(inputs(FIS, "any"))
    def test_outputs_stay_in_range(x):
        assert_in_range(FIS, [x])

    @given(inputs(FIS, "inside"))
    def test_nan_propagates(x):
        assert_nan_propagates(FIS, x)
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

try:
    from hypothesis import strategies as st
except ImportError as exc:  # pragma: no cover - depends on the environment
    raise ImportError("fuzzcore.testing needs hypothesis: pip install 'fuzzrisk[test]' "
                      "(or pip install hypothesis)") from exc

from .rules import Rule
from .system import FuzzySystem
from .variables import Term, Variable
from .verification.cells import vertices
from .verification.coverage import coverage, decompose
from .verification.surface import monotonicity, sample_lines

__all__ = ["INPUT_KINDS", "PIECEWISE", "assert_covered", "assert_in_range", "assert_matches_reference",
           "assert_monotone", "assert_nan_propagates", "inputs", "systems", "term_params", "variables"]

#: membership-function kinds of inputs and Mamdani outputs
INPUT_KINDS = ("trimf", "trapmf", "gaussmf", "gauss2mf", "gbellmf", "sigmf", "dsigmf", "psigmf",
               "smf", "zmf", "pimf", "linsmf", "linzmf")
#: the piecewise-linear ones (coverage is exact for these)
PIECEWISE = ("trimf", "trapmf", "linsmf", "linzmf")
#: where :func:`inputs` draws from
WHERE = ("inside", "breakpoints", "edges", "nonfinite", "any")

_width = st.floats(0.05, 1.0, allow_nan=False)


# --------------------------------------------------------------------------- strategies
@st.composite
def term_params(draw, kind: str, lo: float = -1.0, hi: float = 1.0):
    """Valid parameters of ``kind`` with features inside [lo, hi] (sorted draws, no filter)."""
    span = hi - lo

    def points(n):
        return sorted(draw(st.lists(st.floats(lo, hi), min_size=n, max_size=n)))

    if kind in ("trimf", "pimf", "trapmf", "smf", "zmf", "linsmf", "linzmf"):
        n = {"trimf": 3, "trapmf": 4, "pimf": 4}.get(kind, 2)
        return points(n)
    if kind == "gaussmf":
        return [draw(_width) * span, draw(st.floats(lo, hi))]
    if kind == "gauss2mf":
        c1, c2 = points(2)
        return [draw(_width) * span, c1, draw(_width) * span, c2]
    if kind == "gbellmf":
        return [draw(_width) * span, draw(st.floats(0.5, 4.0)), draw(st.floats(lo, hi))]
    slope = st.floats(-20.0, 20.0).map(lambda a: a / span)
    if kind == "sigmf":
        return [draw(slope), draw(st.floats(lo, hi))]
    return [draw(slope), draw(st.floats(lo, hi)), draw(slope), draw(st.floats(lo, hi))]


@st.composite
def variables(draw, name: str, kinds=INPUT_KINDS, min_terms=1, max_terms=4):
    """A variable called ``name`` with a random range and 1-4 random valid terms of ``kinds``."""
    lo = draw(st.floats(-2.0, 0.0))
    hi = lo + draw(st.floats(0.5, 3.0))
    n = draw(st.integers(min_terms, max_terms))
    terms = []
    for k in range(n):
        kind = draw(st.sampled_from(kinds))
        terms.append(Term(f"t{k}", kind, draw(term_params(kind, lo, hi))))
    return Variable(name, (lo, hi), tuple(terms))


@st.composite
def systems(draw, kinds=INPUT_KINDS, max_inputs=3, max_rules=8):
    """Random valid single-output Mamdani systems (centroid) with inputs ``x0, x1, ...``.

    Every rule mentions at least one input, so every system has a text form (saves as YAML).
    """
    n_in = draw(st.integers(1, max_inputs))
    inputs_ = [draw(variables(f"x{i}", kinds)) for i in range(n_in)]
    output = draw(variables("y", kinds))
    rules = []
    for _ in range(draw(st.integers(1, max_rules))):
        ante = [draw(st.integers(-len(v.terms), len(v.terms))) for v in inputs_]
        if not any(ante):
            ante[0] = draw(st.integers(1, len(inputs_[0].terms)))
        rules.append(Rule(tuple(ante), (draw(st.integers(1, len(output.terms))),),
                          draw(st.sampled_from((1.0, 0.5))), draw(st.sampled_from(("and", "or")))))
    return FuzzySystem(name="random", inputs=tuple(inputs_), outputs=(output,), rules=tuple(rules),
                       and_method=draw(st.sampled_from(("min", "prod"))),
                       or_method=draw(st.sampled_from(("max", "probor"))),
                       implication=draw(st.sampled_from(("min", "prod"))),
                       aggregation=draw(st.sampled_from(("max", "sum"))))


def _breakpoints(var) -> list[float]:
    """The range ends, every piecewise-linear vertex and smooth-term parameter inside the range,
    and one ulp to either side of each."""
    lo, hi = var.range
    points = {lo, hi}
    for term in var.terms:
        points |= {x for x, _ in vertices(term)} if term.kind in PIECEWISE else set(term.params)
    points = {p for p in points if lo <= p <= hi}
    near = {float(np.nextafter(p, d)) for p in points for d in (-np.inf, np.inf)}
    return sorted(p for p in points | near if lo <= p <= hi)


def inputs(fis: FuzzySystem, where: str = "any"):
    """A strategy of input tuples (one float per input, declared order) of ``fis``.

    Parameters
    ----------
    where : {"inside", "breakpoints", "edges", "nonfinite", "any"}
        ``inside``: anywhere in the box; ``breakpoints``: every input on a range end, a term
        vertex or parameter, or one ulp from one; ``edges``: the box's edges, corners and
        beyond (up to a range's width outside, and +-1e300); ``nonfinite``: at least one
        NaN or infinity, the rest inside; ``any``: all of these.
    """
    if not isinstance(fis, FuzzySystem):
        raise TypeError(f"fis: expected a fuzzcore.FuzzySystem, got {type(fis).__name__}")
    if where not in WHERE:
        raise ValueError(f"where = {where!r}: expected one of {', '.join(WHERE)}")
    inside = [st.floats(*v.range) for v in fis.inputs]
    if where == "inside":
        return st.tuples(*inside)
    if where == "breakpoints":
        return st.tuples(*[st.sampled_from(_breakpoints(v)) for v in fis.inputs])
    if where == "edges":
        edges = []
        for v in fis.inputs:
            lo, hi = v.range
            span = hi - lo
            edges.append(st.one_of(st.sampled_from((lo, hi, -1e300, 1e300)), st.floats(lo - span, lo),
                                   st.floats(hi, hi + span)))
        return st.tuples(*edges)
    if where == "nonfinite":
        special = st.sampled_from((math.nan, math.inf, -math.inf))

        @st.composite
        def draw_nonfinite(draw):
            row = list(draw(st.tuples(*inside)))
            for i in draw(st.sets(st.integers(0, len(row) - 1), min_size=1)):
                row[i] = draw(special)
            return tuple(row)

        return draw_nonfinite()
    return st.one_of(*[inputs(fis, w) for w in WHERE[:-1]])


# --------------------------------------------------------------------------- assertions
def _rows(fis, X) -> np.ndarray:
    X = np.asarray(X, dtype=np.float64)
    if X.ndim == 1:
        X = X[None]
    if X.ndim != 2 or X.shape[1] != len(fis.inputs):
        raise ValueError(f"X has shape {X.shape}, expected (n_samples, {len(fis.inputs)}) with columns "
                         f"{', '.join(fis.input_names)}")
    return X


def _where(fis, x) -> str:
    return ", ".join(f"{n} = {v!r}" for n, v in zip(fis.input_names, np.asarray(x).tolist()))


def assert_in_range(fis: FuzzySystem, X, *, atol: float = 0.0) -> None:
    """Every output at every row of ``X`` (n_samples, n_inputs) without a NaN input lies in its
    declared range (within ``atol``); a NaN output there is allowed only with
    ``no_rule_fired = "nan"``."""
    X = _rows(fis, X)
    Y = fis.evaluate(X)
    rows = ~np.isnan(X).any(axis=1)
    for o, var in enumerate(fis.outputs):
        lo, hi = var.range
        y = Y[rows, o]
        bad = ~((y >= lo - atol) & (y <= hi + atol))
        if fis.no_rule_fired == "nan":
            bad &= ~np.isnan(y)
        if bad.any():
            i = int(np.flatnonzero(rows)[np.argmax(bad)])
            raise AssertionError(f"{fis.name}: output {var.name} = {Y[i, o]!r} at ({_where(fis, X[i])}) is "
                                 f"outside its range [{lo:g}, {hi:g}]")


def assert_monotone(fis: FuzzySystem, input: str, direction: int = 1, *, tol: float = 1e-6,
                    budget: int = 50_000, seed: int | None = 0) -> None:
    """Every output does not decrease (``direction`` +1) or increase (-1) along ``input``.

    Searched as :func:`fuzzcore.verify` does (lines through the cell structure, refined
    locally); a drop above ``tol`` times the output's range fails, naming the two points.
    """
    if input not in fis.input_names:
        raise ValueError(f"input {input!r}: expected one of {', '.join(fis.input_names)}")
    if direction not in (1, -1):
        raise ValueError(f"direction = {direction!r}: expected +1 or -1")
    cells = decompose(fis, 0.0, 1e-9, 10_000_000)
    axis = fis.input_names.index(input)
    lines = sample_lines(fis, cells.axes, axis, budget, np.random.default_rng(seed))
    for m in monotonicity(fis, cells.axes, lines, direction, tol, 5):
        if not m.holds:
            verb = "drops" if direction > 0 else "rises"
            raise AssertionError(f"{fis.name}: {m.output} {verb} by {m.drop:.6g} along {input}: "
                                 f"{m.values[0]!r} at ({_where(fis, list(m.start.values()))}), "
                                 f"{m.values[1]!r} at ({_where(fis, list(m.end.values()))})")


def assert_covered(fis: FuzzySystem, threshold: float = 0.0) -> None:
    """Some rule fires (at ``threshold`` or more, if > 0) at every point of the input box
    (exact for piecewise-linear terms; :mod:`fuzzcore.verification.coverage`)."""
    found = coverage(decompose(fis, threshold, 1e-9, 10_000_000), threshold)
    if not found.covered:
        regions = "; ".join(r.describe() for r in found.regions[:5])
        raise AssertionError(f"{fis.name}: no rule fires{'' if threshold == 0 else f' at {threshold:g}'} on "
                             f"{100 * found.uncovered_share:.4g} % of the input box: {regions}")


def assert_nan_propagates(fis: FuzzySystem, x) -> None:
    """With any one input of the point ``x`` (n_inputs,) set to NaN, and with all of them,
    every output is NaN."""
    x = _rows(fis, x)[0]
    trials = []
    for i in range(x.shape[0]):
        row = x.copy()
        row[i] = math.nan
        trials.append(row)
    trials.append(np.full_like(x, math.nan))
    Y = fis.evaluate(np.array(trials))
    for row, y in zip(trials, Y):
        if not np.isnan(y).all():
            raise AssertionError(f"{fis.name}: outputs {y.tolist()} at ({_where(fis, row)}): expected NaN")


def assert_matches_reference(fis: FuzzySystem, X, reference: Callable | np.ndarray, *, rtol: float = 1e-9,
                             atol: float = 1e-12) -> None:
    """``fis.evaluate(X)`` equals ``reference`` (an array (n_samples, n_outputs), or a callable
    taking ``X`` and returning one) within ``rtol``/``atol``; NaN must match NaN."""
    X = _rows(fis, X)
    expected = np.asarray(reference(X) if callable(reference) else reference, dtype=np.float64)
    got = fis.evaluate(X)
    if expected.shape != got.shape:
        expected = expected.reshape(got.shape) if expected.size == got.size else expected
    if expected.shape != got.shape:
        raise ValueError(f"reference has shape {expected.shape}, expected {got.shape}")
    close = np.isclose(got, expected, rtol=rtol, atol=atol, equal_nan=True)
    if not close.all():
        error = np.where(close, 0.0, np.abs(got - expected))
        error = np.where(np.isnan(error), np.inf, error)
        i, o = np.unravel_index(int(np.argmax(error)), error.shape)
        raise AssertionError(f"{fis.name}: {int((~close).sum())} of {close.size} outputs differ from the reference; "
                             f"worst: {fis.outputs[o].name} = {got[i, o]!r}, reference {expected[i, o]!r} at "
                             f"({_where(fis, X[i])})")
