"""fuzzcore against scikit-fuzzy, simpful and pyfuzzylite, on the same fuzzy system.

Run: ``python benchmarks/peers.py [--rules rules/fuzzrisk.yaml] [--n 2000] [--seed 2025]``

The peers are optional (the ``peers`` extra): ``pip install scikit-fuzzy networkx simpful``
(scikit-fuzzy's control API imports networkx without declaring it) and, because
pyfuzzylite 8.0 declares ``numpy<2`` although it runs on numpy 2, ``pip install --no-deps
pyfuzzylite`` -- a plain install would downgrade numpy. A peer that is not installed is
reported and skipped.

Every installed peer is given the same system: the same membership functions, min for AND
and implication, max for OR and aggregation, the centroid. The script prints, per peer, the
time per sample (one call per sample, and vectorised where the peer can), the ratio to
fuzzcore, and how far its outputs are from fuzzcore's on the same random inputs.

The outputs still differ, because the peers discretise the centroid differently:

- fuzzcore: MATLAB's ``sum(y mu) / sum(mu)`` on ``RES`` grid points from lo to hi (both
  ends included; 101 here, as MATLAB), sums in grid order.
- simpful: the same sum on numpy's ``linspace(lo, hi, subdivisions)``; run with
  ``subdivisions = RES`` it is the same centroid up to rounding (numpy's linspace rounds
  some grid points differently from MATLAB's, simpful computes a slope as
  ``(x - a) * (1 / (b - a))``).
- scikit-fuzzy: the exact centroid of the piecewise-linear interpolation of the aggregated
  set sampled on the output's universe (here the same ``RES`` points): the trapezoid rule,
  not the sum. Input memberships are interpolated from the inputs' universes, built here to
  contain every breakpoint of the terms, so they are exact.
- pyfuzzylite: the midpoint rule, ``lo + (i + 1/2) (hi - lo) / resolution`` for
  ``i < resolution`` (the ends are never sampled); run with ``resolution = RES - 1``, the
  nearest to MATLAB's grid spacing.

The differences printed are therefore (a) rounding for simpful and (b) the discretisation
error of each centroid rule for scikit-fuzzy and pyfuzzylite.
"""
from __future__ import annotations

import argparse
import importlib.metadata
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

import fuzzcore

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Peer:
    """One library's build of the system.

    ``one(x)``: one sample, ``x`` of shape (n_in,) -> float. ``many(X)``: (n, n_in) -> (n,),
    vectorised by the library itself (None when it has no vectorised path).
    """

    name: str
    version: str
    centroid: str
    one: Callable[[np.ndarray], float]
    many: Callable[[np.ndarray], np.ndarray] | None


def check_supported(system) -> None:
    """Raise ValueError unless every peer can express ``system`` exactly."""
    wanted = {"type": "mamdani", "and_method": "min", "or_method": "max", "implication": "min",
              "aggregation": "max", "defuzzifier": "centroid"}
    for field, value in wanted.items():
        if getattr(system, field) != value:
            raise ValueError(f"{system.name}: {field} {getattr(system, field)!r}; the peer comparison "
                             f"needs {field} {value!r}")
    if len(system.outputs) != 1:
        raise ValueError(f"{system.name} has {len(system.outputs)} outputs; the peer comparison needs one")
    for var in system.inputs + system.outputs:
        for term in var.terms:
            if term.kind not in ("trimf", "trapmf"):
                raise ValueError(f"{var.name}.{term.name} is {term.kind}; the peer comparison needs "
                                 "trimf or trapmf terms")
    for r, rule in enumerate(system.rules):
        if rule.weight != 1.0 or any(c < 0 for c in rule.antecedent + rule.consequent):
            raise ValueError(f"rule {r + 1} has a weight or a NOT; the peer comparison needs plain rules")


def _clauses(system, rule):
    """(variable, term) pairs of a rule's antecedent, in input order."""
    return [(var, var.terms[code - 1]) for var, code in zip(system.inputs, rule.antecedent) if code]


def _matlab_grid(lo: float, hi: float, n: int) -> np.ndarray:
    y = lo + (np.arange(n) * (hi - lo)) / (n - 1)
    y[-1] = hi
    return y


def skfuzzy_peer(system) -> Peer:
    import skfuzzy as fuzz
    from skfuzzy import control as ctrl

    def mf(term, universe):
        return (fuzz.trimf if term.kind == "trimf" else fuzz.trapmf)(universe, list(term.params))

    inputs = {}
    for var in system.inputs:
        lo, hi = var.range
        breaks = [p for t in var.terms for p in t.params if lo <= p <= hi]
        inputs[var.name] = ant = ctrl.Antecedent(np.union1d(np.linspace(lo, hi, 201), breaks), var.name)
        for term in var.terms:
            ant[term.name] = mf(term, ant.universe)
    out = system.outputs[0]
    con = ctrl.Consequent(_matlab_grid(*out.range, system.resolution), out.name, defuzzify_method="centroid")
    for term in out.terms:
        con[term.name] = mf(term, con.universe)
    rules = []
    for rule in system.rules:
        clauses = [inputs[var.name][term.name] for var, term in _clauses(system, rule)]
        antecedent = clauses[0]
        for clause in clauses[1:]:
            antecedent = (antecedent & clause) if rule.connective == "and" else (antecedent | clause)
        rules.append(ctrl.Rule(antecedent, con[out.terms[rule.consequent[0] - 1].name]))
    control = ctrl.ControlSystem(rules)
    names = [v.name for v in system.inputs]
    scalar_sim = ctrl.ControlSystemSimulation(control, cache=False)

    def run(sim, values):
        for name, value in zip(names, values):
            sim.input[name] = value
        sim.compute()
        return sim.output[out.name]

    def many(X):  # a new simulation per batch: one keeps the shape of its first array inputs
        return np.asarray(run(ctrl.ControlSystemSimulation(control, cache=False), X.T), dtype=float)

    return Peer("scikit-fuzzy", importlib.metadata.version("scikit-fuzzy"),
                f"exact centroid of the piecewise-linear set on {system.resolution} points",
                lambda x: float(run(scalar_sim, x)), many)


def simpful_peer(system) -> Peer:
    import simpful as sf

    fs = sf.FuzzySystem(show_banner=False, verbose=False)
    for var in system.inputs + system.outputs:
        sets = [sf.FuzzySet(term=t.name, function=(sf.Triangular_MF(*t.params) if t.kind == "trimf"
                                                   else sf.Trapezoidal_MF(*t.params)))
                for t in var.terms]
        fs.add_linguistic_variable(var.name, sf.LinguisticVariable(sets, universe_of_discourse=list(var.range)))
    out = system.outputs[0]
    texts = []
    for rule in system.rules:
        join = " AND " if rule.connective == "and" else " OR "
        clauses = join.join(f"({var.name} IS {term.name})" for var, term in _clauses(system, rule))
        texts.append(f"IF {clauses} THEN ({out.name} IS {out.terms[rule.consequent[0] - 1].name})")
    fs.add_rules(texts, verbose=False)
    names = [v.name for v in system.inputs]

    def one(x):
        for name, value in zip(names, x):
            fs.set_variable(name, float(value), verbose=False)
        return float(fs.Mamdani_inference([out.name], subdivisions=system.resolution)[out.name])

    return Peer("simpful", importlib.metadata.version("simpful"),
                f"sum(y mu) / sum(mu) on numpy's linspace, {system.resolution} points", one, None)


def pyfuzzylite_peer(system) -> Peer:
    import fuzzylite as fl

    def term_of(t):
        return fl.Triangle(t.name, *t.params) if t.kind == "trimf" else fl.Trapezoid(t.name, *t.params)

    out = system.outputs[0]
    resolution = system.resolution - 1
    engine = fl.Engine(
        name=system.name,
        input_variables=[fl.InputVariable(name=v.name, minimum=v.range[0], maximum=v.range[1],
                                          terms=[term_of(t) for t in v.terms]) for v in system.inputs],
        output_variables=[fl.OutputVariable(name=out.name, minimum=out.range[0], maximum=out.range[1],
                                            aggregation=fl.Maximum(), defuzzifier=fl.Centroid(resolution),
                                            default_value=0.5 * sum(out.range),
                                            terms=[term_of(t) for t in out.terms])],
        rule_blocks=[fl.RuleBlock(conjunction=fl.Minimum(), disjunction=fl.Maximum(),
                                  implication=fl.Minimum(), activation=fl.General())])
    for rule in system.rules:
        clauses = f" {rule.connective} ".join(f"{var.name} is {term.name}"
                                              for var, term in _clauses(system, rule))
        text = f"if {clauses} then {out.name} is {out.terms[rule.consequent[0] - 1].name}"
        engine.rule_blocks[0].rules.append(fl.Rule.create(text, engine))

    def run(X):
        engine.input_values = X
        engine.process()
        return engine.output_values[:, 0]

    return Peer("pyfuzzylite", importlib.metadata.version("pyfuzzylite"),
                f"midpoint rule, {resolution} points, ends not sampled",
                lambda x: float(run(np.atleast_2d(x))[0]), run)


BUILDERS = {"scikit-fuzzy": skfuzzy_peer, "simpful": simpful_peer, "pyfuzzylite": pyfuzzylite_peer}


def build_peers(system) -> tuple[list[Peer], dict[str, str]]:
    """The installed peers' builds of ``system`` and, for the others, why they are missing."""
    check_supported(system)
    peers, missing = [], {}
    for name, build in BUILDERS.items():
        try:
            peers.append(build(system))
        except ImportError as exc:
            missing[name] = f"not installed ({exc})"
    return peers, missing


def sample_inputs(system, n: int, seed: int) -> np.ndarray:
    """``n`` rows uniform over each input's range (seeded)."""
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(*v.range, n) for v in system.inputs])


def cpu_seconds(fn, repeats: int = 5) -> float:
    """Smallest CPU time of ``repeats`` calls (the machine is shared: CPU time, min of N)."""
    best = np.inf
    for _ in range(repeats):
        start = time.process_time()
        fn()
        best = min(best, time.process_time() - start)
    return best


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rules", default=str(ROOT / "rules" / "fuzzrisk.yaml"))
    parser.add_argument("--n", type=int, default=2000, help="samples (default 2000)")
    parser.add_argument("--seed", type=int, default=2025)
    args = parser.parse_args(argv)

    fis = fuzzcore.load(args.rules).warmup()
    peers, missing = build_peers(fis)
    X = sample_inputs(fis, args.n, args.seed)
    ours = fis.evaluate(X)[:, 0]
    rows = [(tuple(map(float, x))) for x in X]

    def per_sample(seconds, count):
        return seconds / count * 1e6

    ours_one = per_sample(cpu_seconds(lambda: [fis.infer(*r) for r in rows]), len(rows))
    ours_many = per_sample(cpu_seconds(lambda: fis.evaluate(X), 20), len(rows))
    print(f"system {fis.name} ({args.rules}), {args.n} samples, seed {args.seed}; CPU time, min of N\n")
    print(f"{'library':14s} {'version':9s} {'us/call':>9s} {'x fuzzcore':>10s} {'us/sample vec':>14s} "
          f"{'x fuzzcore':>10s} {'max |diff|':>11s} {'mean |diff|':>11s}  centroid")
    print(f"{'fuzzcore':14s} {importlib.metadata.version('fuzzrisk'):9s} {ours_one:9.3f} {1.0:10.1f} "
          f"{ours_many:14.4f} {1.0:10.1f} {0.0:11.2e} {0.0:11.2e}  MATLAB's: sum on {fis.resolution} points")
    for peer in peers:
        m = min(len(X), 300)  # one call per sample is slow for some peers
        one = per_sample(cpu_seconds(lambda: [peer.one(x) for x in X[:m]], 3), m)
        theirs = np.array([peer.one(x) for x in X[:m]])
        many = None
        if peer.many is not None:
            many = per_sample(cpu_seconds(lambda: peer.many(X), 3), len(X))
            theirs = peer.many(X)
        diff = np.abs(theirs - ours[:len(theirs)])
        vec = f"{many:14.4f} {many / ours_many:10.0f}" if many is not None else f"{'-':>14s} {'-':>10s}"
        print(f"{peer.name:14s} {peer.version:9s} {one:9.1f} {one / ours_one:10.0f} {vec} "
              f"{diff.max():11.2e} {diff.mean():11.2e}  {peer.centroid}")
    for name, why in missing.items():
        print(f"{name:14s} {why}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
