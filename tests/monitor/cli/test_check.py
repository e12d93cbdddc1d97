"""fuzzrisk check and fuzzrisk plot, end to end."""
import json
from pathlib import Path

import pytest

from monitor.cli import main

HOLE = """\
name: hole
inputs:
  x:
    range: [0, 1]
    terms:
      low: [trimf, 0, 0, 0.4]
      high: [trimf, 0.6, 1, 1]
outputs:
  z:
    range: [0, 1]
    terms:
      low: [trimf, 0, 0, 1]
      high: [trimf, 0, 1, 1]
rules:
  - if x is low then z is low
  - if x is high then z is high
"""


@pytest.fixture
def hole(tmp_path):
    path = tmp_path / "hole.yaml"
    path.write_text(HOLE)
    return path


def test_the_paper_system_is_covered(capsys):
    assert main(["check", "rules/fuzzrisk.yaml"]) == 0
    out = capsys.readouterr().out
    assert "coverage: every point of the input box fires a rule" in out and out.rstrip().endswith("PASS")


def test_a_declared_property_that_fails_exits_1(capsys):
    assert main(["check", "rules/fuzzrisk.yaml", "--monotone", "rdd:+"]) == 1
    assert "risk increasing in rdd: VIOLATED" in capsys.readouterr().out


def test_a_hole_exits_1_and_json_says_where(hole, capsys):
    assert main(["check", str(hole), "--json"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["ok"] is False
    assert data["coverage"]["regions"][0]["bounds"]["x"] == {"lo": 0.4, "hi": 0.6, "lo_closed": True,
                                                             "hi_closed": True}


@pytest.mark.parametrize("rules", sorted(str(p) for p in Path("rules").glob("*.yaml")))
def test_every_shipped_rule_base_fires_a_rule_everywhere(rules, capsys):
    assert main(["check", rules]) == 0, capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["check", "rules/fuzzrisk.yaml", "--monotone", "rdd"], "expected INPUT:+ or INPUT:-"),
    (["check", "rules/fuzzrisk.yaml", "--monotone", "speed:+"], "'speed' is not an input"),
    (["check", "rules/none.yaml"], "no such rule base file"),
    (["plot", "rules/fuzzrisk.yaml", "-o", "out.jpg"], "figure out.jpg: suffix '.jpg', expected .png"),
    (["plot", "rules/fuzzrisk.yaml", "-o", "no/such/folder/out.png"], "does not exist; create it first"),
])
def test_errors_are_messages(argv, message, capsys):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_plot_writes_a_png(hole, tmp_path, capsys):
    out = tmp_path / "hole.png"
    assert main(["plot", str(hole), "-o", str(out), "--monotone", "x:-"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "FAIL: no rule fires on 20 %" in capsys.readouterr().out
    assert [p.name for p in tmp_path.iterdir() if p.suffix == ".png"] == ["hole.png"]  # no temp file left


def test_plot_replaces_a_file_only_with_overwrite(hole, tmp_path, capsys):
    out = tmp_path / "mine.png"
    out.write_bytes(b"mine")
    assert main(["plot", str(hole), "-o", str(out)]) == 2
    assert f"figure {out} already exists; choose another name or allow replacing it (--overwrite)" in \
        capsys.readouterr().err
    assert out.read_bytes() == b"mine"
    assert main(["plot", str(hole), "-o", str(out), "--overwrite"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
