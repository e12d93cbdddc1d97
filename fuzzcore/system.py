"""The fuzzy system: definition, validation, and the public inference calls.

Inference reads as three steps, each in :mod:`fuzzcore._kernels`: memberships and rule
firing strengths; implication and aggregation into one fuzzy set per output (Mamdani) or
weighted rule outputs (Sugeno); defuzzification.
"""
from __future__ import annotations

import functools
import math
import numbers
import operator
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numba
import numpy as np

from . import _kernels as K
from .compiled import (AGGREGATIONS, AND_METHODS, IMPLICATIONS, MAMDANI_DEFUZZIFIERS,
                       OR_METHODS, POLICIES, SUGENO_DEFUZZIFIERS, SYSTEMS, Layout, pack)
from .errors import RuleBaseError
from .inputs import REAL_SCALARS, real_array
from .membership import PIECEWISE_LINEAR, resolve_kind
from .rules import Rule, format_rule
from .variables import Variable

#: batches smaller than this run on the calling thread (thread start-up costs more than it saves)
PARALLEL_THRESHOLD = 4 * K.CHUNK


def _choice(value: Any, choices: Mapping[str, int], what: str, of: str = "") -> None:
    """Refuse ``value`` of setting ``what`` unless among ``choices`` (``of`` says whose choices)."""
    if value not in choices:
        raise RuleBaseError(f"{value!r}: expected one of {', '.join(choices)}{of}", place=what)


@dataclass(frozen=True)
class FuzzySystem:
    """A Mamdani or Takagi-Sugeno fuzzy inference system, MATLAB's semantics.

    Parameters
    ----------
    name : str
    inputs, outputs : sequence of :class:`~fuzzcore.variables.Variable`
        In declared order; ``infer`` takes inputs positionally in this order.
    rules : sequence of :class:`~fuzzcore.rules.Rule`
    type : {"mamdani", "sugeno"}
    and_method : {"min", "prod"}
    or_method : {"max", "probor"}
    implication : {"min", "prod"}
        Mamdani only (Sugeno weights rule outputs by firing strength).
    aggregation : {"max", "sum", "probor"}
        Mamdani only.
    defuzzifier : str
        Mamdani: ``centroid`` (MATLAB's discrete form on ``resolution`` points, both ends
        included), ``centroid_exact`` (exact integral; piecewise-linear output terms and max
        or sum aggregation only), ``bisector``, ``mom``, ``som``, ``lom`` (MATLAB's discrete
        forms; ``som``/``lom`` pick the smallest/largest *magnitude* among the maxima, as
        MATLAB does). Sugeno: ``wtaver`` or ``wtsum``.
    resolution : int >= 2
        Points of the output grid (MATLAB: 101).
    no_rule_fired : "midpoint" | "nan" | float
        Output when no rule fires (empty aggregated set / all Sugeno weights 0):
        MATLAB's midpoint of the output range, NaN, or a fixed number. Never a silent 0.
        Only an empty set takes it: any other NaN (a NaN membership, a Sugeno rule output
        ``0 * inf``) gives NaN.
    description : str
    metadata : mapping
        Free provenance (e.g. how a tuned system was made); saved and loaded with the system.

    Notes
    -----
    Any NaN input gives NaN outputs for that sample. Inputs outside their range are
    evaluated as given (MATLAB warns and does the same); infinite inputs take the
    membership functions' limits.
    """

    name: str
    inputs: tuple[Variable, ...]
    outputs: tuple[Variable, ...]
    rules: tuple[Rule, ...]
    type: str = "mamdani"
    and_method: str = "min"
    or_method: str = "max"
    implication: str = "min"
    aggregation: str = "max"
    defuzzifier: str = "centroid"
    resolution: int = 101
    no_rule_fired: str | float = "midpoint"
    description: str = ""
    metadata: dict = field(default_factory=dict)

    # ------------------------------------------------------------------ validation
    def __post_init__(self) -> None:
        for name in ("inputs", "outputs", "rules"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        object.__setattr__(self, "metadata", dict(self.metadata))
        for name in ("name", "description"):
            if not isinstance(getattr(self, name), str):
                raise RuleBaseError(f"{name} {getattr(self, name)!r} must be text", place=name)
        _choice(self.type, SYSTEMS, "type")
        _choice(self.and_method, AND_METHODS, "and")
        _choice(self.or_method, OR_METHODS, "or")
        _choice(self.implication, IMPLICATIONS, "implication")
        _choice(self.aggregation, AGGREGATIONS, "aggregation")
        mamdani = self.type == "mamdani"
        _choice(self.defuzzifier, MAMDANI_DEFUZZIFIERS if mamdani else SUGENO_DEFUZZIFIERS, "defuzzifier",
                f" (the defuzzifiers of a {self.type} system)")
        if isinstance(self.resolution, bool) or not isinstance(self.resolution, numbers.Integral) \
                or self.resolution < 2:
            raise RuleBaseError(f"resolution {self.resolution!r}: expected an integer >= 2", place="resolution")
        object.__setattr__(self, "resolution", int(self.resolution))
        self._check_policy()
        if not self.inputs or not self.outputs:
            raise RuleBaseError("a system needs at least one input and one output")
        names = [v.name for v in self.inputs + self.outputs]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise RuleBaseError(f"variable names must be unique; repeated: {', '.join(repeated)}")
        n_in = len(self.inputs)
        for kind, variables in (("inputs", self.inputs), ("outputs", self.outputs)):
            for var in variables:
                try:
                    var.check_terms(n_in, is_input=kind == "inputs")
                except RuleBaseError as exc:
                    raise RuleBaseError(exc.detail, place=f"{kind}.{var.name}") from None
        self._check_outputs()
        if isinstance(self.no_rule_fired, float):
            outside = [v.name for v in self.outputs if not v.range[0] <= self.no_rule_fired <= v.range[1]]
            if outside:
                raise RuleBaseError(f"no_rule_fired {self.no_rule_fired!r} lies outside the range of "
                                    f"{', '.join(outside)}; a fallback output must be a possible output",
                                    place="no_rule_fired")
        if not self.rules:
            raise RuleBaseError("the rule list is empty; expected at least one rule", place="rules")
        for r, rule in enumerate(self.rules):
            try:
                rule.check(self.inputs, self.outputs)
                if not mamdani and any(c < 0 for c in rule.consequent):
                    raise RuleBaseError("a Sugeno rule cannot negate its output term")
            except RuleBaseError as exc:
                raise RuleBaseError(exc.detail, place=f"rules[{r}]") from None
        fblob, iblob, layout = pack(self)
        object.__setattr__(self, "_fblob", fblob)
        object.__setattr__(self, "_iblob", iblob)
        object.__setattr__(self, "_layout", layout)
        object.__setattr__(self, "_fast", None)

    def _check_policy(self) -> None:
        policy = self.no_rule_fired
        if isinstance(policy, str):
            _choice(policy, POLICIES, "no_rule_fired")
        elif isinstance(policy, numbers.Real) and not isinstance(policy, bool) and math.isfinite(policy):
            object.__setattr__(self, "no_rule_fired", float(policy))
        else:
            raise RuleBaseError(f"no_rule_fired {policy!r}: expected 'midpoint', 'nan' or a finite number",
                                place="no_rule_fired")

    def _check_outputs(self) -> None:
        for var in self.outputs:
            for term in var.terms:
                kind = resolve_kind(term.kind)
                where = f"outputs.{var.name}.terms.{term.name}"
                if self.type == "mamdani" and kind.output_only:
                    raise RuleBaseError(f"{kind.name} is a Sugeno output kind; a Mamdani output needs a "
                                        "membership function", place=where)
                if self.type == "sugeno" and not kind.output_only:
                    raise RuleBaseError(f"{kind.name}: a Sugeno output term must be 'constant' or 'linear'",
                                        place=where)
                if self.defuzzifier == "centroid_exact" and kind.name not in PIECEWISE_LINEAR:
                    raise RuleBaseError(f"{kind.name} is not piecewise linear; centroid_exact needs one of "
                                        f"{', '.join(sorted(PIECEWISE_LINEAR))}", place=where)
        if self.type == "mamdani":
            for var in self.outputs:
                lo, hi = var.range
                if not math.isfinite((self.resolution - 1) * (hi - lo)):
                    raise RuleBaseError(f"range [{lo!r}, {hi!r}] is degenerate for a grid of {self.resolution} "
                                        "points: (resolution - 1) * (hi - lo) overflows", place=f"outputs.{var.name}")
        if self.defuzzifier == "centroid_exact" and self.aggregation == "probor":
            raise RuleBaseError("centroid_exact needs aggregation 'max' or 'sum' (probor is not "
                                "piecewise linear)", place="aggregation")

    # ------------------------------------------------------------------ properties
    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.inputs)

    @property
    def output_names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.outputs)

    @property
    def packed(self) -> tuple[np.ndarray, np.ndarray, Layout]:
        """``(fblob, iblob, layout)``: the arrays the kernels read (copies; see :mod:`fuzzcore.compiled`)."""
        return self._fblob.copy(), self._iblob.copy(), self._layout

    def rule_text(self, index: int) -> str:
        """The readable text of rule ``index`` (0-based), as :meth:`explain` reports it.

        A rule whose every input is "don't care" (possible in MATLAB files) has no text
        form in a rule base; it reads ``always then ...`` here.
        """
        return self._rule_texts[index]

    @functools.cached_property
    def _rule_texts(self) -> tuple[str, ...]:
        return tuple(format_rule(rule, self.inputs, self.outputs, display=True) for rule in self.rules)

    @property
    def output_grid(self) -> np.ndarray | None:
        """(n_outputs, resolution) the grid the Mamdani defuzzifiers sample (MATLAB's
        ``linspace``, as the kernels computed it); None for Sugeno."""
        if self.type != "mamdani":
            return None
        start, res = self._iblob[K.F_GRID], self._layout.resolution
        return self._fblob[start:start + len(self.outputs) * res].reshape(len(self.outputs), res).copy()

    # ------------------------------------------------------------------ inference
    def _inputs(self, args: Sequence[Any], kwargs: Mapping[str, Any]) -> list[Any]:
        if kwargs:
            if args:
                raise TypeError("give the inputs either all by position or all by name")
            unknown = sorted(set(kwargs) - set(self.input_names))
            missing = [n for n in self.input_names if n not in kwargs]
            if unknown or missing:
                raise TypeError(f"inputs by name must be exactly {', '.join(self.input_names)}"
                                + (f"; unknown: {', '.join(unknown)}" if unknown else "")
                                + (f"; missing: {', '.join(missing)}" if missing else ""))
            return [kwargs[n] for n in self.input_names]
        if len(args) != len(self.inputs):
            raise TypeError(f"{self.name} takes {len(self.inputs)} inputs ({', '.join(self.input_names)}), "
                            f"got {len(args)}")
        return list(args)

    #: inputs the bound scalar kernel takes (set by _bind_fast; -1: not bound, or several outputs)
    _fast_arity = -1

    def infer(self, *args: Any, **kwargs: Any):
        """Evaluate the system.

        Inputs are given positionally in declared order (``fis.infer(iou, rdd)``) or by
        name (``fis.infer(iou=..., rdd=...)``). Scalars give a float (single output) or an
        ndarray of shape (n_out,); arrays broadcast against each other and give an ndarray
        of the broadcast shape (single output) or broadcast shape + (n_out,).

        Inputs are real numbers (Python or NumPy integers and floats, NaN and inf included)
        or arrays of them. ``None``, text, ``bool``, complex numbers, dates, time spans,
        masked arrays and object arrays raise ``TypeError`` naming the input; a number too
        large for a float64 raises ``ValueError`` (:func:`fuzzcore.inputs.real_array`).
        """
        # the scalar path: real scalars of the exact types in REAL_SCALARS go straight to the
        # compiled entry point, which converts each as float() would (a loop: no generator)
        if not kwargs:
            if len(args) == self._fast_arity:
                for a in args:
                    if type(a) not in REAL_SCALARS:
                        break
                else:
                    try:
                        return self._fast(args, self._fblob, self._iblob)
                    except (TypeError, OverflowError):  # an int beyond float64: named below
                        pass
        elif not args and len(kwargs) == self._fast_arity:
            try:  # as many names as inputs, each found: exactly the inputs
                values = self._by_name(kwargs)
            except KeyError:
                values = ()
            for a in values:
                if type(a) not in REAL_SCALARS:
                    break
            else:
                if values:
                    try:
                        return self._fast(values, self._fblob, self._iblob)
                    except (TypeError, OverflowError):
                        pass
        values = self._inputs(args, kwargs)
        if len(self.outputs) == 1 and all(type(v) in REAL_SCALARS for v in values):
            fast = self._fast if self._fast is not None else self._bind_fast()
            try:
                return fast(tuple(values), self._fblob, self._iblob)
            except (TypeError, OverflowError):
                pass
        arrays = [real_array(value, f"input {name!r}") for name, value in zip(self.input_names, values)]
        try:
            arrays = np.broadcast_arrays(*arrays)
        except ValueError:
            shapes = ", ".join(f"{n}{a.shape}" for n, a in zip(self.input_names, arrays))
            raise ValueError(f"input shapes do not broadcast: {shapes}") from None
        shape = arrays[0].shape
        X = np.stack([a.ravel() for a in arrays], axis=1) if arrays[0].size else np.empty((0, len(arrays)))
        Y = self._evaluate(np.ascontiguousarray(X))
        if len(self.outputs) == 1:
            return float(Y[0, 0]) if shape == () else Y[:, 0].reshape(shape)
        return Y.reshape(shape + (len(self.outputs),))

    def evaluate(self, X) -> np.ndarray:
        """Evaluate many samples.

        Parameters
        ----------
        X : array_like of shape (n_samples, n_inputs)
            Columns in declared input order.

        Returns
        -------
        ndarray of shape (n_samples, n_outputs)
        """
        X = real_array(X, "X")
        if X.ndim != 2 or X.shape[1] != len(self.inputs):
            raise ValueError(f"X has shape {X.shape}, expected (n_samples, {len(self.inputs)}) "
                             f"with columns {', '.join(self.input_names)}")
        return self._evaluate(np.ascontiguousarray(X))

    def _evaluate(self, X: np.ndarray) -> np.ndarray:
        out = np.empty((X.shape[0], len(self.outputs)))
        kernel = K.evaluate_batch if X.shape[0] >= PARALLEL_THRESHOLD else K.evaluate_serial
        kernel(X, self._fblob, self._iblob, out)
        return out

    def explain(self, *args: Any, **kwargs: Any) -> "Explanation":
        """Evaluate one sample and say why: memberships, rule strengths, aggregated sets."""
        values = self._inputs(args, kwargs)
        arrays = [real_array(value, f"input {name!r}") for name, value in zip(self.input_names, values)]
        shaped = [f"{name}{a.shape}" for name, a in zip(self.input_names, arrays) if a.shape != ()]
        if shaped:
            raise TypeError(f"explain takes one sample, a number per input; got arrays: {', '.join(shaped)}")
        x = np.array([[float(a) for a in arrays]])
        layout = self._layout
        mu = np.empty(layout.n_terms_in)
        fire = np.empty(layout.n_rules)
        res = layout.resolution
        agg = np.zeros((layout.n_out, res))
        out = np.empty((1, layout.n_out))
        K.explain_one(x, self._fblob, self._iblob, mu, fire, agg, out)
        x, out = x[0], out[0]
        memberships, t = {}, 0
        for var in self.inputs:
            memberships[var.name] = {term.name: float(mu[t + k]) for k, term in enumerate(var.terms)}
            t += len(var.terms)
        return Explanation(
            inputs=dict(zip(self.input_names, x.tolist())),
            memberships=memberships,
            rules=self._rule_texts,
            strengths=fire,
            outputs=dict(zip(self.output_names, out.tolist())),
            grid=self.output_grid,
            aggregated=agg if self.type == "mamdani" else None,
        )

    def warmup(self) -> "FuzzySystem":
        """Compile (or load from Numba's cache) every kernel this system uses; returns self.

        Call once before a real-time loop so no call inside it pays for compilation.
        """
        args = tuple(0.5 * sum(v.range) for v in self.inputs)
        self._bind_fast()
        X = np.tile(np.array(args), (PARALLEL_THRESHOLD, 1))
        self._evaluate(X[:1])
        self._evaluate(X)
        self.explain(*args)
        return self

    def _bind_fast(self):
        """Compile the scalar kernel for this input count and keep its compiled entry point.

        Calling the entry point skips Numba's per-call type dispatch (about half the cost
        of a scalar call); the arguments are then always (tuple, fblob, iblob), the tuple
        holding scalars of the types in :data:`~fuzzcore.inputs.REAL_SCALARS`, which the
        entry point converts as ``float()`` does (``PyNumber_Float``; it would also parse
        text and take ``True`` as 1.0, hence the exact-type check before every call).
        """
        args = tuple(0.5 * sum(v.range) for v in self.inputs)
        K.infer_one(args, self._fblob, self._iblob)
        signature = (numba.typeof(args), numba.typeof(self._fblob), numba.typeof(self._iblob))
        fast = K.infer_one.overloads[signature].entry_point
        names = self.input_names
        by_name = operator.itemgetter(*names) if len(names) > 1 else (lambda kwargs: (kwargs[names[0]],))
        object.__setattr__(self, "_fast", fast)
        object.__setattr__(self, "_by_name", by_name)
        object.__setattr__(self, "_fast_arity", len(self.inputs) if len(self.outputs) == 1 else -1)
        return fast

    def __getstate__(self):
        # the bound scalar kernel is a compiled function, which cannot be pickled: rebound on use
        state = dict(self.__dict__)
        state["_fast"] = None
        state.pop("_fast_arity", None)
        state.pop("_by_name", None)
        return state

    def save(self, path) -> None:
        """Write the system to ``path``; the format follows the extension (see :func:`fuzzcore.save`)."""
        from .io import save

        save(self, path)


@dataclass(frozen=True)
class Explanation:
    """Why a system gave its output for one sample (see :meth:`FuzzySystem.explain`).

    ``strengths`` (n_rules,) are weighted firing strengths in rule order; ``grid`` and
    ``aggregated`` (n_outputs, resolution) are the output grid and aggregated fuzzy set
    of a Mamdani system (``None`` for Sugeno).
    """

    inputs: dict[str, float]
    memberships: dict[str, dict[str, float]]
    rules: tuple[str, ...]
    strengths: np.ndarray
    outputs: dict[str, float]
    grid: np.ndarray | None
    aggregated: np.ndarray | None

    def fired(self) -> list[tuple[int, str, float]]:
        """Rules with a positive strength, strongest first: (index, text, strength)."""
        strengths = self.strengths.tolist()
        order = sorted((r for r, v in enumerate(strengths) if v > 0), key=lambda r: -strengths[r])
        return [(r, self.rules[r], strengths[r]) for r in order]

    def __str__(self) -> str:
        lines = ["inputs: " + ", ".join(f"{k} = {v:g}" for k, v in self.inputs.items())]
        for name, terms in self.memberships.items():
            lines.append(f"  {name}: " + ", ".join(f"{t} {m:.3f}" for t, m in terms.items()))
        fired = self.fired()
        lines.append(f"rules fired: {len(fired)} of {len(self.rules)}")
        lines += [f"  [{r + 1}] {s:.3f}  {text}" for r, text, s in fired]
        lines.append("outputs: " + ", ".join(f"{k} = {v:.6g}" for k, v in self.outputs.items()))
        return "\n".join(lines)
