"""Speed of the depth-based retrieval on one 1600 x 900 synthetic frame, one thread.

Peers in the same run: the fused version (:class:`monitor.depth.retrieval.Retriever`: two Numba
passes, blur and Canny on the non-zero region) against a straight NumPy/OpenCV version of
the same computation (:func:`retrieve_numpy` below), whole retrieval and per-pixel part
alone. Both give identical boxes (checked before timing). The frame is synthetic
(:mod:`monitor.synthetic`, nominal, seed 0, frame 3; prior from 10 frames of seed 1000).

OpenCV runs Canny and the blur on its own thread pool; the module sets
``cv2.setNumThreads(1)`` for its duration so that every timing is single-threaded (the
Numba kernels are serial). Run::

    python -m pytest benchmarks/bench_retrieval.py -o python_files='bench_*.py'

The medians and their ratios are printed at the end of the module.
"""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from reporting import single_cv2_thread, write_report
from monitor.depth import _retrieval_kernels as kernels
from monitor.geometry.boxes import within_range
from monitor.depth.prior import build_prior
from monitor.depth.retrieval import RetrievalParams, Retriever, warmup
from monitor.synthetic.generate import generate_frames

PARAMS = RetrievalParams()
_MEDIANS: dict[str, float] = {}


@pytest.fixture(scope="module", autouse=True)
def one_thread_and_report(request):
    with single_cv2_thread():
        yield
    lines = [f"  {name}: median {1e3 * t:.3f} ms" for name, t in _MEDIANS.items()]
    for fused, straight in (("retrieve_fused", "retrieve_numpy"), ("foreground_fused", "foreground_numpy")):
        if fused in _MEDIANS and straight in _MEDIANS:
            lines.append(f"  {straight} / {fused} = {_MEDIANS[straight] / _MEDIANS[fused]:.2f}x")
    write_report(request, "retrieval medians (1600x900, one thread):", lines)


@pytest.fixture(scope="module")
def frame():
    training = generate_frames("nominal", 1000, n_frames=10)
    prior = build_prior((str(f.index), f.depth_est) for f in training).mean()
    depth = list(generate_frames("nominal", 0, n_frames=4))[3].depth_est
    warmup()
    return depth, prior, block_prior_numpy(prior)  # once per camera, as Retriever


def _record(benchmark, name):
    _MEDIANS[name] = benchmark.stats.stats.median


# --- the straight NumPy/OpenCV version --------------------------------------------------------


def block_prior_numpy(prior):
    """Mean of the finite values of each 2 x 2 block (NaN if none), float32, as Retriever's."""
    height, width = prior.shape
    padded = np.pad(prior.astype(np.float64), ((0, height % 2), (0, width % 2)),
                    constant_values=np.nan)
    blocks = padded.reshape(padded.shape[0] // 2, 2, padded.shape[1] // 2, 2)
    blocks = blocks.transpose(0, 2, 1, 3).reshape(blocks.shape[0], blocks.shape[2], 4)
    finite = np.isfinite(blocks)
    sums = np.where(finite, blocks, 0.0).sum(axis=2)  # in order: top left, top right, ...
    counts = finite.sum(axis=2)
    with np.errstate(invalid="ignore"):
        return np.where(counts > 0, sums / counts, np.nan).astype(np.float32)


def foreground_numpy(depth, block_prior):
    """Block mean of 1/D over valid pixels minus the block prior, to uint8 (steps 1-2)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        valid = np.isfinite(depth) & (depth > 0)
        inverse = np.where(valid, np.float32(1.0) / depth, np.float32(0.0)).astype(np.float32)
    count = valid.astype(np.int32)
    inverse = inverse[0::2] + inverse[1::2]  # same float32 order as the kernel: rows, then columns
    inverse = inverse[:, 0::2] + inverse[:, 1::2]
    count = count[0::2] + count[1::2]
    count = count[:, 0::2] + count[:, 1::2]
    known = np.isfinite(block_prior)
    mean = inverse / np.maximum(count, 1).astype(np.float32) - block_prior
    values = np.where((count > 0) & known, np.maximum(mean, np.float32(0.0)), np.float32(-1.0))
    scale = np.float32(255.0 / PARAMS.full_scale)
    quantised = np.floor(np.minimum(values * scale + np.float32(0.5), np.float32(255.0)))
    n_invalid = int((~valid).sum() + count[~known].sum())
    return np.where(values > 0, quantised, 0).astype(np.uint8), values < 0, n_invalid


def retrieve_numpy(depth, block_prior):
    """The whole retrieval, straight: NumPy arithmetic, OpenCV on the whole image."""
    image, invalid, n_invalid = foreground_numpy(depth, block_prior)
    assert n_invalid / depth.size <= PARAMS.max_invalid_fraction
    edges = _blur_canny(image)
    if invalid.any():
        reach = 2 * (PARAMS.blur_radius + 1) + 1
        edges[cv2.dilate(invalid.astype(np.uint8), np.ones((reach, reach), np.uint8)) > 0] = 0
    contours, _ = cv2.findContours(edges, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    rows = []
    for contour in contours:
        x, y, w, h = (2 * v for v in cv2.boundingRect(contour))
        w, h = min(w, depth.shape[1] - x), min(h, depth.shape[0] - y)
        if w < PARAMS.min_size or h < PARAMS.min_size:
            continue
        window = depth[y:y + h, x:x + w]
        d = float(window[np.isfinite(window) & (window > 0)].min())
        rows.append((x + w / 2, y + h / 2, w, h, d))
    boxes = within_range(np.array(rows, dtype=np.float64).reshape(-1, 5), PARAMS.max_range)
    return boxes[np.argsort(boxes[:, 4], kind="stable")]


def _blur_canny(image):
    size = (PARAMS.blur_size, PARAMS.blur_size)
    blurred = cv2.blur(cv2.blur(image, size, borderType=cv2.BORDER_REPLICATE), size,
                       borderType=cv2.BORDER_REPLICATE)
    return cv2.Canny(blurred, PARAMS.canny_low, PARAMS.canny_high, apertureSize=3, L2gradient=False)


# --- benchmarks ---------------------------------------------------------------------------------


def test_retrieve_fused(benchmark, frame):
    depth, prior, block_prior = frame
    retriever = Retriever(prior, PARAMS)
    expected = retrieve_numpy(depth, block_prior)
    assert len(expected) > 0
    np.testing.assert_array_equal(retriever(depth), expected)
    benchmark(retriever, depth)
    _record(benchmark, "retrieve_fused")


def test_retrieve_numpy(benchmark, frame):
    depth, prior, block_prior = frame
    np.testing.assert_array_equal(retrieve_numpy(depth, block_prior), Retriever(prior, PARAMS)(depth))
    benchmark(retrieve_numpy, depth, block_prior)
    _record(benchmark, "retrieve_numpy")


def _foreground_fused(depth, block_prior, values, nearest):
    n_invalid = kernels.foreground_pairs(depth, block_prior, values, nearest)
    rows, cols = values.shape
    image = np.empty((rows, cols), np.uint8)
    invalid = np.zeros((rows, cols), np.uint8)
    kernels.foreground_u8(values, np.float32(255.0 / PARAMS.full_scale), image,
                          np.empty(rows, np.uint8), np.empty(cols, np.uint8), invalid, n_invalid > 0)
    return image


def test_foreground_fused(benchmark, frame):
    depth, _, block_prior = frame
    values = np.empty((depth.shape[0] // 2, depth.shape[1] // 2), np.float32)
    nearest = np.empty_like(values)
    np.testing.assert_array_equal(_foreground_fused(depth, block_prior, values, nearest),
                                  foreground_numpy(depth, block_prior)[0])
    benchmark(_foreground_fused, depth, block_prior, values, nearest)
    _record(benchmark, "foreground_fused")


def test_foreground_numpy(benchmark, frame):
    depth, _, block_prior = frame
    benchmark(foreground_numpy, depth, block_prior)
    _record(benchmark, "foreground_numpy")


def test_blur_and_canny_whole_half_size_image(benchmark, frame):
    # for reference: the OpenCV part the fused version cannot fuse, on the whole image
    depth, _, block_prior = frame
    benchmark(_blur_canny, foreground_numpy(depth, block_prior)[0])
    _record(benchmark, "blur_and_canny")
