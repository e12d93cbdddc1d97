"""Depth maps from camera images in batches: read with OpenCV, estimated by an ONNX model.

:class:`DepthModel` describes the network (picklable, so that worker processes and Ray
actors build their own session from it); :class:`ImageDepth` is the built stage: a list of
image files in, one depth map (or the reason there is none) per image out, optionally
saved as ``.npy`` for reuse (``--depth-dir`` of a later run).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from monitor.depth.onnx_model import OnnxDepthEstimator
from monitor.userfiles import write_npy


def read_image(path: str | Path) -> np.ndarray:
    """An image file as RGB uint8 ``(H, W, 3)``.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        OpenCV cannot decode it (the message names the file).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"image {path} does not exist")
    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if bgr is None:
        raise ValueError(f"image {path}: OpenCV cannot decode it; expected a JPEG, PNG or other image "
                         "file OpenCV reads")
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


@dataclass(frozen=True)
class DepthModel:
    """How to build the depth network: an ONNX file and how to run it.

    Parameters
    ----------
    path : Path
        The ``.onnx`` file.
    preset : str
        A name in :data:`monitor.depth.onnx_model.PRESETS`.
    scale : float or None
        As :class:`~monitor.depth.onnx_model.OnnxDepthEstimator`'s ``scale``.
    device : {"auto", "cpu", "cuda"}
    batch_size : int >= 1
        Images per network call.
    save_dir : Path or None
        Where to save each estimated map as ``<key>.npy`` (float32 metres).
    threads : int or None
        onnxruntime intra-op threads.
    """

    path: Path
    preset: str
    scale: float | None = None
    device: str = "auto"
    batch_size: int = 4
    save_dir: Path | None = None
    threads: int | None = None

    def __post_init__(self):
        if isinstance(self.batch_size, bool) or not isinstance(self.batch_size, int) or self.batch_size < 1:
            raise ValueError(f"depth batch size = {self.batch_size!r}, must be an integer >= 1")
        if self.save_dir is not None and not Path(self.save_dir).is_dir():
            raise FileNotFoundError(f"depth save folder {self.save_dir} does not exist; create it first")

    def build(self) -> "ImageDepth":
        """Load the model (the estimator checks the file, its shapes and the preset)."""
        estimator = OnnxDepthEstimator(self.path, self.preset, scale=self.scale, device=self.device,
                                       threads=self.threads)
        return ImageDepth(estimator, self.batch_size, self.save_dir)


class ImageDepth:
    """A depth network over image files, ``batch_size`` images per call.

    Parameters
    ----------
    estimator : OnnxDepthEstimator
    batch_size : int
    save_dir : Path or None
    """

    def __init__(self, estimator: OnnxDepthEstimator, batch_size: int, save_dir: Path | None):
        self.estimator = estimator
        self.batch_size = batch_size
        self.save_dir = save_dir

    def __call__(self, images: list[tuple[str, Path]]) -> list[np.ndarray | str]:
        """Depth of ``(key, image path)`` pairs, in order.

        Returns
        -------
        list
            Per image: float32 ``(H, W)`` metres, or the message saying why there is none
            (an unreadable image). An error of the model itself (an output of the wrong
            shape) is raised: it would fail every image.
        """
        out: list[np.ndarray | str] = []
        for start in range(0, len(images), self.batch_size):
            batch = images[start:start + self.batch_size]
            read, ok = [], []
            for key, path in batch:
                try:
                    read.append(read_image(path))
                    ok.append(True)
                except (ValueError, OSError) as exc:
                    read.append(str(exc))
                    ok.append(False)
            depths = iter(self.estimator.estimate_batch([r for r, good in zip(read, ok) if good]))
            for (key, _), r, good in zip(batch, read, ok):
                if not good:
                    out.append(r)
                    continue
                depth = next(depths)
                if self.save_dir is not None:
                    write_npy(Path(self.save_dir) / f"{key}.npy", depth)
                out.append(depth)
        return out
