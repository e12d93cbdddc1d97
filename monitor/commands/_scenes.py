"""Scene selection shared by ``fuzzrisk eval`` and ``fuzzrisk features``.

Either the built-in synthetic benchmark (:mod:`monitor.benchmark`; the default) or scene
folders on disk (:mod:`monitor.frames` format) with a prior file.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Iterator

import numpy as np

from monitor.benchmark import SYNTHETIC_NOTE, Benchmark
from monitor.camera import Camera
from monitor.frames import SceneReader
from monitor.prior import load_prior
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
                       help="scene folders on disk instead (monitor.frames format); needs --prior")
    group.add_argument("--prior", default=None, metavar="PRIOR.npy",
                       help="inverse-depth prior for --scene-dir (see 'fuzzrisk prior build')")


def select_scenes(args: argparse.Namespace, split: str | None, progress=None) -> Selection:
    """The scenes of ``split`` ("train", "test" or None for all): synthetic or from disk.

    Scenes on disk have no train/test split of their own: all of them are used.
    """
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


def count_frames(args: argparse.Namespace, split: str | None) -> int | None:
    """Frames a progress bar will see (None when unknown: scenes on disk)."""
    if args.scene_dir:
        return None
    per_split = {"test": args.test_scenes, "train": args.scenes - args.test_scenes, None: args.scenes}[split]
    return (len(args.conditions) * per_split + args.prior_scenes) * args.frames
