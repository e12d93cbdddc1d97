"""Rules: MATLAB's index form, and the readable text form used in YAML rule bases.

A rule is stored as MATLAB stores it: one integer per input (0 = don't care, k = term k,
-k = NOT term k, 1-based) and one per output, a weight in [0, 1] and a connective joining
the antecedent clauses (``and`` or ``or``; one connective per rule, as in MATLAB).

Text form::

    if rdd is medium and iou is not low then risk is medium

Inputs a rule does not mention are "don't care". Several outputs are assigned with ``and``
after ``then`` (``then risk is high and speed is low``). Mixing ``and`` and ``or`` in one
antecedent, parentheses, and mentioning an input twice are refused: MATLAB's rule form has
no way to say them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from .errors import RuleBaseError
from .variables import Variable

CONNECTIVES = ("and", "or")


@dataclass(frozen=True)
class Rule:
    """One rule in MATLAB's index form.

    Parameters
    ----------
    antecedent : tuple of int, one per input
        0 = don't care, k = the input's k-th term (1-based), -k = NOT that term.
    consequent : tuple of int, one per output
        0 = the rule does not set this output, k / -k as for the antecedent.
    weight : float in [0, 1]
        Multiplies the rule's firing strength.
    connective : {"and", "or"}
        How the antecedent's clauses combine.
    """

    antecedent: tuple[int, ...]
    consequent: tuple[int, ...]
    weight: float = 1.0
    connective: str = "and"

    def __post_init__(self) -> None:
        object.__setattr__(self, "antecedent", tuple(int(v) for v in self.antecedent))
        object.__setattr__(self, "consequent", tuple(int(v) for v in self.consequent))
        object.__setattr__(self, "weight", float(self.weight))
        if not (math.isfinite(self.weight) and 0.0 <= self.weight <= 1.0):
            raise RuleBaseError(f"rule weight {self.weight!r}: expected a number in [0, 1]")
        if self.connective not in CONNECTIVES:
            raise RuleBaseError(f"rule connective {self.connective!r}: expected 'and' or 'or'")

    def check(self, inputs: Sequence[Variable], outputs: Sequence[Variable]) -> None:
        """Raise :class:`RuleBaseError` if an index does not name a term of its variable."""
        for kind, indices, variables in (
            ("antecedent", self.antecedent, inputs),
            ("consequent", self.consequent, outputs),
        ):
            if len(indices) != len(variables):
                raise RuleBaseError(
                    f"rule {kind} has {len(indices)} entries, expected {len(variables)} (one per "
                    f"{'input' if kind == 'antecedent' else 'output'})"
                )
            for index, var in zip(indices, variables):
                if abs(index) > len(var.terms):
                    raise RuleBaseError(
                        f"rule {kind} index {index} for {var.name!r}: expected 0 or +-1..+-{len(var.terms)}"
                    )
        if not any(self.consequent):
            raise RuleBaseError("rule sets no output; expected at least one output term")


def _clause(words: list[str], variables: Sequence[Variable], where: str) -> tuple[int, int]:
    """Parse ``VAR is [not] TERM`` into (variable position, signed 1-based term index)."""
    if len(words) not in (3, 4) or words[1] != "is" or (len(words) == 4 and words[2] != "not"):
        raise RuleBaseError(f"{where}: {' '.join(words)!r} is not of the form 'VARIABLE is [not] TERM'")
    name, term = words[0], words[-1]
    for position, var in enumerate(variables):
        if var.name == name:
            try:
                index = var.term_index(term)
            except KeyError:
                names = ", ".join(t.name for t in var.terms)
                raise RuleBaseError(f"{where}: {name!r} has no term {term!r}; its terms are: {names}") from None
            return position, -index if len(words) == 4 else index
    names = ", ".join(v.name for v in variables)
    raise RuleBaseError(f"{where}: unknown variable {name!r}; expected one of: {names}")


def parse_rule(text: str, inputs: Sequence[Variable], outputs: Sequence[Variable],
               weight: float = 1.0) -> Rule:
    """Parse the text form of a rule (see the module docstring) into a :class:`Rule`."""
    if not isinstance(text, str):
        raise RuleBaseError(f"rule {text!r}: expected text like 'if X is a then Y is b'")
    words = text.split()
    where = f"rule {text!r}"
    if "(" in text or ")" in text:
        raise RuleBaseError(f"{where}: parentheses are not supported (one connective per rule, as in MATLAB)")
    if not words or words[0] != "if" or words.count("then") != 1:
        raise RuleBaseError(f"{where}: expected 'if CLAUSE [and|or CLAUSE ...] then OUTPUT is TERM'")
    then = words.index("then")
    condition, conclusion = words[1:then], words[then + 1:]
    used = {w for w in condition if w in CONNECTIVES}
    if len(used) > 1:
        raise RuleBaseError(f"{where}: mixes 'and' and 'or'; MATLAB rules have one connective each")
    connective = used.pop() if used else "and"

    antecedent = [0] * len(inputs)
    for clause in _split(condition, connective, where):
        position, index = _clause(clause, inputs, where)
        if antecedent[position]:
            raise RuleBaseError(f"{where}: input {inputs[position].name!r} appears twice")
        antecedent[position] = index
    consequent = [0] * len(outputs)
    for clause in _split(conclusion, "and", where):
        position, index = _clause(clause, outputs, where)
        if consequent[position]:
            raise RuleBaseError(f"{where}: output {outputs[position].name!r} is assigned twice")
        consequent[position] = index
    try:
        return Rule(tuple(antecedent), tuple(consequent), weight, connective)
    except RuleBaseError as exc:
        raise RuleBaseError(f"{where}: {exc.detail}") from None


def _split(words: list[str], connective: str, where: str) -> list[list[str]]:
    clauses, current = [], []
    for word in words:
        if word == connective:
            clauses.append(current)
            current = []
        else:
            current.append(word)
    clauses.append(current)
    if any(not c for c in clauses):
        raise RuleBaseError(f"{where}: a clause is missing around {connective!r} or 'then'")
    return clauses


def format_rule(rule: Rule, inputs: Sequence[Variable], outputs: Sequence[Variable],
                display: bool = False) -> str:
    """The text form of ``rule`` (weight not included). Inverse of :func:`parse_rule`.

    A rule whose antecedent is all "don't care" has no text form and raises, unless
    ``display`` asks for a description to show (``always then ...``), which is not parseable.
    """
    def clauses(indices: Sequence[int], variables: Sequence[Variable]) -> list[str]:
        out = []
        for index, var in zip(indices, variables):
            if index:
                negation = "not " if index < 0 else ""
                out.append(f"{var.name} is {negation}{var.terms[abs(index) - 1].name}")
        return out

    condition = clauses(rule.antecedent, inputs)
    conclusion = " and ".join(clauses(rule.consequent, outputs))
    if not condition:
        if display:
            return f"always then {conclusion}"
        raise RuleBaseError("a rule with every input 'don't care' has no text form")
    return f"if {f' {rule.connective} '.join(condition)} then {conclusion}"
