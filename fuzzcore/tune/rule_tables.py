"""Exact lookup tables for rule learning: each sample scored once per relevant consequent combination.

A rule whose firing strength is 0 for a sample contributes nothing to that sample's
output, whatever it concludes (min/prod implication of 0 is 0, and max/sum/probor
aggregation of 0 changes nothing; a Sugeno rule of weight 0 is skipped). So a sample's
output depends only on the consequents of the learned rules that fire for it. Samples
are grouped by that set of rules; for every group and every combination of its rules'
consequents the group's summed loss is computed once, by the engine, with the same
arithmetic as a direct evaluation. Scoring a candidate is then one lookup per group.

Which rules fire is read from the engine itself: a Sugeno "probe" system with the same
inputs, antecedents, weights and operators, and one output per rule that only that rule
sets to the constant 1 (``wtsum``, 0 when it does not fire), returns every rule's
firing strength.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..rules import Rule
from ..system import FuzzySystem
from ..variables import Term, Variable
from .batch import Samples, full_sums

#: most consequent combinations tabulated for one group (beyond it, tables are not used)
MAX_COMBINATIONS = 4096


def firing_strengths(system, X: np.ndarray) -> np.ndarray:
    """Weighted firing strength of every rule for every sample, from the engine.

    Parameters
    ----------
    system : FuzzySystem
    X : ndarray (n_samples, n_inputs)

    Returns
    -------
    ndarray (n_samples, n_rules)
    """
    R = len(system.rules)
    one = (Term("one", "constant", (1.0,)),)
    outputs = tuple(Variable(f"rule{r + 1}", (0.0, 1.0), one) for r in range(R))
    rules = tuple(Rule(rule.antecedent, tuple(int(o == r) for o in range(R)), rule.weight, rule.connective)
                  for r, rule in enumerate(system.rules))
    probe = FuzzySystem(name="firing-probe", inputs=system.inputs, outputs=outputs, rules=rules,
                        type="sugeno", and_method=system.and_method, or_method=system.or_method,
                        defuzzifier="wtsum", no_rule_fired=0.0)
    return probe.evaluate(X)


@dataclass(frozen=True)
class Grouping:
    """Samples grouped by which learned slots' rules fire.

    ``slots[g]`` are the slot indices whose rule fires for group ``g``; ``members[g]`` the
    sample indices; ``n_rows[g]`` their distinct input rows; ``sizes[g]`` the number of
    choices of each of those slots.
    """

    slots: tuple[np.ndarray, ...]
    members: tuple[np.ndarray, ...]
    n_rows: tuple[int, ...]
    sizes: tuple[np.ndarray, ...]

    @property
    def cost(self) -> int | None:
        """Inferences needed to build the tables; ``None`` if a group has too many combinations."""
        combos = [int(np.prod(s)) for s in self.sizes]
        if max(combos) > MAX_COMBINATIONS:
            return None
        return int(sum(c * m for c, m in zip(combos, self.n_rows)))


def group_by_firing(space, data: Samples) -> Grouping:
    """Group the samples of ``data`` by the set of ``space``'s slots whose rule fires."""
    fires = firing_strengths(space.system, data.unique)[:, space.slots[:, 0]] > 0.0
    keys, inverse = np.unique(fires, axis=0, return_inverse=True)
    inverse = inverse.ravel()[data.inverse]
    choices = (space.upper - space.lower + 1).astype(np.int64)
    slots = tuple(np.flatnonzero(key) for key in keys)
    members = tuple(np.flatnonzero(inverse == g) for g in range(keys.shape[0]))
    n_rows = tuple(int(np.unique(data.inverse[m]).shape[0]) for m in members)
    return Grouping(slots=slots, members=members, n_rows=n_rows, sizes=tuple(choices[s] for s in slots))


class RuleTables:
    """Summed loss of every sample group under every combination of its firing rules' consequents.

    Parameters
    ----------
    space : RuleSpace
    packed : (fblob, iblob)
        The packed system the candidates modify (:mod:`fuzzcore.tune.batch`).
    data : Samples
    loss : int
        Loss code (:mod:`fuzzcore.tune._objective_kernels`).
    """

    def __init__(self, space, packed, data: Samples, loss: int):
        grouping = group_by_firing(space, data)
        if grouping.cost is None:
            raise ValueError(f"a group of samples fires more than log2({MAX_COMBINATIONS}) learned rules' "
                             "worth of consequent combinations; score candidates directly")
        self.space = space
        self.grouping = grouping
        lower = space.lower.astype(np.int64)
        tables = []
        for slots, members, sizes in zip(grouping.slots, grouping.members, grouping.sizes):
            values = [range(int(lower[s]), int(lower[s] + n)) for s, n in zip(slots, sizes)]
            combos = np.array(list(itertools.product(*values)), dtype=np.float64).reshape(
                int(np.prod(sizes)), slots.shape[0])  # (1, 0) for a group where no learned rule fires
            P = np.tile(space.x0, (combos.shape[0], 1))
            P[:, slots] = combos
            tables.append(full_sums(space, packed, data.take(members), P, loss))
        self.tables = tuple(tables)

    def sums(self, P: np.ndarray) -> np.ndarray:
        """Summed loss of each feasible candidate row of ``P`` (n_candidates, n_params)."""
        lower = self.space.lower.astype(np.int64)
        total = np.zeros(P.shape[0])
        values = np.rint(P).astype(np.int64) - lower
        for slots, sizes, table in zip(self.grouping.slots, self.grouping.sizes, self.tables):
            if slots.shape[0] == 0:
                total += table[0]
            else:
                total += table[np.ravel_multi_index(tuple(values[:, slots].T), tuple(sizes))]
        return total
