"""``fuzzrisk demo``: the monitor on built-in synthetic scenes, end to end.

Generates a few scenes per condition (:mod:`monitor.synthetic.suite`), builds the inverse-depth
prior from separate nominal scenes, runs the :class:`~monitor.RiskMonitor` and the shield
on every frame, prints a per-condition summary and writes to the output folder:

- ``frames.jsonl``: one monitor report per frame (with the ego's speed, m/s, the shield's
  decision and the ground-truth target 1 - USC~);
- ``report.md``: first the quality measures of the risk (:mod:`monitor.offline.measures`)
  on the held-out half of the scenes (the other half gives the constant predictor's mean),
  then the summary table, the figures, and how the data were made;
- ``quality.png``: ROC curves for hazard frames and risk against target;
- ``retrieval_stages.png`` (paper Fig. 2), ``fis.png`` (Fig. 4), ``frame_<condition>.png``
  (Fig. 5: the riskiest frame of each condition), ``risk_timeline.png``.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

import fuzzcore
from fuzzcore.outputs import check_output_folder, write_text
from monitor.synthetic.suite import SYNTHETIC_NOTE, Benchmark
from monitor.config import load_config
from monitor.offline.evaluation import observe, recall_table, rmse_table
from monitor.offline.measures import frame_truth, quality_tables, training_mean
from monitor.report.quality_figure import save_quality_figure
from monitor.report.figures import save_fis_figure, save_frame_figure, save_risk_timeline
from monitor.report.retrieval_figure import save_retrieval_figure
from monitor.risk_monitor import INVALID_INPUT, NO_OBJECTS, NO_RULE_FIRED, NO_VIEW, OK, RiskMonitor, shift_earlier
from monitor.shield import Shield, describe_shield
from monitor.walkers import walker_positions
from monitor.shipped import shipped_rules
from monitor.report.tables import format_table
from monitor.synthetic import CONDITIONS, shade


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("-o", "--out", default="fuzzrisk-demo", help="output folder (default %(default)s)")
    parser.add_argument("--overwrite", action="store_true", help="replace the output folder's earlier files")
    parser.add_argument("--rules", default=None, help="rule base (default: the shipped rules/fuzzrisk.yaml)")
    parser.add_argument("--config", default=None, help="monitor configuration YAML (default: shipped defaults)")
    parser.add_argument("--scenes", type=int, default=2, help="scenes per condition (default %(default)s)")
    parser.add_argument("--frames", type=int, default=12, help="frames per scene, 2 Hz (default %(default)s)")
    parser.add_argument("--conditions", nargs="+", default=list(CONDITIONS), choices=list(CONDITIONS),
                        metavar="CONDITION", help="conditions to run (default: all six)")
    parser.add_argument("--seed", type=int, default=0, help="benchmark seed (default %(default)s)")


def _summary(rows: list[dict], obs_by_condition: dict, fis) -> list[dict]:
    table = []
    for condition, obs in obs_by_condition.items():
        mine = [r for r in rows if r["condition"] == condition]
        status = [r["status"] for r in mine]
        targets = np.array([r["target"] if r["target"] is not None else np.nan for r in mine])
        recall = recall_table(obs, 0.3, 0.2)
        rmse = rmse_table(obs, {"fis": fis})[0]
        table.append({
            "condition": condition, "frames": len(mine),
            "ok": status.count(OK), "no_objects": status.count(NO_OBJECTS),
            "invalid": status.count(INVALID_INPUT), "no_view": status.count(NO_VIEW),
            "no_rule": status.count(NO_RULE_FIRED),
            "mean_risk": float(np.mean([r["risk"] for r in mine])),
            "shield_on": float(np.mean([r["shield"]["engaged"] for r in mine])),
            "mean_target": float(np.nanmean(targets)) if np.isfinite(targets).any() else float("nan"),
            "rmse": rmse["rmse"], "recall_s": recall["recall_s"], "recall_p": recall["recall_p"],
            "ms_per_frame": float(np.median([sum(r["timings_ms"].values()) for r in mine])),
        })
    return table


_COLUMNS = [("condition", "condition", "{}"), ("frames", "frames", "{}"), ("ok", "ok", "{}"),
            ("no_objects", "no-obj", "{}"), ("invalid", "invalid", "{}"), ("no_view", "no-view", "{}"),
            ("no_rule", "no rule", "{}"), ("mean_risk", "risk", "{:.2f}"),
            ("shield_on", "shield", "{:.0%}"), ("mean_target", "1-USC~", "{:.2f}"), ("rmse", "RMSE", "{:.3f}"),
            ("recall_s", "rec S", "{:.2f}"), ("recall_p", "rec P", "{:.2f}"), ("ms_per_frame", "ms/frame", "{:.1f}")]


#: how the report names ``alignment.objects``
_OBJECTS = {"known": "the known objects (the S no detection covers and the detections)",
            "depth": "the depth view's objects S (the paper's)"}

_QUALITY = [("condition", "condition", "{}"), ("predictor", "predictor", "{}"), ("frames", "frames", "{}"),
            ("hazards", "hazards", "{}"), ("pearson", "r", "{:.2f}"), ("spearman", "rho", "{:.2f}"),
            ("rmse", "RMSE", "{:.3f}"), ("skill", "skill", "{:.2f}"), ("auroc", "AUROC", "{:.2f}"),
            ("auprc", "AUPRC", "{:.2f}"), ("hit_rate", "hit", "{:.0%}"),
            ("false_alarm_rate", "false al.", "{:.0%}"), ("fpr80", "FPR@80", "{:.0%}"),
            ("fpr95", "FPR@95", "{:.0%}"),
            ("recall", "S recall", "{:.2f}"), ("precision", "S precision", "{:.2f}"),
            ("hazards_in_view", "in view", "{:.0%}")]


def _quality(split: list, fis, name: str, config, out: Path) -> dict:
    """The measures of :mod:`monitor.offline.measures` on the test scenes (all scenes when
    there is no split), the constant predictor from the training scenes; writes quality.png."""
    test = [ob for part, ob in split if part == "test"] or [ob for _, ob in split]
    train = [ob for part, ob in split if part == "train"] if len(test) < len(split) else []
    test_truth = [frame_truth(ob) for ob in test]
    reference, note = training_mean([frame_truth(ob) for ob in train], test_truth)
    threshold = config.shield.threshold
    risk_rows, depth_rows, risks = quality_tables(test, test_truth, {name: fis}, reference, threshold,
                                                  config.risk.fail_safe)
    depth = {r["condition"]: r for r in depth_rows}
    view = ("recall", "precision", "hazards_in_view")
    rows = [{**r, **{k: depth[r["condition"]][k] for k in view}} if r["predictor"] == name else r
            for r in risk_rows]
    conditions = list(dict.fromkeys(ob.condition for ob in test))
    save_quality_figure(out / "quality.png",
                        {c: risks[name][[ob.condition == c for ob in test]] for c in conditions},
                        {c: [t for t, ob in zip(test_truth, test) if ob.condition == c] for c in conditions},
                        threshold, f"{name} on {len({ob.scene for ob in test})} held-out scenes")
    title = (f"Quality of the risk on {len({ob.scene for ob in test})} held-out scenes ({len(test)} frames; "
             f"constant predictor: {note}; hazard: a ground truth within {config.max_range:g} m that no "
             f"detection covers with IoG > 0.5 and DR > 0.8; alarm: risk > {threshold})")
    notes = sorted({f"{r['condition']}: {r['notes']}" for r in risk_rows if r["notes"]})
    return {"title": title, "rows": rows, "notes": notes}


def run(args: argparse.Namespace) -> int:
    started = time.perf_counter()
    frame_figures = [f"frame_{c.replace(' ', '_')}.png" for c in args.conditions]
    out = check_output_folder(args.out, ["frames.jsonl", "fis.png", "risk_timeline.png", "retrieval_stages.png",
                                         "quality.png", "report.md", *frame_figures], args.overwrite)
    rules_path = Path(args.rules) if args.rules else shipped_rules()
    fis = fuzzcore.load(rules_path)
    config = load_config(args.config)
    bench = Benchmark(conditions=tuple(args.conditions), scenes_per_condition=args.scenes,
                      test_scenes=args.scenes // 2, n_frames=args.frames, prior_scenes=2, seed=args.seed)
    n_frames = len(bench.scenes()) * args.frames + bench.prior_scenes * args.frames
    bar = tqdm(total=n_frames, unit="frame", desc="demo", disable=None)
    prior = bench.prior(progress=bar.update)
    monitor = RiskMonitor(fis, prior, bench.camera, config)

    rows, series, obs_by_condition, riskiest, split = [], [], {}, {}, []
    for scene in bench.scenes():
        shield = Shield(config.shield)
        times, risks, targets, statuses = [], [], [], []
        earlier = []  # the reports of the last frames, with the ego's travel since
        for frame in scene.frames:
            ob = observe(monitor, frame, scene.name, scene.condition)
            moved = frame.ego_speed * (frame.timestamp - times[-1]) if times else 0.0
            before, earlier = shift_earlier(earlier, ob.report, moved)
            walkers = walker_positions(frame.det_boxes3d, frame.det_classes, frame.det_scores,
                                       config.detections.min_score)
            decision = shield.update(ob.report.risk, speed=frame.ego_speed, unseen=ob.report.unseen,
                                     time=frame.timestamp, emerged=monitor.emerged(ob.report, before),
                                     walkers=walkers, contact=ob.report.unseen_contact)
            obs_by_condition.setdefault(scene.condition, []).append(ob)
            split.append((scene.split, ob))
            target = ob.target if np.isfinite(ob.target) else None
            rows.append({"scene": scene.name, "condition": scene.condition, "frame": frame.index,
                         "time": frame.timestamp, "ego_speed": frame.ego_speed, **ob.report.to_dict(),
                         "target": target,
                         "shield": {"engaged": decision.engaged, "deceleration": decision.deceleration}})
            times.append(frame.timestamp)
            risks.append(ob.report.risk)
            targets.append(np.nan if target is None else target)
            statuses.append(ob.report.status)
            best = riskiest.get(scene.condition)
            if best is None or ob.report.risk > best[1].risk:
                riskiest[scene.condition] = (frame, ob.report, scene.name)
            bar.update()
        series.append({"name": scene.name, "time": times, "risk": risks, "target": targets, "status": statuses})
    bar.close()

    write_text(out / "frames.jsonl", "".join(json.dumps(row, allow_nan=False) + "\n" for row in rows))
    figures = {"fis.png": save_fis_figure(fis, out / "fis.png"),
               "risk_timeline.png": save_risk_timeline(series, out / "risk_timeline.png",
                                                        config.shield.threshold)}
    nominal = riskiest.get("nominal") or next(iter(riskiest.values()))
    save_retrieval_figure(out / "retrieval_stages.png", nominal[0].depth_est, prior, shade(nominal[0]),
                          config.retrieval.paper)
    figures["retrieval_stages.png"] = out / "retrieval_stages.png"
    for condition, (frame, report, scene_name) in riskiest.items():
        name = f"frame_{condition.replace(' ', '_')}.png"
        figures[name] = save_frame_figure(shade(frame), report, out / name,
                                          f"{scene_name} frame {frame.index}")

    quality = _quality(split, fis, rules_path.name, config, out)
    table = _summary(rows, obs_by_condition, fis)
    elapsed = time.perf_counter() - started
    print(SYNTHETIC_NOTE)
    print(f"rule base: {rules_path} ({fis.name}); shield: {describe_shield(config.shield)}")
    print(quality["title"])
    print(format_table(quality["rows"], _QUALITY))
    print(format_table(table, _COLUMNS))
    write_text(out / "report.md", _report(table, quality, rules_path, fis, bench, config, figures, elapsed))
    print(f"{len(rows)} frames in {elapsed:.1f} s; reports and figures in {out}/")
    return 0


def _report(table, quality, rules_path, fis, bench, config, figures, elapsed) -> str:
    lines = [
        "# fuzzrisk demo", "",
        f"> {SYNTHETIC_NOTE}", "",
        "## Quality of the risk", "",
        quality["title"] + ". r, rho: Pearson and Spearman correlation of the risk with the target 1 - USC~; "
        "skill: 1 - RMSE / RMSE of the constant; hit / false al.: alarms on hazard / other frames; FPR@80, "
        "FPR@95: false alarms at an 80 %, a 95 % hit rate; S recall / precision: the depth view against the "
        "ground truth within range (IoG > 0.5 / intersection over S > 0.5, depths within a ratio of 0.8); in view: the "
        "share of hazard frames in which the depth view finds a ground truth no detection covers. Every frame "
        "counts, with the risk the monitor reported. '-': undefined on these frames.", "",
        format_table(quality["rows"], _QUALITY, markdown=True), "",
        *[f"- {note}" for note in quality["notes"]], "",
        "![quality.png](quality.png)", "",
        f"- Rule base: `{rules_path}` ({fis.name}, {len(fis.rules)} rules, {fis.defuzzifier}).",
        f"- Scenes: {bench.scenes_per_condition} per condition x {bench.n_frames} frames at 2 Hz, seed {bench.seed}; "
        f"prior from {bench.prior_scenes} separate nominal scenes.",
        f"- Alignment: {config.alignment.matching} matching (alpha {config.alignment.alpha:g}, beta "
        f"{config.alignment.beta:g}); features over {_OBJECTS[config.alignment.objects]} within "
        f"{config.max_range:g} m; shield: {describe_shield(config.shield)}.",
        f"- Run time: {elapsed:.1f} s.", "",
        "## Per condition", "",
        "risk: mean monitor risk; shield: share of frames with the shield engaged; 1-USC~: the ground-truth "
        "target; RMSE: the rule base against it on frames with features; rec S / rec P: recall of the ground "
        "truth by the depth view / the detector (IoU > 0.3, |RDD| < 0.2).", "",
        format_table(table, _COLUMNS, markdown=True), "",
        "## Figures", "",
    ]
    for name in figures:
        lines += [f"![{name}]({name})", ""]
    lines += ["Per-frame reports: `frames.jsonl`.", ""]
    return "\n".join(lines)
