"""The quality figure of ``fuzzrisk eval`` and the demo: ROC curves and risk against target.

Left: the ROC curve of the risk for hazard frames (:mod:`monitor.offline.measures`), one
line per condition and one for all frames, with the shield threshold's operating point
marked. Right: the risk of every frame against its target ``1 - USC~`` (frames without a
target are left out), hazard frames in red, with the diagonal a perfect monitor would lie
on and the shield threshold.

Matplotlib runs on its Agg canvas directly (no pyplot), so this works headless.
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from monitor.userfiles import save_figure
from monitor.offline.measures import FrameTruth, alarm_rates, auroc, roc_curve


def save_quality_figure(path: str | Path, risk: Mapping[str, np.ndarray],
                        truth: Mapping[str, Sequence[FrameTruth]], threshold: float,
                        title: str = "") -> Path:
    """Write the ROC curves and the risk-against-target scatter as a PNG.

    Parameters
    ----------
    path : str or Path
    risk : mapping of condition -> ndarray of shape (n,)
        The risk per frame.
    truth : mapping of condition -> sequence of n FrameTruth
        The same frames' ground truth (same keys as ``risk``).
    threshold : float
        The shield threshold.
    title : str

    Returns
    -------
    Path
    """
    fig = Figure(figsize=(11, 4.8))
    FigureCanvasAgg(fig)
    roc_ax, scatter_ax = fig.subplots(1, 2)
    all_risk = np.concatenate([np.asarray(risk[c], dtype=np.float64) for c in risk]) if risk else np.zeros(0)
    all_truth = [t for c in risk for t in truth[c]]
    curves = [(c, np.asarray(risk[c], dtype=np.float64), truth[c]) for c in risk]
    curves.append(("all", all_risk, all_truth))
    for name, r, ts in curves:
        hazard = np.array([t.hazard for t in ts], dtype=bool)
        if r.size == 0 or hazard.all() or not hazard.any():
            continue
        fpr, tpr, _ = roc_curve(r, hazard)
        style = {"color": "black", "lw": 2.2} if name == "all" else {"lw": 1.2}
        line, = roc_ax.plot(fpr, tpr, label=f"{name} (AUROC {auroc(r, hazard):.2f})", **style)
        hit, false = alarm_rates(r, hazard, threshold)
        roc_ax.plot([false], [hit], "o", color=line.get_color(), ms=5)
    roc_ax.plot([0, 1], [0, 1], ":", color="grey", lw=0.8)
    roc_ax.set_xlabel("false-alarm rate")
    roc_ax.set_ylabel("hit rate (hazard frames)")
    roc_ax.set_title(f"ROC for hazard frames (dots: risk > {threshold:g})", fontsize=10)
    roc_ax.set_xlim(-0.01, 1.01)
    roc_ax.set_ylim(-0.01, 1.01)
    if roc_ax.get_legend_handles_labels()[0]:
        roc_ax.legend(fontsize=7, loc="lower right")
    else:
        roc_ax.text(0.5, 0.5, "no ROC: the frames are all hazards or none are", ha="center", fontsize=8)

    target = np.array([t.target for t in all_truth], dtype=np.float64)
    hazard = np.array([t.hazard for t in all_truth], dtype=bool)
    has = np.isfinite(target)
    for mask, colour, label in ((has & ~hazard, "#1f77b4", "no hazard"), (has & hazard, "#d62728", "hazard")):
        scatter_ax.scatter(target[mask], all_risk[mask], s=9, alpha=0.6, color=colour, label=label)
    scatter_ax.plot([0, 1], [0, 1], ":", color="grey", lw=0.8)
    scatter_ax.axhline(threshold, color="red", lw=0.8, ls="--")
    scatter_ax.set_xlabel("target 1 - USC~")
    scatter_ax.set_ylabel("risk")
    scatter_ax.set_title("risk against target (frames with a target)", fontsize=10)
    scatter_ax.set_xlim(-0.02, 1.02)
    scatter_ax.set_ylim(-0.02, 1.02)
    scatter_ax.legend(fontsize=7, loc="upper left")
    if title:
        fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    path = Path(path)
    save_figure(fig, path, 90)
    return path
