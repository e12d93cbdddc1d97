"""``fuzzrisk infer RULES --iou 0.4 --rdd 0.3 [--explain]``: evaluate a rule base once.

The input options are the rule base's own input names (``--NAME VALUE`` for each, in any
order); ``--explain`` also prints the memberships and the rules that fired.
"""
from __future__ import annotations

import argparse
import math

import fuzzcore


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("rules", metavar="RULES", help="rule base file (.yaml, .yml or .fis)")
    parser.add_argument("--explain", action="store_true", help="print memberships and the rules that fired")
    parser.add_argument("values", nargs=argparse.REMAINDER, metavar="--INPUT VALUE",
                        help="one --NAME VALUE per input of the rule base, e.g. --iou 0.4 --rdd 0.3")


def _values(fis: fuzzcore.FuzzySystem, tokens: list[str]) -> tuple[dict[str, float], bool]:
    """The input values (and whether --explain came among them) from the remaining tokens."""
    usage = " ".join(f"--{n} VALUE" for n in fis.input_names)
    explain = "--explain" in tokens
    tokens = [t for t in tokens if t != "--explain"]
    values: dict[str, float] = {}
    for flag, value in zip(tokens[::2], tokens[1::2] + [None]):
        name = flag[2:] if flag.startswith("--") else None
        if name not in fis.input_names:
            raise ValueError(f"unexpected {flag!r}; {fis.name} takes {usage}")
        if value is None:
            raise ValueError(f"{flag} needs a value")
        if name in values:
            raise ValueError(f"{flag} is given twice ({values[name]!r}, then {value!r}); give each input once")
        try:
            number = float(value)
        except ValueError:
            raise ValueError(f"{flag} {value!r}: expected a number") from None
        if math.isinf(number) and "inf" not in value.lower():
            raise ValueError(f"{flag} {value!r} is too large for a float64 (|x| < 1.8e308)")
        values[name] = number
    missing = [n for n in fis.input_names if n not in values]
    if missing:
        raise ValueError(f"missing {', '.join('--' + n for n in missing)}; {fis.name} takes {usage}")
    return values, explain


def run(args: argparse.Namespace) -> int:
    fis = fuzzcore.load(args.rules)
    values, explain = _values(fis, args.values)
    if args.explain or explain:
        print(fis.explain(**values))
        return 0
    result = fis.infer(**values)
    if len(fis.outputs) == 1:
        print(f"{fis.output_names[0]} = {result:.6g}")
    else:
        print(", ".join(f"{n} = {v:.6g}" for n, v in zip(fis.output_names, result)))
    return 0
