"""The stages of the depth-based retrieval as one image, like the paper's Fig. 2.

Panels, left to right: (a) the depth map, (b) its inverse, (c) the inverse minus the prior
(the foreground the edges are found on, at the retrieval's resolution), (d) the Canny
edges (red, thickened to stay visible at panel size) and the retrieved boxes with their
depth (green) over the camera frame, or over the depth map when no frame is given. (a) and
(b) are linearly normalised over their valid pixels; invalid pixels (blocks in (c)) are
drawn blue in (a)-(c).

Matplotlib runs on its Agg canvas directly (no pyplot, no global backend switch), so this
works headless and from threads.
"""
from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from fuzzcore.outputs import write_atomic
from monitor.depth.retrieval import RetrievalParams, RetrievalStages, Retriever

_INVALID_RGB = (0.25, 0.45, 0.85)


def save_retrieval_figure(path: str | Path, depth: np.ndarray, prior: np.ndarray,
                          image: np.ndarray | None = None,
                          params: RetrievalParams = RetrievalParams(), *,
                          panel_width: int = 800) -> RetrievalStages:
    """Run the retrieval on one frame and write its stages as a PNG.

    Parameters
    ----------
    path : str or Path
        Destination, ``.png``.
    depth : ndarray of shape (H, W), float32
        Metres.
    prior : ndarray of shape (H, W), floating
        Mean inverse depth, 1/m (see :mod:`monitor.depth.prior`).
    image : ndarray of shape (H, W, 3), uint8, optional
        The RGB camera frame for panel (d).
    params : RetrievalParams
        Thresholds of the retrieval.
    panel_width : int
        Width of each of the four panels in the PNG, pixels.

    Returns
    -------
    RetrievalStages
        What the retrieval computed (boxes included).

    Raises
    ------
    InvalidDepthError
        The frame has too many invalid pixels (from the retrieval).
    ValueError
        Bad path, image or arrays.
    """
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise ValueError(f"figure path {path} must end in .png")
    if panel_width < 16:
        raise ValueError(f"panel_width = {panel_width}, must be >= 16 pixels")
    stages = Retriever(prior, params).stages(depth)  # validates depth and prior first
    height, width = depth.shape
    if image is not None and (not isinstance(image, np.ndarray) or image.dtype != np.uint8
                              or image.shape != (height, width, 3)):
        raise ValueError(
            f"image: shape {getattr(image, 'shape', None)}, dtype {getattr(image, 'dtype', None)}; "
            f"expected a uint8 ({height}, {width}, 3) RGB frame matching the depth map"
        )

    valid = np.isfinite(depth) & (depth > 0)
    inverse = np.zeros_like(depth)
    np.divide(1.0, depth, out=inverse, where=valid)
    panels = [
        ("(a) depth", _normalised(depth, valid)),
        ("(b) inverse depth", _normalised(inverse, valid)),
        ("(c) inverse minus prior", _grey_rgb(stages.foreground / 255.0, ~stages.invalid)),
    ]
    backdrop = image.astype(np.float64) / 255.0 if image is not None else panels[0][1].copy()
    edges = cv2.resize(stages.edges, (width, height), interpolation=cv2.INTER_NEAREST)
    thickness = max(1, int(round(width / panel_width)))  # about one panel pixel
    edges = cv2.dilate(edges, np.ones((thickness, thickness), np.uint8))
    backdrop[edges > 0] = (1.0, 0.0, 0.0)

    dpi = 100
    panel_in = panel_width / dpi
    figure = Figure(figsize=(4 * panel_in, panel_in * height / width + 0.4), dpi=dpi)
    axes = figure.subplots(1, 4)
    for ax, (title, rgb) in zip(axes, panels + [("(d) edges and boxes", backdrop)]):
        ax.imshow(rgb, interpolation="nearest", extent=(0, width, height, 0))
        ax.set_title(title, fontsize=9)
        ax.set_axis_off()
    for cx, cy, w, h, d in stages.boxes:
        axes[3].add_patch(Rectangle((cx - w / 2, cy - h / 2), w, h, fill=False, edgecolor="lime",
                                    linewidth=1.2))
        axes[3].text(cx - w / 2, cy - h / 2, f"{d:.1f} m", color="lime", fontsize=7, va="bottom")
    figure.tight_layout()
    write_atomic(path, FigureCanvasAgg(figure).print_png)
    return stages


def _normalised(values: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Linear 0..1 over the valid pixels as grey RGB, invalid pixels marked blue."""
    grey = np.zeros(values.shape)
    if valid.any():
        lo, hi = float(values[valid].min()), float(values[valid].max())
        grey[valid] = (values[valid] - lo) / (hi - lo) if hi > lo else 0.0
    return _grey_rgb(grey, valid)


def _grey_rgb(grey: np.ndarray, valid: np.ndarray) -> np.ndarray:
    rgb = np.repeat(grey[..., None], 3, axis=2).astype(np.float64)
    rgb[~valid] = _INVALID_RGB
    return rgb
