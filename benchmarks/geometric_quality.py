"""Recall, precision, box IoU and depth error of the two depth views on synthetic frames.

Targets are the ground-truth objects of each frame (:mod:`monitor.synthetic`) with at least
``--min-px`` visible pixels and a nearest visible true depth within 20 m; a target's box is
its visible extent in the label map and its depth the nearest true camera depth of those
pixels. A target is *in the corridor* when its 3D box reaches within the geometric view's
straight corridor (``|y| - w / 2 <= half width``, yaw ignored). A retrieved box recalls a
target at IoU >= 0.3 (the paper's alpha; a target is recalled by its best box); it is
correct when it overlaps a visible object within 25 m at IoU >= 0.3. The depth error is
``(d_S - d_true) / d_true`` of recalled targets. Run::

    python benchmarks/geometric_quality.py --scenes 3 --frames 4

The paper's view uses the inverse-depth prior of :class:`monitor.synthetic.suite.Benchmark`
(its nominal prior scenes). Frames the geometric view calls blind are counted apart.
"""
from __future__ import annotations

import argparse

import numpy as np

from monitor.depth.geometric import BlindViewError, GeometricParams, GeometricRetriever
from monitor.depth.retrieval import InvalidDepthError, Retriever
from monitor.geometry.boxes import iou
from monitor.synthetic import generate_frames
from monitor.synthetic.suite import Benchmark


def _targets(frame, min_px):
    """(n, 5) visible boxes and nearest true depths, and whether each is in the corridor."""
    rows = []
    for k, box in enumerate(frame.gt_boxes3d):
        mask = frame.labels == k + 1
        if mask.sum() < min_px:
            continue
        r, c = np.nonzero(mask)
        d = float(frame.depth_true[mask].min())
        rows.append(((c.min() + c.max() + 1) / 2, (r.min() + r.max() + 1) / 2,
                     c.max() + 1 - c.min(), r.max() + 1 - r.min(), d, abs(box[1]) - box[3] / 2))
    return np.array(rows, dtype=np.float64).reshape(-1, 6)


def _score(found, targets, half_width, tally):
    ious = np.array([[iou(f, t[:5]) for t in targets] for f in found]).reshape(len(found), len(targets))
    tally["boxes"] += len(found)
    if len(targets):
        tally["correct"] += int(np.sum((ious * (targets[:, 4] <= 25.0)).max(axis=1, initial=0) >= 0.3))
    for j in np.flatnonzero(targets[:, 4] <= 20.0):
        t = targets[j]
        inside = t[5] <= half_width
        key = "corridor" if inside else "outside"
        tally[f"{key}_targets"] += 1
        if len(found) and ious[:, j].max() >= 0.3:
            best = int(np.argmax(ious[:, j]))
            tally[f"{key}_recalled"] += 1
            tally[f"{key}_iou"].append(ious[best, j])
            tally[f"{key}_depth_error"].append((found[best, 4] - t[4]) / t[4])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--conditions", nargs="+", default=["nominal", "noise", "night"])
    parser.add_argument("--scenes", type=int, default=3)
    parser.add_argument("--frames", type=int, default=4)
    parser.add_argument("--min-px", type=int, default=1000)
    args = parser.parse_args(argv)
    suite = Benchmark(conditions=tuple(args.conditions), scenes_per_condition=args.scenes,
                      n_frames=args.frames)
    paper = Retriever(suite.prior())
    params = GeometricParams()
    geometric = GeometricRetriever(suite.camera, params)
    print(f"{'condition':10s} {'view':9s} {'frames':>6s} {'blind':>5s} {'recall in corridor':>19s} "
          f"{'recall outside':>14s} {'precision':>9s} {'boxes/frame':>11s} {'IoU':>5s} "
          f"{'depth err (median |.|)':>22s}")
    for condition in args.conditions:
        tallies = {name: {"boxes": 0, "correct": 0, "corridor_targets": 0, "corridor_recalled": 0,
                          "outside_targets": 0, "outside_recalled": 0, "corridor_iou": [],
                          "outside_iou": [], "corridor_depth_error": [], "outside_depth_error": [],
                          "frames": 0, "blind": 0}
                   for name in ("paper", "geometric")}
        for scene in suite.scenes():
            if scene.condition != condition:
                continue
            for frame in generate_frames(condition, scene.seed, n_frames=args.frames):
                targets = _targets(frame, args.min_px)
                for name, view in (("paper", paper), ("geometric", geometric)):
                    tally = tallies[name]
                    tally["frames"] += 1
                    try:
                        found = view(frame.depth_est)
                    except (BlindViewError, InvalidDepthError):
                        tally["blind"] += 1
                        continue
                    _score(found, targets, params.corridor_half_width, tally)
        for name, t in tallies.items():
            recall_in = t["corridor_recalled"] / max(t["corridor_targets"], 1)
            recall_out = t["outside_recalled"] / max(t["outside_targets"], 1)
            precision = t["correct"] / max(t["boxes"], 1)
            ious = t["corridor_iou"] + t["outside_iou"]
            errors = np.abs(t["corridor_depth_error"] + t["outside_depth_error"])
            print(f"{condition:10s} {name:9s} {t['frames']:6d} {t['blind']:5d} "
                  f"{recall_in:8.2f} ({t['corridor_recalled']:3d}/{t['corridor_targets']:3d}) "
                  f"{recall_out:5.2f} ({t['outside_recalled']:3d}/{t['outside_targets']:3d}) "
                  f"{precision:9.2f} {t['boxes'] / max(t['frames'] - t['blind'], 1):11.2f} "
                  f"{np.mean(ious) if ious else float('nan'):5.2f} "
                  f"{np.median(errors) if errors.size else float('nan'):22.3f}")


if __name__ == "__main__":
    main()
