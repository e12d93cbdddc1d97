"""``fuzzrisk monitor``: the monitor over recordings, one report per frame; resumable, at scale.

Sources (see :mod:`monitor.cli.scenes`): the built-in synthetic scenes (default), recording
folders of your own drives (``--recording DIR ...``, :mod:`monitor.datasets.recordings`),
scene folders (``--scene-dir``) or nuScenes (``--nuscenes DATAROOT --version V --detections
RESULTS.json``); depth maps from files (``--depth-dir``, a recording's ``depth/``) or an
ONNX depth network on the camera images (``--depth-model MODEL.onnx --depth-preset ...``).
Ground truth is used when the source has it (target 1 - USC~ in the reports), never needed.

Writes to ``-o OUT`` (:mod:`monitor.offline.run_output`): ``scenes/<scene>.jsonl`` (one
report per frame), ``scenes/<scene>.png`` (risk timeline), ``summary.md`` and ``run.json``.
Started again after an interruption it continues where it stopped; an output of another run
is not replaced without ``--overwrite``. Frames that cannot be processed are reported and
skipped (``--strict``: the first one stops the run, exit status 2).
"""
from __future__ import annotations

import argparse
import dataclasses
import hashlib
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from monitor.cli.scenes import add_parallel_arguments, add_scene_arguments, run_spec, select_scenes
from monitor.config import load_config
from monitor.depth.geometric import GeometricRetriever
from monitor.offline.parallel import check_workers
from monitor.offline.run import process_chunks
from monitor.offline.run_output import COLUMNS, RunOutput
from monitor.report.tables import format_table
from monitor.shield import describe_shield
from monitor.shipped import shipped_rules

def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("-o", "--out", default="fuzzrisk-monitor", help="output folder (default %(default)s)")
    parser.add_argument("--rules", default=None, help="rule base (default: the shipped rules/fuzzrisk.yaml)")
    parser.add_argument("--config", default=None, help="monitor configuration YAML (default: shipped defaults)")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace an output folder holding another run (default: refuse; the same run resumes)")
    parser.add_argument("--strict", action="store_true",
                        help="stop at the first frame that cannot be processed (default: report it and go on)")
    parser.add_argument("--no-explain", action="store_true", help="leave out the rules fired (slightly faster)")
    add_scene_arguments(parser, default_scenes=1, default_test=0)
    add_parallel_arguments(parser)
    parser.add_argument("--depth-actors", type=int, default=None, metavar="N",
                        help="with --ray and --depth-model: depth network actors (default: one per GPU, else 1)")


def _sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def describe(args: argparse.Namespace, spec, selection) -> dict:
    """What the run is, for ``run.json``: a later run into the same folder must match it."""
    sources = {k: getattr(args, k) for k in ("recording", "scene_dir", "nuscenes", "version", "detections",
                                              "depth_dir", "camera", "nuscenes_scenes", "prior")}
    if not (args.recording or args.scene_dir or args.nuscenes):
        sources = {k: getattr(args, k) for k in ("scenes", "frames", "prior_scenes", "conditions", "seed")}
    depth = None if spec.depth_model is None else {
        "model_sha256": _sha256(spec.depth_model.path), "preset": spec.depth_model.preset,
        "scale": spec.depth_model.scale}
    return {"format": "fuzzrisk-monitor-run", "version": 1, "sources": sources,
            "rules": str(spec.rules), "rules_sha256": _sha256(spec.rules),
            "prior_sha256": hashlib.sha256(np.ascontiguousarray(spec.prior).tobytes()).hexdigest(),
            "config": dataclasses.asdict(spec.config), "explain": spec.explain, "depth": depth,
            "scenes": [[p.name, p.n_frames] for p in selection.scenes]}


def run(args: argparse.Namespace) -> int:
    started = time.perf_counter()
    check_workers(args.workers)
    config = load_config(args.config)
    selection = select_scenes(args, None)
    spec = run_spec(args, selection, config, rules=args.rules or shipped_rules(), explain=not args.no_explain)
    # the workers' geometric views keep their blocks; the paper's view measures nothing
    measured = config.shield.confirm_emerged is not None and config.retrieval.method == "geometric"
    output = RunOutput(args.out, describe(args, spec, selection), selection.scenes, config.shield,
                       overwrite=args.overwrite,
                       retriever=GeometricRetriever(spec.camera, config.retrieval.geometric) if measured else None)
    print(selection.note)
    if output.resumed:
        print(f"resuming {args.out}: {output.resumed} frames done, {output.remaining} to go")
    bar = tqdm(total=output.remaining, unit="frame", desc="monitor", disable=None)
    processed = 0
    try:
        for results in process_chunks(spec, output.pending(), workers=args.workers, ray=args.ray,
                                      depth_actors=args.depth_actors):
            output.add(results)
            processed += len(results)
            bar.update(len(results))
            failed = next((r for r in results if r.observation is None), None)
            if args.strict and failed is not None:
                raise ValueError(f"{failed.error} (--strict: stopped; the frames before it are in {args.out})")
    finally:
        bar.close()
        elapsed = time.perf_counter() - started
        notes = [selection.note, f"Rule base: {spec.rules}; shield: {describe_shield(config.shield)}.",
                 f"This run: {processed} frames in {elapsed:.1f} s"
                 + (f" ({processed / elapsed:.1f} frames/s)" if processed else "")
                 + (f"; {output.resumed} frames were done before (resumed)." if output.resumed else ".")]
        summary = output.close(notes)
    print(format_table(output.table(), COLUMNS))
    errors = output.errors()
    if errors:
        print(f"{len(errors)} frames could not be processed (listed in {summary}); first: "
              f"{errors[0][0]} frame {errors[0][1]}: {errors[0][3]}")
    print(f"reports: {output.out}/scenes/*.jsonl; summary: {summary}")
    return 0
