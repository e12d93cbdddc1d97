"""``fuzzrisk compare BEFORE AFTER``: two ``fuzzrisk simulate`` runs of the same scenarios,
scenario by scenario.

Each of BEFORE and AFTER is a simulate output folder (or its ``runs.jsonl``). Prints, as
Markdown, per kind the avoidable collisions each shield avoided (the hazard-free drives it
braked in), then every scenario whose shielded drive changed: a hazard hit in one run and
not in the other, a hazard-free drive that started or stopped braking
(:mod:`monitor.offline.comparison`). Runs of different scenarios, or whose baselines differ,
are refused.
"""
from __future__ import annotations

import argparse

from monitor.offline.comparison import compare_runs, load_runs, to_markdown


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("before", metavar="BEFORE", help="fuzzrisk simulate output folder (or its runs.jsonl)")
    parser.add_argument("after", metavar="AFTER", help="the same scenarios with the shield changed")


def run(args) -> int:
    names = (args.before, args.after)
    comparison = compare_runs(load_runs(args.before), load_runs(args.after), names)
    print(to_markdown(comparison, names), end="")
    return 0
