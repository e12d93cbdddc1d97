"""Hypothesis strategies: random valid terms and fuzzy systems, built without filtering."""
from __future__ import annotations

from hypothesis import strategies as st

from fuzzcore import FuzzySystem, Rule, Term, Variable
from fuzzcore.testing import INPUT_KINDS, PIECEWISE, term_params, variables  # noqa: F401 (used by tests)

_coord = st.floats(-1.0, 1.0, allow_nan=False, width=64)


@st.composite
def mamdani_systems(draw, kinds=INPUT_KINDS, output_kinds=INPUT_KINDS, defuzzifiers=None,
                    aggregations=("max", "sum", "probor"), max_inputs=3, max_outputs=2, textual=False):
    """Random valid Mamdani systems; ``textual``: every rule has a text form (some input used)."""
    n_in = draw(st.integers(1, max_inputs))
    n_out = draw(st.integers(1, max_outputs))
    inputs = [draw(variables(f"x{i}", kinds)) for i in range(n_in)]
    outputs = [draw(variables(f"y{o}", output_kinds)) for o in range(n_out)]
    rules = []
    for _ in range(draw(st.integers(1, 8))):
        ante = _antecedent(draw, inputs, textual)
        cons = [draw(st.integers(1, len(v.terms))) * draw(st.sampled_from((1, 1, 1, -1))) for v in outputs]
        rules.append(Rule(tuple(ante), tuple(cons), draw(st.sampled_from((1.0, 0.5, 0.25))),
                          draw(st.sampled_from(("and", "or")))))
    return FuzzySystem(
        name="random", inputs=tuple(inputs), outputs=tuple(outputs), rules=tuple(rules),
        and_method=draw(st.sampled_from(("min", "prod"))),
        or_method=draw(st.sampled_from(("max", "probor"))),
        implication=draw(st.sampled_from(("min", "prod"))),
        aggregation=draw(st.sampled_from(aggregations)),
        defuzzifier=draw(st.sampled_from(defuzzifiers or ("centroid", "bisector", "mom", "som", "lom"))),
        resolution=draw(st.sampled_from((101, 101, 11, 257))),
        no_rule_fired=draw(_policies(outputs)),
    )


def _antecedent(draw, inputs, textual):
    ante = [draw(st.integers(-len(v.terms), len(v.terms))) for v in inputs]
    if textual and not any(ante):
        ante[0] = draw(st.integers(1, len(inputs[0].terms)))
    return ante


def _policies(outputs):
    lo, hi = max(v.range[0] for v in outputs), min(v.range[1] for v in outputs)
    numbers = [st.floats(lo, hi)] if lo <= hi else []
    return st.one_of(st.sampled_from(("midpoint", "nan")), *numbers)


@st.composite
def sugeno_systems(draw, max_inputs=3, textual=False):
    n_in = draw(st.integers(1, max_inputs))
    inputs = [draw(variables(f"x{i}")) for i in range(n_in)]
    terms = []
    for k in range(draw(st.integers(1, 4))):
        if draw(st.booleans()):
            terms.append(Term(f"c{k}", "constant", [draw(_coord)]))
        else:
            terms.append(Term(f"l{k}", "linear", draw(st.lists(_coord, min_size=n_in + 1, max_size=n_in + 1))))
    output = Variable("z", (-3.0, 3.0), tuple(terms))
    rules = []
    for _ in range(draw(st.integers(1, 6))):
        ante = _antecedent(draw, inputs, textual)
        rules.append(Rule(tuple(ante), (draw(st.integers(1, len(terms))),), draw(st.sampled_from((1.0, 0.5))),
                          draw(st.sampled_from(("and", "or")))))
    return FuzzySystem(
        name="random_sugeno", type="sugeno", inputs=tuple(inputs), outputs=(output,), rules=tuple(rules),
        and_method=draw(st.sampled_from(("min", "prod"))), or_method=draw(st.sampled_from(("max", "probor"))),
        defuzzifier=draw(st.sampled_from(("wtaver", "wtsum"))),
        no_rule_fired=draw(_policies((output,))),
    )


def samples(system, n: int, draw):
    """``n`` input rows spread a little beyond each input's range."""
    rows = []
    for _ in range(n):
        row = []
        for v in system.inputs:
            lo, hi = v.range
            pad = 0.1 * (hi - lo)
            row.append(draw(st.floats(lo - pad, hi + pad)))
        rows.append(row)
    return rows
