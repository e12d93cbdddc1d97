"""Depth-based retrieval of safety-critical objects (paper, Section III-A, Fig. 2).

From a metric depth map D and the inverse-depth prior (:mod:`monitor.depth.prior`):

1. foreground ``F = max(1/D - prior, 0)``: inverse depth makes near things steep and far
   things flat, and subtracting the prior removes what is usually there (the road just
   ahead, the usual traffic). With ``downsample = 2`` F is computed per 2 x 2 block: the
   mean of 1/D over the block's valid pixels minus the block's mean prior, clipped at 0.
   A depth network's output is upsampled anyway, and the block mean halves the pixel
   noise that otherwise turns into edges on the road.
2. F is normalised linearly to uint8: ``full_scale`` (1/m) becomes 255 and larger values
   saturate (``full_scale = None``: the frame's largest F becomes 255, as in the paper's
   figure; one absurdly near pixel then flattens every other object).
3. A blur (two passes of a ``blur_size`` box filter), then Canny edges (3x3 Sobel, L1
   gradient, thresholds ``canny_low``/``canny_high``). Edges within reach of an invalid
   block (the blur's reach plus one) are removed: the step between an object and a hole in
   the depth map is no object boundary.
4. External contours of the edges (``cv2.RETR_EXTERNAL``) and their bounding rectangles,
   scaled back to full resolution.
5. Each rectangle's depth d is the smallest valid depth of D inside it (a percentile of the
   valid depths as an option). Rectangles with a side below ``min_size`` or farther than
   ``max_range`` are dropped.

The result is the set S of the paper: float64 (M, 5) rows ``cx, cy, w, h, d`` (pixels,
metres), nearest first. A rectangle covering columns x..x+w-1 and rows y..y+h-1 has
``cx = x + w/2``, ``cy = y + h/2`` (pixel i spans [i, i+1), as in :mod:`monitor.geometry.boxes`).

Invalid pixels (depth NaN, inf or <= 0, or no prior: NaN at that pixel, or at
``downsample = 2`` in the whole block) are masked: they are left out of the block means, a
block without a valid pixel counts as "no foreground", and no edge is kept within reach
of one. A frame with more than ``max_invalid_fraction`` invalid pixels raises
:class:`InvalidDepthError`, so that garbage never becomes boxes.

Speed: the per-pixel arithmetic is two fused Numba passes (:mod:`monitor.depth._retrieval_kernels`:
one over the full-resolution depth map, which also keeps each block's nearest depth, and
one over the blocks); the prior is averaged to blocks once per :class:`Retriever`; the
blur and Canny run only on the bounding region of the non-zero foreground (with a margin
that makes this exactly equal to running them on the whole image). Call
:func:`warmup` once before a real-time loop (the kernels are also cached on disk). OpenCV
may run Canny on its own thread pool: set ``cv2.setNumThreads`` as the application needs.

Threads: a :class:`Retriever` may be called from several threads at once; each thread gets
its own scratch memory (allocated at its first call).
"""
from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import cv2
import numpy as np

from monitor.depth import _retrieval_kernels as kernels
from monitor.geometry.boxes import DEFAULT_RANGE_M, within_range
from monitor.depth.prior import check_prior

#: block sizes the retrieval supports (see RetrievalParams.downsample)
DOWNSAMPLE_FACTORS = (1, 2)

#: zero pixels the 3x3 Sobel and the non-maximum suppression of Canny need around the
#: non-zero foreground for a window to give exactly the edges of the whole image
_CANNY_MARGIN = 2


class InvalidDepthError(ValueError):
    """A depth map too invalid to retrieve objects from.

    Attributes
    ----------
    invalid_fraction : float
        Share of invalid pixels in the frame, 0..1.
    max_invalid_fraction : float
        The limit that was exceeded.
    """

    def __init__(self, invalid_fraction: float, max_invalid_fraction: float):
        self.invalid_fraction = float(invalid_fraction)
        self.max_invalid_fraction = float(max_invalid_fraction)
        super().__init__(
            f"depth map is {100 * invalid_fraction:.1f}% invalid (depth NaN, inf or <= 0, or no "
            f"prior), more than max_invalid_fraction = {100 * max_invalid_fraction:.1f}%; "
            "no objects retrieved"
        )


@dataclass(frozen=True)
class RetrievalParams:
    """The retrieval's parameters, with defaults measured on synthetic scenes.

    How the defaults were chosen. Data: :func:`monitor.synthetic.generate.generate_frames`
    (1600 x 900 nuScenes CAM_FRONT); prior from 120 nominal frames (seeds 1000-1011, 10
    frames each); test frames 4 per seed, 1.5 s apart: nominal seeds 0-24, noise and night
    seeds 0-14. Targets: the visible extent (label map) of every object nearer than 20 m
    with at least 1000 visible pixels; a target is recalled when a retrieved box overlaps
    it with IoU >= 0.3 (the paper's alpha); a retrieved box is correct when it overlaps an
    object nearer than 25 m with IoU >= 0.3; score F1 of the two.

    1. Every other nominal frame, grid ``downsample`` {1, 2} x ``full_scale`` {None, 0.05,
       0.1, 0.2} x Gaussian blur sigma {0, 1, 1.5, 2} x ``canny_low`` {20, 30, 40} (high =
       3 x low) x ``min_size`` {16, 32, 48}: ``downsample = 2`` beat 1 in 118 of 144
       settings (F1 +0.05 on average); the best fixed ``full_scale`` (0.1: F1 0.56) beat
       the best per-frame peak (0.50), and on the other nominal frames and the noise and
       night conditions the peak normalisation did worse still (F1 0.42 / 0.19 / 0.15
       against 0.50 / 0.28 / 0.32).
    2. All three conditions, ``downsample = 2``, ``full_scale`` {0.05, 0.1} x sigma
       {2, 2.5} x ``canny_low`` {30, 40, 50, 60} x high/low {2, 3} at ``min_size`` 40:
       full_scale 0.1, sigma 2, Canny 40/120 is within 0.003 of the best mean F1 (0.372).
    3. OpenCV's GaussianBlur takes 1.15 ms on the 800 x 450 image; two passes of a box
       filter take 0.33 ms. Two 5-pixel passes (also sigma 2) scored the same or better:
       mean F1 0.376, recall 0.31 / 0.27 / 0.18 and precision 0.88 / 0.63 / 0.80 (nominal /
       noise / night), about 2 boxes per frame. One pass of 5, 7 or 9 pixels, and two of
       3 or 7 or three of 5, scored lower (0.01-0.35). For comparison, the paper's
       pipeline recalls 0.37 (nominal) and 0.24 (noise) of the ground truth on nuScenes,
       at IoU > 0.3 and |RDD| < 0.2 (Table II).

    ``min_size`` is set by geometry, not by the score: a pedestrian (0.67 m wide) at 20 m
    is 42 px wide in this camera; larger minima scored higher but drop pedestrians before
    the range limit. ``max_invalid_fraction``: with random invalid discs (radius 20-120 px)
    covering a share q of the nominal frames, recall / precision went from 0.31 / 0.88
    (q = 0) to 0.21 / 0.66, 0.16 / 0.49, 0.08 / 0.29 and 0.04 / 0.23 at q = 0.1, 0.2, 0.3
    and 0.4: beyond 0.3 most boxes are wrong.

    Parameters
    ----------
    downsample : {1, 2}
        Block size: 2 works on the mean of each 2 x 2 block (more accurate on the synthetic
        data, and a quarter of the work after the first pass), 1 on single pixels.
    full_scale : float or None
        Foreground value (1/m) drawn as 255; larger values saturate. None: the frame's
        largest value (the paper's per-frame normalisation).
    blur_size : int
        Width of the box filter applied twice before Canny, (downsampled) pixels; odd,
        1 for no blur. Two passes of a 5-pixel box are a 9 x 9 tent kernel with a
        standard deviation of 2 pixels.
    canny_low, canny_high : float
        Canny hysteresis thresholds on the L1 Sobel gradient (3x3 aperture) of the uint8
        foreground; a step of s grey levels gives a gradient of about 4 s.
    min_size : float
        Smallest kept rectangle side, full-resolution pixels: a rectangle with
        w < min_size or h < min_size is dropped.
    max_range : float
        Farthest kept depth d, metres (the paper's 20 m).
    depth_percentile : float or None
        None: d is the smallest valid depth inside the rectangle (the paper). A number in
        [0, 100]: that percentile of the valid depths inside it, robust to a few outliers.
    max_invalid_fraction : float
        Largest share of invalid pixels (0..1) a frame may have; more raises
        :class:`InvalidDepthError`.
    """

    downsample: int = 2
    full_scale: float | None = 0.1
    blur_size: int = 5
    canny_low: float = 40.0
    canny_high: float = 120.0
    min_size: float = 40.0
    max_range: float = DEFAULT_RANGE_M
    depth_percentile: float | None = None
    max_invalid_fraction: float = 0.3

    def __post_init__(self):
        if self.downsample not in DOWNSAMPLE_FACTORS or isinstance(self.downsample, bool):
            raise ValueError(f"downsample = {self.downsample!r}, must be one of {DOWNSAMPLE_FACTORS}")
        if self.full_scale is not None and not (math.isfinite(self.full_scale) and self.full_scale > 0):
            raise ValueError(
                f"full_scale = {self.full_scale}, must be None (the frame's peak) or a finite "
                "inverse depth > 0 (1/m)"
            )
        if isinstance(self.blur_size, bool) or not isinstance(self.blur_size, int) \
                or self.blur_size < 1 or self.blur_size % 2 == 0:
            raise ValueError(
                f"blur_size = {self.blur_size!r}, must be an odd integer >= 1 (pixels; 1 = no blur)"
            )
        if not (math.isfinite(self.canny_low) and self.canny_low >= 0):
            raise ValueError(f"canny_low = {self.canny_low}, must be a finite number >= 0")
        if not (math.isfinite(self.canny_high) and self.canny_high >= self.canny_low):
            raise ValueError(
                f"canny_high = {self.canny_high}, must be finite and >= canny_low = {self.canny_low}"
            )
        if not (math.isfinite(self.min_size) and self.min_size >= 0):
            raise ValueError(f"min_size = {self.min_size}, must be a finite number of pixels >= 0")
        if not (self.max_range > 0):  # inf is allowed: no range limit
            raise ValueError(f"max_range = {self.max_range}, must be > 0 metres")
        if self.depth_percentile is not None and not (0 <= self.depth_percentile <= 100):
            raise ValueError(
                f"depth_percentile = {self.depth_percentile}, must be None (minimum) or in [0, 100]"
            )
        if not (0 <= self.max_invalid_fraction <= 1):
            raise ValueError(
                f"max_invalid_fraction = {self.max_invalid_fraction}, must be in [0, 1]"
            )

    @property
    def blur_radius(self) -> int:
        """Reach of the blur (both passes) in (downsampled) pixels, 0 without blur."""
        return 2 * (self.blur_size // 2)


@dataclass(frozen=True)
class RetrievalStages:
    """Everything one retrieval computed (for figures and diagnosis).

    The images are at the retrieval's resolution, (ceil(H / f), ceil(W / f)) for
    ``f = downsample``.

    Attributes
    ----------
    foreground : ndarray, uint8
        F scaled so that ``full_scale`` is 255 (before the blur); invalid blocks are 0.
    full_scale : float
        The foreground value drawn as 255, 1/m (the frame's peak when
        ``params.full_scale`` is None; then 0 if nothing is nearer than the prior).
    invalid : ndarray, bool
        Blocks without a valid pixel.
    invalid_fraction : float
        Share of invalid full-resolution pixels, 0..1.
    edges : ndarray, uint8
        Canny edges (255) after removing those within reach of invalid blocks.
    boxes : ndarray of shape (M, 5), float64
        The retrieved objects ``cx, cy, w, h, d`` in full-resolution pixels, nearest first.
    """

    foreground: np.ndarray
    full_scale: float
    invalid: np.ndarray
    invalid_fraction: float
    edges: np.ndarray
    boxes: np.ndarray


class Retriever:
    """The retrieval for one camera: a validated prior, the parameters and scratch memory.

    Use one per camera in a frame loop: it validates the prior and averages it to blocks
    once, and reuses its float32 scratch buffers from frame to frame (one set per thread,
    so an instance may be shared between threads). :func:`retrieve` is the one-shot form.

    Parameters
    ----------
    prior : ndarray of shape (H, W), floating
        Mean inverse depth of training frames, 1/m, NaN where unknown (see
        :mod:`monitor.depth.prior`); validated once here.
    params : RetrievalParams
    """

    def __init__(self, prior: np.ndarray, params: RetrievalParams = RetrievalParams()):
        if not isinstance(params, RetrievalParams):
            raise ValueError(f"params is a {type(params).__name__}, expected RetrievalParams")
        self.prior = check_prior(prior)
        self.params = params
        if params.downsample == 2:
            self._block_prior = _block_means(self.prior)
        self._local = threading.local()

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W), the size of the depth maps this retriever takes."""
        return self.prior.shape

    def __call__(self, depth: np.ndarray) -> np.ndarray:
        """The objects S of one depth map (see :func:`retrieve`)."""
        return self._run(as_depth_map(depth, self.prior.shape), keep_stages=False)

    def stages(self, depth: np.ndarray) -> RetrievalStages:
        """:meth:`__call__`, also returning the intermediate images."""
        return self._run(as_depth_map(depth, self.prior.shape), keep_stages=True)

    def _scratch(self) -> tuple[np.ndarray, np.ndarray]:
        """This thread's pass-1 buffers: block values and (at ``downsample = 2``) block minima."""
        local = self._local
        if not hasattr(local, "values"):
            f = self.params.downsample
            height, width = self.prior.shape
            local.values = np.empty((-(-height // f), -(-width // f)), dtype=np.float32)
            local.nearest = np.empty_like(local.values) if f == 2 else None
        return local.values, local.nearest

    def _run(self, depth: np.ndarray, keep_stages: bool):
        params = self.params
        values, nearest = self._scratch()
        rows, cols = values.shape
        foreground = np.empty((rows, cols), dtype=np.uint8)
        invalid = np.zeros((rows, cols), dtype=np.uint8)
        row_any = np.empty(rows, dtype=np.uint8)
        col_any = np.empty(cols, dtype=np.uint8)
        if params.downsample == 2:
            n_invalid = kernels.foreground_pairs(depth, self._block_prior, values, nearest)
        else:
            n_invalid = kernels.foreground_pixels(depth, self.prior, values)
            nearest = depth
        invalid_fraction = n_invalid / depth.size
        if invalid_fraction > params.max_invalid_fraction:
            raise InvalidDepthError(invalid_fraction, params.max_invalid_fraction)
        full_scale = params.full_scale if params.full_scale is not None else max(float(values.max()), 0.0)
        scale = np.float32(255.0 / full_scale) if full_scale > 0 else np.float32(0.0)
        kernels.foreground_u8(values, scale, foreground, row_any, col_any, invalid, n_invalid > 0)

        edges = np.zeros((rows, cols), dtype=np.uint8)
        nonzero_rows, nonzero_cols = np.flatnonzero(row_any), np.flatnonzero(col_any)
        if nonzero_rows.size:
            # Blur and Canny see only zeros beyond this margin, so the window's edges are
            # exactly those of the whole image.
            margin = params.blur_radius + _CANNY_MARGIN
            y0, y1 = max(nonzero_rows[0] - margin, 0), min(nonzero_rows[-1] + margin + 1, rows)
            x0, x1 = max(nonzero_cols[0] - margin, 0), min(nonzero_cols[-1] + margin + 1, cols)
            window = (slice(y0, y1), slice(x0, x1))
            edges[window] = _canny(foreground[window], params)
            if n_invalid:
                reach = 2 * (params.blur_radius + 1) + 1  # the blur's reach plus Sobel's
                near_invalid = cv2.dilate(invalid, np.ones((reach, reach), np.uint8))
                edges[near_invalid.view(bool)] = 0
            boxes = _boxes_from_edges(edges[window], (x0, y0), depth, nearest, params)
        else:
            boxes = np.zeros((0, 5))
        if not keep_stages:
            return boxes
        return RetrievalStages(
            foreground=foreground,
            full_scale=full_scale,
            invalid=invalid.view(bool),
            invalid_fraction=invalid_fraction,
            edges=edges,
            boxes=boxes,
        )


def as_depth_map(depth, shape: tuple[int, int], name: str = "depth") -> np.ndarray:
    """Validate a depth map and return it as C-ordered float32 (H, W) metres.

    The one check of a depth map's form; its values are judged by the retrieval (invalid
    pixels: NaN, inf or <= 0; too many of them raise :class:`InvalidDepthError`). On a
    C-ordered float32 array of the right shape this costs a few microseconds (no copy).

    Parameters
    ----------
    depth : ndarray of shape (H, W), real floating point
        Metres. float64 (or float16) is converted to float32: values beyond float32's range
        become inf, an invalid pixel.
    shape : tuple of int
        The expected (H, W).
    name : str
        The argument's name, for messages.

    Raises
    ------
    ValueError
        A masked array (its mask would be ignored: give invalid pixels as NaN instead),
        a non-floating dtype (integers, bool, complex, strings, objects) or another shape.
    """
    if isinstance(depth, np.ma.MaskedArray):
        raise ValueError(f"{name} is a masked array; its mask would be ignored: mark invalid "
                         "pixels NaN in a plain float array instead")
    if not isinstance(depth, np.ndarray):
        try:
            depth = np.asarray(depth)
        except (ValueError, TypeError) as exc:  # ragged nested lists
            raise ValueError(f"{name} is not an array of depths ({exc})") from None
    if depth.dtype.kind != "f":
        raise ValueError(f"{name} has dtype {depth.dtype}, expected real floating-point metres "
                         "(float32 or float64)")
    if depth.shape != tuple(shape):
        raise ValueError(
            f"{name} has shape {depth.shape} (H, W), expected {tuple(shape)}; "
            "the prior and the camera fix the size"
        )
    if depth.dtype != np.float32:
        with np.errstate(over="ignore"):
            return np.ascontiguousarray(depth, dtype=np.float32)
    return np.ascontiguousarray(depth)


def retrieve(depth: np.ndarray, prior: np.ndarray,
             params: RetrievalParams = RetrievalParams()) -> np.ndarray:
    """The safety-critical objects S of one depth map.

    One-shot form of :class:`Retriever` (which validates the prior and averages it to
    blocks once and reuses memory; use it in a frame loop). The one-shot form pays those
    per call: about 0.5 ms more than a Retriever on a 1600 x 900 frame.

    Parameters
    ----------
    depth : ndarray of shape (H, W), real floating point
        Metric depth, metres; non-finite or <= 0 pixels are invalid (see :func:`as_depth_map`).
    prior : ndarray of shape (H, W), floating
        Mean inverse depth of training frames, 1/m (NaN where unknown), see
        :mod:`monitor.depth.prior`.
    params : RetrievalParams

    Returns
    -------
    ndarray of shape (M, 5), float64
        Rows ``cx, cy, w, h, d`` (pixels, metres), nearest first; (0, 5) if none.

    Raises
    ------
    InvalidDepthError
        More than ``params.max_invalid_fraction`` of the pixels are invalid.
    ValueError
        Wrong shapes or dtypes, a masked depth map, or a prior with inf or negative values.
    """
    return Retriever(prior, params)(depth)


def retrieve_stages(depth: np.ndarray, prior: np.ndarray,
                    params: RetrievalParams = RetrievalParams()) -> RetrievalStages:
    """:func:`retrieve`, also returning the intermediate images (see :class:`RetrievalStages`)."""
    return Retriever(prior, params).stages(depth)


def _canny(foreground: np.ndarray, params: RetrievalParams) -> np.ndarray:
    """Step 3: the blur, then Canny; uint8 edges (255) of the same shape."""
    if params.blur_size > 1:
        size = (params.blur_size, params.blur_size)
        foreground = cv2.blur(foreground, size, borderType=cv2.BORDER_REPLICATE)
        foreground = cv2.blur(foreground, size, borderType=cv2.BORDER_REPLICATE)
    return cv2.Canny(foreground, params.canny_low, params.canny_high, apertureSize=3, L2gradient=False)


def _boxes_from_edges(edges: np.ndarray, offset: tuple[int, int], depth: np.ndarray,
                      nearest: np.ndarray, params: RetrievalParams) -> np.ndarray:
    """Steps 4-5: rectangles around the external contours of ``edges`` (a window whose
    top-left pixel is ``offset`` = (x, y) in the downsampled frame), at full resolution,
    with their depth; float64 (M, 5) rows ``cx, cy, w, h, d``, nearest first.

    ``nearest`` is the smallest valid depth per downsampled pixel (the depth map itself at
    ``downsample = 1``): the minimum over a rectangle's blocks is the minimum over its
    pixels, found with a quarter of the reads.
    """
    contours, _ = cv2.findContours(edges, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE, offset=offset)
    small = np.array([cv2.boundingRect(c) for c in contours], dtype=np.int64).reshape(-1, 4)
    f = params.downsample
    height, width = depth.shape
    x0, y0 = small[:, 0] * f, small[:, 1] * f
    x1 = np.minimum((small[:, 0] + small[:, 2]) * f, width)
    y1 = np.minimum((small[:, 1] + small[:, 3]) * f, height)
    rects = np.column_stack([x0, y0, x1 - x0, y1 - y0])
    keep = (rects[:, 2] >= params.min_size) & (rects[:, 3] >= params.min_size)
    rects, small = rects[keep], small[keep]
    if params.depth_percentile is None:
        d = kernels.rect_min_depth(nearest, small)
    else:
        d = np.array([_percentile_depth(depth, r, params.depth_percentile) for r in rects], dtype=np.float64)
    boxes = np.empty((len(rects), 5))
    boxes[:, 0] = rects[:, 0] + rects[:, 2] / 2
    boxes[:, 1] = rects[:, 1] + rects[:, 3] / 2
    boxes[:, 2:4] = rects[:, 2:4]
    boxes[:, 4] = d
    boxes = within_range(boxes, params.max_range)
    return boxes[np.argsort(boxes[:, 4], kind="stable")]


def _block_means(prior: np.ndarray) -> np.ndarray:
    """Mean of the finite values of each 2 x 2 block (partial at odd edges), NaN if none;
    float32 (ceil(H / 2), ceil(W / 2))."""
    height, width = prior.shape
    out = np.empty((-(-height // 2), -(-width // 2)), dtype=np.float32)
    kernels.block_means(prior, out)
    return out


def _percentile_depth(depth: np.ndarray, rect: np.ndarray, q: float) -> float:
    x, y, w, h = rect
    window = depth[y:y + h, x:x + w]
    values = window[np.isfinite(window) & (window > 0)]
    return float(np.percentile(values, q)) if values.size else math.nan


def warmup() -> None:
    """Compile (or load from the disk cache) every Numba kernel on a tiny frame."""
    depth = np.ones((3, 3), dtype=np.float32)
    prior = np.zeros((3, 3), dtype=np.float32)
    values = np.zeros((2, 2), dtype=np.float32)
    flags = np.empty(2, dtype=np.uint8)
    image = np.empty((2, 2), dtype=np.uint8)
    kernels.foreground_pixels(depth, prior, np.empty((3, 3), dtype=np.float32))
    kernels.foreground_pairs(depth, values.copy(), values, np.empty_like(values))
    kernels.foreground_u8(values, np.float32(1.0), image, flags, flags.copy(), image.copy(), True)
    kernels.rect_min_depth(depth, np.zeros((1, 4), dtype=np.int64))
    kernels.block_means(prior, values)
