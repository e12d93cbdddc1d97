"""Each command imports only what it needs: ``fuzzrisk infer`` and ``--help`` load no OpenCV,
matplotlib, ONNX Runtime or SciPy optimiser; ``monitor``'s public names load on first use."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
HEAVY = ("cv2", "matplotlib", "onnxruntime", "scipy.optimize")

SCRIPT = """
import json, sys
from monitor.cli import main
try:
    code = main(sys.argv[1:])
except SystemExit as stop:  # --help exits
    code = stop.code
print(json.dumps({"code": code, "loaded": sorted(m for m in %r if m in sys.modules),
                  "commands": sorted(m for m in sys.modules if m.startswith("monitor.cli."))}))
""" % (HEAVY,)


def _run(*argv):
    done = subprocess.run([sys.executable, "-c", SCRIPT, *argv], cwd=ROOT, capture_output=True,
                          text=True, check=True)
    return done.stdout, json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("argv", [
    ("infer", "rules/fuzzrisk.yaml", "--iou", "0.4", "--rdd", "0.3"),
    ("infer", "--help"),
    ("--help",),
])
def test_infer_and_help_load_no_heavy_module(argv):
    stdout, result = _run(*argv)
    assert result["code"] == 0
    assert result["loaded"] == []
    assert result["commands"] == (["monitor.cli.infer"] if argv[0] == "infer" else [])
    if argv == ("--help",):  # every command listed with its help line, from the registry alone
        from monitor.cli import COMMANDS
        for name, (_, help_line) in COMMANDS.items():
            assert name in stdout and help_line[:30] in " ".join(stdout.split())
    elif "--help" not in argv:
        assert stdout.startswith("risk = 0.54")  # the command ran (fuzzrisk.yaml: 0.5498...)


def test_a_named_command_declares_its_arguments():
    stdout, result = _run("convert", "--help")
    assert result["code"] == 0 and result["commands"] == ["monitor.cli.convert"]
    assert "usage: fuzzrisk convert" in stdout


def test_unknown_command_is_an_error_that_lists_the_commands():
    done = subprocess.run([sys.executable, "-m", "monitor.cli", "infre"], cwd=ROOT,
                          capture_output=True, text=True)
    assert done.returncode == 2
    assert "invalid choice: 'infre'" in done.stderr and "'infer'" in done.stderr


def test_monitor_names_load_on_first_use():
    code = ("import sys, monitor; before = 'cv2' in sys.modules; "
            "from monitor import (Camera, MonitorConfig, RiskMonitor, RiskReport, Shield, "
            "ShieldDecision, load_config, load_prior); "
            "from monitor.risk_monitor import RiskMonitor as R; from monitor.depth.prior import "
            "load_prior as L; from monitor.geometry.camera import Camera as C; "
            "print(before, RiskMonitor is R, load_prior is L, Camera is C, sorted(monitor.__all__))")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                          check=True)
    assert done.stdout.split(" [")[0] == "False True True True"
    assert done.stdout.strip().endswith("['Camera', 'MonitorConfig', 'RiskMonitor', 'RiskReport', "
                                        "'Shield', 'ShieldDecision', 'load_config', 'load_prior']")


def test_monitor_unknown_name_is_an_attribute_error():
    import monitor

    with pytest.raises(AttributeError, match="module 'monitor' has no attribute 'RiskMonitr'"):
        monitor.RiskMonitr  # noqa: B018
    with pytest.raises(ImportError):
        exec("from monitor import RiskMonitr")
