"""How sure the quality measures are: intervals from resampling whole scenes.

The held-out frames of a benchmark come in scenes, and the frames of one scene are alike
(the same street, traffic and detector run), so the uncertainty of a measure is that of a
few scenes, not of many frames: 8 held-out scenes per condition, and in some conditions a
handful of hazard-free frames in one or two of them. :func:`bootstrap_tables` draws whole
scenes with replacement, as many as there are, within each condition (over all conditions,
within each one: every draw keeps the benchmark's mix), computes each measure of
:mod:`monitor.offline.measures` on every draw, and reports the central interval of the
draws (the percentile bootstrap; Efron and Tibshirani 1993). Paired differences from one
predictor use the same draws for both, so what the scenes share cancels.

A draw on which a measure is undefined (no hazard-free frame among the scenes drawn, say)
does not count towards its interval; the row's ``notes`` say on how many of the draws that
happened, and a measure undefined on every draw has no interval (NaN), never a plausible 0.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from monitor.offline.measures import FrameTruth, core_measures

#: the measures with an interval of their own (of :func:`monitor.offline.measures.core_measures`)
INTERVAL_MEASURES = ("pearson", "skill", "auroc", "hit_rate", "false_alarm_rate", "fpr80")
#: the measures whose difference from the reference predictor gets an interval
PAIRED_MEASURES = ("pearson", "rmse", "auroc")
#: how the notes name the measures
NAMES = {"pearson": "r", "rmse": "RMSE", "skill": "skill", "auroc": "AUROC", "hit_rate": "hit rate",
         "false_alarm_rate": "false-alarm rate", "fpr80": "false-alarm rate at an 80 % hit rate"}


def scene_draws(scenes: Sequence[str], strata: Sequence[str], draws: int,
                rng: np.random.Generator) -> list[np.ndarray]:
    """Frame indices of ``draws`` resamples of whole scenes.

    Parameters
    ----------
    scenes, strata : sequence of str, length n_frames
        Each frame's scene and stratum (its condition). A scene lies in one stratum.
    draws : int >= 1
    rng : numpy.random.Generator

    Returns
    -------
    list of ndarray of int64
        Per draw, the indices of the frames of the scenes drawn: in each stratum, as many
        scenes as it has, with replacement, in stratum order.
    """
    if len(scenes) != len(strata):
        raise ValueError(f"{len(scenes)} scene names but {len(strata)} strata; expected one of each per frame")
    frames: dict[str, dict[str, list[int]]] = {}
    for k, (scene, stratum) in enumerate(zip(scenes, strata)):
        frames.setdefault(stratum, {}).setdefault(scene, []).append(k)
    owners = {}
    for stratum, by_scene in frames.items():
        for scene in by_scene:
            if owners.setdefault(scene, stratum) != stratum:
                raise ValueError(f"scene {scene!r} has frames in strata {owners[scene]!r} and {stratum!r}")
    groups = [[np.array(f, dtype=np.int64) for f in by_scene.values()] for by_scene in frames.values()]
    out = []
    for _ in range(draws):
        picks = [group[j] for group in groups for j in rng.integers(len(group), size=len(group))]
        out.append(np.concatenate(picks) if picks else np.zeros(0, dtype=np.int64))
    return out


def _interval(values: np.ndarray, level: float) -> tuple[float, float]:
    values = values[np.isfinite(values)]
    if not values.size:
        return float("nan"), float("nan")
    tail = 50.0 * (1.0 - level)
    lo, hi = np.percentile(values, [tail, 100.0 - tail])
    return float(lo), float(hi)


def _undefined_note(measure: str, values: np.ndarray) -> str:
    missing = int(np.sum(~np.isfinite(values)))
    return f"{NAMES[measure]} undefined on {missing} of {values.size} draws" if missing else ""


def bootstrap_tables(truth: Sequence[FrameTruth], scenes: Sequence[str], risks: dict, reference: float,
                     threshold: float, paired_with: str | None, *, draws: int = 2000, seed: int = 0,
                     level: float = 0.95) -> tuple[list[dict], list[dict]]:
    """Intervals of each predictor's measures, and of its differences from one predictor,
    per condition (in order of appearance) and over all frames.

    Parameters
    ----------
    truth : sequence of FrameTruth
        One per frame (:func:`monitor.offline.measures.frame_truth`); its ``condition`` is
        the stratum.
    scenes : sequence of str
        Each frame's scene.
    risks : dict of str -> ndarray of shape (n_frames,)
        Each predictor's risk per frame (:func:`monitor.offline.measures.quality_tables`).
    reference : float
        The constant predictor's value (for skill).
    threshold : float
        The shield threshold; an alarm is ``risk > threshold``.
    paired_with : str or None
        The predictor the others are compared with (a key of ``risks``); None: no paired rows.
    draws : int >= 1
        Resamples.
    seed : int >= 0
        Of the resampling; the same seed gives the same intervals.
    level : float in (0, 1)
        The intervals' coverage.

    Returns
    -------
    interval_rows : list of dict
        ``condition, predictor, draws`` and per measure of :data:`INTERVAL_MEASURES` its
        ``<measure>_lo`` and ``<measure>_hi``; ``notes``.
    paired_rows : list of dict
        ``condition, predictor, against`` and per measure of :data:`PAIRED_MEASURES` the
        difference on the frames themselves (``<measure>_diff``) and its interval
        (``<measure>_diff_lo``, ``<measure>_diff_hi``); ``notes``.
    """
    n = len(truth)
    if len(scenes) != n or any(len(r) != n for r in risks.values()):
        raise ValueError(f"{n} FrameTruth, {len(scenes)} scene names and risks of {[len(r) for r in risks.values()]} "
                         "frames; expected one each")
    if paired_with is not None and paired_with not in risks:
        raise ValueError(f"paired_with = {paired_with!r} is not one of the predictors {list(risks)}")
    if isinstance(draws, bool) or not isinstance(draws, int) or draws < 1:
        raise ValueError(f"draws = {draws!r}, must be an integer >= 1")
    if not 0.0 < level < 1.0:
        raise ValueError(f"level = {level!r}, must be in (0, 1)")
    rng = np.random.default_rng(seed)
    condition = np.array([t.condition for t in truth])
    target = np.array([t.target for t in truth], dtype=np.float64)
    hazard = np.array([t.hazard for t in truth], dtype=bool)
    risks = {name: np.asarray(r, dtype=np.float64) for name, r in risks.items()}
    scenes = np.asarray(scenes)
    groups = [(c, np.flatnonzero(condition == c)) for c in dict.fromkeys(condition.tolist())]
    groups.append(("all", np.arange(n)))
    interval_rows, paired_rows = [], []
    for name, rows in groups:
        picks = [rows[k] for k in scene_draws(scenes[rows], condition[rows], draws, rng)]
        per = {p: [core_measures(r[k], target[k], hazard[k], reference, threshold) for k in picks]
               for p, r in risks.items()}
        for p in risks:
            row = {"condition": name, "predictor": p, "draws": draws}
            notes = []
            for m in INTERVAL_MEASURES:
                values = np.array([d[m] for d in per[p]])
                row[f"{m}_lo"], row[f"{m}_hi"] = _interval(values, level)
                notes.append(_undefined_note(m, values))
            row["notes"] = "; ".join(filter(None, notes))
            interval_rows.append(row)
        if paired_with is None:
            continue
        base = core_measures(risks[paired_with][rows], target[rows], hazard[rows], reference, threshold)
        for p in risks:
            if p == paired_with:
                continue
            whole = core_measures(risks[p][rows], target[rows], hazard[rows], reference, threshold)
            row = {"condition": name, "predictor": p, "against": paired_with}
            notes = []
            for m in PAIRED_MEASURES:
                values = np.array([a[m] - b[m] for a, b in zip(per[p], per[paired_with])])
                row[f"{m}_diff"] = whole[m] - base[m]
                row[f"{m}_diff_lo"], row[f"{m}_diff_hi"] = _interval(values, level)
                notes.append(_undefined_note(m, values))
            row["notes"] = "; ".join(filter(None, notes))
            paired_rows.append(row)
    return interval_rows, paired_rows
