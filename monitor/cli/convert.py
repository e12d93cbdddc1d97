"""``fuzzrisk convert IN OUT``: convert a rule base between YAML and MATLAB ``.fis``.

Each file's format follows its extension (``.yaml``/``.yml`` or ``.fis``; see
:mod:`fuzzcore.io`). The system is read, validated and written; numbers cross unchanged.
What one format cannot hold is refused with an error naming it (see
:mod:`fuzzcore.fis_format` and :mod:`fuzzcore.yaml_format`), and ``.fis`` names that are not
usable in rule text are renamed with a warning.
"""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import fuzzcore


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("input", metavar="IN", help="rule base to read (.yaml, .yml or .fis)")
    parser.add_argument("output", metavar="OUT", help="file to write (.yaml, .yml or .fis); overwritten")


def run(args: argparse.Namespace) -> int:
    source, target = Path(args.input), Path(args.output)
    if target.exists() and source.exists() and target.resolve() == source.resolve():
        raise ValueError(f"{target}: OUT is the same file as IN; write to another file")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        system = fuzzcore.load(source)
    for warning in caught:  # e.g. a .fis name renamed to be usable in rule text
        print(f"fuzzrisk convert: warning: {warning.message}", file=sys.stderr)
    fuzzcore.save(system, target)
    print(f"{source} -> {target}: {system.type} system {system.name!r}, {len(system.inputs)} input(s), "
          f"{len(system.outputs)} output(s), {len(system.rules)} rule(s)")
    return 0
