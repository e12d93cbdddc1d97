"""Linguistic variables and their terms."""
from __future__ import annotations

import math
import numbers
import re
from dataclasses import dataclass

import numpy as np

from . import _kernels as K
from .errors import RuleBaseError
from .membership import MAX_PARAMS, check_params, resolve_kind

#: names usable in rule text: a letter or underscore, then letters, digits, ``_``, ``-`` or ``.``
NAME_PATTERN = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*")
#: words of the rule language, which cannot be names
RESERVED = frozenset({"if", "then", "is", "not", "and", "or"})


def check_name(name: object, what: str) -> str:
    """Return ``name`` if usable in rule text, else raise :class:`RuleBaseError` saying why."""
    if not isinstance(name, str) or not NAME_PATTERN.fullmatch(name) or name in RESERVED:
        raise RuleBaseError(
            f"{what} name {name!r} is not usable in rules: expected a letter or '_' then letters, "
            f"digits, '_', '-' or '.', and not one of {sorted(RESERVED)}"
        )
    return name


@dataclass(frozen=True)
class Term:
    """A linguistic term: a name, a membership-function kind (MATLAB name) and its parameters."""

    name: str
    kind: str
    params: tuple[float, ...]

    def __post_init__(self) -> None:
        check_name(self.name, "term")
        kind = resolve_kind(self.kind)
        object.__setattr__(self, "kind", kind.name)
        object.__setattr__(self, "params", tuple(float(p) for p in self.params))

    def membership(self, x):
        """Degree of membership of ``x`` in this term, MATLAB's function of the term's kind.

        Parameters
        ----------
        x : float or array_like of float
            Values of the term's variable, any shape. NaN gives NaN; infinities take the
            function's limits (trimf(+inf) = 0, sigmf(+inf) = 1 for a > 0, ...).

        Returns
        -------
        float for a scalar ``x``, else ndarray of float64 with the shape of ``x``; in [0, 1].

        Raises
        ------
        RuleBaseError
            If the term is a Sugeno output (``constant``, ``linear``: no membership function)
            or its parameters are invalid for its kind.
        TypeError
            If ``x`` is not a real number or an array of real numbers.
        """
        kind = resolve_kind(self.kind)
        if kind.output_only:
            raise RuleBaseError(f"term {self.name!r} ({kind.name}) is a Sugeno output: it has no "
                                "membership function")
        problem = check_params(kind, self.params)
        if problem:
            raise RuleBaseError(f"term {self.name!r} ({kind.name} {list(self.params)}): {problem}")
        scalar = isinstance(x, numbers.Real) and not isinstance(x, bool)
        values = np.asarray(x)
        if values.dtype == bool or values.dtype.kind not in "iuf":
            raise TypeError(f"term {self.name!r}: x must be a real number or an array of real "
                            f"numbers, got {type(x).__name__} of dtype {values.dtype}")
        flat = np.ascontiguousarray(values, dtype=np.float64).ravel()
        params = np.zeros(MAX_PARAMS)
        params[:len(self.params)] = self.params
        out = np.empty_like(flat)
        K.mf_array(kind.code, params, flat, out)
        return float(out[0]) if scalar else out.reshape(values.shape)


@dataclass(frozen=True)
class Variable:
    """An input or output variable: a name, a range ``(lo, hi)`` and its terms, in order.

    Rules refer to terms by their position (1-based, as in MATLAB), so term order matters.
    An input may have no terms (MATLAB allows it; no rule can then use it); an output may not.
    """

    name: str
    range: tuple[float, float]
    terms: tuple[Term, ...]

    def __post_init__(self) -> None:
        check_name(self.name, "variable")
        lo, hi = (float(v) for v in self.range)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise RuleBaseError(f"range [{lo}, {hi}] of {self.name!r}: expected finite lo < hi")
        if not math.isfinite(hi - lo):
            raise RuleBaseError(f"range [{lo}, {hi}] of {self.name!r} is degenerate: its width hi - lo overflows "
                                "to inf")
        object.__setattr__(self, "range", (lo, hi))
        object.__setattr__(self, "terms", tuple(self.terms))

    def term_index(self, name: str) -> int:
        """1-based position of the term called ``name`` (the first, if names repeat)."""
        for i, term in enumerate(self.terms, start=1):
            if term.name == name:
                return i
        raise KeyError(name)

    def check_terms(self, n_inputs: int, is_input: bool) -> None:
        """Validate every term's kind and parameters for this variable's role."""
        if not is_input and not self.terms:
            raise RuleBaseError(f"output {self.name!r} has no terms; expected at least one")
        for term in self.terms:
            kind = resolve_kind(term.kind)
            if is_input and kind.output_only:
                raise RuleBaseError(
                    f"term {term.name!r} of input {self.name!r}: {kind.name} is a Sugeno output kind, "
                    "not usable on an input"
                )
            problem = check_params(kind, term.params, n_inputs)
            if problem:
                raise RuleBaseError(
                    f"term {term.name!r} of {self.name!r} ({kind.name} {list(term.params)}): {problem}"
                )
