"""Numba kernel of :mod:`monitor.synthetic.degrade`. Private: no validation, never raise.

One pass over the image fusing what would be several NumPy temporaries.
"""
from __future__ import annotations

import math

from fuzzcore.jit import SYNTHETIC_IMAGE, kernel


@kernel(fastmath=SYNTHETIC_IMAGE)
def fade_clip_grain(depth_true, labels, background, alpha, max_depth, grain, out):
    """``out = min(depth, max_depth) * grain``, objects first blended towards the background.

    Parameters
    ----------
    depth_true, background : (H, W) float32, metres (inf allowed).
    labels : (H, W) int; label k > 0 is blended with weight ``alpha[k]`` in log depth.
    alpha : (n + 1,) float32 blend weights, ``alpha[0]`` unused; labels <= n.
    max_depth : float
    grain : (H, W) float32 multiplicative noise.
    out : (H, W) float32
    """
    height, width = out.shape
    for v in range(height):
        for u in range(width):
            d = min(depth_true[v, u], max_depth)
            k = labels[v, u]
            if k > 0 and alpha[k] > 0.0:
                a = alpha[k]
                b = min(background[v, u], max_depth)
                d = math.exp((1.0 - a) * math.log(d) + a * math.log(b))
            out[v, u] = d * grain[v, u]
