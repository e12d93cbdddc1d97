"""The fuzzrisk command line, end to end on small inputs."""
import csv
import json

import pytest

from monitor.cli import main
from monitor.config import load_config
from shield_reference import GATE_YAML, gated_engaged


def test_infer_prints_the_risk(capsys):
    assert main(["infer", "rules/fuzzrisk.yaml", "--iou", "0.4", "--rdd", "0.3"]) == 0
    assert capsys.readouterr().out.strip() == "risk = 0.549833"


def test_infer_explain_lists_fired_rules(capsys):
    assert main(["infer", "rules/fuzzrisk.yaml", "--rdd", "0.3", "--iou", "0.4", "--explain"]) == 0
    out = capsys.readouterr().out
    assert "rules fired: 4 of 9" in out and "if iou is medium and rdd is high then risk is high" in out


@pytest.mark.parametrize("argv, message", [
    (["infer", "rules/fuzzrisk.yaml", "--iou", "0.4"], "missing --rdd"),
    (["infer", "rules/fuzzrisk.yaml", "--iou", "0.4", "--rdd", "x"], "--rdd 'x': expected a number"),
    (["infer", "rules/fuzzrisk.yaml", "--iou", "0.4", "--rdd", "0", "--speed", "1"], "unexpected '--speed'"),
    (["infer", "rules/none.yaml", "--iou", "0.4", "--rdd", "0"], "no such rule base file"),
])
def test_infer_errors_are_messages_not_tracebacks(argv, message, capsys):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_demo_writes_its_reports(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "-o", str(out), "--scenes", "1", "--frames", "2", "--conditions", "nominal", "night"]) == 0
    printed = capsys.readouterr().out
    assert "synthetic" in printed and "nominal" in printed and "night" in printed
    rows = [json.loads(line) for line in (out / "frames.jsonl").read_text().splitlines()]
    assert len(rows) == 4 and {r["condition"] for r in rows} == {"nominal", "night"}
    assert all(0.0 <= r["risk"] <= 1.0 and r["status"] in ("ok", "no-objects", "invalid-input") for r in rows)
    report = (out / "report.md").read_text()
    assert "synthetic" in report and "| nominal |" in report and "| in view |" in report
    for name in ("fis.png", "risk_timeline.png", "retrieval_stages.png", "frame_nominal.png", "frame_night.png"):
        assert (out / name).stat().st_size > 1000


def test_demo_runs_a_path_gated_shield(tmp_path):
    config = tmp_path / "gate.yaml"
    config.write_text(GATE_YAML)
    out = tmp_path / "demo"
    assert main(["demo", "-o", str(out), "--scenes", "1", "--frames", "2", "--conditions", "nominal", "night",
                 "--config", str(config)]) == 0
    rows = [json.loads(line) for line in (out / "frames.jsonl").read_text().splitlines()]
    c = load_config(config).shield
    assert len(rows) == 4 and all(r["ego_speed"] > 0 for r in rows)  # the synthetic cars move
    # the gate has no memory here (no hold, no hysteresis): each frame's decision from its row
    assert [r["shield"]["engaged"] for r in rows] == [gated_engaged(r, c) for r in rows]
    assert all(r["shield"]["deceleration"] == (c.deceleration if r["shield"]["engaged"] else 0.0) for r in rows)
    # and it lets go of at least one frame the paper's shield brakes for (risk above the threshold)
    assert any(r["risk"] > c.threshold and not r["shield"]["engaged"] for r in rows)


def test_features_csv_has_one_row_per_frame_with_features(tmp_path, capsys):
    out = tmp_path / "f.csv"
    assert main(["features", "-o", str(out), "--scenes", "2", "--test-scenes", "1", "--frames", "2",
                 "--prior-scenes", "1", "--conditions", "nominal", "--split", "train"]) == 0
    with open(out) as f:
        rows = list(csv.DictReader(f))
    assert rows and set(rows[0]) == {"scene", "frame", "condition", "iou", "rdd", "target"}
    assert {r["scene"] for r in rows} == {"nominal-0"}  # the training scene only, never the test one
    for r in rows:
        assert 0.0 <= float(r["iou"]) <= 1.0 and -1.0 <= float(r["rdd"]) <= 1.0
        assert r["target"] == "" or 0.0 <= float(r["target"]) <= 1.0
