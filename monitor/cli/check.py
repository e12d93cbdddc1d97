"""``fuzzrisk check RULES [--monotone rdd:+] [--threshold T] [--json]``: verify a rule base.

Prints :func:`fuzzcore.verify`'s report: where in the input box no rule fires (exact for
piecewise-linear terms), declared monotonicity, the output range reached, the steepest
change, rules never firing / redundant / conflicting, unused terms and the term partitions.

Exit status, for scripts and CI: 0 when every point of the input box fires a rule (at the
threshold) and every declared property holds; 1 when not; 2 for an error (unreadable file,
bad option).
"""
from __future__ import annotations

import argparse
import json

import fuzzcore
from fuzzcore.verification import parse_monotone_specs


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("rules", metavar="RULES", help="rule base (.yaml or .fis)")
    parser.add_argument("--monotone", nargs="+", default=[], metavar="INPUT:+|-",
                        help="inputs along which every output must not decrease (+) or not increase (-), "
                             "e.g. rdd:+")
    parser.add_argument("--threshold", type=float, default=0.0,
                        help="coverage asks the strongest rule to fire at least this much (default 0: at all)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the sampled searches (default %(default)s)")
    parser.add_argument("--json", action="store_true", help="print the whole report as JSON")


def run(args: argparse.Namespace) -> int:
    fis = fuzzcore.load(args.rules)
    monotone = parse_monotone_specs(args.monotone)
    report = fuzzcore.verify(fis, monotone, threshold=args.threshold, seed=args.seed)
    if args.json:
        print(json.dumps(report.to_dict(), indent=2, allow_nan=False))
    else:
        print(report)
    return 0 if report.ok else 1
