"""``fuzzrisk simulate``: the monitor and its shield in a closed loop with traffic (paper, Sec. IV-B).

Scenarios of :mod:`monitor.offline.scenarios` (a rare object, a pedestrian between parked
cars, a lead vehicle braking hard, a cut-in, hazard-free drives), ``--scenarios`` of each
kind, spread over the conditions; each is driven by the baseline and by the shielded car
(:mod:`monitor.offline.closed_loop`). ``--sweep M`` drives the first M scenarios of each kind
with a grid of shield settings as well. Writes, in ``--out``:

- ``runs.jsonl``: one line per run (per driver: the baseline, the shield and, for a hazard,
  the shield switched on at the hazard's onset), with its history;
- ``summary.md`` and ``summary.json``: the measures of :mod:`monitor.offline.safety_measures`;
- ``traces.png``, ``conditions.png`` and, with ``--sweep``, ``sweep.jsonl`` and ``trade_off.png``.

``--no-depth-error PART ...`` drives with parts of the depth network's error switched off
(:func:`~monitor.synthetic.without_depth_errors`; ``all``: the true depth), the detector as
the condition degrades it: an ablation that tells what the shield's braking owes to the
depth estimate and what to the monitor's own logic. The summary says so.

Needs highway-env (``pip install fuzzrisk[sim]``). ``--workers N`` drives scenarios in N
processes; the results are the same, in the same order, as with one.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from tqdm import tqdm

from fuzzcore.outputs import check_output_folder, write_text
from monitor.offline.parallel import ordered_map

SWEEP_THRESHOLDS = (0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
#: (threshold - release, hold_frames) of the sweep's hysteresis settings
SWEEP_HYSTERESIS = ((0.0, 0), (0.1, 0), (0.0, 5), (0.1, 5))
OUTPUTS = ("runs.jsonl", "summary.md", "summary.json", "traces.png", "conditions.png")
SWEEP_OUTPUTS = ("sweep.jsonl", "trade_off.png")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from monitor.cli.scenes import add_depth_ablation_argument
    from monitor.offline.scenarios import KINDS
    from monitor.synthetic import CONDITIONS

    parser.add_argument("-o", "--out", default="fuzzrisk-simulation", help="output folder (default %(default)s)")
    parser.add_argument("--overwrite", action="store_true", help="replace outputs already in --out")
    parser.add_argument("--rules", default=None, help="rule base (default: the shipped rules/fuzzrisk.yaml)")
    parser.add_argument("--config", default=None, help="monitor configuration YAML (default: shipped defaults)")
    parser.add_argument("--scenarios", type=int, default=12,
                        help="scenarios per kind, spread over the conditions (default %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the first scenario (default %(default)s)")
    parser.add_argument("--kind", nargs="+", default=list(KINDS), choices=list(KINDS), help="scenario kinds")
    parser.add_argument("--condition", nargs="+", default=list(CONDITIONS), choices=list(CONDITIONS),
                        help="conditions (default: all six)")
    parser.add_argument("--sweep", type=int, default=0,
                        help="also drive the first SWEEP scenarios of each kind with every shield setting of "
                             "the threshold/hysteresis grid (default 0: no sweep)")
    add_depth_ablation_argument(parser)
    parser.add_argument("--workers", type=int, default=1, help="processes (default %(default)s)")


def _check(args: argparse.Namespace) -> list[Path]:
    for name in ("scenarios", "workers"):
        if getattr(args, name) < 1:
            raise ValueError(f"--{name} {getattr(args, name)}: must be >= 1")
    if args.seed < 0:
        raise ValueError(f"--seed {args.seed}: must be >= 0")
    if not 0 <= args.sweep <= args.scenarios:
        raise ValueError(f"--sweep {args.sweep}: must be in [0, --scenarios = {args.scenarios}]")
    names = OUTPUTS + (SWEEP_OUTPUTS if args.sweep else ())
    out = check_output_folder(args.out, names, overwrite=args.overwrite)
    targets = [out / name for name in names]
    return targets


def _jobs(kinds, conditions, n, seed):
    from monitor.offline.scenarios import ScenarioSpec

    return [ScenarioSpec(kind, conditions[j % len(conditions)], seed + j) for kind in kinds for j in range(n)]


def sweep_settings(default):
    """The shield settings of the sweep (ShieldConfig): threshold, release and hold vary, the
    rest (deceleration, path gate) is the default's."""
    from dataclasses import replace

    return [replace(default, threshold=t, release=round(t - gap, 10), hold_frames=hold)
            for t in SWEEP_THRESHOLDS for gap, hold in SWEEP_HYSTERESIS]


@dataclass(frozen=True, eq=False)
class Driver:
    """What every process needs to drive jobs (:func:`monitor.offline.parallel.ordered_map`'s
    spec): the rule base and config paths, the inverse-depth prior (H, W), the
    :class:`~monitor.geometry.camera.Camera` and the depth errors switched off. ``build()``
    makes the monitor once per process and gives the function that drives one job."""

    rules: str | Path
    config_path: str | Path | None
    prior: object
    camera: object
    depth_off: tuple = ()

    def build(self):
        import fuzzcore
        from monitor.config import load_config
        from monitor.offline.closed_loop import Perception
        from monitor.risk_monitor import RiskMonitor

        monitor = RiskMonitor(fuzzcore.load(self.rules), self.prior, self.camera, load_config(self.config_path),
                              explain=False)
        return partial(_drive, Perception(self.camera), monitor, self.depth_off)


def _drive(perception, monitor, off, job):
    """The runs of one ``(spec, shields)`` job: the baseline's, one per shield and, for a hazard,
    the first shield's switched on at the hazard's onset."""
    from monitor.offline.closed_loop import run_scenario
    from monitor.offline.scenarios import HAZARD_KINDS
    from monitor.synthetic import get_condition, without_depth_errors

    spec, shields = job
    condition = without_depth_errors(get_condition(spec.condition), off) if off else None
    return run_scenario(spec, perception, monitor, shields, condition=condition,
                        from_onset=spec.kind in HAZARD_KINDS)


def drive_all(jobs, rules, config_path, prior, camera, workers: int, progress=None, depth_off=()) -> list:
    """Run ``(spec, shields)`` jobs, in ``workers`` processes; results in the order of ``jobs``.
    ``depth_off``: parts of the depth network's error switched off in every job
    (:func:`~monitor.synthetic.without_depth_errors`)."""
    results = []
    for result in ordered_map(Driver(rules, config_path, prior, camera, tuple(depth_off)), jobs, workers=workers):
        results.append(result)
        if progress is not None:
            progress()
    return results


def run(args: argparse.Namespace) -> int:
    targets = _check(args)
    from monitor.offline.scenarios import require_highway_env

    try:
        require_highway_env()
    except ImportError as exc:
        print(f"fuzzrisk simulate: error: {exc}", file=sys.stderr)
        return 2
    from monitor.config import load_config
    from monitor.offline import safety_measures as sm
    from monitor.offline.closed_loop import BASELINE, FROM_ONSET, driver_label
    from monitor.report.closed_loop_figures import condition_figure, trade_off_figure, traces_figure
    from monitor.shipped import shipped_rules
    from monitor.cli.scenes import depth_ablation
    from monitor.synthetic.suite import SYNTHETIC_NOTE, Benchmark

    config = load_config(args.config)  # errors before the work starts
    rules = args.rules or str(shipped_rules())
    if not Path(rules).is_file():
        raise FileNotFoundError(f"--rules {rules}: no such file")
    depth_off = depth_ablation(args)
    bench = Benchmark(conditions=("nominal",), prior_scenes=2, seed=0, depth_off=depth_off)
    prior = bench.prior()
    specs = _jobs(args.kind, args.condition, args.scenarios, args.seed)
    sweep = sweep_settings(config.shield) if args.sweep else []
    sweep_specs = {s for s in _jobs(args.kind, args.condition, args.sweep, args.seed)}
    default = driver_label(config.shield)
    jobs = [(spec, [config.shield] + [c for c in sweep if spec in sweep_specs and driver_label(c) != default])
            for spec in specs]
    start = time.perf_counter()
    bar = tqdm(total=len(jobs), unit="scenario", desc="simulate", disable=None)
    results = drive_all(jobs, rules, args.config, prior, bench.camera, args.workers, bar.update, depth_off)
    bar.close()
    seconds = time.perf_counter() - start

    main = (BASELINE, default, default + FROM_ONSET)
    main_runs = [run for runs in results for run in runs if run.driver in main]
    all_runs = [run for runs in results for run in runs if run.driver != default + FROM_ONSET]
    summary = sm.summarise(main_runs, default)
    summary["seconds"] = seconds
    summary["depth_errors_off"] = list(depth_off)
    ablation = f"--no-depth-error {' '.join(depth_off)} " if depth_off else ""
    summary["command"] = (f"fuzzrisk simulate --scenarios {args.scenarios} --seed {args.seed} --kind "
                          f"{' '.join(args.kind)} --condition {' '.join(args.condition)} --sweep {args.sweep} "
                          f"{ablation}--workers {args.workers}")
    paths = dict(zip(OUTPUTS + (SWEEP_OUTPUTS if args.sweep else ()), targets))
    write_text(paths["runs.jsonl"], "".join(json.dumps(r.to_dict()) + "\n" for r in main_runs))
    write_text(paths["summary.json"], json.dumps(_clean(summary), indent=1) + "\n")
    points = []
    if args.sweep:
        swept = [r for r in all_runs if (r.kind, r.condition, r.seed) in
                 {(s.kind, s.condition, s.seed) for s in sweep_specs}]
        points = sm.trade_off(swept)
        write_text(paths["sweep.jsonl"], "".join(json.dumps(_clean(p)) + "\n" for p in points))
        trade_off_figure(points, default, paths["trade_off.png"])
    write_text(paths["summary.md"], markdown(summary, points, default, len(specs), seconds, args.workers,
                                              SYNTHETIC_NOTE))
    pairs = sm.pair_runs(main_runs, default)
    shown = [p for p in pairs if p[0].collided][:4] + [p for p in pairs if p[0].kind == "hazard-free"][:1]
    traces_figure(shown or pairs[:4], config.shield.threshold, paths["traces.png"])
    condition_figure(summary["by_condition"], paths["conditions.png"])
    print(SYNTHETIC_NOTE)
    print(markdown(summary, points, default, len(specs), seconds, args.workers, None))
    print(f"runs, summary and figures in {args.out}/")
    return 0


def _clean(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def _pct(value) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{100 * value:.0f}%"


def _interval(bounds) -> str:
    """`` [lo, hi]`` of a rate's 95 % interval in per cent, "" when it is undefined."""
    lo, hi = (float("nan"), float("nan")) if bounds is None else bounds
    return "" if any(v is None or math.isnan(v) for v in (lo, hi)) else f" [{100 * lo:.0f}%, {100 * hi:.0f}%]"


def _num(value, fmt="{:.1f}") -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else fmt.format(value)


def markdown(summary: dict, points: list, default: str, n_scenarios: int, seconds: float, workers: int,
             note: str | None) -> str:
    """The summary as Markdown tables."""
    from monitor.cli.scenes import ablation_note

    lines = []
    if note:
        lines += ["# Closed-loop simulation", "", note, ""]
    lines += [f"`{summary['command']}`", ""]
    if summary.get("depth_errors_off"):
        lines += [ablation_note(tuple(summary["depth_errors_off"])), ""]
    lines += [f"Shield `{default}`; {n_scenarios} scenarios, {seconds:.0f} s with {workers} worker(s). "
              "Brackets: 95 % intervals (Wilson's for rates; t for the mean added trip time)."]
    hazard_kinds = [kind for kind in summary["by_kind_condition"] if kind != "hazard-free"]
    if hazard_kinds:
        lines += ["", "## Hazards (baseline collisions avoided by the shield)", "",
                  "| kind | condition | runs | base coll. | shield coll. | avoided | avoidable: avoided | "
                  "avoidable: avoided by the shield switched on at the onset | "
                  "avoidable, detector missed: avoided | avoidable once in the path: avoided | unavoidable | "
                  "impact v (shield) | shield-only | rear-ended |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    rows = []
    for kind in hazard_kinds:
        by_condition = summary["by_kind_condition"][kind]
        for condition, m in list(by_condition.items()) + [("all", summary["by_kind"][kind])]:
            rows.append(f"| {kind} | {condition} | {m['runs']} | {_pct(m['baseline_collision_rate'])} | "
                        f"{_pct(m['shielded_collision_rate'])} | {_pct(m['avoidance_rate'])} | "
                        f"{_pct(m['avoidance_rate_avoidable'])} of {m['avoidable_collisions']}"
                        f"{_interval(m['avoidance_rate_avoidable_interval'])} | "
                        f"{_pct(m['avoidance_rate_avoidable_from_onset'])}"
                        f"{_interval(m['avoidance_rate_avoidable_from_onset_interval'])} | "
                        f"{_pct(m['avoidance_rate_avoidable_missed'])} of {m['avoidable_missed_collisions']}"
                        f"{_interval(m['avoidance_rate_avoidable_missed_interval'])} | "
                        f"{_pct(m['avoidance_rate_avoidable_in_path'])} of {m['avoidable_in_path_collisions']}"
                        f"{_interval(m['avoidance_rate_avoidable_in_path_interval'])} | "
                        f"{m['unavoidable_collisions']} ({_pct(m['avoidance_rate_unavoidable'])} avoided) | "
                        f"{_num(m['impact_speed_shielded'])} m/s | {m['shield_only_collisions']} | "
                        f"{m['rear_ended_shielded']} |")
    lines += rows
    if summary["by_hazard"]:
        lines += ["", "## By what the hazard is (every hazard kind; sizes in runs.jsonl)", "",
                  "| hazard | runs | base coll. | avoidable: avoided | unavoidable | shield-only |",
                  "|---|---|---|---|---|---|"]
        for name, m in summary["by_hazard"].items():
            lines.append(f"| {name} | {m['runs']} | {_pct(m['baseline_collision_rate'])} | "
                         f"{_pct(m['avoidance_rate_avoidable'])} of {m['avoidable_collisions']}"
                         f"{_interval(m['avoidance_rate_avoidable_interval'])} | "
                         f"{m['unavoidable_collisions']} ({_pct(m['avoidance_rate_unavoidable'])} avoided) | "
                         f"{m['shield_only_collisions']} |")
    if "hazard-free" in summary["by_kind"]:
        lines += ["", "## Hazard-free drives (what the shield costs)", "",
                  "| condition | runs | false-brake rate | first engaged by | first engaged on | baseline braked | "
                  "time braking | shield engaged | added trip time | not arrived |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        by_condition = summary["by_kind_condition"]["hazard-free"]
        for condition, m in list(by_condition.items()) + [("all", summary["by_kind"]["hazard-free"])]:
            first = ", ".join(f"{cause} {n}" for cause, n in m["first_engagement"].items()) or "-"
            on = ", ".join(f"{what} {n}" for what, n in m["first_engaged_on"].items()) or "-"
            lines.append(f"| {condition} | {m['runs']} | {_pct(m['false_brake_rate'])}"
                         f"{_interval(m['false_brake_rate_interval'])} | {first} | {on} | "
                         f"{_pct(m['baseline_brake_rate'])} | {_pct(m['braking_share'])} | "
                         f"{_pct(m['engaged_share'])} | {_pct(m['added_trip_time'])}"
                         f"{_interval(m['added_trip_time_interval'])} | {m['not_arrived']} |")
    lines += ["", "## System level (Guerin et al. 2022)", "",
              "| condition | safety gain | residual hazard | availability cost |", "|---|---|---|---|"]
    for condition, m in summary["by_condition"].items():
        g = m["guerin"]
        lines.append(f"| {condition} | {_num(g['safety_gain'], '{:.3f}')} | {_num(g['residual_hazard'], '{:.3f}')} | "
                     f"{_num(g['availability_cost'], '{:.3f}')} |")
    g = summary["overall"]["guerin"]
    lines.append(f"| all | {_num(g['safety_gain'], '{:.3f}')} | {_num(g['residual_hazard'], '{:.3f}')} | "
                 f"{_num(g['availability_cost'], '{:.3f}')} |")
    if points:
        lines += ["", "## Shield settings (sweep)", "",
                  "| setting | avoidance | avoidance (avoidable) | false-brake rate | added trip time |",
                  "|---|---|---|---|---|"]
        for p in points:
            mark = " (default)" if p["driver"] == default else ""
            lines.append(f"| `{p['driver']}`{mark} | {_pct(p['avoidance_rate'])} | "
                         f"{_pct(p['avoidance_rate_avoidable'])} | {_pct(p['false_brake_rate'])} | "
                         f"{_pct(p['added_trip_time'])} |")
    return "\n".join(lines) + "\n"
