"""The ``fuzzrisk`` command line: one subcommand per module in :mod:`monitor.cli`.

Each command module defines ``add_arguments(parser)`` and ``run(args) -> int`` (the process
exit code); its one-line help is in :data:`COMMANDS`.

A command's module, and with it what the command needs (OpenCV, matplotlib, ...), is
imported only when that command is named on the command line: ``fuzzrisk --help`` lists
the commands from :data:`COMMANDS` alone, and ``fuzzrisk infer`` imports the fuzzy engine
and nothing else.
"""
from __future__ import annotations

import argparse
import importlib
import sys

#: subcommand name -> (module implementing it, one-line help); see the module docstring
COMMANDS = {
    "infer": ("monitor.cli.infer", "evaluate a rule base (YAML or MATLAB .fis) for one set of inputs"),
    "demo": ("monitor.cli.demo", "run the monitor on built-in synthetic scenes and write reports and figures"),
    "eval": ("monitor.cli.eval", "the monitor's quality measures and the paper's validation tables, "
                                 "on synthetic or recorded scenes"),
    "features": ("monitor.cli.features",
                 "export per-frame features (iou, rdd) and targets (1 - USC~) of scenes as CSV"),
    "simulate": ("monitor.cli.simulate",
                 "closed loop with traffic: collisions avoided and false braking of the monitor's shield"),
    "compare": ("monitor.cli.compare", "two simulate runs of the same scenarios, scenario by scenario: "
                                       "the collisions and false braking a change to the shield moved"),
    "prior": ("monitor.cli.prior",
              "build the inverse-depth prior (mean 1/D of training frames) used by the retrieval"),
    "convert": ("monitor.cli.convert",
                "convert a rule base between YAML and MATLAB .fis (the format follows each extension)"),
    "tune": ("monitor.cli.tune", "tune a rule base on a feature table: membership functions "
                                 "(patternsearch), rules (pso) or both (joint)"),
    "bench": ("monitor.cli.bench",
              "measure the latency of a rule base (or of the monitor) against a real-time budget"),
    "monitor": ("monitor.cli.monitor", "run the monitor over recordings (yours, nuScenes, synthetic): "
                                       "per-frame reports, timelines, summary"),
    "check": ("monitor.cli.check", "verify a rule base: coverage of the input box, monotonicity, "
                                   "output range, rules and terms"),
    "plot": ("monitor.cli.plot", "draw a rule base's terms and output surface, with uncovered and "
                                 "non-monotone regions marked"),
}


def _named_command(argv: list[str]) -> str | None:
    """The subcommand ``argv`` names (its first word that is not an option), if it is one."""
    for token in argv:
        if not token.startswith("-"):
            return token if token in COMMANDS else None
    return None


def build_parser(argv: list[str]) -> argparse.ArgumentParser:
    """The ``fuzzrisk`` parser for the command line ``argv`` (without the program name).

    Every command is listed with its help line; only the command ``argv`` names has its
    module imported and its arguments declared.
    """
    parser = argparse.ArgumentParser(
        prog="fuzzrisk",
        description="Run-time collision-risk monitor on a Numba Mamdani fuzzy engine.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    named = _named_command(argv)
    for name, (module_name, help_line) in COMMANDS.items():
        cmd = sub.add_parser(name, help=help_line, description=help_line)
        if name == named:
            module = importlib.import_module(module_name)
            module.add_arguments(cmd)
            cmd.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = build_parser(argv).parse_args(argv)
    try:
        return int(args._run(args) or 0)
    except (ValueError, OSError) as exc:  # user-facing errors: a message, not a traceback
        print(f"fuzzrisk {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
