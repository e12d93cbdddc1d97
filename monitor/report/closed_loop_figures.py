"""Figures of the closed-loop simulation (:mod:`monitor.offline.closed_loop`): PNG files.

- :func:`traces_figure`: speed, gap to the hazard and risk over time for a few scenarios,
  the baseline and the shielded car side by side;
- :func:`trade_off_figure`: avoidance of the avoidable collisions against false braking, one
  point per shield setting, the default marked;
- :func:`condition_figure`: collision rates and avoidance per condition.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import rcParams
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from monitor.offline.closed_loop import BASELINE
from monitor.userfiles import save_figure


def _subplots(ncols: int, size: tuple[float, float]):
    """A figure on its own Agg canvas (no pyplot, no backend switch) and its axes."""
    fig = Figure(figsize=size)
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, ncols)
    return fig, axes


def traces_figure(pairs, threshold: float, path: Path) -> None:
    """Speed, gap and risk over time.

    Parameters
    ----------
    pairs : list of (Run, Run)
        (baseline, shielded) runs of the scenarios to draw (a handful).
    threshold : float
        The shield's threshold, drawn on the risk panel.
    path : Path
    """
    fig, axes = _subplots(3, (14, 3.8))
    colours = rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (base, shielded) in enumerate(pairs):
        colour = colours[k % len(colours)]
        label = f"{base.kind} {base.condition} #{base.seed}"
        for run, style in ((base, ":"), (shielded, "-")):
            h = run.history
            axes[0].plot(h["time"], h["speed"], style, color=colour, lw=1.2, label=label if run is base else None)
            axes[1].plot(h["time"], h["gap"], style, color=colour, lw=1.2)
        axes[2].plot(shielded.history["time"], shielded.history["risk"], color=colour, lw=1)
    axes[0].set(xlabel="time (s)", ylabel="speed (m/s)", title="speed (dotted: baseline, solid: shield)")
    axes[1].axhline(0, color="red", lw=0.8)
    axes[1].set(xlabel="time (s)", ylabel="gap to the hazard (m)", title="gap")
    axes[2].axhline(threshold, color="red", lw=0.8, ls=":")
    axes[2].set(xlabel="time (s)", ylabel="risk", ylim=(-0.02, 1.02), title="monitor risk (shielded car)")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path, 80)


def trade_off_figure(points: list[dict], default: str, path: Path) -> None:
    """Avoidance of the avoidable collisions (the issue's goal: 95 %) against the false-brake
    rate (goal: 5 %), one point per shield setting, the default marked; the points are
    numbered, and a key beside the axes names the settings at each (:func:`point_labels`).

    Parameters
    ----------
    points : list of dict
        :func:`monitor.offline.safety_measures.trade_off`.
    default : str
        Label of the default setting (marked).
    path : Path
    """
    fig, ax = _subplots(1, (10, 5))
    shown = [p for p in points  # no drives or no avoidable collisions to measure on: not drawn
             if np.isfinite(p["false_brake_rate"]) and np.isfinite(p["avoidance_rate_avoidable"])]
    key = []
    for k, ((x, y), label) in enumerate(point_labels(shown).items(), 1):
        ax.plot(x, y, "o", color="tab:blue", ms=5)
        ax.annotate(str(k), (x, y), fontsize=8, xytext=(4, 3), textcoords="offset points")
        key.append(f"{k}: " + label.replace("\n", "\n   "))
    marked = next((p for p in shown if p["driver"] == default), None)
    if marked is not None:
        ax.plot(marked["false_brake_rate"], marked["avoidance_rate_avoidable"], "r*", ms=16, zorder=3,
                label=f"default {default}")
        ax.legend(fontsize=8, loc="lower right")
    ax.axvline(0.05, color="grey", lw=0.8, ls=":")
    ax.axhline(0.95, color="grey", lw=0.8, ls=":")
    ax.set(xlabel="false-brake rate (hazard-free drives the shield braked in)",
           ylabel="avoidable baseline collisions avoided", xlim=(-0.02, 1.02), ylim=(-0.02, 1.02),
           title="shield settings: safety against availability")
    if not shown:
        ax.text(0.5, 0.5, "nothing to plot: these runs have no hazard-free drives\nor no avoidable collisions",
                ha="center", va="center", transform=ax.transAxes)
    fig.tight_layout(rect=(0, 0, 0.62, 1))
    fig.text(0.63, 0.95, "\n".join(key), va="top", fontsize=7, family="monospace")
    save_figure(fig, path, 80)


def point_labels(points: list[dict]) -> dict[tuple[float, float], str]:
    """One label per point of the trade-off figure: ``{(false-brake rate, avoidable
    avoidance): text}``, the settings that land there one per line. Each setting is named by
    the words of its driver label (``t0.50 r0.50 h5 p1.25 ...``) that differ between the
    settings, with its added trip time: the words every setting shares say nothing."""
    words = [p["driver"].split() for p in points]
    varying = [k for k in range(max(map(len, words), default=0))
               if len({w[k] if k < len(w) else None for w in words}) > 1]
    labels: dict[tuple[float, float], list[str]] = {}
    for point, w in zip(points, words):
        name = " ".join(w[k] for k in varying if k < len(w)) or point["driver"]
        trip = point["added_trip_time"]
        name += f" ({trip:+.0%} trip)" if np.isfinite(trip) else ""
        labels.setdefault((point["false_brake_rate"], point["avoidance_rate_avoidable"]), []).append(name)
    return {xy: "\n".join(names) for xy, names in labels.items()}


def condition_figure(by_condition: dict, path: Path) -> None:
    """Baseline and shielded collision rates, and avoidance, per condition (hazard kinds).

    Parameters
    ----------
    by_condition : dict
        ``summarise(...)["by_condition"]``.
    path : Path
    """
    names = list(by_condition)
    x = np.arange(len(names))
    get = lambda key: [by_condition[c]["hazard"][key] for c in names]  # noqa: E731
    fig, ax = _subplots(1, (8, 4))
    ax.bar(x - 0.27, get("baseline_collision_rate"), 0.27, label="baseline collision rate", color="tab:red")
    ax.bar(x, get("shielded_collision_rate"), 0.27, label="shielded collision rate", color="tab:green")
    ax.bar(x + 0.27, np.nan_to_num(get("avoidance_rate")), 0.27, label="avoidance rate", color="tab:blue")
    ax.set_xticks(x, names)
    ax.set(ylim=(0, 1.05), ylabel="rate", title=f"hazard scenarios by condition ({BASELINE} vs shield)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, 80)
