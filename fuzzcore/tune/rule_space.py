"""Rule consequents as one integer vector: which output term each rule concludes.

:class:`RuleSpace` has one slot per (rule, output) pair that a rule sets. A slot's value
is the 1-based index of the output term the rule concludes, or 0 (with ``allow_off``)
for "the rule does not set this output"; a rule that sets no output any more is off,
i.e. it leaves the rule base. Slots sit in rule order, outputs in declared order.

Swarm optimisers move continuous positions; :meth:`RuleSpace.round` maps a position to
the nearest integer value (``floor(x + 0.5)``, clipped to the slot's choices), so the
interval ``[v - 0.5, v + 0.5)`` means value ``v`` and every value gets a cell of width 1.
"""
from __future__ import annotations

import dataclasses
from typing import Sequence

import numpy as np


class RuleSpace:
    """The consequents of a system's rules as one integer vector.

    Parameters
    ----------
    system : FuzzySystem
    rules : sequence of int, optional
        0-based indices of the rules to learn; default all.
    allow_off : bool
        Whether a slot may take 0 (the rule stops setting that output).

    Attributes
    ----------
    system : FuzzySystem
    names : tuple of str
        ``"rule 3 -> risk"`` per slot (1-based rule numbers, as MATLAB prints them).
    slots : ndarray (n_params, 2), int64
        (rule index, output index) of each slot.
    x0 : ndarray (n_params,)
        The starting consequents.
    lower, upper : ndarray (n_params,)
        Smallest and largest value of each slot (0 or 1, the number of output terms).
    f_positions : ndarray (0,), int64
    i_positions : ndarray (n_params,), int64
        Index of each slot in ``iblob``.
    refresh : bool
        Always False (consequents leave the output tables unchanged).
    """

    def __init__(self, system, rules: Sequence[int] | None = None, allow_off: bool = False):
        n_rules = len(system.rules)
        if rules is None:
            chosen = list(range(n_rules))
        else:
            chosen = [int(r) for r in rules]
            bad = [r for r in chosen if not 0 <= r < n_rules]
            if bad or not chosen or len(set(chosen)) != len(chosen):
                raise ValueError(f"rules {list(rules)!r}: expected distinct 0-based indices in 0..{n_rules - 1}")
            chosen.sort()
        _, _, layout = system.packed
        n_out = layout.n_out
        slots, names, x0, upper = [], [], [], []
        for r in chosen:
            for o, code in enumerate(system.rules[r].consequent):
                if code == 0:
                    continue
                if code < 0:
                    raise ValueError(f"rule {r + 1} ({system.rule_text(r)!r}) concludes a negated term; "
                                     "rule learning chooses among the output's terms, so negated "
                                     "consequents cannot be learned: leave the rule out of `rules`")
                slots.append((r, o))
                names.append(f"rule {r + 1} -> {system.outputs[o].name}")
                x0.append(code)
                upper.append(len(system.outputs[o].terms))
        self.system = system
        self.allow_off = bool(allow_off)
        self.names = tuple(names)
        self.slots = np.array(slots, dtype=np.int64).reshape(-1, 2)
        self.x0 = np.array(x0, dtype=np.float64)
        self.lower = np.full(len(x0), 0.0 if allow_off else 1.0)
        self.upper = np.array(upper, dtype=np.float64)
        self.f_positions = np.empty(0, dtype=np.int64)
        self.i_positions = layout.consequent.start + self.slots[:, 0] * n_out + self.slots[:, 1]
        self.refresh = False
        # rules outside the space always stay on
        self._fixed_on = len(chosen) < n_rules

    @property
    def n_params(self) -> int:
        return self.x0.shape[0]

    def round(self, positions: np.ndarray) -> np.ndarray:
        """Nearest slot values of continuous ``positions`` (n, n_params), as float."""
        return np.clip(np.floor(positions + 0.5), self.lower, self.upper)

    def feasible(self, P: np.ndarray) -> np.ndarray:
        """Integer values within each slot's choices, with at least one rule still on."""
        ok = np.isfinite(P).all(axis=1)
        with np.errstate(invalid="ignore"):
            ok &= (P == np.round(P)).all(axis=1) & (P >= self.lower).all(axis=1) & (P <= self.upper).all(axis=1)
        if self.allow_off and not self._fixed_on:
            ok &= (P != 0).any(axis=1)
        return ok

    def changes(self, base: np.ndarray, p: np.ndarray) -> list[tuple]:
        """``("rule", r)`` for each rule whose consequents differ between ``base`` and ``p``
        (only samples where rule r fires can change)."""
        return [("rule", int(r)) for r in np.unique(self.slots[np.flatnonzero(p != base), 0])]

    def blob_values(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(fblob values (n, 0), iblob values (n, n_params))`` to write at the positions."""
        return np.empty((P.shape[0], 0)), np.ascontiguousarray(np.rint(P).astype(np.int64))

    def to_system(self, p: np.ndarray):
        """The system with consequents ``p`` (n_params,); rules left setting no output are dropped."""
        p = np.asarray(p, dtype=np.float64)
        if p.shape != self.x0.shape:
            raise ValueError(f"consequent vector has shape {p.shape}, expected {self.x0.shape}")
        if not self.feasible(p[None])[0]:
            raise ValueError(f"consequent vector {p.tolist()} is not valid: expected integers in "
                             f"[{self.lower.tolist()}, {self.upper.tolist()}] with at least one rule on")
        consequents = [list(rule.consequent) for rule in self.system.rules]
        for (r, o), value in zip(self.slots.tolist(), p.tolist()):
            consequents[r][o] = int(value)
        rules = tuple(dataclasses.replace(rule, consequent=tuple(c))
                      for rule, c in zip(self.system.rules, consequents) if any(c))
        return dataclasses.replace(self.system, rules=rules)
