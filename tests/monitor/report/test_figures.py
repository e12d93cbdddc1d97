"""Figures draw on their own Agg canvas: the user's matplotlib backend is left alone."""
import json
import struct
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]

SCRIPT = """
import json, sys
import matplotlib
matplotlib.use("svg")                      # the user's choice, before importing ours
import fuzzcore
import monitor.report.figures as figures
after_import = matplotlib.get_backend()
path = figures.save_fis_figure(fuzzcore.load("rules/fuzzrisk.yaml"), sys.argv[1], resolution=11)
print(json.dumps({"after_import": after_import, "after_drawing": matplotlib.get_backend(),
                  "pyplot": "matplotlib.pyplot" in sys.modules, "path": str(path)}))
"""


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])  # the IHDR chunk: width, height


def test_importing_and_drawing_leave_the_backend_alone(tmp_path):
    out = tmp_path / "fis.png"
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(out)], cwd=ROOT, capture_output=True,
                          text=True, check=True)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result == {"after_import": "svg", "after_drawing": "svg", "pyplot": False,
                      "path": str(out)}
    # two inputs + one output + the surface = 4 panels of 4 in, 3.6 in high, at 90 dpi
    assert _png_size(out) == (4 * 4 * 90, round(3.6 * 90))
