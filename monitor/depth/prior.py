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

Memory is constant in the number of frames: two (H, W) arrays.
"""
from __future__ import annotations

from pathlib import Path
from typing import Iterable

import numpy as np

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


def save_prior(path: str | Path, prior: np.ndarray) -> None:
    """Write a prior (float32 (H, W), 1/m, NaN = no sample) as ``.npy``, whole or not at
    all (:func:`monitor.userfiles.write_atomic`)."""
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
