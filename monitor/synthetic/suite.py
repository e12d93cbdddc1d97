"""The synthetic benchmark: which scenes, which seeds, which are for training, the prior.

Every scene is generated from its seed by :mod:`monitor.synthetic`, so a benchmark is fully
described by a :class:`Benchmark` (and reproduced by it). Scene ``k`` of condition ``c``
(``c`` its position in :data:`CONDITIONS`) has seed ``seed + 1000 * c + k``; the inverse-
depth prior comes from separate nominal training scenes (seeds ``seed + 100000 + k``), as
the paper averages the training frames' inverse depth. The split into training and test
scenes is by scene, never by frame: the last ``test_scenes`` scenes of each condition are
the test scenes (the paper holds out four per condition). ``depth_off`` switches parts of
the depth network's error off in every scene and in the prior's
(:func:`~monitor.synthetic.without_depth_errors`): an ablation.

These are synthetic stand-ins for nuScenes, PGD and ZoeDepth: every report built on them
says so.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterator

import numpy as np

from monitor.geometry.camera import Camera
from monitor.depth.prior import build_prior
from monitor.synthetic import CONDITIONS, generate_frames, get_condition, without_depth_errors

SYNTHETIC_NOTE = ("Data: synthetic driving scenes (monitor.synthetic), a stand-in for nuScenes, "
                  "PGD detections and ZoeDepth depth maps; numbers on them are not the paper's.")


@dataclass(frozen=True)
class SceneSource:
    """A scene to be generated: its name, condition, seed and split; ``frames`` generates it
    (with the parts of the depth network's error named in ``depth_off`` switched off)."""

    name: str
    condition: str
    seed: int
    split: str  # "train" or "test"
    n_frames: int
    camera: Camera
    depth_off: tuple[str, ...] = ()

    @property
    def frames(self) -> Iterator:
        return generate_frames(_ablated(self.condition, self.depth_off), self.seed, n_frames=self.n_frames,
                               camera=self.camera)


def _ablated(condition: str, depth_off: tuple[str, ...]):
    """The condition's name, or its Condition with ``depth_off`` switched off."""
    return without_depth_errors(get_condition(condition), depth_off) if depth_off else condition


@dataclass(frozen=True)
class Benchmark:
    """A set of synthetic scenes.

    Parameters
    ----------
    conditions : tuple of str
        Keys of :data:`monitor.synthetic.CONDITIONS`.
    scenes_per_condition : int >= 1
    test_scenes : int >= 0
        How many of each condition's scenes are held out for testing.
    n_frames : int >= 1
        Frames per scene (2 Hz).
    prior_scenes : int >= 1
        Nominal scenes whose frames make the inverse-depth prior.
    seed : int >= 0
    depth_off : tuple of str
        Parts of :data:`~monitor.synthetic.DEPTH_ERROR_PARTS` switched off (an ablation).
    """

    conditions: tuple[str, ...] = tuple(CONDITIONS)
    scenes_per_condition: int = 2
    test_scenes: int = 0
    n_frames: int = 20
    prior_scenes: int = 2
    seed: int = 0
    depth_off: tuple[str, ...] = ()

    def __post_init__(self):
        unknown = [c for c in self.conditions if c not in CONDITIONS]
        if unknown or not self.conditions:
            raise ValueError(f"conditions {list(self.conditions)}: expected some of {', '.join(CONDITIONS)}")
        for name in ("scenes_per_condition", "n_frames", "prior_scenes"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} = {getattr(self, name)}, must be >= 1")
        if not 0 <= self.test_scenes <= self.scenes_per_condition:
            raise ValueError(f"test_scenes = {self.test_scenes}, must be in [0, scenes_per_condition = "
                             f"{self.scenes_per_condition}]")
        if self.seed < 0:
            raise ValueError(f"seed = {self.seed}, must be >= 0")
        without_depth_errors(CONDITIONS["nominal"], self.depth_off)  # names the unknown parts

    @property
    def camera(self) -> Camera:
        return Camera.nuscenes_front()

    def scenes(self, split: str | None = None) -> list[SceneSource]:
        """The scenes, condition by condition; only those of ``split`` ("train"/"test") if given."""
        names = list(CONDITIONS)
        out = []
        for condition in self.conditions:
            for k in range(self.scenes_per_condition):
                seed = self.seed + 1000 * names.index(condition) + k
                part = "test" if k >= self.scenes_per_condition - self.test_scenes else "train"
                if split in (None, part):
                    out.append(SceneSource(f"{condition}-{seed}", condition, seed, part, self.n_frames,
                                           self.camera, self.depth_off))
        return out

    def prior(self, progress: Callable[[], None] | None = None) -> np.ndarray:
        """The mean inverse depth of the prior scenes' estimated depth maps, float32 (H, W)."""
        def depths():
            for k in range(self.prior_scenes):
                seed = self.seed + 100000 + k
                for frame in generate_frames(_ablated("nominal", self.depth_off), seed, n_frames=self.n_frames,
                                             camera=self.camera):
                    if progress is not None:
                        progress()
                    yield f"prior-{seed}/{frame.index}", frame.depth_est

        return build_prior(depths()).mean()
