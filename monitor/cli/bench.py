"""``fuzzrisk bench [RULES]``: does a rule base, or the whole monitor, fit a real-time budget here?

Rule base (:func:`fuzzcore.bench.latency`)::

    fuzzrisk bench RULES [--calls N] [--budget 5us] [--percentile p99.9] [--call infer]
                         [--json] [--compare old.json]

prints the per-call latency percentiles of ``fis.infer`` (Python floats; with the garbage
collector frozen; numpy scalars; by name) beside a plain Python call (the floor), the
``evaluate`` throughput on 1 and all threads and a fresh process's start-up.

Monitor (:func:`monitor.offline.latency.monitor_latency`)::

    fuzzrisk bench --monitor [RULES] [--camera calib.yaml | --size 1600x900] [--frames N]
                   [--repeat R] [--hz 12] [--budget 50ms] [--percentile p99]

prints the per-stage latency of ``RiskMonitor.step`` on synthetic frames of that camera
and the share of the frame period at ``--hz``.

RULES defaults to the shipped ``rules/fuzzrisk.yaml``. With ``--budget`` (a time with a
unit: ns, us, µs, ms, s) the exit status is 1 when the chosen percentile of ``--call``
(or, with ``--monitor``, of the whole step) exceeds it. ``--json`` prints the result as
JSON instead of tables (``> run.json`` keeps it for a later ``--compare run.json``).
"""
from __future__ import annotations

import argparse
import json
import math
import re
import sys

import numpy as np

import fuzzcore
from fuzzcore.bench import CALLS, PERCENTILES, BenchResult, latency
from monitor.report.tables import format_table
from monitor.shipped import shipped_rules

#: time units for --budget -> nanoseconds (µ: the micro sign and the Greek letter mu)
UNITS = {"ns": 1.0, "us": 1e3, "\u00b5s": 1e3, "\u03bcs": 1e3, "ms": 1e6, "s": 1e9}
#: ratios within this of 1 are not called better or worse (a shared machine's noise)
NOISE = 0.05
_TIME = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*([^\s0-9.]*)\s*$")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("rules", metavar="RULES", nargs="?", default=None,
                        help="rule base file (.yaml, .yml or .fis; default: the shipped rules/fuzzrisk.yaml)")
    parser.add_argument("--budget", default=None, metavar="TIME",
                        help="fail (exit 1) when the chosen percentile exceeds this time, e.g. 5us, 2ms")
    parser.add_argument("--percentile", default="p99.9", choices=list(PERCENTILES),
                        help="percentile held against --budget (default %(default)s)")
    parser.add_argument("--json", action="store_true", help="print the result as JSON instead of tables")
    parser.add_argument("--seed", type=int, default=0, help="seed of the inputs / scenes (default %(default)s)")
    rules = parser.add_argument_group("rule base")
    rules.add_argument("--calls", type=int, default=None, metavar="N",
                       help="timed calls per way of calling (default 200,000)")
    rules.add_argument("--evaluate-samples", type=int, default=None, metavar="N",
                       help="batch size of the evaluate throughput (default 1,000,000)")
    rules.add_argument("--call", default=None, choices=[c for c in CALLS if c != "floor"],
                       help="the way of calling held against --budget (default infer)")
    rules.add_argument("--compare", default=None, metavar="OLD.json",
                       help="print ratios to an earlier run saved with --json")
    mon = parser.add_argument_group("monitor")
    mon.add_argument("--monitor", action="store_true", help="time RiskMonitor.step stage by stage instead")
    where = mon.add_mutually_exclusive_group()
    where.add_argument("--camera", default=None, metavar="CALIB.yaml",
                       help="camera calibration file (format: monitor.datasets.calibration)")
    where.add_argument("--size", default=None, metavar="WxH",
                       help="image size; nuScenes CAM_FRONT scaled to it (default 1600x900)")
    mon.add_argument("--frames", type=int, default=None, help="distinct synthetic frames (default 24)")
    mon.add_argument("--repeat", type=int, default=None, help="timed steps per frame (default 10)")
    mon.add_argument("--hz", type=float, default=None, help="frame rate of the budget share (default 12)")


def parse_time(text: str, what: str = "--budget") -> float:
    """``"5us"`` -> 5000.0 nanoseconds; a number without a unit is an error naming ``what``."""
    units = ", ".join(u for u in UNITS if u != "\u03bcs")
    match = _TIME.match(text)
    if match is None or (match.group(2) and match.group(2) not in UNITS):
        raise ValueError(f"{what} {text!r}: expected a time with a unit ({units}), e.g. 5us")
    if not match.group(2):
        raise ValueError(f"{what} {text!r} has no unit; write it with one of {units}, e.g. {text.strip()}us")
    value = float(match.group(1)) * UNITS[match.group(2)]
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{what} {text!r}: expected a time > 0")
    return value


def parse_size(text: str) -> tuple[int, int]:
    """``"1600x900"`` -> (1600, 900)."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if match is None or int(match.group(1)) < 1 or int(match.group(2)) < 1:
        raise ValueError(f"--size {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 1600x900")
    return int(match.group(1)), int(match.group(2))


#: table units -> nanoseconds
_TABLE_UNITS = {"us": 1e3, "ms": 1e6}


def _number(value: float) -> str:
    return f"{value:,.3g}" if abs(value) < 100 else f"{value:,.0f}"


def _time(ns: float) -> str:
    """A time in the unit that suits it: ``850 ns``, ``1.41 us``, ``12.3 ms``, ``2 s``."""
    for unit, scale in (("s", 1e9), ("ms", 1e6), ("us", 1e3)):
        if ns >= scale:
            return f"{_number(ns / scale)} {unit}"
    return f"{_number(ns)} ns"


def _latency_table(latencies: dict, first: str, unit: str, count: str) -> str:
    """One row per Latency: its percentiles in ``unit`` (a key of _TABLE_UNITS) and its count."""
    scale = _TABLE_UNITS[unit]
    rows = [{"name": name, **{p: _number(v / scale) for p, v in lat.percentiles_ns.items()},
             "n": f"{lat.count:,}"} for name, lat in latencies.items()]
    columns = [("name", f"{first}, {unit}", "{}")] + [(p, p, "{}") for p in PERCENTILES] + [("n", count, "{}")]
    return format_table(rows, columns)


def _few_samples(latencies: dict) -> str:
    n = min(lat.count for lat in latencies.values())
    if n >= 10_000:
        return ""
    return (f"\n(only {n:,} samples: percentiles above p{100 - 100 / n:.4g} lie between the largest "
            "samples; p99.99 needs 10,000)")


def _check_budget(value_ns: float, budget_ns: float | None, label: str, as_json: bool) -> int:
    """The exit status; the verdict goes to stdout (stderr beside JSON)."""
    if budget_ns is None:
        return 0
    verdict = "within" if value_ns <= budget_ns else "EXCEEDS"
    print(f"budget: {label} = {_time(value_ns)} {verdict} {_time(budget_ns)}",
          file=sys.stderr if as_json else sys.stdout)
    return 0 if value_ns <= budget_ns else 1


def _print_rules(result: BenchResult, path, calls: int) -> None:
    print(f"rule base {path} ({result.system}): {calls:,} timed calls per way, distinct inputs "
          f"(seed {result.seed}), after a warm-up")
    print(f"machine: {result.machine}\n")
    print(_latency_table(result.latencies, "latency per call", "us", "calls") + _few_samples(result.latencies))
    for name, description in CALLS.items():
        print(f"  {name}: {description}")
    print()
    for tp in result.throughput:
        print(f"evaluate, {tp.threads} thread(s), {tp.samples:,} samples: "
              f"{tp.median_per_s / 1e6:,.3g} M samples/s median (best {tp.best_per_s / 1e6:,.3g} M)")
    fresh = result.fresh_process
    if fresh is not None:
        how = (f"{fresh.compiled} kernel(s) compiled" if fresh.compiled
               else f"{fresh.cached} kernel(s) loaded from Numba's cache")
        print(f"fresh process: import {fresh.import_s:.2f} s, load {fresh.load_s:.2f} s, "
              f"warmup {fresh.warmup_s:.2f} s ({how}); {fresh.total_s:.2f} s from start to ready")


def _print_comparison(result: BenchResult, old: BenchResult, path: str) -> None:
    print(f"\ncompared with {path} ({old.machine.cpu}, numba {old.machine.numba}): new / old")
    rows = []
    for r in result.compare(old):
        better = (r.ratio > 1) == r.higher_is_better
        shown = [_time(v) if r.unit == "ns" else f"{_number(v)} {r.unit}" for v in (r.old, r.new)]
        rows.append({"what": r.what, "old": shown[0], "new": shown[1], "ratio": f"x{r.ratio:.2f}",
                     "verdict": "" if abs(r.ratio - 1) < NOISE else ("better" if better else "worse")})
    print(format_table(rows, [("what", "figure", "{}"), ("old", "old", "{}"),
                              ("new", "new", "{}"), ("ratio", "ratio", "{}"), ("verdict", "", "{}")]))


def _run_rules(args, fis, path, budget_ns) -> int:
    old = BenchResult.read(args.compare) if args.compare else None
    calls = 200_000 if args.calls is None else args.calls
    samples = 1_000_000 if args.evaluate_samples is None else args.evaluate_samples
    result = latency(fis, calls, seed=args.seed, evaluate_samples=samples, path=path)
    if args.json:
        print(json.dumps(result.to_dict(), indent=1))
    else:
        _print_rules(result, path, calls)
        if old is not None:
            _print_comparison(result, old, args.compare)
    call = args.call or "infer"
    value = result.latencies[call].percentiles_ns[args.percentile]
    return _check_budget(value, budget_ns, f"{call} {args.percentile}", args.json)


def _camera(args):
    from monitor.datasets.calibration import load_camera
    from monitor.geometry.camera import Camera

    if args.camera is not None:
        return load_camera(args.camera)
    front = Camera.nuscenes_front()
    if args.size is None:
        return front
    width, height = parse_size(args.size)
    scale = np.array([[width / front.width], [height / front.height], [1.0]])
    return Camera(scale * front.K, width, height, front.cam_to_ego)


def _run_monitor(args, fis, budget_ns) -> int:
    from tqdm import tqdm

    from monitor.offline.latency import STAGES, monitor_latency

    camera = _camera(args)
    frames = 24 if args.frames is None else args.frames
    repeat = 10 if args.repeat is None else args.repeat
    hz = 12.0 if args.hz is None else args.hz
    with tqdm(total=frames + repeat, unit="step", desc="bench", disable=None) as bar:
        result = monitor_latency(fis, camera, frames=frames, repeat=repeat, hz=hz, seed=args.seed,
                                 progress=bar.update)
    value = result.stages["step"].percentiles_ns[args.percentile]
    if args.json:
        print(json.dumps(result.to_dict(), indent=1))
        return _check_budget(value, budget_ns, f"step {args.percentile}", True)
    objects = ", ".join(f"{v:.1f} {k}" for k, v in result.objects.items())
    statuses = ", ".join(f"{n} {s}" for s, n in result.statuses.items())
    print(f"RiskMonitor.step on {result.frames} synthetic frames of {result.width}x{result.height} "
          f"(six conditions in turn), each stepped {result.repeat} times; per frame: {objects}; "
          f"status: {statuses}")
    print(f"machine: {result.machine}\n")
    print(_latency_table(result.stages, "latency per stage", "ms", "steps") + _few_samples(result.stages))
    for name, description in STAGES.items():
        print(f"  {name}: {description}")
    share = "  ".join(f"{p} {v:.1%}" for p, v in result.budget_share().items())
    print(f"\nshare of the frame period at {result.hz:g} Hz ({result.frame_budget_ns / 1e6:.1f} ms): {share}")
    return _check_budget(value, budget_ns, f"step {args.percentile}", False)


def run(args: argparse.Namespace) -> int:
    budget_ns = None if args.budget is None else parse_time(args.budget)
    mode, other = ("--monitor", ("calls", "evaluate_samples", "call", "compare")) if args.monitor \
        else ("the rule-base bench", ("camera", "size", "frames", "repeat", "hz"))
    given = [f"--{name.replace('_', '-')}" for name in other if getattr(args, name) is not None]
    if given:
        raise ValueError(f"{', '.join(given)}: not an option of {mode}")
    path = args.rules if args.rules is not None else shipped_rules()
    fis = fuzzcore.load(path)
    if args.monitor:
        return _run_monitor(args, fis, budget_ns)
    return _run_rules(args, fis, path, budget_ns)
