"""Membership-function kinds: MATLAB names, parameter orders, codes and validation.

Every term is described by its kind and its parameter list, as in MATLAB's Fuzzy Logic
Toolbox, so a term prints, parses and round-trips. The numbers are evaluated by the Numba
kernels in :mod:`fuzzcore._kernels` (``_mf``), which switch on the integer ``code`` below.

=========  ====================  =====================================================
kind       parameters            shape
=========  ====================  =====================================================
trimf      a, b, c               triangle, feet a and c, peak b (a <= b <= c)
trapmf     a, b, c, d            trapezoid, feet a and d, shoulders b and c (sorted)
gaussmf    sigma, c              exp(-(x - c)^2 / (2 sigma^2)), sigma > 0
gauss2mf   sigma1, c1, sigma2, c2  left Gaussian below c1, 1 between, right above c2
gbellmf    a, b, c               1 / (1 + |(x - c) / a|^(2b)), a != 0
sigmf      a, c                  1 / (1 + exp(-a (x - c)))
dsigmf     a1, c1, a2, c2        |sigmf(a1, c1) - sigmf(a2, c2)|
psigmf     a1, c1, a2, c2        sigmf(a1, c1) * sigmf(a2, c2)
smf        a, b                  spline-based S curve from 0 at a to 1 at b (a <= b)
zmf        a, b                  spline-based Z curve from 1 at a to 0 at b (a <= b)
pimf       a, b, c, d            smf(a, b) * zmf(c, d) (a <= b <= c <= d)
linsmf     a, b                  0 below a, linear to 1 at b (a <= b)
linzmf     a, b                  1 below a, linear to 0 at b (a <= b)
constant   p0                    Sugeno output: z = p0
linear     p1, ..., pn, p0       Sugeno output: z = p1 x1 + ... + pn xn + p0
=========  ====================  =====================================================

Where a MATLAB function has a degenerate case (trimf with a == b, smf with a == b, ...) the
kernel follows MATLAB's own code. Readable aliases (``triangle``, ``trapezoid``, ...) are
accepted on input and written back under the MATLAB name.

Parameters the kernels' float64 arithmetic cannot evaluate are refused (:func:`check_params`),
because they would give NaN or a meaningless shape for ordinary inputs:

- every kind but the Sugeno outputs: a parameter beyond +-:data:`POINT_MAX` (half the largest
  float64), where a difference or sum of two parameters (a width ``b - a``, a midpoint
  ``(a + b) / 2``) or ``x - c`` overflows to inf, and ``inf / inf`` is NaN;
- gaussmf, gauss2mf (sigma) and gbellmf (a): a width ``w`` whose ``2 w^2`` is not a positive
  normal float64 (``|w|`` outside [:data:`WIDTH_MIN`, :data:`WIDTH_MAX`]): sigma = 1e-200
  squares to 0 and ``exp(-0 / 0)`` at the centre is NaN; gbellmf's ``(x - c) / a`` overflows
  for every x off the centre.

sigmf, dsigmf and psigmf have no degenerate slope (a = 0 is MATLAB's constant 0.5; any other
finite a is a sigmoid, however steep); vertex kinds need only the bound on points (a zero
width is MATLAB's own degenerate case, above).
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Callable, Sequence


@dataclass(frozen=True)
class MFKind:
    """One membership-function kind: its kernel code, parameter names and validity check.

    ``check(params)`` returns an explanation of what is wrong, or ``None`` when valid.
    ``n_params`` is ``None`` for ``linear``, whose length depends on the number of inputs.
    """

    name: str
    code: int
    params: tuple[str, ...]
    check: Callable[[Sequence[float]], str | None]
    output_only: bool = False

    @property
    def n_params(self) -> int | None:
        return None if self.name == "linear" else len(self.params)


#: largest magnitude of a parameter: differences and sums of two parameters stay finite
POINT_MAX = sys.float_info.max / 2
#: smallest and largest magnitude of a width (sigma, gbellmf's a): 2 w^2 is a positive normal float64
WIDTH_MIN = math.sqrt(sys.float_info.min)
WIDTH_MAX = math.sqrt(sys.float_info.max / 2)


def _sorted(params: Sequence[float]) -> str | None:
    if any(a > b for a, b in zip(params, params[1:])):
        return "parameters must be in non-decreasing order"
    return None


def _width(params: Sequence[float], index: int, name: str) -> str | None:
    w = abs(params[index])
    if not WIDTH_MIN <= w <= WIDTH_MAX:
        return (f"parameter {index + 1} ({name}, a width) = {params[index]!r} is degenerate: 2 {name}^2 must be "
                f"a positive normal float64, so |{name}| must lie in [{WIDTH_MIN:.3g}, {WIDTH_MAX:.3g}]")
    return None


def _positive(*indices: int) -> Callable[[Sequence[float]], str | None]:
    def check(params: Sequence[float]) -> str | None:
        bad = [i for i in indices if not params[i] > 0]
        if bad:
            return f"parameter {bad[0] + 1} (a width) must be > 0"
        for i in indices:
            problem = _width(params, i, "sigma")
            if problem:
                return problem
        return None

    return check


def _nonzero_first(params: Sequence[float]) -> str | None:
    if params[0] == 0:
        return "parameter 1 (a, the width) must be != 0"
    return _width(params, 0, "a")


def _pimf(params: Sequence[float]) -> str | None:
    return _sorted(params)


def _anything(params: Sequence[float]) -> str | None:
    return None


_KINDS = (
    MFKind("trimf", 0, ("a", "b", "c"), _sorted),
    MFKind("trapmf", 1, ("a", "b", "c", "d"), _sorted),
    MFKind("gaussmf", 2, ("sigma", "c"), _positive(0)),
    MFKind("gauss2mf", 3, ("sigma1", "c1", "sigma2", "c2"), _positive(0, 2)),
    MFKind("gbellmf", 4, ("a", "b", "c"), _nonzero_first),
    MFKind("sigmf", 5, ("a", "c"), _anything),
    MFKind("dsigmf", 6, ("a1", "c1", "a2", "c2"), _anything),
    MFKind("psigmf", 7, ("a1", "c1", "a2", "c2"), _anything),
    MFKind("smf", 8, ("a", "b"), _sorted),
    MFKind("zmf", 9, ("a", "b"), _sorted),
    MFKind("pimf", 10, ("a", "b", "c", "d"), _pimf),
    MFKind("linsmf", 11, ("a", "b"), _sorted),
    MFKind("linzmf", 12, ("a", "b"), _sorted),
    MFKind("constant", 20, ("p0",), _anything, output_only=True),
    MFKind("linear", 21, ("p1..pn", "p0"), _anything, output_only=True),
)

#: kind name -> :class:`MFKind`
KINDS: dict[str, MFKind] = {k.name: k for k in _KINDS}

#: readable alias -> MATLAB name
ALIASES: dict[str, str] = {
    "triangle": "trimf",
    "trapezoid": "trapmf",
    "gaussian": "gaussmf",
    "gaussian2": "gauss2mf",
    "bell": "gbellmf",
    "sigmoid": "sigmf",
    "sigmoid_difference": "dsigmf",
    "sigmoid_product": "psigmf",
    "s_shape": "smf",
    "z_shape": "zmf",
    "pi_shape": "pimf",
    "ramp_up": "linsmf",
    "ramp_down": "linzmf",
}

#: kinds whose shape is piecewise linear (the exact centroid integrates these exactly)
PIECEWISE_LINEAR = frozenset({"trimf", "trapmf", "linsmf", "linzmf"})

#: widest parameter list of an input/Mamdani-output kind (rows of the packed parameter array)
MAX_PARAMS = 4


def resolve_kind(name: str) -> MFKind:
    """Return the :class:`MFKind` for a MATLAB name or alias; ``ValueError`` names the choices."""
    key = ALIASES.get(name, name)
    try:
        return KINDS[key]
    except KeyError:
        choices = ", ".join(sorted(KINDS) + sorted(ALIASES))
        raise ValueError(f"unknown membership function {name!r}; expected one of: {choices}") from None


def check_params(kind: MFKind, params: Sequence[float], n_inputs: int | None = None) -> str | None:
    """Explain why ``params`` are invalid for ``kind`` (count, finiteness, shape), or ``None``.

    ``n_inputs`` is needed for ``linear`` (n_inputs + 1 coefficients).
    """
    expected = kind.n_params if kind.n_params is not None else (n_inputs or 0) + 1
    if len(params) != expected:
        names = ", ".join(kind.params) if kind.n_params is not None else f"{expected - 1} coefficients then p0"
        return f"{kind.name} takes {expected} parameters ({names}), got {len(params)}"
    if not all(math.isfinite(p) for p in params):
        return "parameters must be finite numbers"
    if not kind.output_only:
        far = [p for p in params if abs(p) > POINT_MAX]
        if far:
            return (f"parameter {far[0]!r} is degenerate: beyond +-{POINT_MAX:.4g} (half the largest float64) "
                    "differences of parameters overflow")
    return kind.check(params)
