"""monitor.offline.comparison and fuzzrisk compare: two runs paired scenario by scenario, on
hand-made runs whose changes are known."""
import json

import pytest

from monitor.cli import main
from monitor.offline.comparison import Change, compare_runs, load_runs, to_markdown

SHIELD = "t0.30 r0.30 h5 p1.25"


def _run(kind, seed, driver, outcome, engaged=0, avoidable=None, frames=40, condition="night"):
    onset = None if avoidable is None else {"avoidable": avoidable, "time": 1.0}
    return {"kind": kind, "seed": seed, "condition": condition, "driver": driver, "outcome": outcome,
            "frames": frames, "engaged_frames": engaged, "onset": onset}


def _runs(shield_outcomes, braked, label=SHIELD):
    """Three rare objects the baseline hits (seeds 0, 1 avoidable, 2 not) and two hazard-free
    drives (seeds 3, 4); the shield's outcomes and whether it braked in each drive as given."""
    runs = []
    for seed, avoidable in ((0, True), (1, True), (2, False)):
        runs += [_run("rare-object", seed, "baseline", "collision", avoidable=avoidable),
                 _run("rare-object", seed, label, shield_outcomes[seed], engaged=5, avoidable=avoidable),
                 _run("rare-object", seed, label + " from onset", "collision", avoidable=avoidable)]
    for seed, engaged in zip((3, 4), braked):
        runs += [_run("hazard-free", seed, "baseline", "arrived", condition="snow"),
                 _run("hazard-free", seed, label, "arrived", engaged=engaged, condition="snow")]
    return runs


def test_changes_are_the_drives_that_moved():
    before = _runs(["stopped", "collision", "collision"], [0, 7])
    after = _runs(["collision", "stopped", "stopped"], [2, 0], label=SHIELD + " g0.3")
    comparison = compare_runs(before, after)
    assert comparison.drivers == (SHIELD, SHIELD + " g0.3")
    # avoidable: seeds 0 and 1; before the shield avoided seed 0, after seed 1
    assert comparison.kinds == {"rare-object": {"scenarios": 3, "avoidable": 2, "avoided": (1, 1)},
                                "hazard-free": {"scenarios": 2, "braked": (1, 1)}}
    assert comparison.changes == (
        Change("rare-object", "night", 0, "stopped", "collision", "collision", True),
        Change("rare-object", "night", 1, "collision", "stopped", "collision", True),
        Change("rare-object", "night", 2, "collision", "stopped", "collision", False),
        Change("hazard-free", "snow", 3, "no braking", "braked", "arrived", False),
        Change("hazard-free", "snow", 4, "braked", "no braking", "arrived", False))
    text = to_markdown(comparison)
    assert "| rare-object | 3 | avoided 1 of 2 avoidable | avoided 1 of 2 avoidable | 3 |" in text
    assert "| hazard-free | 2 | braked in 1 | braked in 1 | 2 |" in text
    assert "| rare-object | 2 | night | collision | stopped | collision | no |" in text


def test_an_outcome_that_is_no_collision_either_way_is_no_change():
    before = _runs(["stopped", "timeout", "collision"], [0, 0])
    after = _runs(["passed", "stopped", "collision"], [0, 0])
    comparison = compare_runs(before, after)
    assert comparison.changes == ()
    assert comparison.kinds["rare-object"]["avoided"] == (2, 2)
    assert "| (none) |" in to_markdown(comparison)


def test_a_different_world_is_refused():
    before = _runs(["stopped"] * 3, [0, 0])
    after = _runs(["stopped"] * 3, [0, 0])
    after[3]["frames"] = 41  # the baseline of rare object 1 ran one frame longer
    with pytest.raises(ValueError, match=r"the baseline of rare-object 1 \(night\) ended 'collision' after 40 "
                                         r"frames in before and 'collision' after 41 in after: not the same world"):
        compare_runs(before, after)
    with pytest.raises(ValueError, match=r"hold different scenarios \(e.g. \[\('hazard-free', 4\)\]\)"):
        compare_runs(before, before[:-2])


def test_runs_that_are_not_one_shield_are_refused():
    runs = _runs(["stopped"] * 3, [0, 0])
    other = [dict(r, driver="t0.50") for r in runs if r["driver"] == SHIELD]
    with pytest.raises(ValueError, match=r"before has the shield drivers \['t0.30 r0.30 h5 p1.25', 't0.50'\]; "
                                         "expected one"):
        compare_runs(runs + other, runs)
    with pytest.raises(ValueError, match=r"after: scenarios \[\('hazard-free', 4\)\] have a baseline run but no "
                                         "shield run"):
        compare_runs(runs, runs[:-1])


def test_load_runs_names_the_file_and_line(tmp_path):
    path = tmp_path / "runs.jsonl"
    path.write_text(json.dumps(_run("cut-in", 0, "baseline", "stopped")) + "\n{\"kind\": \"cut-in\"}\n")
    with pytest.raises(ValueError, match=r"runs.jsonl, line 2: no seed, condition, driver, outcome, frames, "
                                         "engaged_frames, onset; expected a run"):
        load_runs(tmp_path)  # the folder holding runs.jsonl
    path.write_text(json.dumps(_run("cut-in", "0", "baseline", "stopped", avoidable=True)) + "\n")
    with pytest.raises(ValueError, match=r"runs.jsonl, line 1: seed = '0'; expected integers seed"):
        load_runs(path)
    path.write_text(json.dumps(dict(_run("cut-in", 0, "baseline", "stopped"), onset={"time": 1.0})) + "\n")
    with pytest.raises(ValueError, match=r"line 1: onset = \{'time': 1.0\}; expected .* an onset that is null or"):
        load_runs(path)
    path.write_text("not json\n")
    with pytest.raises(ValueError, match=r"runs.jsonl, line 1: not JSON"):
        load_runs(path)
    path.write_text("")
    with pytest.raises(ValueError, match="holds no runs"):
        load_runs(path)


def test_the_command_prints_the_comparison_and_refuses_with_a_message(tmp_path, capsys):
    for name, runs in (("a", _runs(["stopped", "collision", "collision"], [0, 7])),
                       ("b", _runs(["collision", "collision", "collision"], [0, 0]))):
        (tmp_path / name).mkdir()
        (tmp_path / name / "runs.jsonl").write_text("".join(json.dumps(r) + "\n" for r in runs))
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    out = capsys.readouterr().out
    assert "| rare-object | 3 | avoided 1 of 2 avoidable | avoided 0 of 2 avoidable | 1 |" in out
    assert "| hazard-free | 4 | snow | braked | no braking | arrived | no |" in out
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "missing")]) == 2
    assert "fuzzrisk compare: error:" in capsys.readouterr().err
