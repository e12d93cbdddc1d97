"""Figures of the demo and the evaluation (PNG, drawn on matplotlib's Agg canvas).

- :func:`save_fis_figure`: a rule base's membership functions and its output surface over
  (IoU~, RDD~) (paper, Fig. 4);
- :func:`save_frame_figure`: a frame with the detector's boxes (blue), the depth view's
  boxes (yellow) and the risk (paper, Fig. 5);
- :func:`save_risk_timeline`: risk over time per scene, with the shield threshold and the
  offline target 1 - USC~;

The retrieval stages (paper, Fig. 2) are drawn by :mod:`monitor.report.retrieval_figure`.
Figures are :class:`matplotlib.figure.Figure` objects on their own Agg canvas: no pyplot, no
global state and no switch of the user's matplotlib backend.
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from fuzzcore import FuzzySystem
from monitor.userfiles import save_figure

DETECTOR_COLOUR = "#1f77ff"
DEPTH_COLOUR = "#ffd400"


def _figure(width: float, height: float) -> Figure:
    """A figure of ``width`` x ``height`` inches on its own Agg canvas."""
    figure = Figure(figsize=(width, height))
    FigureCanvasAgg(figure)
    return figure


def save_fis_figure(fis: FuzzySystem, path: str | Path, resolution: int = 61) -> Path:
    """Membership functions of every variable, and the output surface over the first two
    inputs (a two-input, Mamdani or Sugeno, single-output system)."""
    variables = list(fis.inputs) + list(fis.outputs)
    fig = _figure(4 * (len(variables) + 1), 3.6)
    for i, var in enumerate(variables):
        ax = fig.add_subplot(1, len(variables) + 1, i + 1)
        if fis.type == "sugeno" and var in fis.outputs:
            ax.text(0.5, 0.5, "Sugeno output:\n" + "\n".join(f"{t.name}: {t.kind} {list(t.params)}"
                                                          for t in var.terms),
                    ha="center", va="center", fontsize=8, transform=ax.transAxes)
            ax.set_axis_off()
            continue
        x = np.linspace(*var.range, 401)
        for term in var.terms:
            ax.plot(x, term.membership(x), label=term.name)
        ax.set_title(f"{'output' if var in fis.outputs else 'input'}: {var.name}")
        ax.set_ylim(-0.02, 1.05)
        ax.legend(fontsize=8)
    if len(fis.inputs) >= 2 and len(fis.outputs) == 1:
        a, b = fis.inputs[0], fis.inputs[1]
        xa, xb = np.linspace(*a.range, resolution), np.linspace(*b.range, resolution)
        A, B = np.meshgrid(xa, xb)
        rest = [np.full_like(A, 0.5 * sum(v.range)) for v in fis.inputs[2:]]
        Z = fis.infer(A, B, *rest)
        ax = fig.add_subplot(1, len(variables) + 1, len(variables) + 1, projection="3d")
        ax.plot_surface(A, B, Z, cmap="viridis", linewidth=0)
        ax.set_xlabel(a.name)
        ax.set_ylabel(b.name)
        ax.set_zlabel(fis.outputs[0].name)
        ax.set_title("output surface")
    fig.suptitle(f"rule base {fis.name}: {len(fis.rules)} rules, {fis.defuzzifier}")
    fig.tight_layout()
    path = Path(path)
    save_figure(fig, path, 90)
    return path


def _draw_boxes(ax, boxes: np.ndarray, colour: str, label: str) -> None:
    for k, (cx, cy, w, h, d) in enumerate(boxes):
        ax.add_patch(Rectangle((cx - w / 2, cy - h / 2), w, h, fill=False, lw=1.6, ec=colour,
                               label=label if k == 0 else None))
        ax.text(cx - w / 2, cy - h / 2 - 4, f"{d:.1f} m", color=colour, fontsize=7)


def save_frame_figure(image: np.ndarray, report, path: str | Path, title: str = "") -> Path:
    """``image`` (H, W, 3) uint8 with P (blue), S (yellow) and the report's risk."""
    fig = _figure(10, 5.8)
    ax = fig.subplots()
    ax.imshow(image)
    _draw_boxes(ax, report.P, DETECTOR_COLOUR, "detector (P)")
    _draw_boxes(ax, report.S, DEPTH_COLOUR, "depth view (S)")
    ax.set_axis_off()
    colour = "red" if report.risk > 0.5 else "green"
    features = (f"IoU~ {report.iou:.2f}, RDD~ {report.rdd:.2f}" if report.status == "ok"
                else report.status)
    ax.set_title(f"{title}  risk {report.risk:.2f} ({features})", color=colour)
    if len(report.P) or len(report.S):
        ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    path = Path(path)
    save_figure(fig, path, 80)
    return path


def save_risk_timeline(series: Sequence[dict], path: str | Path, threshold: float = 0.5) -> Path:
    """One panel per scene: risk (solid), target 1 - USC~ (dashed), shield threshold.

    ``series``: dicts with ``name``, ``time`` (s), ``risk`` and ``target`` arrays (NaN
    where there is none: a frame not processed, no ground truth) and ``status`` (list of
    str; invalid frames are marked with an x). Drawn on a :class:`matplotlib.figure.Figure`
    (no pyplot state, safe in worker processes) and written whole or not at all
    (:func:`monitor.userfiles.save_figure`).
    """
    n = len(series)
    cols = min(3, n)
    rows = -(-n // cols)
    fig = _figure(4.5 * cols, 2.6 * rows)
    axes = fig.subplots(rows, cols, squeeze=False, sharey=True)
    for ax, s in zip(axes.ravel(), series):
        t = np.asarray(s["time"], dtype=np.float64)
        risk = np.asarray(s["risk"], dtype=np.float64)
        ax.plot(t, risk, "-o", ms=3, label="risk")
        target = np.asarray(s["target"], dtype=np.float64)
        if np.isfinite(target).any():
            ax.plot(t, target, "--", color="grey", label="1 - USC~ (truth)")
        invalid = np.array([st == "invalid-input" for st in s["status"]], dtype=bool)
        if invalid.any():
            ax.plot(t[invalid], risk[invalid], "rx", label="invalid frame")
        ax.axhline(threshold, color="red", lw=0.8, ls=":")
        ax.set_title(s["name"], fontsize=9)
        ax.set_ylim(-0.02, 1.02)
        ax.set_xlabel("time (s)")
    for ax in axes.ravel()[n:]:
        ax.set_axis_off()
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    path = Path(path)
    save_figure(fig, path, 80)
    return path
