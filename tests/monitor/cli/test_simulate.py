"""fuzzrisk simulate: a tiny run end to end, outputs kept unless --overwrite, serial = parallel, the
depth ablation."""
import json

import numpy as np
import pytest

pytest.importorskip("highway_env", reason="fuzzrisk simulate needs the 'sim' extra (highway-env)")

from monitor.cli import main  # noqa: E402
from monitor.cli.simulate import OUTPUTS, SWEEP_OUTPUTS, drive_all, sweep_settings  # noqa: E402
from monitor.config import ShieldConfig, load_config  # noqa: E402
from monitor.depth.prior import build_prior  # noqa: E402
from monitor.geometry.camera import Camera  # noqa: E402
from monitor.offline.closed_loop import Perception, run_scenario  # noqa: E402
from monitor.offline.scenarios import ScenarioSpec  # noqa: E402
from monitor.risk_monitor import RiskMonitor  # noqa: E402
from monitor.shipped import shipped_rules  # noqa: E402
from monitor.synthetic import CONDITIONS, generate_frames, without_depth_errors  # noqa: E402
import fuzzcore  # noqa: E402


def test_simulate_smoke(tmp_path, capsys):
    out = tmp_path / "sim"
    args = ["simulate", "--scenarios", "2", "--kind", "cut-in", "--condition", "nominal", "snow",
            "--sweep", "1", "-o", str(out)]
    assert main(args) == 0
    for name in OUTPUTS + SWEEP_OUTPUTS:
        assert (out / name).stat().st_size > 0, name
    runs = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    shield = "t0.30 r0.30 h5 p1.25 c2/3<0.30 n2.5 o0.8 k0.5 e6 m1 w1 u1"
    # per scenario the baseline, the shield and the shield switched on at the hazard's onset
    assert [(r["condition"], r["seed"], r["driver"]) for r in runs] == [
        (condition, seed, driver) for condition, seed in (("nominal", 0), ("snow", 1))
        for driver in ("baseline", shield, shield + " from onset")]
    assert len(runs[0]["history"]["time"]) == runs[0]["frames"]
    sweep = [json.loads(line) for line in (out / "sweep.jsonl").read_text().splitlines()]
    assert len(sweep) == len(sweep_settings(ShieldConfig()))  # 6 thresholds x 4 hysteresis settings
    summary = (out / "summary.md").read_text()
    assert "avoidable: avoided by the shield switched on at the onset" in summary
    assert "| cut-in | nominal | 1 |" in summary and "| cut-in | all | 2 |" in summary
    assert runs[0]["hazard"]["class"] == "car" and len(runs[0]["hazard"]["size"]) == 3
    assert "| car | 2 |" in summary  # the cut-in car, by what the hazard is
    # fuzzrisk compare of the run with itself: nothing moved, and its counts are the summary's
    cut_in = json.loads((out / "summary.json").read_text())["by_kind"]["cut-in"]
    m = cut_in["avoidable_collisions"]
    n = round((cut_in["avoidance_rate_avoidable"] or 0.0) * m)
    capsys.readouterr()
    assert main(["compare", str(out), str(out / "runs.jsonl")]) == 0
    assert f"| cut-in | 2 | avoided {n} of {m} avoidable | avoided {n} of {m} avoidable | 0 |" in \
        capsys.readouterr().out
    # the outputs are there: a second run refuses to replace them, then does with --overwrite
    capsys.readouterr()
    assert main(args) == 2
    assert "--overwrite" in capsys.readouterr().err


def test_simulate_rejects_bad_arguments(tmp_path, capsys):
    assert main(["simulate", "--scenarios", "0", "-o", str(tmp_path / "x")]) == 2
    assert "--scenarios 0" in capsys.readouterr().err
    assert main(["simulate", "--scenarios", "2", "--sweep", "3", "-o", str(tmp_path / "x")]) == 2
    assert "--sweep 3" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()  # checked before any work


def _small_world():
    """A quarter-size camera and its prior."""
    front = Camera.nuscenes_front()
    camera = Camera(np.diag([0.25, 0.25, 1.0]) @ front.K, 400, 225, front.cam_to_ego)
    prior = build_prior((str(f.index), f.depth_est)
                        for f in generate_frames("nominal", 100000, n_frames=6, camera=camera)).mean()
    return camera, prior


def test_serial_and_parallel_agree():
    camera, prior = _small_world()
    shield = load_config().shield
    jobs = [(ScenarioSpec("cut-in", "snow", 1), [shield]), (ScenarioSpec("pedestrian", "night", 2), [shield]),
            (ScenarioSpec("rare-object", "noise", 3), [shield])]
    rules = str(shipped_rules())
    serial = drive_all(jobs, rules, None, prior, camera, workers=1)
    parallel = drive_all(jobs, rules, None, prior, camera, workers=2)
    assert [[r.to_dict() for r in runs] for runs in serial] == [[r.to_dict() for r in runs] for runs in parallel]
    assert [runs[0].kind for runs in parallel] == ["cut-in", "pedestrian", "rare-object"]


def test_depth_ablation_drives_the_condition_without_those_errors():
    camera, prior = _small_world()
    shield = load_config().shield
    spec = ScenarioSpec("rare-object", "snow", 4)
    rules = str(shipped_rules())
    [ablated] = drive_all([(spec, [shield])], rules, None, prior, camera, workers=1, depth_off=("blobs", "scale"))
    [shipped] = drive_all([(spec, [shield])], rules, None, prior, camera, workers=1)
    monitor = RiskMonitor(fuzzcore.load(rules), prior, camera, load_config(), explain=False)
    expected = run_scenario(spec, Perception(camera), monitor, [shield], from_onset=True,
                            condition=without_depth_errors(CONDITIONS["snow"], ["blobs", "scale"]))
    dicts = [[r.to_dict() for r in runs] for runs in (ablated, expected, shipped)]
    assert dicts[0] == dicts[1]
    assert dicts[0][1]["history"]["risk"] != dicts[2][1]["history"]["risk"]  # the shield saw another depth
    assert dicts[0][0]["history"] == dicts[2][0]["history"]  # the baseline sees only the detector


def test_simulate_says_what_it_switched_off(tmp_path):
    out = tmp_path / "sim"
    assert main(["simulate", "--scenarios", "1", "--kind", "hazard-free", "--condition", "nominal",
                 "--no-depth-error", "blobs", "all", "-o", str(out)]) == 0
    summary = (out / "summary.md").read_text()
    assert "--sweep 0 --no-depth-error fade grain blobs blur scale --workers 1`" in summary
    assert "An ablation: the depth network's fade, grain, blobs, blur, scale switched off" in summary
    assert "## Hazard-free drives" in summary and "## Hazards" not in summary  # no hazard kind, no table
    assert json.loads((out / "summary.json").read_text())["depth_errors_off"] == [
        "fade", "grain", "blobs", "blur", "scale"]
