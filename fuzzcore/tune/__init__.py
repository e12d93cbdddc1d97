"""fuzzcore.tune: data-driven tuning of fuzzy systems (the paper's Sec. III-B and its future work).

- :class:`PatternSearch` tunes membership functions (generalised pattern search, k-fold
  cross-validation with early stopping), the paper's "tuned" variant;
- :class:`ParticleSwarm` learns rule consequents (global particle swarm), the paper's
  "learned" variant;
- :class:`LeastSquares` fits Sugeno consequents, one per rule, by least squares within the
  output's range and along declared monotone inputs (ANFIS's estimate, with guarantees);
- :class:`JointTuner` alternates the two until neither improves (terms and rules jointly);
- :class:`Objective` scores many candidate systems at once (RMSE or MAE) in Numba;
- :func:`read_csv` reads a feature table (inputs, target, optional scene column).

>>> from fuzzcore.tune import PatternSearch, read_csv
>>> table = read_csv("train.csv", fis.input_names)
>>> tuned = PatternSearch(fis, seed=0).fit(table.X, table.y, table.groups).system_
"""
from .data import FeatureTable, check_data, read_csv
from .joint import JointTuner
from .kfold import EarlyStopping, fold_labels
from .least_squares import LeastSquares
from .objective import Objective
from .particleswarm import ParticleSwarm
from .patternsearch import PatternSearch
from .rule_space import RuleSpace
from .term_space import TermSpace

__all__ = ["EarlyStopping", "FeatureTable", "JointTuner", "LeastSquares", "Objective", "ParticleSwarm", "PatternSearch",
           "RuleSpace", "TermSpace", "check_data", "fold_labels", "read_csv"]
