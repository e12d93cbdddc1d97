"""``fuzzrisk eval``: the paper's validation (Tables I-III) and the rule bases' RMSE.

On the synthetic benchmark by default (the report says so), or on scene folders:

- Table I: Pearson r between the features measured against the depth view S and against
  the ground truth G, for (alpha, beta) = (0.5, 0.1) and (0.3, 0.2);
- Table II: recall of G by S and by P, per condition, for both settings;
- Table III: approved true positives and identified false negatives per condition;
- the RMSE of every rule base in the rules folder against 1 - USC~ on the held-out test
  scenes (split by scene, never by frame).
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from tqdm import tqdm

import fuzzcore
from monitor.cli.scenes import add_scene_arguments, count_frames, select_scenes
from monitor.config import load_config
from monitor.offline.evaluation import (PAPER_THRESHOLDS, correlation_table, detection_analysis,
                                observe_scenes, recall_table, rmse_table)
from monitor.risk_monitor import RiskMonitor
from monitor.shipped import rules_dir, shipped_rules
from monitor.report.tables import format_table

CORRELATION = [("alpha", "alpha", "{}"), ("beta", "beta", "{}"), ("frames", "frames", "{}"),
               ("iou_r", "r IoU~", "{:.2f}"), ("rdd_r", "r RDD~", "{:.2f}")]
RECALL = [("condition", "condition", "{}"), ("setting", "(alpha, beta)", "{}"), ("gts", "GTs", "{}"),
          ("recall_s", "recall S", "{:.2f}"), ("recall_p", "recall P", "{:.2f}")]
ANALYSIS = [("condition", "condition", "{}"), ("scenes", "scenes", "{}"), ("gts", "GTs", "{}"),
            ("approved", "approved TPs", "{}"), ("identified", "identified FNs", "{}")]
RMSE = [("rules", "rule base", "{}"), ("frames", "test frames", "{}"), ("rmse", "RMSE", "{:.4f}"),
        ("mae", "MAE", "{:.4f}")]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("-o", "--out", default="fuzzrisk-eval", help="output folder (default %(default)s)")
    parser.add_argument("--rules-dir", default=None, help="rule bases to compare (default: the shipped rules/)")
    parser.add_argument("--config", default=None, help="monitor configuration YAML (default: shipped defaults)")
    add_scene_arguments(parser, default_scenes=6, default_test=2)


def _by_condition(observations):
    groups = {}
    for ob in observations:
        groups.setdefault(ob.condition, []).append(ob)
    return groups


def run(args: argparse.Namespace) -> int:
    bar = tqdm(total=count_frames(args, None), unit="frame", desc="eval", disable=None)
    selection = select_scenes(args, None, progress=bar.update)
    config = load_config(args.config)
    monitor = RiskMonitor(fuzzcore.load(shipped_rules()), selection.prior, selection.camera, config,
                          explain=False)
    observations = observe_scenes(monitor, selection.scenes, progress=bar.update)
    bar.close()
    test_names = {s.name for s in selection.scenes if s.split == "test"}
    folder = Path(args.rules_dir) if args.rules_dir else rules_dir()
    systems = {p.name: fuzzcore.load(p) for p in sorted(folder.glob("*.yaml")) + sorted(folder.glob("*.fis"))}
    if not systems:
        raise ValueError(f"no rule bases (.yaml, .fis) in {folder}")

    groups = _by_condition(observations)
    tables = {
        "correlation": correlation_table(observations),
        "recall": [{"condition": c, "setting": f"({a}, {b})", **recall_table(obs, a, b)}
                   for c, obs in groups.items() for a, b in PAPER_THRESHOLDS],
        "analysis": [], "rmse": rmse_table([ob for ob in observations if ob.scene in test_names], systems),
    }
    for condition, obs in groups.items():
        counts = detection_analysis(obs, config.alpha, config.beta)
        tables["analysis"].append({
            "condition": condition, "scenes": len({ob.scene for ob in obs}),
            "gts": counts["tps"] + counts["fns"],
            "approved": f"{counts['approved_tps']} / {counts['tps']}",
            "identified": f"{counts['identified_fns']} / {counts['fns']}", **counts})
    sections = [
        ("Table I: correlation of S-based and G-based features (all frames)", tables["correlation"], CORRELATION),
        ("Table II: recall of the ground truth by S and by P", tables["recall"], RECALL),
        (f"Table III: the depth view over the detector's TPs and FNs (alpha {config.alpha}, beta {config.beta})",
         tables["analysis"], ANALYSIS),
        (f"Rule bases against 1 - USC~ on the {len(test_names)} held-out test scenes", tables["rmse"], RMSE),
    ]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(selection.note)
    lines = ["# fuzzrisk evaluation", "", f"> {selection.note}", ""]
    for title, rows, columns in sections:
        print(f"\n{title}\n{format_table(rows, columns)}")
        lines += [f"## {title}", "", format_table(rows, columns, markdown=True), ""]
    (out / "report.md").write_text("\n".join(lines), encoding="utf-8")
    (out / "tables.json").write_text(json.dumps({"note": selection.note, **tables}, indent=1), encoding="utf-8")
    print(f"\nreport: {out / 'report.md'}")
    return 0
