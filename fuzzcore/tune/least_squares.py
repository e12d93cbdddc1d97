"""Sugeno rule consequents by least squares: ANFIS's least-squares estimate, with guarantees.

A Takagi-Sugeno system's output is linear in its consequent parameters (Jang 1993, ANFIS):
with ``wbar_k(x)`` rule ``k``'s firing strength over the sum of all strengths (``wtaver``;
the strength itself for ``wtsum``) and ``f_k(x) = a_k . x + c_k`` its output term,

    y(x) = sum_k wbar_k(x) f_k(x),

so for fixed antecedents the consequents minimising the squared error on data solve a
linear least-squares problem; ANFIS's hybrid rule alternates that estimate with gradient
steps on the terms. :class:`LeastSquares` makes that estimate from any starting system,
Mamdani or Sugeno: it keeps the inputs, their terms and every rule's antecedent, weight and
connective, gives each rule an output term of its own (``linear``, order 1, or
``constant``, order 0) and fits them all at once. It draws nothing at random.

The regressors ``wbar_k(x) x_j`` come from the engine's own firing strengths
(:func:`~fuzzcore.tune.rule_tables.firing_strengths`), so the fit is exact for whatever the
engine computes (AND/OR methods, NOT clauses, rule weights, ``wtaver``/``wtsum``), and the
fitted system reproduces the least-squares prediction to rounding.

A free fit can leave the output's range and break what the rule base means: a first-order
fit of the paper's rule base on the benchmark's features stays within [0.34, 0.99] on the
training frames but reaches -35 and 133 where few frames fall, for a risk in [0, 1]. So by
default it is a quadratic programme:

- ``bounded``: every rule's output term stays inside the output's range over the whole
  input box, hence so does the output, a weighted average of the terms (``wtaver``; a
  ``wtsum`` system's terms are bounded, its sum is not). For
  ``f_k = a . x + c`` on a box the extremes are ``c + sum_j max/min(a_j lo_j, a_j hi_j)``;
  with ``a = a+ - a-`` (both >= 0) that is two linear constraints per rule.
- ``monotone``: the output does not decrease (+1) or increase (-1) along the named inputs,
  between neighbours of a grid over the input box (``grid`` points per input, plus every
  breakpoint of the inputs' terms inside the range). Between grid points the output is a
  ratio of the rules' strengths and can still turn a little, so the fit is then checked by
  :func:`fuzzcore.verify` with the same ``monotone``; each violation it finds adds the
  constraint between its two points, and the programme is solved again, until verify finds
  none (at most :data:`MAX_REFINEMENTS` times; ``result_.message`` says how many were added).

The programme is solved by SLSQP (:func:`scipy.optimize.minimize`), started from a feasible
point (every term the middle of the output range); without constraints, by
:func:`numpy.linalg.lstsq`. A rule that fires on no training sample has nothing to fit: it
keeps a constant at the middle of the output's range, and ``result_.message`` names it.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.optimize import OptimizeResult, minimize

from ..rules import Rule
from ..system import FuzzySystem
from ..variables import Term, Variable
from ..verification import verify
from .base import CALLBACK_STOP, CONVERGED, MAX_ITER, STATUS, Reporter, Tuner, check_number
from .data import check_data
from .rule_tables import firing_strengths

#: largest number of grid points the monotone constraints may use
MAX_GRID_POINTS = 200_000
#: times the monotone constraints are refined where :func:`fuzzcore.verify` finds a violation
MAX_REFINEMENTS = 20
#: how far the solution may break a constraint, in output units, and still count as meeting it
FEASIBILITY_TOL = 1e-9


class LeastSquares(Tuner):
    """Fit one Sugeno output term per rule by (constrained) least squares.

    Parameters
    ----------
    system : FuzzySystem
        The starting system, Mamdani or Sugeno; its inputs, terms and antecedents are kept.
        A rule that negates its output term has no Sugeno form and is refused.
    order : {0, 1}
        1: ``linear`` terms ``a . x + c`` (first-order Takagi-Sugeno, ANFIS's); 0:
        ``constant`` terms.
    bounded : bool
        Keep every term, hence the output, inside the output's range over the input box.
    monotone : mapping of str to {+1, -1}, optional
        Inputs along which the output must not decrease (+1) or not increase (-1).
    grid : int >= 2
        Grid points per input for the monotone constraints.
    max_iter : int >= 1
        SLSQP iterations at most, per programme solved (its tolerance is 1e-15: the shipped
        file's 3 programmes, about 50 unknowns each, took 2,958 in all).
    callback : callable, optional
        Called after each SLSQP iteration (:mod:`fuzzcore.tune.base`).

    Attributes
    ----------
    system_ : FuzzySystem
        The Sugeno system (``wtaver``), ``metadata["tuning"]`` saying how it was made.
    result_ : OptimizeResult
        ``x`` (per output, per rule: ``a_1 .. a_n, c``, MATLAB's order; order 0: ``c``),
        ``fun`` (RMSE of the fitted system on the data), ``initial_fun`` (the starting
        system's), ``nit`` (SLSQP iterations, all rounds), ``nfev`` (programmes solved),
        ``status``, ``message``, ``names``.

    >>> tuner = LeastSquares(fis, monotone={"iou": -1}).fit(X, y)
    >>> tuner.system_.save("fuzzrisk-lse.yaml")
    """

    method = "lse"
    metric = "rmse"  # least squares minimises the squared error
    seed = None  # nothing random

    def __init__(self, system: FuzzySystem, order: int = 1, bounded: bool = True, monotone=None,
                 grid: int = 51, max_iter: int = 10_000, callback=None):
        self.system = system
        self.order = order
        self.bounded = bounded
        self.monotone = monotone
        self.grid = grid
        self.max_iter = max_iter
        self.callback = callback

    def _check_params(self) -> dict[int, int]:
        """Validate the settings; return the monotone properties as {input index: direction}."""
        if self.order not in (0, 1) or isinstance(self.order, bool):
            raise ValueError(f"order = {self.order!r}: expected 0 (constant terms) or 1 (linear terms)")
        if not isinstance(self.bounded, bool):
            raise ValueError(f"bounded = {self.bounded!r}: expected True or False")
        check_number("grid", self.grid, 2, integer=True)
        check_number("max_iter", self.max_iter, 1, integer=True)
        names = self.system.input_names
        monotone = {}
        for name, direction in dict(self.monotone or {}).items():
            if name not in names:
                raise ValueError(f"monotone: {name!r} is not an input of {self.system.name!r}; its inputs are "
                                 f"{', '.join(names)}")
            if isinstance(direction, bool) or direction not in (1, -1):
                raise ValueError(f"monotone[{name!r}] = {direction!r}: expected +1 (increasing) or -1 (decreasing)")
            monotone[names.index(name)] = int(direction)
        for r, rule in enumerate(self.system.rules):
            if any(c < 0 for c in rule.consequent):
                raise ValueError(f"rule {r + 1} ({self.system.rule_text(r)}) negates its output term; a Sugeno "
                                 "rule cannot, so its consequent has no least-squares form")
        return monotone

    def fit(self, X, y, groups=None):
        """Fit on ``X`` (n_samples, n_inputs) and ``y`` (n_samples,) or (n_samples, n_outputs);
        ``groups`` is accepted for the tuners' common signature and not used. Returns ``self``."""
        self._check_common()
        monotone = self._check_params()
        X, Y, _ = check_data(self.system, X, y, groups)
        initial_fun = float(np.sqrt(np.mean((self.system.evaluate(X) - Y) ** 2)))
        reporter = Reporter(self.method, self.callback, [])
        width = self._width
        names, notes, fits = [], [], []
        for o, var in enumerate(self.system.outputs):  # the data's regressors and the grid's constraints
            rules = [r for r, rule in enumerate(self.system.rules) if rule.consequent[o] != 0]
            A = self._regressors(X, o, rules, "the training data")
            fired = np.any(A.reshape(A.shape[0], len(rules), width) != 0.0, axis=(0, 2))
            if not fired.all():
                idle = [rules[k] + 1 for k in np.flatnonzero(~fired)]
                notes.append(f"output {var.name!r}: rule{'s' if len(idle) > 1 else ''} "
                             f"{', '.join(map(str, idle))} fire{'' if len(idle) > 1 else 's'} on no training "
                             "sample: a constant at the middle of the range")
            fits.append((rules, A, fired, self._grid_rows(o, rules, monotone)))
            names += [f"{var.name}.rule{r + 1}.{n}" for r in rules
                      for n in (self.system.input_names + ("const",) if self.order == 1 else ("const",))]
        by_name = {self.system.input_names[i]: d for i, d in monotone.items()}
        nit, solved, added = 0, 0, 0
        params = [None] * len(fits)
        for _ in range(MAX_REFINEMENTS + 1):
            statuses = []
            for o, (rules, A, fired, M) in enumerate(fits):  # each round starts from the last one's fit
                p, status, it = self._solve(A, Y[:, o], self.system.outputs[o].range, fired, width, M, o, reporter,
                                            params[o])
                params[o] = p
                statuses.append(status)
                nit += it
                solved += 1
            fitted = self._system(params, [fit[0] for fit in fits])
            if not monotone or CALLBACK_STOP in statuses:
                break
            broken = [m for m in verify(fitted, by_name).monotonicity if not m.holds]
            if not broken:
                break
            for m in broken:  # a cutting plane through the pair of points verify found
                o = self.system.output_names.index(m.output)
                rules, A, fired, M = fits[o]
                ends = np.array([[m.start[n] for n in self.system.input_names],
                                 [m.end[n] for n in self.system.input_names]])
                G = self._regressors(ends, o, rules, "the points verify found")
                fits[o] = (rules, A, fired, np.vstack([M, -m.direction * (G[1] - G[0])]))
                added += 1
        else:
            statuses.append(MAX_ITER)
            notes.append(f"fuzzcore.verify still finds the output non-monotone after {MAX_REFINEMENTS} "
                         "refinements of the grid")
        if added:
            notes.append(f"{added} constraints added where fuzzcore.verify found the grid's fit non-monotone")
        status = max(statuses)
        fun = float(np.sqrt(np.mean((fitted.evaluate(X) - Y) ** 2)))
        self.result_ = OptimizeResult(
            x=np.concatenate(params), fun=fun, nit=nit, nfev=solved, success=status == CONVERGED, status=status,
            message=STATUS[status] + "".join(f"; {n}" for n in notes), initial_fun=initial_fun,
            cv_scores=np.array([]), cv_score=math.nan, fold_nit=[nit], names=tuple(names), metric=self.metric,
            n_samples=X.shape[0], n_groups=None if groups is None else int(np.unique(np.asarray(groups)).shape[0]))
        self.system_ = self._provenance(fitted, self.result_)
        return self

    # ------------------------------------------------------------------ the linear model
    @property
    def _width(self) -> int:
        """Parameters per rule: ``a_1 .. a_n, c`` (order 1) or ``c`` (order 0)."""
        return len(self.system.inputs) + 1 if self.order == 1 else 1

    @property
    def _defuzzifier(self) -> str:
        return self.system.defuzzifier if self.system.type == "sugeno" else "wtaver"

    def _regressors(self, X: np.ndarray, o: int, rules: list[int], what: str) -> np.ndarray:
        """(n_samples, len(rules) * width) design matrix of output ``o`` on ``X``: per rule,
        its share of the strength of the rules setting ``o`` (``wtaver``; the strength itself
        for ``wtsum``) times ``x_1 .. x_n, 1``. Raises if some sample fires none of them
        (least squares cannot fit the ``no_rule_fired`` fallback)."""
        w = firing_strengths(self.system, X)[:, rules]
        total = w.sum(axis=1)
        if not np.all(total > 0.0):
            i = int(np.flatnonzero(~(total > 0.0))[0])
            point = ", ".join(f"{n} = {v:g}" for n, v in zip(self.system.input_names, X[i]))
            raise ValueError(f"{int(np.sum(~(total > 0.0)))} samples of {what} fire no rule of output "
                             f"{self.system.outputs[o].name!r} (the first: {point}); least squares needs every "
                             "sample covered by some rule")
        if self._defuzzifier == "wtaver":
            w = w / total[:, None]
        if self.order == 0:
            return w
        ones = np.ones((X.shape[0], 1))
        return (w[:, :, None] * np.hstack([X, ones])[:, None, :]).reshape(X.shape[0], -1)

    def _grid_rows(self, o: int, rules: list[int], monotone: dict[int, int]) -> np.ndarray:
        """The monotone constraints of output ``o`` on the grid, rows ``M`` of ``M p <= 0``:
        ``-direction`` times the regressors' change between neighbours along each monotone
        input. The grid has ``grid`` points per input and every breakpoint of the inputs'
        terms inside the range."""
        width = self._width
        if not monotone:
            return np.zeros((0, len(rules) * width))
        axes = []
        for var in self.system.inputs:
            lo, hi = var.range
            points = [np.linspace(lo, hi, self.grid)]
            points += [np.array([p for p in term.params if lo < p < hi]) for term in var.terms]
            axes.append(np.unique(np.concatenate(points)))
        size = math.prod(a.shape[0] for a in axes)
        if size > MAX_GRID_POINTS:
            raise ValueError(f"grid = {self.grid}: the monotone constraints would take {size:,} grid points over "
                             f"{len(axes)} inputs (at most {MAX_GRID_POINTS:,}); use a smaller grid")
        points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(axes))
        G = self._regressors(points, o, rules, "the monotone grid")
        G = G.reshape(tuple(a.shape[0] for a in axes) + (G.shape[1],))
        rows = [-direction * np.diff(G, axis=axis).reshape(-1, G.shape[-1]) for axis, direction in monotone.items()]
        M = np.concatenate(rows)
        return M[np.any(M != 0.0, axis=1)]  # pairs no parameter moves

    # ------------------------------------------------------------------ the programme
    def _solve(self, A, y, out_range, fired, width, M, o, reporter, start=None):
        """Minimise the squared error of ``A p`` to ``y`` subject to ``M p <= 0`` and, if
        ``bounded``, the range, from ``start`` (default: every term the middle of the range);
        the parameters of the rules that never ``fired`` stay at the middle of the range.
        Returns ``p`` (n_rules * width,), the status and the iterations."""
        lo_out, hi_out = out_range
        mid = 0.5 * (lo_out + hi_out)
        n_rules = fired.shape[0]
        free = np.repeat(fired, width)
        if not self.bounded and M.shape[0] == 0:
            p = np.zeros(n_rules * width)
            p[width - 1::width] = mid  # the constants (MATLAB's order: a_1 .. a_n, c) of idle rules
            p[free] = np.linalg.lstsq(A[:, free], y, rcond=None)[0]
            stopped = reporter.iteration(p, np.sqrt(np.mean((A @ p - y) ** 2)))
            return p, CALLBACK_STOP if stopped else CONVERGED, 1
        # split every slope a = a+ - a- (both >= 0) so that the range constraints are linear:
        # z = (p with a+ in the slopes' places, then a- per slope), p = S z
        n_in = width - 1
        n_p = n_rules * width
        const = np.arange(n_rules) * width + n_in
        slopes = np.setdiff1d(np.arange(n_p), const)  # rule k's slope j is slopes[k * n_in + j]
        S = np.hstack([np.eye(n_p), np.zeros((n_p, slopes.shape[0]))])
        S[slopes, n_p + np.arange(slopes.shape[0])] = -1.0
        G_ineq, h_ineq = [M @ S], [np.zeros(M.shape[0])]
        if self.bounded:  # per rule: c + sum(a+ hi - a- lo) <= hi_out and c + sum(a+ lo - a- hi) >= lo_out
            lo_in = np.array([v.range[0] for v in self.system.inputs])
            hi_in = np.array([v.range[1] for v in self.system.inputs])
            top, bottom = np.zeros((n_rules, S.shape[1])), np.zeros((n_rules, S.shape[1]))
            for k in range(n_rules):
                top[k, const[k]] = bottom[k, const[k]] = 1.0
                if n_in:  # first order: the slopes' extremes over the input box
                    plus, minus = k * width + np.arange(n_in), n_p + k * n_in + np.arange(n_in)
                    top[k, plus], top[k, minus] = hi_in, -lo_in
                    bottom[k, plus], bottom[k, minus] = lo_in, -hi_in
            G_ineq += [top, -bottom]
            h_ineq += [np.full(n_rules, hi_out), np.full(n_rules, -lo_out)]
        G, h = np.concatenate(G_ineq), np.concatenate(h_ineq)
        z0 = np.zeros(S.shape[1])
        z0[const] = mid  # feasible: every term the middle of the range, which is monotone too
        keep = np.concatenate([free, free[slopes]])  # the idle rules stay at z0
        h_free = h - G[:, ~keep] @ z0[~keep]
        G_free = G[:, keep]
        B = (A @ S)[:, keep]
        H, g = B.T @ B / B.shape[0], B.T @ y / B.shape[0]  # half the mean squared error, less a constant
        lower = np.where(np.isin(np.flatnonzero(keep), const), -np.inf, 0.0)
        best = {"z": z0[keep], "f": 0.5 * z0[keep] @ H @ z0[keep] - g @ z0[keep], "stopped": False}

        def step(z):  # SLSQP's iterates may break constraints: a stopped run ends at the best that does not
            f = 0.5 * z @ H @ z - g @ z
            if f < best["f"] and np.all(G_free @ z - h_free <= FEASIBILITY_TOL) and np.all(z >= lower):
                best["z"], best["f"] = z.copy(), f
            if reporter.iteration(S[:, keep] @ z, np.sqrt(np.mean((B @ z - y) ** 2))):
                best["stopped"] = True
                raise StopIteration

        first = z0.copy()
        if start is not None:
            first[:n_p] = start
            first[slopes], first[n_p:] = np.maximum(start[slopes], 0.0), np.maximum(-start[slopes], 0.0)
        solution = minimize(lambda z: 0.5 * z @ H @ z - g @ z, first[keep], jac=lambda z: H @ z - g, method="SLSQP",
                            bounds=[(b, None) for b in lower],
                            constraints=[{"type": "ineq", "fun": lambda z: h_free - G_free @ z,
                                          "jac": lambda z: -G_free}],
                            options={"maxiter": self.max_iter, "ftol": 1e-15}, callback=step)
        z = z0.copy()
        z[keep] = best["z"] if best["stopped"] else solution.x
        worst = float(np.max(G @ z - h, initial=-math.inf))
        if worst > FEASIBILITY_TOL:
            raise RuntimeError(f"least squares for output {self.system.outputs[o].name!r}: SLSQP ended "
                               f"({solution.message}) {worst:.3g} beyond a constraint")
        status = CALLBACK_STOP if best["stopped"] else CONVERGED if solution.success else MAX_ITER
        return S @ z, status, int(solution.nit)

    # ------------------------------------------------------------------ the result
    def _system(self, params: list[np.ndarray], rules_of: list[list[int]]) -> FuzzySystem:
        """The fitted Sugeno system: the starting inputs and antecedents, one term per rule
        (``rules_of[o]``: the rules setting output ``o``, in ``params[o]``'s order)."""
        width = self._width
        kind = "linear" if self.order == 1 else "constant"
        outputs, consequents = [], [[0] * len(self.system.outputs) for _ in self.system.rules]
        for o, (var, rules) in enumerate(zip(self.system.outputs, rules_of)):
            terms = []
            for i, r in enumerate(rules):
                terms.append(Term(f"rule{r + 1}", kind, tuple(float(v) for v in params[o][i * width:(i + 1) * width])))
                consequents[r][o] = i + 1
            outputs.append(Variable(var.name, var.range, tuple(terms)))
        rules = [Rule(rule.antecedent, tuple(consequents[r]), rule.weight, rule.connective)
                 for r, rule in enumerate(self.system.rules)]
        return dataclasses.replace(self.system, outputs=tuple(outputs), rules=tuple(rules), type="sugeno",
                                   defuzzifier=self._defuzzifier)

    def _label(self) -> str:
        terms = "linear" if self.order == 1 else "constant"
        monotone = "".join(f", {n} {'increasing' if d > 0 else 'decreasing'}" for n, d in (self.monotone or {}).items())
        return f"least squares ({terms} terms{', bounded' if self.bounded else ''}{monotone})"

    def _settings(self) -> dict:
        settings = super()._settings()
        settings["monotone"] = dict(self.monotone or {})
        return settings

