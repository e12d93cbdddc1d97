"""The ``fuzzrisk`` command line: one subcommand per module in :mod:`monitor.cli`.

Each command module defines ``HELP`` (one line), ``add_arguments(parser)`` and
``run(args) -> int`` (the process exit code).
"""
from __future__ import annotations

import argparse
import importlib
import sys

#: subcommand name -> module implementing it (see the module docstring for the protocol)
COMMANDS = {
    "infer": "monitor.cli.infer",
    "demo": "monitor.cli.demo",
    "eval": "monitor.cli.eval",
    "features": "monitor.cli.features",
    "simulate": "monitor.cli.simulate",
    "prior": "monitor.cli.prior",
    "convert": "monitor.cli.convert",
    "tune": "monitor.cli.tune",
    "bench": "monitor.cli.bench",
    "check": "monitor.cli.check",
    "plot": "monitor.cli.plot",
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fuzzrisk",
        description="Run-time collision-risk monitor on a Numba Mamdani fuzzy engine.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, module_name in COMMANDS.items():
        module = importlib.import_module(module_name)
        cmd = sub.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(cmd)
        cmd.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args._run(args) or 0)
    except (ValueError, OSError) as exc:  # user-facing errors: a message, not a traceback
        print(f"fuzzrisk {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
