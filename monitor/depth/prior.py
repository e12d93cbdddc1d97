"""The inverse-depth prior: the per-pixel mean of 1/D over training frames (paper, III-A).

An AV sees the road ahead from a near-constant perspective, so the mean inverse depth of
many frames is mostly the road surface just ahead of the car. The retrieval subtracts it
from each frame's inverse depth so that only things closer than usual stand out.

How invalid pixels enter the mean
---------------------------------
Per pixel, the mean is taken over the frames in which that pixel is valid (finite and
> 0): the accumulator keeps a float64 sum of 1/D and an integer count of valid samples
per pixel, and the prior is ``sum / count``. An invalid pixel therefore neither pulls the
mean towards 0 nor counts as a sample. A pixel that was never valid has no prior: it is
NaN in the result, and the retrieval judges nothing it has no background for: such a
pixel is invalid in every frame (at ``downsample = 2`` the retrieval averages the prior
over 2 x 2 blocks, and only a block without any prior is invalid). Where validity depends on depth (say a sensor
that drops far returns) the mean over the valid samples is biased towards near values;
:attr:`InverseDepthPrior.count` is kept so that callers can inspect the support.

Memory is constant in the number of frames: two (H, W) arrays. Accumulators of parts of the
frames merge (:meth:`InverseDepthPrior.merge`): :func:`prior_of_files` builds a prior on
several processes or on Ray.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

import numpy as np

from monitor.depth.files import load_depth
from monitor.offline.parallel import ordered_map
from monitor.userfiles import read_npy, write_npy


class InverseDepthPrior:
    """Streaming per-pixel mean of inverse depth over valid samples.

    The first depth map added fixes the size; a map of another size is refused.

    Attributes
    ----------
    shape : tuple of int (H, W) or None
        The size of the maps, None before the first one.
    n_frames : int
        Depth maps added so far.
    count : ndarray of shape (H, W), int64, or None
        Per pixel, the number of frames in which it was valid.
    """

    def __init__(self):
        self.shape: tuple[int, int] | None = None
        self.n_frames = 0
        self.count: np.ndarray | None = None
        self._sum: np.ndarray | None = None

    def add(self, depth: np.ndarray, *, name: str = "depth") -> None:
        """Add one depth map (float (H, W) metres; non-finite or <= 0 pixels are skipped).

        ``name`` names the map in errors (a frame key or a file).
        """
        depth = np.asarray(depth)
        if depth.ndim != 2 or not np.issubdtype(depth.dtype, np.floating):
            raise ValueError(
                f"{name}: shape {depth.shape}, dtype {depth.dtype}; expected a floating-point "
                "(H, W) depth map in metres"
            )
        if self.shape is None:
            self.shape = depth.shape
            self.count = np.zeros(self.shape, dtype=np.int64)
            self._sum = np.zeros(self.shape, dtype=np.float64)
        elif depth.shape != self.shape:
            raise ValueError(
                f"{name}: depth map is {depth.shape[1]}x{depth.shape[0]} (W x H), the prior is "
                f"{self.shape[1]}x{self.shape[0]}; every frame must have the same size"
            )
        with np.errstate(invalid="ignore"):
            valid = np.isfinite(depth) & (depth > 0)
        inverse = np.divide(1.0, depth, out=np.zeros(self.shape, dtype=np.float64), where=valid)
        self._sum += inverse
        self.count += valid
        self.n_frames += 1

    def merge(self, other: "InverseDepthPrior") -> None:
        """Add the frames another accumulator has seen (the same size, or this one still empty)."""
        if other.n_frames == 0:
            return
        if self.shape is None:
            self.shape, self.count, self._sum = other.shape, other.count.copy(), other._sum.copy()
        elif other.shape != self.shape:
            raise ValueError(f"cannot merge a prior of {other.shape[1]}x{other.shape[0]} (W x H) into one of "
                             f"{self.shape[1]}x{self.shape[0]}; every frame must have the same size")
        else:
            self._sum += other._sum
            self.count += other.count
        self.n_frames += other.n_frames

    def mean(self) -> np.ndarray:
        """The prior: float32 (H, W) mean inverse depth in 1/m, NaN where never valid."""
        if self.n_frames == 0:
            raise ValueError("the prior has no frames yet; add at least one depth map")
        prior = np.full(self.shape, np.nan, dtype=np.float64)
        np.divide(self._sum, self.count, out=prior, where=self.count > 0)
        return prior.astype(np.float32)


def build_prior(depths: Iterable[tuple[str, np.ndarray]]) -> InverseDepthPrior:
    """Accumulate ``(name, depth)`` pairs (e.g. a :class:`monitor.depth.files.DepthFolder`).

    The first map fixes the size; a map of another size is refused with its name. Wrap the
    iterable in ``tqdm`` for a progress bar.

    Returns
    -------
    InverseDepthPrior
        Call ``.mean()`` for the prior itself.
    """
    prior = InverseDepthPrior()
    for name, depth in depths:
        prior.add(depth, name=name)
    if prior.n_frames == 0:
        raise ValueError("no depth maps given; the prior needs at least one training frame")
    return prior


#: depth files per part of :func:`prior_of_files` (the parts, not the workers, fix the order
#: of the float64 sums: any number of workers gives the same prior, bit for bit)
PRIOR_PART_FILES = 32


@dataclass(frozen=True)
class PriorPart:
    """A picklable job for workers: ``build()`` returns a function that accumulates a list of
    depth files (:func:`monitor.depth.files.load_depth`, PNGs at ``png_scale``) into an
    :class:`InverseDepthPrior`."""

    png_scale: float

    def build(self):
        def accumulate(paths: list) -> InverseDepthPrior:
            return build_prior((str(path), training_depth(path, self.png_scale)) for path in paths)
        return accumulate


#: A training map whose median valid value is below this many metres is refused: as metres
#: the whole view would be within reach of the camera, so it is an inverse depth in 1/m.
MIN_MEDIAN_DEPTH_M = 1.0


def training_depth(path: Path, png_scale: float) -> np.ndarray:
    """The depth map in ``path``, refused (ValueError naming the file) when its median valid
    value is below :data:`MIN_MEDIAN_DEPTH_M`: not metres but 1/m (a prior?)."""
    depth = load_depth(path, png_scale=png_scale)
    valid = depth[np.isfinite(depth) & (depth > 0)]
    if valid.size and np.median(valid) < MIN_MEDIAN_DEPTH_M:
        raise ValueError(
            f"{path}: median valid value {float(np.median(valid)):.3g} is below "
            f"{MIN_MEDIAN_DEPTH_M:g} m: not a depth map in metres but an inverse depth in 1/m "
            "(a prior from an earlier run?); move it out of the depth folder"
        )
    return depth


def prior_of_files(paths: list, png_scale: float, *, workers: int = 1, ray: str | None = None,
                   progress=None) -> InverseDepthPrior:
    """The prior of depth files, in parts of :data:`PRIOR_PART_FILES` on ``workers`` processes or Ray.

    The parts are merged in order, so the result does not depend on ``workers`` or ``ray``.
    ``progress(n)`` is called with the files of each part done.
    """
    parts = [list(paths[a:a + PRIOR_PART_FILES]) for a in range(0, len(paths), PRIOR_PART_FILES)]
    total = InverseDepthPrior()
    for part, partial in zip(parts, ordered_map(PriorPart(png_scale), parts, workers=workers, ray=ray)):
        total.merge(partial)
        if progress is not None:
            progress(len(part))
    if total.n_frames == 0:
        raise ValueError("no depth maps given; the prior needs at least one training frame")
    return total


def save_prior(path: str | Path, prior: np.ndarray) -> None:
    """Write a prior (float32 (H, W), 1/m, NaN = no sample) as ``.npy``, whole or not at
    all (:func:`fuzzcore.outputs.write_atomic`)."""
    path = Path(path)
    if path.suffix.lower() != ".npy":
        raise ValueError(f"prior path {path} must end in .npy")
    write_npy(path, check_prior(prior, name=str(path)))


def load_prior(path: str | Path) -> np.ndarray:
    """Read a prior written by :func:`save_prior` (or ``fuzzrisk prior build``).

    The header is checked against the file before anything is allocated
    (:func:`monitor.userfiles.read_npy`); errors name the file.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(
            f"prior file {path} does not exist; build one with "
            "`fuzzrisk prior build DEPTH_DIR -o PRIOR.npy`"
        )
    return check_prior(read_npy(path, "prior file"), name=f"prior file {path}")


def check_prior(prior: np.ndarray, *, name: str = "prior") -> np.ndarray:
    """Validate a prior and return it as float32 (H, W).

    A prior holds mean inverse depths: finite values >= 0 in 1/m, or NaN where no training
    sample was valid. Anything else (inf, negatives, values too large for float32 such as a
    float64 1e300, a wrong shape or dtype) is an error.
    """
    if not isinstance(prior, np.ndarray) or prior.ndim != 2 or not np.issubdtype(prior.dtype, np.floating):
        shape = getattr(prior, "shape", None)
        dtype = getattr(prior, "dtype", type(prior).__name__)
        raise ValueError(
            f"{name}: shape {shape}, dtype {dtype}; expected a floating-point (H, W) "
            "mean inverse depth in 1/m"
        )
    with np.errstate(over="ignore"):
        single = np.ascontiguousarray(prior, dtype=np.float32)
    bad = np.isinf(single) | (single < 0)
    if bad.any():
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        value = float(prior[first])
        kind = "too large for float32 (> 3.4e38)" if np.isfinite(value) and value > 0 else "inf or negative"
        raise ValueError(
            f"{name}: {int(bad.sum())} pixels are inf, negative or too large for float32 (first "
            f"at row, col {first}: {value!r}, {kind}); a prior holds mean inverse depths >= 0 in "
            "1/m, NaN where no sample"
        )
    return single
