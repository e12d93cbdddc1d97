"""``fuzzrisk prior build DEPTH_DIR -o PRIOR.npy``: the inverse-depth prior of training frames.

Streams the depth maps of DEPTH_DIR (``.npy`` metres or 16-bit ``.png``, see
:mod:`monitor.depth.files`) in sorted frame order through :class:`monitor.depth.prior.InverseDepthPrior`
(constant memory; in parts on ``--workers`` processes or ``--ray``, the same prior bit for
bit) and writes the per-pixel mean of 1/D over valid samples as float32 ``.npy`` (1/m, NaN
where no frame had a valid depth).

The output is checked before any map is read: it ends in ``.npy``, its folder exists, it
is not inside DEPTH_DIR (a prior written there would be read as a depth map by the next
run), and an existing file is replaced only with ``--overwrite``; it is written whole or not
at all. A file in DEPTH_DIR whose median valid value is below
:data:`monitor.depth.prior.MIN_MEDIAN_DEPTH_M` (1 m) is refused, naming it: as metres the
whole view would be within reach of the camera, so it is an inverse depth in 1/m, such as a
prior from an earlier run.
"""
from __future__ import annotations

import argparse

import numpy as np
from tqdm import tqdm

from fuzzcore.outputs import check_output
from monitor.depth.files import KITTI_PNG_SCALE, DepthFolder
from monitor.cli.scenes import add_parallel_arguments
from monitor.depth.prior import prior_of_files, save_prior


def add_arguments(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    build = actions.add_parser(
        "build", help="mean inverse depth of a folder of depth maps",
        description="Per-pixel mean of 1/D over the valid samples of every depth map in "
                    "DEPTH_DIR (.npy in metres or 16-bit .png), written as float32 .npy "
                    "(1/m, NaN where no frame had a valid depth).",
    )
    build.add_argument("depth_dir", metavar="DEPTH_DIR", help="folder of training depth maps")
    build.add_argument("-o", "--output", required=True, metavar="PRIOR.npy",
                       help="where to write the prior (not inside DEPTH_DIR)")
    build.add_argument("--overwrite", action="store_true", help="replace PRIOR.npy if it exists")
    build.add_argument("--png-scale", type=float, default=KITTI_PNG_SCALE,
                       help="stored PNG value per metre (default %(default)g, KITTI)")
    add_parallel_arguments(build)


def run(args: argparse.Namespace) -> int:
    # "build" is the only action (argparse enforces it)
    check_output(args.output, (".npy",), [args.depth_dir], args.overwrite, what="prior")
    folder = DepthFolder(args.depth_dir, png_scale=args.png_scale)
    if len(folder) == 0:
        raise ValueError(f"no depth maps (.npy or .png) in {folder.root}")
    bar = tqdm(total=len(folder), unit="frame", desc="prior", disable=None)
    accumulator = prior_of_files([folder.path(frame) for frame in folder.frames], folder.png_scale,
                                 workers=args.workers, ray=args.ray, progress=bar.update)
    bar.close()
    save_prior(args.output, accumulator.mean())
    count = accumulator.count
    height, width = accumulator.shape
    never = int(np.count_nonzero(count == 0))
    print(f"prior of {accumulator.n_frames} frames ({width}x{height}) written to {args.output}; "
          f"valid samples per pixel: min {int(count.min())}, median {int(np.median(count))}; "
          f"{never} pixels ({100 * never / count.size:.2f}%) never valid (NaN in the prior)")
    return 0
