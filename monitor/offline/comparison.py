"""Two closed-loop runs of the same scenarios, compared scenario by scenario.

A change to the shield (a setting, a rule of the depth view) moves some drives: a hazard
avoided before is hit now, a hazard-free drive stops braking. The rates of two
``summary.md`` files hide which drives moved, and two changes with the same rates can move
different drives. :func:`compare_runs` pairs the drives of two ``fuzzrisk simulate`` runs by
scenario (kind and seed) and lists every one whose outcome changed (``fuzzrisk compare``).

Both runs must hold the same scenarios, with the same baseline: the baseline sees only its
detector, so a change to the shield leaves its runs as they were. A baseline that differs
means a different world (another seed, condition or version of the scenarios), and the
comparison would pair drives that are not the same; it is refused.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from monitor.offline.closed_loop import BASELINE, FROM_ONSET

#: the fields of a ``runs.jsonl`` line (:meth:`monitor.offline.closed_loop.Run.to_dict`) read here
FIELDS = ("kind", "seed", "condition", "driver", "outcome", "frames", "engaged_frames", "onset")


@dataclass(frozen=True)
class Change:
    """One scenario whose shielded drive ended differently.

    Attributes
    ----------
    kind, condition : str
    seed : int
    before, after : str
        The shielded drive's outcome in each run (``collision``, ``stopped``, ``arrived`` ...);
        for a hazard-free drive, ``braked`` or ``no braking``.
    baseline : str
        The baseline's outcome (the same in both runs).
    avoidable : bool
        A hazard the baseline hit, with a gap at its onset in which the shield's deceleration
        could still stop the car (``Run.onset["avoidable"]``); False for a hazard-free drive.
    """

    kind: str
    condition: str
    seed: int
    before: str
    after: str
    baseline: str
    avoidable: bool


@dataclass(frozen=True)
class Comparison:
    """What changed between two runs of the same scenarios.

    Attributes
    ----------
    drivers : tuple of str
        The shield's label in the run before and in the run after.
    kinds : dict
        Per kind: ``scenarios``, and for a hazard kind ``avoidable`` (the baseline's avoidable
        collisions) with ``avoided`` (before, after) of them by the shield; for
        ``hazard-free``, ``braked`` (before, after): drives in which the shield engaged.
    changes : tuple of Change
        Hazard runs whose shielded drive went from a collision to none or back; hazard-free
        drives that started or stopped braking; in the order of the run before (simulate's:
        by kind, then seed).
    """

    drivers: tuple[str, str]
    kinds: dict
    changes: tuple[Change, ...]


def load_runs(path: str | Path) -> list[dict]:
    """The runs of a ``fuzzrisk simulate`` output: its ``runs.jsonl``, or the folder holding it.

    Raises
    ------
    ValueError
        A line that is not a JSON object with :data:`FIELDS` of the right types, naming the
        file, the line and the field.
    OSError
        No such file.
    """
    path = Path(path)
    if path.is_dir():
        path = path / "runs.jsonl"
    runs = []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            try:
                run = json.loads(line)
            except json.JSONDecodeError as exc:
                raise ValueError(f"{path}, line {number}: not JSON ({exc.msg}); expected one run per "
                                 "line, as fuzzrisk simulate writes runs.jsonl") from None
            missing = [k for k in FIELDS if not isinstance(run, dict) or k not in run]
            if missing:
                raise ValueError(f"{path}, line {number}: no {', '.join(missing)}; expected a run of "
                                 "fuzzrisk simulate's runs.jsonl")
            wrong = [k for k in ("seed", "frames", "engaged_frames") if type(run[k]) is not int] + \
                [k for k in ("kind", "condition", "driver", "outcome") if not isinstance(run[k], str)] + \
                ([] if run["onset"] is None or isinstance(run["onset"], dict) and "avoidable" in run["onset"]
                 else ["onset"])
            if wrong:
                raise ValueError(f"{path}, line {number}: {', '.join(f'{k} = {run[k]!r}' for k in wrong)}; expected "
                                 "integers seed, frames, engaged_frames, strings kind, condition, driver, outcome "
                                 "and an onset that is null or says whether it was avoidable")
            runs.append(run)
    if not runs:
        raise ValueError(f"{path} holds no runs; expected fuzzrisk simulate's runs.jsonl")
    return runs


def _by_scenario(runs: list[dict], name: str) -> tuple[str, dict, dict]:
    """The shield's label, and the baseline's and the shield's run per (kind, seed)."""
    labels = sorted({r["driver"] for r in runs} - {BASELINE})
    shields = [d for d in labels if not d.endswith(FROM_ONSET)]
    if len(shields) != 1:
        raise ValueError(f"{name} has the shield drivers {shields}; expected one, as fuzzrisk simulate "
                         "writes runs.jsonl")
    baseline, shield = {}, {}
    for run in runs:
        key = (run["kind"], run["seed"])
        table = baseline if run["driver"] == BASELINE else shield if run["driver"] == shields[0] else None
        if table is None:
            continue
        if key in table:
            raise ValueError(f"{name} has two {run['driver']} runs of {key[0]} {key[1]}; expected one per scenario")
        table[key] = run
    if baseline.keys() != shield.keys():
        odd = sorted(baseline.keys() ^ shield.keys())[:3]
        raise ValueError(f"{name}: scenarios {odd} have a baseline run but no shield run, or the other way")
    return shields[0], baseline, shield


def _collided(run: dict) -> bool:
    return run["outcome"] == "collision"


def _avoidable(run: dict) -> bool:
    """A baseline collision the shield's deceleration could avoid from the hazard's onset."""
    return _collided(run) and run["onset"] is not None and bool(run["onset"]["avoidable"])


def compare_runs(before: list[dict], after: list[dict], names: tuple[str, str] = ("before", "after")) -> Comparison:
    """Pair two runs' drives by scenario and list what changed.

    Parameters
    ----------
    before, after : list of dict
        :func:`load_runs` of each (each a baseline and a shield run per scenario; the shield
        switched on at the onset is not read).
    names : (str, str)
        What the errors call them (their paths).

    Raises
    ------
    ValueError
        Not the same scenarios, or a scenario whose baseline ended differently or after a
        different number of frames (not the same world).
    """
    label_a, base_a, shield_a = _by_scenario(before, names[0])
    label_b, base_b, shield_b = _by_scenario(after, names[1])
    if base_a.keys() != base_b.keys():
        odd = sorted(base_a.keys() ^ base_b.keys())[:3]
        raise ValueError(f"{names[0]} and {names[1]} hold different scenarios (e.g. {odd}); expected the same "
                         "--seed, --scenarios, --kind and --condition")
    kinds, changes = {}, []
    for key in base_a:  # in the order the run before lists them (simulate: by kind, then seed)
        kind, seed = key
        base, other, a, b = base_a[key], base_b[key], shield_a[key], shield_b[key]
        if (base["outcome"], base["frames"]) != (other["outcome"], other["frames"]):
            raise ValueError(f"the baseline of {kind} {seed} ({base['condition']}) ended '{base['outcome']}' after "
                             f"{base['frames']} frames in {names[0]} and '{other['outcome']}' after {other['frames']} "
                             f"in {names[1]}: not the same world (scenarios, detector or depth), so the shields' "
                             "drives cannot be paired")
        row = kinds.setdefault(kind, {"scenarios": 0})
        row["scenarios"] += 1
        if kind == "hazard-free":
            braked = (a["engaged_frames"] > 0, b["engaged_frames"] > 0)
            row["braked"] = tuple(n + k for n, k in zip(row.get("braked", (0, 0)), braked))
            if braked[0] != braked[1]:
                said = ("no braking", "braked")
                changes.append(Change(kind, a["condition"], seed, said[braked[0]], said[braked[1]],
                                      base["outcome"], False))
            continue
        row.setdefault("avoidable", 0)
        row.setdefault("avoided", (0, 0))
        if _avoidable(base):
            row["avoidable"] += 1
            row["avoided"] = (row["avoided"][0] + (not _collided(a)), row["avoided"][1] + (not _collided(b)))
        if _collided(a) != _collided(b):
            changes.append(Change(kind, a["condition"], seed, a["outcome"], b["outcome"], base["outcome"],
                                  _avoidable(base)))
    return Comparison((label_a, label_b), kinds, tuple(changes))


def to_markdown(comparison: Comparison, names: tuple[str, str] = ("before", "after")) -> str:
    """The comparison as Markdown: a table per kind, then every changed drive."""
    lines = [f"Shield before: `{comparison.drivers[0]}` ({names[0]})",
             f"Shield after: `{comparison.drivers[1]}` ({names[1]})", "",
             "| kind | scenarios | before | after | drives changed |", "|---|---|---|---|---|"]
    for kind, row in comparison.kinds.items():
        moved = sum(c.kind == kind for c in comparison.changes)
        if kind == "hazard-free":
            cells = [f"braked in {row['braked'][0]}", f"braked in {row['braked'][1]}"]
        else:
            cells = [f"avoided {n} of {row['avoidable']} avoidable" for n in row["avoided"]]
        lines.append(f"| {kind} | {row['scenarios']} | {cells[0]} | {cells[1]} | {moved} |")
    lines += ["", "| kind | seed | condition | before | after | baseline | avoidable |",
              "|---|---|---|---|---|---|---|"]
    lines += [f"| {c.kind} | {c.seed} | {c.condition} | {c.before} | {c.after} | {c.baseline} | "
              f"{'yes' if c.avoidable else 'no'} |" for c in comparison.changes]
    if not comparison.changes:
        lines.append("| (none) | | | | | | |")
    return "\n".join(lines) + "\n"
