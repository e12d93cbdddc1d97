"""``fuzzrisk convert IN OUT``: convert a rule base between YAML and MATLAB ``.fis``.

Each file's format follows its extension (``.yaml``/``.yml`` or ``.fis``; see
:mod:`fuzzcore.io`). The system is read, validated and written; numbers cross unchanged.
What one format cannot hold is refused with an error naming it (see
:mod:`fuzzcore.fis_format` and :mod:`fuzzcore.yaml_format`), and ``.fis`` names that are not
usable in rule text are renamed with a warning. OUT is checked before reading IN (a known
extension, an existing folder, not IN itself under any name, not an existing file unless
``--overwrite``) and written whole or not at all.
"""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import fuzzcore
from fuzzcore.io import check_save_path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("input", metavar="IN", help="rule base to read (.yaml, .yml or .fis)")
    parser.add_argument("output", metavar="OUT", help="file to write (.yaml, .yml or .fis)")
    parser.add_argument("--overwrite", action="store_true", help="replace OUT if it exists")


def run(args: argparse.Namespace) -> int:
    source = Path(args.input)
    target = check_save_path(args.output, [source], overwrite=args.overwrite, overwrite_hint="--overwrite")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        system = fuzzcore.load(source)
    for warning in caught:  # e.g. a .fis name renamed to be usable in rule text
        print(f"fuzzrisk convert: warning: {warning.message}", file=sys.stderr)
    fuzzcore.save(system, target)
    print(f"{source} -> {target}: {system.type} system {system.name!r}, {len(system.inputs)} input(s), "
          f"{len(system.outputs)} output(s), {len(system.rules)} rule(s)")
    return 0
