"""``fuzzrisk tune --features train.csv --method patternsearch|pso|joint|lse --rules R.yaml -o OUT.yaml``.

Tunes a rule base on a feature table (:func:`fuzzcore.tune.read_csv`: the rule base's
inputs, ``target`` = 1 - USC~, optional ``scene``), as the paper builds its variants:

- ``patternsearch``: membership functions by pattern search, 5-fold cross-validation by
  scene, 1000 iterations per fold (the "tuned" FIS);
- ``pso``: rule consequents by particle swarm, a swarm of 100 for 20 iterations (the
  "learned" FIS);
- ``joint``: both, alternated until neither improves (the paper's future work);
- ``lse``: a Sugeno system with the rule base's antecedents, one output term per rule
  (``--order 1``: linear, ``0``: constant) fitted by least squares, inside the output's
  range and monotone along the ``--monotone`` inputs (:class:`fuzzcore.tune.LeastSquares`).

The tuned system is written as YAML, named after the output file, with
``metadata.tuning`` saying how it was made (method, settings, seed, the starting rule
base, data file and its SHA-256, rows skipped, scores, this command).
With ``--test`` the metric on a held-out table is reported and recorded as well.

Paths in the metadata (the data files, and those in the recorded command) are written so
that they mean the same on another machine: relative to the folder the command runs in
(the project) when the file is inside it, as given when given relative, and otherwise by
file name only; the SHA-256 identifies the data whatever its path.

The output is checked before any work (a known extension, an existing folder, not one of
the files read, not an existing file unless ``--overwrite``), and written whole or not at
all (:func:`fuzzcore.outputs.write_text`).
"""
from __future__ import annotations

import argparse
import dataclasses
import hashlib
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

import fuzzcore
from fuzzcore.io import check_save_path
from fuzzcore.tune import JointTuner, LeastSquares, ParticleSwarm, PatternSearch, read_csv
from fuzzcore.verification import parse_monotone_specs

METHODS = ("patternsearch", "pso", "joint", "lse")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--features", required=True, metavar="TRAIN.csv",
                        help="feature table: the rule base's inputs, target, optional scene column")
    parser.add_argument("--method", required=True, choices=METHODS, help="what to tune")
    parser.add_argument("--rules", required=True, metavar="RULES.yaml", help="starting rule base")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.yaml", help="where to write the tuned system")
    parser.add_argument("--overwrite", action="store_true", help="replace OUT.yaml if it exists")
    parser.add_argument("--test", metavar="TEST.csv", help="held-out feature table to report the metric on")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default %(default)s)")
    parser.add_argument("--metric", choices=("rmse", "mae"), default="rmse", help="objective (default %(default)s)")
    parser.add_argument("--target", default="target", help="target column (default %(default)s)")
    parser.add_argument("--group", default="scene",
                        help="group column kept together by the folds, if present (default %(default)s)")
    ps = parser.add_argument_group("pattern search (patternsearch, joint)")
    ps.add_argument("--folds", type=int, default=5, help="cross-validation folds, 1 = none (default %(default)s)")
    ps.add_argument("--max-iter", type=int, default=1000, help="iterations per fold (default %(default)s)")
    ps.add_argument("--variables", nargs="+", metavar="NAME",
                    help="variables whose terms are tuned (default: all inputs and outputs)")
    ps.add_argument("--free-order", action="store_true",
                    help="let terms pass each other (default: each variable's terms keep their order)")
    ps.add_argument("--free-partition", action="store_true",
                    help="let terms leave a readable partition: gaps, heavy overlap, any width (default: each "
                         "variable's terms stay ordered, cover its range, overlap and width bounded)")
    pso = parser.add_argument_group("particle swarm (pso, joint)")
    pso.add_argument("--swarm-size", type=int, default=100, help="particles (default %(default)s)")
    pso.add_argument("--swarm-iter", type=int, default=20, help="iterations (default %(default)s)")
    pso.add_argument("--allow-off", action="store_true", help="rules may be switched off")
    lse = parser.add_argument_group("least squares (lse)")
    lse.add_argument("--order", type=int, choices=(0, 1), default=1,
                     help="Sugeno output terms: 1 linear, 0 constant (default %(default)s)")
    lse.add_argument("--monotone", nargs="+", default=[], metavar="INPUT:+|-",
                     help="inputs along which the output must not decrease (+) or increase (-), e.g. iou:-")
    lse.add_argument("--grid", type=int, default=51,
                     help="grid points per input for the monotone constraints (default %(default)s)")
    lse.add_argument("--unbounded", action="store_true",
                     help="let the rules' terms leave the output's range (default: kept inside it)")


def recorded_path(path: str) -> str:
    """``path`` as the metadata records it (module docstring): relative to the working
    directory when inside it, as given when relative, else the file name; ``/`` separators."""
    given = Path(path)
    resolved, here = given.resolve(), Path.cwd().resolve()
    if resolved == here or here in resolved.parents:
        return resolved.relative_to(here).as_posix()
    return given.as_posix() if not given.is_absolute() else given.name


def _command(args: argparse.Namespace) -> str:
    """The command line, normalised (every option that applies, at its value; paths as recorded)."""
    parts = ["fuzzrisk tune", f"--features {recorded_path(args.features)}", f"--method {args.method}",
             f"--rules {recorded_path(args.rules)}", f"-o {recorded_path(args.output)}"]
    if args.test:
        parts.append(f"--test {recorded_path(args.test)}")
    if args.method == "lse":
        parts.append(f"--order {args.order}")
        if args.monotone:
            parts += ["--monotone " + " ".join(args.monotone), f"--grid {args.grid}"]
        if args.unbounded:
            parts.append("--unbounded")
        return " ".join(parts)
    parts += [f"--seed {args.seed}", f"--metric {args.metric}"]
    if args.method != "pso":
        parts += [f"--folds {args.folds}", f"--max-iter {args.max_iter}"]
        if args.variables:
            parts.append("--variables " + " ".join(args.variables))
        if args.free_order:
            parts.append("--free-order")
        if args.free_partition:
            parts.append("--free-partition")
    if args.method != "patternsearch":
        parts += [f"--swarm-size {args.swarm_size}", f"--swarm-iter {args.swarm_iter}"]
        if args.allow_off:
            parts.append("--allow-off")
    return " ".join(parts)


def _sha256(path: str) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _score(system, table, metric: str) -> float:
    """The metric of ``system`` on a feature table (NaN if some prediction is NaN)."""
    error = system.evaluate(table.X) - table.y[:, None]
    return float(np.sqrt(np.mean(error**2)) if metric == "rmse" else np.mean(np.abs(error)))


def _describe(table) -> str:
    groups = "" if table.groups is None else f" in {len(np.unique(table.groups))} groups"
    return (f"{len(table)} rows{groups} (skipped {table.n_no_target} without a target, "
            f"{table.n_no_features} without features)")


def run(args: argparse.Namespace) -> int:
    read = [args.rules, args.features] + ([args.test] if args.test else [])
    monotone = parse_monotone_specs(args.monotone)
    if args.method != "lse" and (monotone or args.unbounded):
        raise ValueError("--monotone and --unbounded are options of --method lse")
    if args.method == "lse" and args.metric != "rmse":
        raise ValueError(f"--metric {args.metric}: least squares (--method lse) minimises the RMSE")
    check_save_path(args.output, read, overwrite=args.overwrite, overwrite_hint="--overwrite")
    system = fuzzcore.load(args.rules)
    train = read_csv(args.features, system.input_names, args.target, args.group)
    test = read_csv(args.test, system.input_names, args.target, args.group) if args.test else None
    print(f"training data {args.features}: {_describe(train)}")
    if test is not None:
        print(f"test data {args.test}: {_describe(test)}")
    if train.groups is None and args.method in ("patternsearch", "joint") and args.folds > 1:
        print(f"note: {args.features} has no {args.group!r} column, so the {args.folds} folds split frames at "
              "random: frames of one scene can land in different folds (an optimistic cross-validation)")

    bar = tqdm(desc=args.method, unit="it", disable=None)

    def progress(info):
        bar.update(1)
        shown = {"fun": f"{info.fun:.5g}"}
        for key in ("fold", "step", "block"):
            if key in info and info[key]:
                shown[key] = info[key]
        bar.set_postfix(shown, refresh=False)

    ps_options = {"n_folds": args.folds, "max_iter": args.max_iter, "variables": args.variables,
                  "keep_order": not args.free_order, "partition": not args.free_partition}
    pso_options = {"swarm_size": args.swarm_size, "max_iter": args.swarm_iter, "allow_off": args.allow_off}
    common = {"metric": args.metric, "seed": args.seed, "callback": progress}
    if args.method == "patternsearch":
        tuner = PatternSearch(system, **ps_options, **common)
    elif args.method == "pso":
        tuner = ParticleSwarm(system, **pso_options, **common)
    elif args.method == "lse":
        tuner = LeastSquares(system, order=args.order, bounded=not args.unbounded, monotone=monotone,
                             grid=args.grid, callback=progress)
    else:
        tuner = JointTuner(system, pattern_search=ps_options, particle_swarm=pso_options, **common)
    started = time.perf_counter()
    try:
        tuner.fit(train.X, train.y, train.groups)
    finally:
        bar.close()
    seconds = time.perf_counter() - started
    result = tuner.result_

    tuning = dict(tuner.system_.metadata["tuning"])
    tuning["data"] = {**tuning["data"], "file": recorded_path(args.features), "sha256": _sha256(args.features),
                      "skipped_no_target": train.n_no_target, "skipped_no_features": train.n_no_features}
    if test is not None:
        initial_test, final_test = _score(system, test, args.metric), _score(tuner.system_, test, args.metric)
        tuning["test"] = {"file": recorded_path(args.test), "sha256": _sha256(args.test), "n_samples": len(test),
                          "initial": initial_test, "final": final_test}
    tuning["command"] = _command(args)
    tuned = dataclasses.replace(tuner.system_, name=Path(args.output).stem,
                                metadata={**tuner.system_.metadata, "tuning": tuning})
    tuned.save(args.output)

    print(f"{args.method}: {result.message}")
    scored = "quadratic programmes solved" if args.method == "lse" else "candidate systems scored"
    print(f"  {result.nit} iterations, {result.nfev} {scored}, {seconds:.1f} s")
    print(f"  training {args.metric}: {result.initial_fun:.5f} (start) -> {result.fun:.5f} (tuned)")
    if len(result.cv_scores):
        print(f"  cross-validation {args.metric} per fold: "
              + ", ".join(f"{v:.5f}" for v in result.cv_scores) + f" (mean {result.cv_score:.5f})")
    if test is not None:
        print(f"  test {args.metric}: {initial_test:.5f} (start) -> {final_test:.5f} (tuned)")
    print(f"written to {args.output}")
    print(f"\nfuzzrisk check {args.output}{' --monotone ' + ' '.join(args.monotone) if args.monotone else ''}:")
    print(fuzzcore.verify(tuned, monotone))
    return 0
