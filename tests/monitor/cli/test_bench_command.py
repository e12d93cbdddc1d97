"""fuzzrisk bench: budgets and their exit status, JSON and --compare, the monitor, bad input."""
import json

import pytest

from fuzzcore.bench import CALLS, BenchResult
from monitor.cli import main
from monitor.cli.bench import parse_size, parse_time

RULES = "rules/fuzzrisk.yaml"


@pytest.mark.parametrize("text, ns", [
    ("5us", 5_000.0), ("2 ms", 2e6), ("1.5\u00b5s", 1_500.0), ("3\u03bcs", 3_000.0), ("10ns", 10.0),
    ("1s", 1e9), ("2.5e-3s", 2.5e6),
])
def test_parse_time(text, ns):
    assert parse_time(text) == pytest.approx(ns, rel=1e-15)


@pytest.mark.parametrize("text, message", [
    ("5", "--budget '5' has no unit; write it with one of ns, us, \u00b5s, ms, s"),
    ("5 parsecs", "--budget '5 parsecs': expected a time with a unit"),
    ("fast", "--budget 'fast': expected a time with a unit"),
    ("0us", "--budget '0us': expected a time > 0"),
])
def test_parse_time_errors(text, message):
    with pytest.raises(ValueError) as err:
        parse_time(text)
    assert message in str(err.value)


def test_parse_size():
    assert parse_size("1600x900") == (1600, 900)
    with pytest.raises(ValueError, match="--size '1600': expected WIDTHxHEIGHT"):
        parse_size("1600")


def test_calls_1000_with_a_huge_budget_passes(capsys):
    assert main(["bench", RULES, "--calls", "1000", "--budget", "1000s"]) == 0
    out = capsys.readouterr().out
    first_words = [line.split()[0] for line in out.splitlines() if line.strip()]
    assert all(name in first_words for name in CALLS)  # one table row per way of calling
    assert "1,000" in out and "evaluate, 1 thread(s)" in out and "fresh process" in out
    assert "budget: infer p99.9 = " in out and "within 1,000 s" in out


def test_tiny_budget_fails_and_json_feeds_compare(tmp_path, capsys):
    argv = ["bench", RULES, "--calls", "500", "--evaluate-samples", "1000", "--budget", "1ns"]
    assert main(argv + ["--json", "--percentile", "p50", "--call", "infer_by_name"]) == 1
    captured = capsys.readouterr()
    assert "budget: infer_by_name p50" in captured.err and "EXCEEDS 1 ns" in captured.err
    old = tmp_path / "old.json"
    old.write_text(captured.out, encoding="utf-8")
    result = BenchResult.from_dict(json.loads(captured.out))
    assert result.latencies["infer"].count == 500
    assert main(argv + ["--compare", str(old)]) == 1
    out = capsys.readouterr().out
    assert f"compared with {old}" in out and "infer p99.9" in out and "evaluate, 1 thread(s)" in out


def test_monitor_stages_and_budget(capsys):
    argv = ["bench", "--monitor", "--size", "320x180", "--frames", "2", "--repeat", "2", "--hz", "10"]
    assert main(argv + ["--budget", "1000s"]) == 0
    out = capsys.readouterr().out
    assert "2 synthetic frames of 320x180" in out and "share of the frame period at 10 Hz (100.0 ms)" in out
    for stage in ("retrieval", "projection", "alignment", "step"):
        assert f"  {stage}: " in out
    assert main(argv + ["--budget", "1ns", "--json"]) == 1
    captured = capsys.readouterr()
    assert json.loads(captured.out)["stages"]["step"]["count"] == 4 and "EXCEEDS" in captured.err


@pytest.mark.parametrize("argv, message", [
    (["bench", RULES, "--budget", "5"], "--budget '5' has no unit"),
    (["bench", "rules/none.yaml"], "rules/none.yaml: no such rule base file"),
    (["bench", "--monitor", "--calls", "10"], "--calls: not an option of --monitor"),
    (["bench", RULES, "--frames", "3"], "--frames: not an option of the rule-base bench"),
    (["bench", "--monitor", "--size", "big"], "--size 'big': expected WIDTHxHEIGHT"),
    (["bench", RULES, "--compare", "none.json"], "none.json: no such bench result file"),
])
def test_errors_are_messages(argv, message, capsys):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_a_rule_base_that_does_not_load_is_named(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\ninputs: 3\n", encoding="utf-8")
    assert main(["bench", str(bad), "--calls", "10"]) == 2
    assert str(bad) in capsys.readouterr().err


def test_a_camera_file_with_a_wrong_field_is_named(tmp_path, capsys):
    camera = tmp_path / "calib.yaml"
    camera.write_text("width: 16\nheight: 9\nintrinsic: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n", encoding="utf-8")
    assert main(["bench", "--monitor", "--camera", str(camera)]) == 2
    err = capsys.readouterr().err
    assert str(camera) in err and "unknown field(s) intrinsic" in err
