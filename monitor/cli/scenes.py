"""Scene selection shared by ``fuzzrisk eval`` and ``fuzzrisk features``.

Either the built-in synthetic benchmark (:mod:`monitor.synthetic.suite`; the default), scene
folders on disk (:mod:`monitor.datasets.scene_folder` format) or nuScenes (:mod:`monitor.datasets.nuscenes`: its
tables, a detection-results file and depth maps), the last two with a prior file.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Iterator

import numpy as np

from monitor.synthetic.suite import SYNTHETIC_NOTE, Benchmark
from monitor.geometry.camera import Camera
from monitor.datasets.scene_folder import SceneReader
from monitor.datasets.nuscenes import NuScenesReader
from monitor.depth.prior import load_prior
from monitor.synthetic import CONDITIONS


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
    scenes: list
    note: str


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
    group.add_argument("--scene-dir", nargs="+", default=None, metavar="DIR",
                       help="scene folders on disk instead (monitor.datasets.scene_folder format); needs --prior")
    group.add_argument("--prior", default=None, metavar="PRIOR.npy",
                       help="inverse-depth prior for --scene-dir or --nuscenes (see 'fuzzrisk prior build')")
    nus = parser.add_argument_group("nuScenes instead (needs --prior, --detections and --depth-dir)")
    nus.add_argument("--nuscenes", default=None, metavar="DATAROOT", help="the nuScenes root folder")
    nus.add_argument("--version", default="v1.0-trainval", help="tables folder under DATAROOT (default %(default)s)")
    nus.add_argument("--detections", default=None, metavar="RESULTS.json",
                     help="3D detections in the nuScenes detection-results format; its samples select the scenes")
    nus.add_argument("--depth-dir", default=None, metavar="DIR",
                     help="depth maps (.npy metres or 16-bit .png) named by the camera image's file stem")
    nus.add_argument("--camera", default="CAM_FRONT", help="camera channel (default %(default)s)")
    nus.add_argument("--nuscenes-scenes", nargs="+", default=None, metavar="NAME",
                     help="only these scenes (default: all the detections cover)")


def select_scenes(args: argparse.Namespace, split: str | None, progress=None) -> Selection:
    """The scenes of ``split`` ("train", "test" or None for all): synthetic or from disk.

    Scenes on disk and nuScenes scenes have no train/test split of their own: all of them
    are used.
    """
    if args.nuscenes is not None:
        return _select_nuscenes(args)
    if args.scene_dir:
        if args.prior is None:
            raise ValueError("--scene-dir needs --prior PRIOR.npy (build one with 'fuzzrisk prior build')")
        readers = [SceneReader(d) for d in args.scene_dir]
        cameras = {(r.camera.width, r.camera.height) for r in readers}
        if len(cameras) != 1:
            raise ValueError(f"the scene folders have different image sizes {sorted(cameras)}; run them apart")
        synthetic = all(r.synthetic for r in readers)
        note = (SYNTHETIC_NOTE if synthetic else "Data: recorded scenes") + \
            f" Scenes: {', '.join(str(d) for d in args.scene_dir)}; prior: {args.prior}."
        return Selection(load_prior(args.prior), readers[0].camera, [DiskScene(r) for r in readers], note)
    bench = Benchmark(conditions=tuple(args.conditions), scenes_per_condition=args.scenes,
                      test_scenes=args.test_scenes, n_frames=args.frames, prior_scenes=args.prior_scenes,
                      seed=args.seed)
    note = (f"{SYNTHETIC_NOTE} Benchmark: {args.scenes} scenes per condition ({args.test_scenes} held out "
            f"for testing), {args.frames} frames each at 2 Hz, seed {args.seed}; prior from "
            f"{args.prior_scenes} separate nominal scenes.")
    return Selection(bench.prior(progress), bench.camera, bench.scenes(split), note)


def _select_nuscenes(args: argparse.Namespace) -> Selection:
    if args.scene_dir:
        raise ValueError("--scene-dir and --nuscenes are alternatives; give one")
    missing = [flag for flag, value in (("--prior PRIOR.npy", args.prior), ("--detections RESULTS.json",
               args.detections), ("--depth-dir DIR", args.depth_dir)) if value is None]
    if missing:
        raise ValueError(f"--nuscenes needs {', '.join(missing)}")
    reader = NuScenesReader(args.nuscenes, args.version, detections=args.detections, depth=args.depth_dir,
                            camera=args.camera, scene_names=args.nuscenes_scenes)
    scenes = reader.scenes()
    if not scenes:
        raise ValueError(f"{args.detections} covers no scene of nuScenes {args.version} at {args.nuscenes}")
    camera = scenes[0].camera
    other = next((s for s in scenes if not s.camera.same_as(camera)), None)
    if other is not None:
        raise ValueError(f"nuScenes scenes {scenes[0].name!r} and {other.name!r} have different {args.camera} "
                         "calibrations and the monitor has one camera; run them apart (--nuscenes-scenes)")
    note = (f"Data: nuScenes {args.version} at {args.nuscenes}, {args.camera}, {len(scenes)} scenes "
            f"({len(reader.uncovered_scenes)} more not in the detections); detections: {args.detections}; "
            f"depth: {args.depth_dir}; prior: {args.prior}.")
    return Selection(load_prior(args.prior), camera, scenes, note)


def count_frames(args: argparse.Namespace, split: str | None) -> int | None:
    """Frames a progress bar will see (None when unknown: scenes on disk, nuScenes)."""
    if args.scene_dir or args.nuscenes is not None:
        return None
    per_split = {"test": args.test_scenes, "train": args.scenes - args.test_scenes, None: args.scenes}[split]
    return (len(args.conditions) * per_split + args.prior_scenes) * args.frames
