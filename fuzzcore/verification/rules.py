"""Rules worth a second look: never firing, redundant, conflicting, and terms no rule uses.

- **Never firing**: the rule's strength is 0 in every cell of the input box (exact with
  piecewise-linear terms, :mod:`fuzzcore.verification.coverage`), e.g. a weight of 0 or an
  antecedent whose terms never overlap.
- **Redundant**: removing the rule changes no output by more than ``tol`` at any sample,
  and leaves some other rule firing wherever it fires (a rule that alone covers a region is
  never redundant, even where the no-rule fallback happens to give the same number). A
  rule can change an output only where it fires, so the system without it is evaluated at
  the samples where it fires (a search over the samples given, not a proof).
- **Conflicting**: rules with the same antecedent and connective but different
  consequents; the same antecedent and the same consequent is a **duplicate**.
- **Unused terms**: input terms no antecedent mentions, output terms no rule concludes.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np



@dataclass(frozen=True)
class RuleFindings:
    """Rule indices are 0-based; ``texts`` gives each rule's text (index -> text).

    Attributes
    ----------
    never_firing : tuple of int
    redundant : tuple of (int, float)
        Rule and the largest output change its removal makes, as a fraction of the
        output's range (at most ``tol``).
    conflicting : tuple of tuple of int
        Groups of rules with one antecedent and different consequents.
    duplicates : tuple of tuple of int
    unused_terms : tuple of (str, str)
        (variable, term).
    tol : float
    n_samples : int
        Samples the redundancy check evaluated.
    """

    never_firing: tuple
    redundant: tuple
    conflicting: tuple
    duplicates: tuple
    unused_terms: tuple
    tol: float
    n_samples: int
    texts: tuple

    def to_dict(self) -> dict:
        def rule(r):
            return {"index": r, "text": self.texts[r]}

        return {"never_firing": [rule(r) for r in self.never_firing],
                "redundant": [{**rule(r), "largest_change": change} for r, change in self.redundant],
                "conflicting": [[rule(r) for r in group] for group in self.conflicting],
                "duplicates": [[rule(r) for r in group] for group in self.duplicates],
                "unused_terms": [{"variable": v, "term": t} for v, t in self.unused_terms],
                "redundancy_tol": self.tol, "redundancy_samples": self.n_samples}


def strengths(fis, X: np.ndarray) -> np.ndarray:
    """Weighted firing strengths (n_samples, n_rules) at the rows of ``X``, as the engine computes them."""
    mu = [np.stack([t.membership(X[:, i]) for t in var.terms], axis=1) if var.terms else None
          for i, var in enumerate(fis.inputs)]
    out = np.empty((X.shape[0], len(fis.rules)))
    for r, rule in enumerate(fis.rules):
        is_or = rule.connective == "or"
        f = np.full(X.shape[0], 0.0 if is_or else 1.0)
        for i, code in enumerate(rule.antecedent):
            if code == 0:
                continue
            x = mu[i][:, abs(code) - 1]
            x = 1.0 - x if code < 0 else x
            if is_or:
                f = np.maximum(f, x) if fis.or_method == "max" else f + x - f * x
            else:
                f = np.minimum(f, x) if fis.and_method == "min" else f * x
        out[:, r] = f * rule.weight
    return out


def check_rules(fis, rule_max: np.ndarray, X: np.ndarray, Y: np.ndarray, tol: float) -> RuleFindings:
    """Rule findings for ``fis`` (module docstring).

    Parameters
    ----------
    rule_max : ndarray (n_rules,)
        Each rule's largest strength over the box's cells.
    X : ndarray (n_samples, n_inputs)
        Samples for the redundancy check; ``Y`` (n_samples, n_outputs) the outputs there.
    tol : float
        Largest output change, as a fraction of the output's range, that still counts as
        "no change".
    """
    never = tuple(int(r) for r in np.flatnonzero(~(rule_max > 0)))
    redundant = []
    if len(fis.rules) > 1:
        S = strengths(fis, X)
        for r in range(len(fis.rules)):
            if r in never:
                continue
            where = S[:, r] > 0
            others = np.delete(S[where], r, axis=1)
            if not where.any() or not (others > 0).any(axis=1).all():
                continue  # without it, no rule would fire somewhere: a hole, not redundancy
            reduced = dataclasses.replace(fis, rules=fis.rules[:r] + fis.rules[r + 1:])
            Yr, Yw = reduced.evaluate(X[where]), Y[where]
            spans = np.array([v.range[1] - v.range[0] for v in fis.outputs])
            diff = np.abs(Yr - Yw) / spans
            diff = np.where(np.isnan(Yr) & np.isnan(Yw), 0.0, np.where(np.isnan(diff), np.inf, diff))
            change = float(diff.max())
            if change <= tol:
                redundant.append((r, change))
    groups: dict = {}
    for r, rule in enumerate(fis.rules):
        groups.setdefault((rule.antecedent, rule.connective), []).append(r)
    conflicting, duplicates = [], []
    for members in groups.values():
        if len(members) < 2:
            continue
        consequents = {fis.rules[r].consequent for r in members}
        (duplicates if len(consequents) == 1 else conflicting).append(tuple(members))
    unused = []
    for kind, variables, attr in (("inputs", fis.inputs, "antecedent"), ("outputs", fis.outputs, "consequent")):
        for i, var in enumerate(variables):
            used = {abs(getattr(rule, attr)[i]) for rule in fis.rules}
            unused += [(var.name, term.name) for k, term in enumerate(var.terms, start=1) if k not in used]
    texts = tuple(fis.rule_text(r) for r in range(len(fis.rules)))
    return RuleFindings(never, tuple(redundant), tuple(conflicting), tuple(duplicates), tuple(unused), tol,
                        int(X.shape[0]), texts)
