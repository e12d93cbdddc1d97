"""fuzzcore: a vectorised, Numba-compiled fuzzy inference engine with MATLAB's semantics.

>>> import fuzzcore
>>> fis = fuzzcore.load("rules/fuzzrisk.yaml").warmup()
>>> risk = fis.infer(0.4, 0.3)            # or fis.infer(iou=0.4, rdd=0.3)
>>> risks = fis.evaluate(X)                # X: (n_samples, n_inputs) -> (n_samples, n_outputs)
>>> print(fuzzcore.verify(fis, monotone={"rdd": +1}))   # coverage, monotonicity, rules, terms
"""
from .errors import RuleBaseError
from .io import load, save
from .rules import Rule, parse_rule
from .system import Explanation, FuzzySystem
from .variables import Term, Variable
from .verification import Report, verify

__all__ = ["Explanation", "FuzzySystem", "Report", "Rule", "RuleBaseError", "Term", "Variable", "load",
           "parse_rule", "save", "verify"]
