"""What the shield buys and what it costs, from closed-loop runs (:mod:`monitor.offline.closed_loop`).

Per group of scenarios (a kind, a condition, or both), pairing each shielded run with the
baseline run of the same scenario:

- hazard kinds: the baseline's and the shielded collision rates; the **avoidance rate**,
  baseline collisions the shield avoided / baseline collisions, over all of them and apart
  over the physically avoidable ones (:func:`~monitor.offline.closed_loop.required_gap` at
  the hazard's onset) and the unavoidable ones, and over the avoidable ones whose hazard
  the baseline's detector *missed* (reported in fewer than ``SEEN_SHARE`` of the frames from
  the onset to the collision: the monitor's case; a hazard the detector saw and the planner
  still hit is the planner's), and over the avoidable ones still avoidable when the hazard
  entered the ego's path (``Run.onset["entry"]``: those a shield can avoid without
  foreseeing where the hazard goes); the avoidance of the avoidable ones by the same shield
  switched on at the hazard's onset (``from_onset`` of
  :func:`~monitor.offline.closed_loop.run_scenario`: a shield that had braked before the
  hazard was in view, for something else, met it slower, and may have avoided it for that
  alone); the mean impact speed of the collisions left; collisions only the shielded car
  had; rear-end collisions;
- hazard-free drives: the **false-brake rate** (runs in which the shield engaged at all),
  what engaged it first in those runs (``Run.engagements``' cause: an unseen object counted
  at once or once confirmed, a remembered one, a frame without a view, a walker stepping
  in, detected or unseen) and what the nearest object that engaged it first really lay on (``on``,
  :mod:`monitor.offline.attribution`: the road, a car beside the path, ...), the share of
  time spent braking and the **added trip time** (relative to the baseline's trip over the
  same route).

The rates the goals are stated in (avoidance of the avoidable collisions, also of those the
detector missed, and the false-brake rate) come with 95 % Wilson score intervals: each
scenario is an independent trial, and a rate of 84 % of 38 runs is as far from 95 % as its
interval says, not more. The added trip time comes with a t interval of the mean over the
drives.

System-level measures after Guerin, Ferreira, Delmas and Guiochet, "Unifying Evaluation of
Machine Learning Safety Monitors" (ISSRE 2022, arXiv:2208.14660). They define a monitor's
**safety gain** (the hazard it removes), **residual hazard** (what remains with it) and
**availability cost** (the reward the system loses to its interventions) from two return
functions, a hazard return and a reward return, that each application must state. Ours: the
hazard return of a run is 1 for a collision of the ego's front (0 otherwise), the reward
return is the route covered per second (progress rate). Then, over the runs of a group,

- safety gain ``SG = mean(h_baseline) - mean(h_shielded)``,
- residual hazard ``RH = mean(h_shielded)``,
- availability cost ``AC = 1 - mean(r_shielded) / mean(r_baseline)`` over the hazard-free
  drives (the only runs whose reward does not depend on whether a hazard was struck).
"""
from __future__ import annotations

import math
from collections import Counter, defaultdict

import numpy as np
from scipy.stats import norm, t as student_t

from monitor.offline.closed_loop import BASELINE, FROM_ONSET, Run
from monitor.offline.scenarios import HAZARD_KINDS
from monitor.shield import CAUSES

#: Share of the frames from a hazard's onset in which the baseline's detector must report it
#: for the hazard to count as seen (``Run.onset["seen_frames"] / Run.onset["frames"]``).
SEEN_SHARE = 0.5


def _scenario(run: Run) -> tuple:
    """The scenario a run drove: ``(kind, condition, seed)``."""
    return run.kind, run.condition, run.seed


def pair_runs(runs: list[Run], driver: str) -> list[tuple[Run, Run]]:
    """(baseline, ``driver``) run pairs of the same scenario, in the order of ``runs``.

    Raises ValueError when a scenario lacks one of the two.
    """
    by_scenario: dict[tuple, dict[str, Run]] = defaultdict(dict)
    for run in runs:
        by_scenario[_scenario(run)][run.driver] = run
    pairs = []
    for key, drivers in by_scenario.items():
        if BASELINE not in drivers or driver not in drivers:
            raise ValueError(f"scenario {key} has drivers {sorted(drivers)}; expected {BASELINE!r} and {driver!r}")
        pairs.append((drivers[BASELINE], drivers[driver]))
    return pairs


def _rate(numerator: int, denominator: int) -> float:
    return numerator / denominator if denominator else float("nan")


def _mean(values) -> float:
    values = list(values)
    return float(np.mean(values)) if values else float("nan")


def wilson_interval(successes: int, trials: int, level: float = 0.95) -> tuple[float, float]:
    """Wilson's score interval of a binomial rate (Wilson 1927): ``(lo, hi)``, NaN without
    trials. Unlike the normal approximation it stays inside [0, 1] and is not empty at
    0 or ``trials`` successes."""
    if not trials:
        return float("nan"), float("nan")
    z = float(norm.ppf(0.5 + level / 2))
    p = successes / trials
    centre = (p + z * z / (2 * trials)) / (1 + z * z / trials)
    half = z / (1 + z * z / trials) * math.sqrt(p * (1 - p) / trials + z * z / (4 * trials * trials))
    return max(0.0, centre - half), min(1.0, centre + half)


def mean_interval(values, level: float = 0.95) -> tuple[float, float]:
    """Student's t interval of a mean: ``(lo, hi)``; NaN for fewer than two values."""
    values = np.asarray(list(values), dtype=np.float64)
    if values.size < 2:
        return float("nan"), float("nan")
    half = float(student_t.ppf(0.5 + level / 2, values.size - 1) * values.std(ddof=1) / math.sqrt(values.size))
    return float(values.mean()) - half, float(values.mean()) + half


def hazard_measures(pairs: list[tuple[Run, Run]], from_onset: dict | None = None) -> dict:
    """Collision and avoidance measures of (baseline, shielded) pairs of hazard scenarios.

    ``from_onset`` maps each scenario (``kind, condition, seed``) to the shield's drive
    switched on at the hazard's onset; without it (None) the avoidance from the onset is NaN.
    """
    n = len(pairs)
    base_hits = [(b, s) for b, s in pairs if b.collided]
    avoidable = [(b, s) for b, s in base_hits if b.onset is not None and b.onset["avoidable"]]
    unavoidable = [(b, s) for b, s in base_hits if not (b.onset is not None and b.onset["avoidable"])]
    missed = [(b, s) for b, s in avoidable if b.onset["seen_frames"] < SEEN_SHARE * b.onset["frames"]]
    in_path = [(b, s) for b, s in avoidable if b.onset["entry"] is not None and b.onset["entry"]["avoidable"]]
    avoided = lambda group: sum(not s.collided for _, s in group)  # noqa: E731
    late = float("nan")
    if from_onset is not None:
        late = sum(not from_onset[_scenario(b)].collided for b, _ in avoidable)
    return {
        "runs": n,
        "baseline_collisions": len(base_hits),
        "shielded_collisions": sum(s.collided for _, s in pairs),
        "baseline_collision_rate": _rate(len(base_hits), n),
        "shielded_collision_rate": _rate(sum(s.collided for _, s in pairs), n),
        "avoidance_rate": _rate(avoided(base_hits), len(base_hits)),
        "avoidable_collisions": len(avoidable),
        "avoidance_rate_avoidable": _rate(avoided(avoidable), len(avoidable)),
        "avoidance_rate_avoidable_interval": wilson_interval(avoided(avoidable), len(avoidable)),
        "avoidance_rate_avoidable_from_onset": _rate(late, len(avoidable)),
        "avoidance_rate_avoidable_from_onset_interval": (wilson_interval(late, len(avoidable))
                                                        if from_onset is not None else (float("nan"),) * 2),
        "avoidable_missed_collisions": len(missed),
        "avoidance_rate_avoidable_missed": _rate(avoided(missed), len(missed)),
        "avoidance_rate_avoidable_missed_interval": wilson_interval(avoided(missed), len(missed)),
        "avoidable_in_path_collisions": len(in_path),
        "avoidance_rate_avoidable_in_path": _rate(avoided(in_path), len(in_path)),
        "avoidance_rate_avoidable_in_path_interval": wilson_interval(avoided(in_path), len(in_path)),
        "unavoidable_collisions": len(unavoidable),
        "avoidance_rate_unavoidable": _rate(avoided(unavoidable), len(unavoidable)),
        "impact_speed_baseline": _mean(b.impact_speed for b, _ in base_hits),
        "impact_speed_shielded": _mean(s.impact_speed for _, s in pairs if s.collided),
        "shield_only_collisions": sum(s.collided and not b.collided for b, s in pairs),
        "rear_ended_shielded": sum(s.outcome == "rear-ended" for _, s in pairs),
        "rear_ended_baseline": sum(b.outcome == "rear-ended" for b, _ in pairs),
    }


def availability_measures(pairs: list[tuple[Run, Run]]) -> dict:
    """False braking and trip time of (baseline, shielded) pairs of hazard-free drives."""
    n = len(pairs)
    frames = sum(s.frames for _, s in pairs)
    engaged = sum(s.engaged_frames > 0 for _, s in pairs)
    added = [s.trip_time / b.trip_time - 1.0 for b, s in pairs]
    first = [s.engagements[0]["cause"] for _, s in pairs if s.engagements]
    on = [_nearest_on(s.engagements[0]) for _, s in pairs if s.engagements and s.engagements[0]["objects"]]
    return {
        "runs": n,
        "false_brake_rate": _rate(engaged, n),
        "false_brake_rate_interval": wilson_interval(engaged, n),
        "baseline_brake_rate": _rate(sum(b.braking_frames > 0 for b, _ in pairs), n),
        "braking_share": _rate(sum(s.braking_frames for _, s in pairs), frames),
        "engaged_share": _rate(sum(s.engaged_frames for _, s in pairs), frames),
        "added_trip_time": _mean(added),
        "added_trip_time_interval": mean_interval(added),
        "not_arrived": sum(s.outcome != "arrived" for _, s in pairs),
        "first_engagement": {cause: first.count(cause) for cause in CAUSES if cause in first},
        "first_engaged_on": dict(sorted(Counter(on).items(), key=lambda item: (-item[1], item[0]))),
    }


def _nearest_on(engagement: dict) -> str:
    """What the nearest object that engaged the shield lay on (``Run.engagements``' ``on``)."""
    nearest = min(range(len(engagement["objects"])), key=lambda k: engagement["objects"][k][0])
    return engagement["on"][nearest]


def guerin_measures(pairs: list[tuple[Run, Run]]) -> dict:
    """Safety gain, residual hazard and availability cost (module docstring) of run pairs."""
    hazard_b = [float(b.collided) for b, _ in pairs]
    hazard_s = [float(s.collided) for _, s in pairs]
    drives = [(b, s) for b, s in pairs if b.kind not in HAZARD_KINDS]
    reward_b = _mean(1.0 / b.trip_time for b, _ in drives)
    reward_s = _mean(1.0 / s.trip_time for _, s in drives)
    return {
        "safety_gain": _mean(hazard_b) - _mean(hazard_s) if pairs else float("nan"),
        "residual_hazard": _mean(hazard_s),
        "availability_cost": 1.0 - reward_s / reward_b if drives else float("nan"),
    }


def summarise(runs: list[Run], driver: str) -> dict:
    """Every measure for one shielded driver against the baseline.

    ``runs`` may hold the driver's drives switched on at the hazard's onset too (label
    ``driver`` + :data:`~monitor.offline.closed_loop.FROM_ONSET`), then one for every hazard
    scenario (ValueError otherwise); without them the avoidance from the onset is NaN.

    Returns
    -------
    dict
        ``by_kind``: kind -> measures over all its conditions; ``by_kind_condition``: kind ->
        condition -> measures; ``by_hazard``: the hazard's class (``Run.hazard``) -> hazard
        measures over the scenarios of every hazard kind with a hazard of that class;
        ``by_condition``: condition -> {"hazard": ..., "guerin": ...}; ``overall``:
        {"hazard", "availability", "guerin"} over every run.
    """
    pairs = pair_runs(runs, driver)
    kinds = list(dict.fromkeys(b.kind for b, _ in pairs))
    conditions = list(dict.fromkeys(b.condition for b, _ in pairs))
    hazards = [p for p in pairs if p[0].kind in HAZARD_KINDS]
    late = {_scenario(r): r for r in runs if r.driver == driver + FROM_ONSET} or None
    lacking = [] if late is None else [_scenario(b) for b, _ in hazards if _scenario(b) not in late]
    if lacking:
        raise ValueError(f"scenarios {lacking[:3]}{' ...' if len(lacking) > 3 else ''} have no drive of "
                         f"{driver + FROM_ONSET!r}; expected one for every hazard scenario or none")

    def measures(group, kind):
        return hazard_measures(group, late) if kind in HAZARD_KINDS else availability_measures(group)

    by_kind = {k: measures([p for p in pairs if p[0].kind == k], k) for k in kinds}
    by_kind_condition = {k: {c: measures(g, k) for c in conditions
                             if (g := [p for p in pairs if p[0].kind == k and p[0].condition == c])}
                         for k in kinds}
    drives = [p for p in pairs if p[0].kind not in HAZARD_KINDS]
    classes = list(dict.fromkeys(b.hazard["class"] for b, _ in hazards))
    by_hazard = {c: hazard_measures([p for p in hazards if p[0].hazard["class"] == c], late) for c in classes}
    by_condition = {c: {"hazard": hazard_measures([p for p in hazards if p[0].condition == c], late),
                        "guerin": guerin_measures([p for p in pairs if p[0].condition == c])}
                    for c in conditions}
    return {
        "driver": driver,
        "by_kind": by_kind,
        "by_kind_condition": by_kind_condition,
        "by_hazard": by_hazard,
        "by_condition": by_condition,
        "overall": {"hazard": hazard_measures(hazards, late), "availability": availability_measures(drives),
                    "guerin": guerin_measures(pairs)},
    }


def trade_off(runs: list[Run]) -> list[dict]:
    """Per shield setting: avoidance rate (hazard kinds, over avoidable baseline collisions
    and over all) against false-brake rate and added trip time (hazard-free drives)."""
    drivers = list(dict.fromkeys(r.driver for r in runs if r.driver != BASELINE))
    points = []
    for driver in drivers:
        pairs = pair_runs(runs, driver)
        hazard = hazard_measures([p for p in pairs if p[0].kind in HAZARD_KINDS])
        drives = availability_measures([p for p in pairs if p[0].kind not in HAZARD_KINDS])
        points.append({"driver": driver, "avoidance_rate": hazard["avoidance_rate"],
                       "avoidance_rate_avoidable": hazard["avoidance_rate_avoidable"],
                       "false_brake_rate": drives["false_brake_rate"],
                       "added_trip_time": drives["added_trip_time"]})
    return points

