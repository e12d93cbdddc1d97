"""``fuzzrisk eval``: the monitor's quality measures, then the paper's validation (Tables I-III).

On the synthetic benchmark by default (the report says so), or on scene folders. The
headline (:mod:`monitor.offline.measures`), on the held-out test scenes, per condition and
over all frames, for every rule base in the rules folder and the constant predictor (the
training scenes' mean target):

- r and Spearman's rho of the risk against 1 - USC~, RMSE and skill against the constant;
- AUROC and AUPRC of the risk for hazard frames (a ground truth within range that no
  detection covers: IoG > --hazard-iog and DR > --hazard-dr), hit and false-alarm rates at
  the shield threshold, the AUROC and the hit rate on the hazard frames the depth view has
  in view, FPR at 80 % TPR (the false alarms at an 80 % hit rate, whatever the threshold
  that reaches it) and at 95 %;
- the depth view's recall and precision of the ground truth within range, the share of
  hazard frames in which it finds what the detector missed, the share of frames per
  status; a figure (``quality.png``): ROC curves and risk against target;
- how sure those are (:mod:`monitor.offline.bootstrap`): each rule base's r, skill, AUROC,
  hit and false-alarm rates and FPR at 80 % TPR with 95 % intervals from ``--bootstrap``
  resamples of the held-out scenes, and its differences in r, RMSE and AUROC from the
  monitor's own rule base, paired on the same resamples.

Below them, the paper's tables:

- Table I: Pearson r between the features measured against the depth view S and against
  the ground truth G, for (alpha, beta) = (0.5, 0.1) and (0.3, 0.2);
- Table II: recall of G by S and by P, per condition, for both settings;
- Table III: approved true positives and identified false negatives per condition;
- the RMSE of every rule base in the rules folder against 1 - USC~ on the held-out test
  scenes (split by scene, never by frame).

``frames.jsonl`` holds what they are computed from, one line per frame of every scene
(training and test): its status, features, object counts, target, hazard and each rule
base's risk (:func:`monitor.offline.measures.frame_rows`), for finding the frames behind a
false alarm or measuring something the report does not.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from tqdm import tqdm

import fuzzcore
from fuzzcore.outputs import check_output_folder, write_text
from monitor.cli.scenes import add_parallel_arguments, add_scene_arguments, count_frames, run_spec, select_scenes
from monitor.config import load_config
from monitor.offline.bootstrap import bootstrap_tables
from monitor.offline.evaluation import (PAPER_THRESHOLDS, correlation_table, detection_analysis,
                                recall_table, rmse_table)
from monitor.offline.measures import (HazardCriterion, frame_rows, frame_truth, quality_tables,
                                      rule_base_risk, training_mean)
from monitor.offline.run import observe_plans
from monitor.report.quality_figure import save_quality_figure
from monitor.shipped import rules_dir, shipped_rules
from monitor.report.tables import format_table, interval_cell

QUALITY = [("condition", "condition", "{}"), ("predictor", "predictor", "{}"), ("frames", "frames", "{}"),
           ("hazards", "hazards", "{}"), ("pearson", "r", "{:.2f}"), ("spearman", "rho", "{:.2f}"),
           ("rmse", "RMSE", "{:.3f}"), ("skill", "skill", "{:.2f}"), ("auroc", "AUROC", "{:.2f}"),
           ("auroc_in_view", "AUROC in view", "{:.2f}"), ("auprc", "AUPRC", "{:.2f}"),
           ("hit_rate", "hit", "{:.0%}"), ("hit_in_view", "hit in view", "{:.0%}"),
           ("false_alarm_rate", "false al.", "{:.0%}"),
           ("fpr80", "FPR@80", "{:.0%}"), ("fpr95", "FPR@95", "{:.0%}")]
DEPTH_VIEW = [("condition", "condition", "{}"), ("frames", "frames", "{}"), ("gts", "GTs", "{}"),
              ("recall", "recall", "{:.2f}"), ("objects", "S", "{}"), ("precision", "precision", "{:.2f}"),
              ("hazards_in_view", "hazards in view", "{:.0%}"),
              ("ok", "ok", "{:.0%}"), ("no-objects", "no-objects", "{:.0%}"),
              ("invalid-input", "invalid", "{:.0%}"), ("no-view", "no-view", "{:.0%}"),
              ("no-rule-fired", "no rule", "{:.0%}")]

#: the bootstrap's measures as the report shows them: (row key, header, format of a value)
INTERVAL_COLUMNS = (("pearson", "r", "{:.2f}"), ("skill", "skill", "{:.2f}"), ("auroc", "AUROC", "{:.2f}"),
                    ("hit_rate", "hit", "{:.0%}"), ("false_alarm_rate", "false al.", "{:.0%}"),
                    ("fpr80", "FPR@80", "{:.0%}"))
PAIRED_COLUMNS = (("pearson", "r", "{:+.3f}"), ("rmse", "RMSE", "{:+.3f}"), ("auroc", "AUROC", "{:+.3f}"))
INTERVALS = [("condition", "condition", "{}"), ("predictor", "predictor", "{}")] + \
    [(key, header, "{}") for key, header, _ in INTERVAL_COLUMNS]
PAIRED = [("condition", "condition", "{}"), ("predictor", "predictor", "{}")] + \
    [(key, f"{header} difference", "{}") for key, header, _ in PAIRED_COLUMNS]
#: seed of the scene bootstrap (the report says it)
BOOTSTRAP_SEED = 0

#: the files the command writes in its output folder (checked before the work starts)
OUTPUTS = ("report.md", "tables.json", "quality.png", "frames.jsonl")

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
    parser.add_argument("--overwrite", action="store_true", help="replace the output folder's earlier files")
    parser.add_argument("--rules-dir", default=None, help="rule bases to compare (default: the shipped rules/)")
    parser.add_argument("--config", default=None, help="monitor configuration YAML (default: shipped defaults)")
    parser.add_argument("--hazard-iog", type=float, default=0.5,
                        help="a detection covers a ground truth when IoG > this (default %(default)s)")
    parser.add_argument("--hazard-dr", type=float, default=0.8,
                        help="... and DR = min(1, d_G / d_P) > this (default %(default)s)")
    parser.add_argument("--bootstrap", type=int, default=2000,
                        help="resamples of the held-out scenes for the measures' 95 %% intervals "
                             "(default %(default)s; 0: none)")
    add_scene_arguments(parser, default_scenes=6, default_test=2)
    add_parallel_arguments(parser)


def _by_condition(observations):
    groups = {}
    for ob in observations:
        groups.setdefault(ob.condition, []).append(ob)
    return groups


def _undefined(rows: list[dict]) -> str:
    """Why some measures are '-': one line per condition and reason."""
    reasons = {}
    for row in rows:
        for note in filter(None, row["notes"].split("; ")):
            reasons.setdefault((row["condition"], note), []).append(row["predictor"])
    lines = [f"- {condition}: {note} ({', '.join(who)})" for (condition, note), who in reasons.items()]
    return "\n".join(["Undefined measures ('-'):"] + lines) if lines else "Every measure is defined."


def _uncertainty_sections(quality: list[dict], intervals: list[dict], paired: list[dict], draws: int,
                          against: str) -> list[tuple]:
    """The report's sections of the bootstrap (none without one): its rows as cells
    ``value [lo, hi]``, the value measured on the frames themselves."""
    if not intervals:
        return []
    point = {(row["condition"], row["predictor"]): row for row in quality}
    shown = [{"condition": row["condition"], "predictor": row["predictor"], "notes": row["notes"],
              **{key: interval_cell(point[(row["condition"], row["predictor"])][key], row[f"{key}_lo"],
                                    row[f"{key}_hi"], fmt) for key, _, fmt in INTERVAL_COLUMNS}}
             for row in intervals]
    differences = [{"condition": row["condition"], "predictor": row["predictor"], "notes": row["notes"],
                    **{key: interval_cell(row[f"{key}_diff"], row[f"{key}_diff_lo"], row[f"{key}_diff_hi"], fmt)
                       for key, _, fmt in PAIRED_COLUMNS}}
                   for row in paired]
    how = (f"{draws} resamples of the held-out scenes, whole scenes drawn with replacement within each "
           f"condition, seed {BOOTSTRAP_SEED}")
    sections = [(f"How sure: 95 % intervals of the measures ({how})", shown, INTERVALS)]
    if differences:
        sections.append((f"Against the monitor's rule base {against}: differences, paired on the same "
                         f"resamples (95 % intervals; RMSE below 0 is better)", differences, PAIRED))
    return sections


def run(args: argparse.Namespace) -> int:
    if args.bootstrap < 0:
        raise ValueError(f"--bootstrap {args.bootstrap}: must be >= 0 (0: no intervals)")
    out = check_output_folder(args.out, OUTPUTS, args.overwrite)
    try:
        criterion = HazardCriterion(min_iog=args.hazard_iog, min_dr=args.hazard_dr)
    except ValueError as exc:
        raise ValueError(f"--hazard-iog {args.hazard_iog} / --hazard-dr {args.hazard_dr}: {exc}") from None
    bar = tqdm(total=count_frames(args, None), unit="frame", desc="eval", disable=None)
    selection = select_scenes(args, None, progress=bar.update)
    config = load_config(args.config)
    observations = observe_plans(run_spec(args, selection, config), selection.scenes, workers=args.workers,
                                 ray=args.ray, progress=bar.update)
    bar.close()
    test_names = {s.name for s in selection.scenes if s.split == "test"}
    folder = Path(args.rules_dir) if args.rules_dir else rules_dir()
    systems = {p.name: fuzzcore.load(p) for p in sorted(folder.glob("*.yaml")) + sorted(folder.glob("*.fis"))}
    if not systems:
        raise ValueError(f"no rule bases (.yaml, .fis) in {folder}")

    truth = [frame_truth(ob, criterion) for ob in observations]
    test = [ob for ob in observations if ob.scene in test_names]
    train_truth = [t for t, ob in zip(truth, observations) if ob.scene not in test_names]
    test_truth = [t for t, ob in zip(truth, observations) if ob.scene in test_names]
    reference, reference_note = training_mean(train_truth, test_truth)
    threshold = config.shield.threshold
    quality, depth_view, risks = quality_tables(test, test_truth, systems, reference, threshold,
                                                config.risk.fail_safe)
    shipped = shipped_rules().name if shipped_rules().name in risks else next(iter(systems))
    intervals, paired = [], []
    if args.bootstrap:
        intervals, paired = bootstrap_tables(test_truth, [ob.scene for ob in test],
                                             {name: risks[name] for name in systems}, reference, threshold,
                                             shipped, draws=args.bootstrap, seed=BOOTSTRAP_SEED)
    by_condition = _by_condition(test)
    figure = save_quality_figure(
        out / "quality.png", {c: risks[shipped][[ob.condition == c for ob in test]] for c in by_condition},
        {c: [t for t, ob in zip(test_truth, test) if ob.condition == c] for c in by_condition}, threshold,
        f"{shipped} on {len(test_names)} held-out scenes")

    groups = _by_condition(observations)
    tables = {
        "quality": quality, "depth_view": depth_view,
        "quality_settings": {"reference": reference, "reference_note": reference_note,
                             "threshold": threshold, "hazard_iog": criterion.min_iog,
                             "hazard_dr": criterion.min_dr, "test_scenes": sorted(test_names)},
        "correlation": correlation_table(observations),
        "recall": [{"condition": c, "setting": f"({a}, {b})", **recall_table(obs, a, b)}
                   for c, obs in groups.items() for a, b in PAPER_THRESHOLDS],
        "analysis": [], "rmse": rmse_table(test, systems),
        "intervals": intervals, "paired": paired,
    }
    for condition, obs in groups.items():
        counts = detection_analysis(obs, config.alignment.alpha, config.alignment.beta)
        tables["analysis"].append({
            "condition": condition, "scenes": len({ob.scene for ob in obs}),
            "gts": counts["tps"] + counts["fns"],
            "approved": f"{counts['approved_tps']} / {counts['tps']}",
            "identified": f"{counts['identified_fns']} / {counts['fns']}", **counts})
    sections = [
        (f"Quality of the risk on the {len(test_names)} held-out test scenes (hazard: a ground truth within "
         f"{config.max_range:g} m no detection covers with IoG > {criterion.min_iog} and DR > {criterion.min_dr}; "
         f"alarm: risk > {threshold}; constant: {reference_note})", quality, QUALITY),
        *_uncertainty_sections(quality, intervals, paired, args.bootstrap, shipped),
        (f"The depth view on the held-out test scenes: recall and precision of the ground truth within range "
         f"(IoG > {criterion.min_iog} resp. intersection over S > {criterion.min_iog}, depth ratio min / max > "
         f"{criterion.min_dr}); hazards in view: the share of hazard frames in which the view finds a ground "
         f"truth no detection covers, the highest hit rate that evidence of the missed objects allows; share "
         f"of frames per status", depth_view, DEPTH_VIEW),
        ("Table I: correlation of S-based and G-based features (all frames)", tables["correlation"], CORRELATION),
        ("Table II: recall of the ground truth by S and by P", tables["recall"], RECALL),
        (f"Table III: the depth view over the detector's TPs and FNs (alpha {config.alignment.alpha}, beta {config.alignment.beta})",
         tables["analysis"], ANALYSIS),
        (f"Rule bases against 1 - USC~ on the {len(test_names)} held-out test scenes", tables["rmse"], RMSE),
    ]
    print(selection.note)
    lines = ["# fuzzrisk evaluation", "", f"> {selection.note}", ""]
    for title, rows, columns in sections:
        print(f"\n{title}\n{format_table(rows, columns)}")
        lines += [f"## {title}", "", format_table(rows, columns, markdown=True), ""]
        if columns is QUALITY or columns is INTERVALS or columns is PAIRED:
            notes = _undefined(rows)
            print(notes)
            lines += [notes, ""]
        if columns is DEPTH_VIEW:
            lines += [f"![ROC and risk against target]({figure.name})", ""]
    write_text(out / "report.md", "\n".join(lines))
    write_text(out / "tables.json", json.dumps({"note": selection.note, **tables}, indent=1))
    every_risk = {name: rule_base_risk(observations, fis, config.risk.fail_safe) for name, fis in systems.items()}
    rows = frame_rows(observations, truth, every_risk, test_names)
    write_text(out / "frames.jsonl", "".join(json.dumps(row, allow_nan=False) + "\n" for row in rows))
    print(f"\nreport: {out / 'report.md'}")
    return 0
