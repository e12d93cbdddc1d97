"""Scene selection shared by ``fuzzrisk eval``, ``features`` and ``monitor``, and their scale options.

Either the built-in synthetic benchmark (:mod:`monitor.synthetic.suite`; the default), scene
folders on disk (:mod:`monitor.datasets.scene_folder` format), recording folders of users' drives
(:mod:`monitor.datasets.recordings`) or nuScenes (:mod:`monitor.datasets.nuscenes`: its tables, a
detection-results file and depth maps or camera images), the last three with a prior file.
Depth from camera images comes from an ONNX network (:mod:`monitor.depth.images`). The
scenes become :class:`~monitor.offline.run.ScenePlan` s, run in this process, in ``--workers``
processes or on ``--ray`` (:func:`~monitor.offline.run.process_chunks`).
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from monitor.datasets.nuscenes import NuScenesReader
from monitor.datasets.recordings import RecordingReader
from monitor.datasets.scene_folder import SceneReader
from monitor.depth.images import DepthModel
from monitor.depth.onnx_model import DEVICES, PRESETS
from monitor.depth.prior import load_prior
from monitor.geometry.camera import Camera
from monitor.offline.run import RunSpec, ScenePlan
from monitor.shipped import shipped_rules
from monitor.synthetic import CONDITIONS, DEPTH_ERROR_PARTS
from monitor.synthetic.suite import SYNTHETIC_NOTE, Benchmark


@dataclass(frozen=True)
class DiskScene:
    """A scene folder, read frame by frame when ``frames`` is iterated."""

    reader: SceneReader
    split: str = "test"

    @property
    def name(self) -> str:
        return self.reader.name

    @property
    def condition(self) -> str:
        return self.reader.condition

    @property
    def frames(self) -> Iterator:
        return iter(self.reader)


@dataclass(frozen=True)
class Selection:
    """The scenes to run, the prior and camera they need, and a sentence saying what they are."""

    prior: np.ndarray
    camera: Camera
    scenes: list  # of ScenePlan
    note: str


def add_depth_ablation_argument(group) -> None:
    """``--no-depth-error PART ...`` (synthetic scenes): parts of the depth network's error off."""
    group.add_argument("--no-depth-error", nargs="+", default=[], metavar="PART",
                       choices=list(DEPTH_ERROR_PARTS) + ["all"],
                       help="synthetic scenes: an ablation, these parts of the depth network's error switched off "
                            f"({', '.join(DEPTH_ERROR_PARTS)}; all: the true depth), the detector's as they were")


def depth_ablation(args: argparse.Namespace) -> tuple[str, ...]:
    """The parts ``--no-depth-error`` switches off, in :data:`DEPTH_ERROR_PARTS` order (``all``: every one)."""
    return tuple(p for p in DEPTH_ERROR_PARTS if p in args.no_depth_error or "all" in args.no_depth_error)


def ablation_note(parts: tuple[str, ...]) -> str:
    """The sentence a report on an ablation carries ("" for none)."""
    if not parts:
        return ""
    return (f"An ablation: the depth network's {', '.join(parts)} switched off "
            "(`monitor.synthetic.without_depth_errors`); the scenes and the detector's errors are the conditions'.")


def add_scene_arguments(parser: argparse.ArgumentParser, *, default_scenes: int, default_test: int) -> None:
    group = parser.add_argument_group("scenes (default: the built-in synthetic benchmark)")
    group.add_argument("--scenes", type=int, default=default_scenes, help="synthetic scenes per condition "
                       "(default %(default)s)")
    group.add_argument("--test-scenes", type=int, default=default_test,
                       help="of those, held out for testing per condition (default %(default)s)")
    group.add_argument("--frames", type=int, default=20, help="frames per synthetic scene, 2 Hz (default %(default)s)")
    group.add_argument("--prior-scenes", type=int, default=3,
                       help="nominal scenes averaged into the prior (default %(default)s)")
    group.add_argument("--conditions", nargs="+", default=list(CONDITIONS), choices=list(CONDITIONS),
                       metavar="CONDITION", help="synthetic conditions (default: all six)")
    group.add_argument("--seed", type=int, default=0, help="synthetic benchmark seed (default %(default)s)")
    add_depth_ablation_argument(group)
    group.add_argument("--scene-dir", nargs="+", default=None, metavar="DIR",
                       help="scene folders on disk instead (monitor.datasets.scene_folder format); needs --prior")
    group.add_argument("--recording", nargs="+", default=None, metavar="DIR",
                       help="recording folders of your own drives instead (monitor.datasets.recordings "
                            "format: camera.yaml, frames.jsonl, depth/ or images/, detections); needs --prior")
    group.add_argument("--prior", default=None, metavar="PRIOR.npy",
                       help="inverse-depth prior for --scene-dir, --recording or --nuscenes "
                            "(see 'fuzzrisk prior build')")
    nus = parser.add_argument_group("nuScenes instead (needs --prior, --detections and --depth-dir or --depth-model)")
    nus.add_argument("--nuscenes", default=None, metavar="DATAROOT", help="the nuScenes root folder")
    nus.add_argument("--version", default="v1.0-trainval", help="tables folder under DATAROOT (default %(default)s)")
    nus.add_argument("--detections", default=None, metavar="RESULTS.json",
                     help="3D detections in the nuScenes detection-results format; its samples select the scenes")
    nus.add_argument("--depth-dir", default=None, metavar="DIR",
                     help="depth maps (.npy metres or 16-bit .png) named by the camera image's file stem")
    nus.add_argument("--camera", default="CAM_FRONT", help="camera channel (default %(default)s)")
    nus.add_argument("--nuscenes-scenes", nargs="+", default=None, metavar="NAME",
                     help="only these scenes (default: all the detections cover)")
    net = parser.add_argument_group("depth from camera images (nuScenes, --recording) with an ONNX depth network")
    net.add_argument("--depth-model", default=None, metavar="MODEL.onnx",
                     help="a metric monocular depth model exported to ONNX (README: exporting ZoeDepth, "
                          "Depth Anything V2)")
    net.add_argument("--depth-preset", default="zoedepth", choices=list(PRESETS),
                     help="how the model wants its input and what its output means (default %(default)s)")
    net.add_argument("--depth-scale", type=float, default=None,
                     help="relative models: depth = scale / output; metric: depth = scale * output")
    net.add_argument("--depth-batch", type=int, default=4, help="images per network call (default %(default)s)")
    net.add_argument("--depth-device", default="auto", choices=list(DEVICES),
                     help="onnxruntime device; auto: CUDA when available (default %(default)s)")
    net.add_argument("--save-depth", default=None, metavar="DIR",
                     help="save every estimated depth map as DIR/<image stem>.npy, for --depth-dir next time")


def add_parallel_arguments(parser: argparse.ArgumentParser) -> None:
    """``--workers N`` and ``--ray auto|ADDRESS``: the same work split by scene, same results."""
    group = parser.add_argument_group("scale (same results, in the same order, as one process)")
    group.add_argument("--workers", type=int, default=1, metavar="N",
                       help="local processes (with --ray: monitor actors) (default %(default)s)")
    group.add_argument("--ray", default=None, metavar="auto|ADDRESS",
                       help="run on a Ray cluster with Ray Data (pip install -e '.[ray]'): 'auto' or the "
                            "head's address")


def depth_model(args: argparse.Namespace) -> DepthModel | None:
    """The depth network the arguments ask for, or None."""
    if args.depth_model is None:
        if args.save_depth is not None:
            raise ValueError("--save-depth needs --depth-model (it saves the network's depth maps)")
        return None
    return DepthModel(Path(args.depth_model), args.depth_preset, scale=args.depth_scale,
                      device=args.depth_device, batch_size=args.depth_batch,
                      save_dir=None if args.save_depth is None else Path(args.save_depth))


def _one_camera(scenes) -> Camera:
    camera = scenes[0].camera
    other = next((s for s in scenes if not s.camera.same_as(camera)), None)
    if other is not None:
        raise ValueError(f"scenes {scenes[0].name!r} and {other.name!r} have different cameras and the "
                         "monitor has one camera; run them apart")
    return camera


def select_scenes(args: argparse.Namespace, split: str | None, progress=None) -> Selection:
    """The scenes of ``split`` ("train", "test" or None for all) as :class:`ScenePlan` s.

    Synthetic, scene folders, recordings or nuScenes. Scenes on disk and nuScenes scenes
    have no train/test split of their own: all of them are used.
    """
    given = [flag for flag, value in (("--nuscenes", args.nuscenes), ("--scene-dir", args.scene_dir),
                                      ("--recording", args.recording)) if value]
    if len(given) > 1:
        raise ValueError(f"{' and '.join(given)} are alternatives; give one")
    if args.depth_model is not None and given not in (["--nuscenes"], ["--recording"]):
        raise ValueError("--depth-model estimates depth from the camera images of --nuscenes or --recording")
    if args.no_depth_error and given:
        raise ValueError(f"--no-depth-error switches off errors of the synthetic depth network, not of {given[0]}")
    if args.nuscenes is not None:
        return _select_nuscenes(args)
    if args.scene_dir or args.recording:
        flag = given[0]
        if args.prior is None:
            raise ValueError(f"{flag} needs --prior PRIOR.npy (build one with 'fuzzrisk prior build')")
        if args.scene_dir:
            readers = [SceneReader(d) for d in args.scene_dir]
            plans = [ScenePlan.of_source(DiskScene(r), len(r)) for r in readers]
            data = "synthetic" if all(r.synthetic for r in readers) else "recorded"
        else:
            readers = [RecordingReader(d, need_images=args.depth_model is not None) for d in args.recording]
            plans = [ScenePlan.of_records(r.name, r.condition, r.records()) for r in readers]
            data = "recorded"
        camera = _one_camera(readers)
        note = (SYNTHETIC_NOTE if data == "synthetic" else "Data: recorded scenes.") + \
            f" Scenes: {', '.join(str(d) for d in (args.scene_dir or args.recording))}; prior: {args.prior}."
        return Selection(load_prior(args.prior), camera, plans, note)
    bench = Benchmark(conditions=tuple(args.conditions), scenes_per_condition=args.scenes,
                      test_scenes=args.test_scenes, n_frames=args.frames, prior_scenes=args.prior_scenes,
                      seed=args.seed, depth_off=depth_ablation(args))
    note = (f"{SYNTHETIC_NOTE} Benchmark: {args.scenes} scenes per condition ({args.test_scenes} held out "
            f"for testing), {args.frames} frames each at 2 Hz, seed {args.seed}; prior from "
            f"{args.prior_scenes} separate nominal scenes. {ablation_note(bench.depth_off)}").rstrip()
    plans = [ScenePlan.of_source(s, s.n_frames) for s in bench.scenes(split)]
    return Selection(bench.prior(progress), bench.camera, plans, note)


def _select_nuscenes(args: argparse.Namespace) -> Selection:
    if args.depth_dir is not None and args.depth_model is not None:
        raise ValueError("--depth-dir and --depth-model are alternatives for --nuscenes: depth maps on disk, or "
                         "depth from the camera images; give one")
    missing = [flag for flag, value in (("--prior PRIOR.npy", args.prior), ("--detections RESULTS.json",
               args.detections), ("--depth-dir DIR (or --depth-model MODEL.onnx)",
                                  args.depth_dir or args.depth_model)) if value is None]
    if missing:
        raise ValueError(f"--nuscenes needs {', '.join(missing)}")
    reader = NuScenesReader(args.nuscenes, args.version, detections=args.detections, depth=args.depth_dir,
                            camera=args.camera, scene_names=args.nuscenes_scenes)
    scenes = reader.scenes()
    if not scenes:
        raise ValueError(f"{args.detections} covers no scene of nuScenes {args.version} at {args.nuscenes}")
    camera = _one_camera(scenes)
    plans = [ScenePlan.of_records(s.name, s.condition, s.records()) for s in scenes]
    depth = (args.depth_dir if args.depth_dir is not None
             else f"{args.depth_model} ({args.depth_preset}) on the images")
    note = (f"Data: nuScenes {args.version} at {args.nuscenes}, {args.camera}, {len(scenes)} scenes "
            f"({len(reader.uncovered_scenes)} more not in the detections); detections: {args.detections}; "
            f"depth: {depth}; prior: {args.prior}.")
    return Selection(load_prior(args.prior), camera, plans, note)


def count_frames(args: argparse.Namespace, split: str | None) -> int | None:
    """Frames a progress bar will see (None when unknown: scenes on disk, nuScenes)."""
    if args.scene_dir or args.nuscenes is not None or args.recording:
        return None
    per_split = {"test": args.test_scenes, "train": args.scenes - args.test_scenes, None: args.scenes}[split]
    return (len(args.conditions) * per_split + args.prior_scenes) * args.frames


def run_spec(args: argparse.Namespace, selection: Selection, config, *, rules=None,
             explain: bool = False) -> RunSpec:
    """What every worker builds: the shipped (or given) rule base, the prior, camera, config, depth network."""
    return RunSpec(Path(rules) if rules is not None else shipped_rules(), selection.prior, selection.camera,
                   config, explain=explain, depth_model=depth_model(args))
