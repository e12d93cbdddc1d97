"""``fuzzrisk features -o FEATURES.csv``: the (IoU~, RDD~, 1 - USC~) table of scenes.

One row per frame in which the depth view found objects (status ok): ``scene``,
``frame``, ``condition``, ``iou``, ``rdd`` and ``target`` (1 - USC~; empty when the frame
has no ground truth in range). This is the training data of ``fuzzrisk tune``; ``--split``
picks the synthetic benchmark's training or test scenes (split by scene, never by frame).
The output is checked before any work (``.csv``, an existing folder, not an input, not an
existing file unless ``--overwrite``) and written whole or not at all.
"""
from __future__ import annotations

import argparse
import csv
import io

import numpy as np
from tqdm import tqdm

from fuzzcore.outputs import check_output, write_text
from monitor.cli.scenes import add_parallel_arguments, add_scene_arguments, count_frames, run_spec, select_scenes
from monitor.config import load_config
from monitor.offline.evaluation import feature_rows
from monitor.offline.run import observe_plans

FIELDS = ("scene", "frame", "condition", "iou", "rdd", "target")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("-o", "--output", required=True, metavar="FEATURES.csv", help="where to write the table")
    parser.add_argument("--overwrite", action="store_true", help="replace FEATURES.csv if it exists")
    parser.add_argument("--split", choices=("train", "test", "all"), default="train",
                        help="synthetic scenes to use (default %(default)s)")
    parser.add_argument("--config", default=None, help="monitor configuration YAML (default: shipped defaults)")
    add_scene_arguments(parser, default_scenes=10, default_test=4)
    add_parallel_arguments(parser)


def run(args: argparse.Namespace) -> int:
    read = [p for p in (args.config, args.prior, args.detections, args.depth_dir, *(args.scene_dir or ()),
                        *(args.recording or ())) if p]
    check_output(args.output, (".csv",), read, args.overwrite, what="features table")
    split = None if args.split == "all" else args.split
    bar = tqdm(total=count_frames(args, split), unit="frame", desc="features", disable=None)
    selection = select_scenes(args, split, progress=bar.update)
    observations = observe_plans(run_spec(args, selection, load_config(args.config)), selection.scenes,
                                 workers=args.workers, ray=args.ray, progress=bar.update)
    bar.close()
    rows = feature_rows(observations)
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, fieldnames=FIELDS)
    writer.writeheader()
    for row in rows:
        writer.writerow({**row, "target": "" if np.isnan(row["target"]) else repr(row["target"])})
    write_text(args.output, text.getvalue())
    no_target = sum(1 for r in rows if np.isnan(r["target"]))
    print(selection.note)
    print(f"{len(rows)} frames with features from {len(selection.scenes)} scenes "
          f"({len(observations) - len(rows)} frames without: no objects or invalid; "
          f"{no_target} with no ground truth in range, target left empty) -> {args.output}")
    return 0
