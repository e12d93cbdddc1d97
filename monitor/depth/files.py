"""Depth maps from files: ``.npy`` in metres, 16-bit PNG with a scale, and folders of them.

Every reader returns the project's depth-map type: a float32 ``(H, W)`` array in metres
in which non-finite or non-positive pixels are invalid.

=========  ==============================================================================
format     meaning
=========  ==============================================================================
``.npy``   a 2-D floating-point array in metres (float16/32/64; read as float32).
           NaN, inf and values <= 0 are kept as they are: they are the invalid pixels.
``.png``   a single-channel 16-bit PNG; depth = value / ``png_scale`` metres (KITTI
           depth-completion style, ``png_scale = 256``); value 0 means "no depth" and
           is read as NaN.
=========  ==============================================================================

:class:`DepthFolder` serves a directory of such files keyed by frame (the file name
without its extension), in sorted order.
"""
from __future__ import annotations

from pathlib import Path
from typing import Iterator

import cv2
import numpy as np

from fuzzcore.outputs import write_atomic
from monitor.userfiles import check_png_size, read_npy

#: KITTI's depth PNGs store metres * 256 in uint16
KITTI_PNG_SCALE = 256.0

#: file extensions :func:`load_depth` reads
DEPTH_SUFFIXES = (".npy", ".png")


def load_depth(path: str | Path, *, png_scale: float = KITTI_PNG_SCALE) -> np.ndarray:
    """Read one depth map from a ``.npy`` or 16-bit ``.png`` file.

    Parameters
    ----------
    path : str or Path
        The file; its extension selects the format (see the module docstring).
    png_scale : float, default 256
        Stored value per metre in a PNG (depth = value / png_scale). Ignored for ``.npy``.

    Returns
    -------
    ndarray of shape (H, W), float32
        Depth in metres; invalid pixels are non-finite or <= 0 (PNG zeros become NaN).

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        Naming the file: unknown extension, a file that cannot be decoded, a header that
        does not match the file or declares more than
        :data:`monitor.userfiles.MAX_PIXELS` pixels (checked before anything is
        allocated), an array that is not 2-D, a dtype that is not floating (``.npy``) or
        not uint16 (``.png``), or a bad scale.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in DEPTH_SUFFIXES:
        raise ValueError(
            f"depth file {path}: extension {path.suffix!r} is not supported, "
            f"expected one of {', '.join(DEPTH_SUFFIXES)}"
        )
    if not path.is_file():
        raise FileNotFoundError(f"depth file {path} does not exist")
    if suffix == ".npy":
        return _load_npy(path)
    return _load_png(path, png_scale)


def _load_npy(path: Path) -> np.ndarray:
    array = read_npy(path, "depth file")
    if array.ndim != 2:
        raise ValueError(
            f"depth file {path}: array has shape {array.shape} ({array.ndim}-D), "
            "expected a 2-D (H, W) depth map in metres"
        )
    if not np.issubdtype(array.dtype, np.floating):
        raise ValueError(
            f"depth file {path}: dtype is {array.dtype}, expected a floating-point depth in "
            "metres (integer maps are ambiguous about their unit; store them as a 16-bit "
            "PNG with a scale instead)"
        )
    return np.ascontiguousarray(array, dtype=np.float32)


def _load_png(path: Path, png_scale: float) -> np.ndarray:
    if not (np.isfinite(png_scale) and png_scale > 0):
        raise ValueError(f"png_scale = {png_scale}, must be a finite number > 0 (values per metre)")
    check_png_size(path, "depth file")
    raw = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if raw is None:
        raise ValueError(f"depth file {path}: OpenCV cannot decode it as a PNG image")
    if raw.ndim != 2:
        raise ValueError(
            f"depth file {path}: image has shape {raw.shape}, expected a single-channel "
            "16-bit depth PNG"
        )
    if raw.dtype != np.uint16:
        raise ValueError(
            f"depth file {path}: pixel type is {raw.dtype}, expected uint16 "
            f"(depth = value / {png_scale:g} m, 0 = no depth)"
        )
    depth = raw.astype(np.float32) / np.float32(png_scale)
    depth[raw == 0] = np.nan
    return depth


def save_depth_png(path: str | Path, depth: np.ndarray, *, png_scale: float = KITTI_PNG_SCALE) -> None:
    """Write a depth map as a 16-bit PNG (value = round(depth * png_scale), 0 = invalid),
    whole or not at all (:func:`fuzzcore.outputs.write_atomic`).

    Parameters
    ----------
    path : str or Path
        Destination; must end in ``.png``.
    depth : ndarray of shape (H, W), floating
        Metres; invalid pixels (non-finite or <= 0) are written as 0.
    png_scale : float, default 256
        Stored value per metre.

    Raises
    ------
    ValueError
        Wrong suffix, shape or dtype, a bad scale, or a valid depth that does not fit in
        uint16 at this scale (more than 65535 / png_scale metres, or so small it rounds
        to the "no depth" value 0).
    """
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise ValueError(f"depth PNG path {path} must end in .png")
    if not (np.isfinite(png_scale) and png_scale > 0):
        raise ValueError(f"png_scale = {png_scale}, must be a finite number > 0 (values per metre)")
    depth = np.asarray(depth)
    if depth.ndim != 2 or not np.issubdtype(depth.dtype, np.floating):
        raise ValueError(
            f"depth has shape {depth.shape} and dtype {depth.dtype}, expected a 2-D "
            "floating-point (H, W) map in metres"
        )
    valid = np.isfinite(depth) & (depth > 0)
    scaled = np.zeros(depth.shape, dtype=np.float64)
    scaled[valid] = np.rint(depth[valid].astype(np.float64) * png_scale)
    if valid.any() and (scaled[valid].max() > 65535 or scaled[valid].min() < 1):
        raise ValueError(
            f"depth range {depth[valid].min():g}..{depth[valid].max():g} m does not fit a "
            f"16-bit PNG at png_scale = {png_scale:g} (1..65535 stored values)"
        )
    ok, encoded = cv2.imencode(".png", scaled.astype(np.uint16))
    if not ok:
        raise OSError(f"cannot encode depth PNG {path}")
    write_atomic(path, lambda handle: handle.write(encoded.tobytes()))


class DepthFolder:
    """A directory of depth maps keyed by frame, in sorted order.

    A frame's key is its file name without the extension (``000123.png`` -> ``"000123"``).
    Files with other extensions are ignored; the same key in two formats is an error.
    Keys are sorted as strings, so number frames with zero padding.

    Parameters
    ----------
    root : str or Path
        The directory.
    png_scale : float, default 256
        Stored value per metre of the PNG files (see :func:`load_depth`).

    Examples
    --------
    >>> folder = DepthFolder("depth/")                    # doctest: +SKIP
    >>> for frame, depth in folder: ...                   # doctest: +SKIP
    >>> depth = folder["000123"]                          # doctest: +SKIP
    """

    def __init__(self, root: str | Path, *, png_scale: float = KITTI_PNG_SCALE):
        root = Path(root)
        if not root.is_dir():
            raise FileNotFoundError(f"depth folder {root} does not exist or is not a directory")
        if not (np.isfinite(png_scale) and png_scale > 0):
            raise ValueError(f"png_scale = {png_scale}, must be a finite number > 0 (values per metre)")
        files: dict[str, Path] = {}
        for path in root.iterdir():
            if not path.is_file() or path.suffix.lower() not in DEPTH_SUFFIXES:
                continue
            if path.stem in files:
                raise ValueError(
                    f"depth folder {root}: frame {path.stem!r} exists twice "
                    f"({files[path.stem].name} and {path.name}); keep one"
                )
            files[path.stem] = path
        self.root = root
        self.png_scale = float(png_scale)
        self._files = dict(sorted(files.items()))

    @property
    def frames(self) -> list[str]:
        """The frame keys, sorted."""
        return list(self._files)

    def path(self, frame: str) -> Path:
        """The file holding ``frame``; KeyError naming the folder if there is none."""
        try:
            return self._files[frame]
        except KeyError:
            raise KeyError(
                f"depth folder {self.root} has no frame {frame!r} "
                f"(looked for {frame}.npy / {frame}.png; {len(self._files)} frames present)"
            ) from None

    def __getitem__(self, frame: str) -> np.ndarray:
        """The depth map of ``frame``: float32 (H, W) metres (see :func:`load_depth`)."""
        return load_depth(self.path(frame), png_scale=self.png_scale)

    def __contains__(self, frame: object) -> bool:
        return frame in self._files

    def __len__(self) -> int:
        return len(self._files)

    def __iter__(self) -> Iterator[tuple[str, np.ndarray]]:
        """Yield ``(frame, depth)`` in sorted frame order, reading one file at a time."""
        for frame, path in self._files.items():
            yield frame, load_depth(path, png_scale=self.png_scale)

    def __repr__(self) -> str:
        return f"DepthFolder({str(self.root)!r}, {len(self)} frames)"
