"""Linguistic variables and their terms."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from .errors import RuleBaseError
from .membership import check_params, resolve_kind

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
