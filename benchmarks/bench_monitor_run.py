"""Frames per second of ``fuzzrisk monitor`` on depth maps, one process and two workers.

The input is a recording folder (:mod:`monitor.datasets.recordings`) written from a
synthetic nominal scene: 1600 x 900 float32 depth maps (``.npy``), ego-frame detections and
ground truth, ``FRAMES`` frames. Each round is the whole command as a user runs it, into a
fresh output folder: reading the recording, the monitor on every frame (retrieval,
projection, alignment, inference with the rules fired), the ground-truth score, the JSON
lines, the timeline and the summary; with ``--workers 2`` also the start of two ``spawn``
worker processes (each loads the Numba cache once). The reports of both are checked to be
equal (timings aside) before anything is timed.

Printed at the end: frames/s of each, the scaling from 1 to 2 workers (ideal 2.0 on two
free cores; this machine's 2 cores are shared), and the monitor's own share of a 12 Hz
frame budget (the median over frames of the stage timings the reports carry, against
1000 / 12 ms). Run::

    python -m pytest benchmarks/bench_monitor_run.py -o python_files='bench_*.py' -q
"""
from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from reporting import write_report
from monitor.cli import main

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from recording_fixture import read_rows, write_prior, write_recording  # noqa: E402

FRAMES = 48
HZ = 12.0
_MEDIANS: dict[str, float] = {}
_SHARE: list[float] = []


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    root = tmp_path_factory.mktemp("bench")
    frames = write_recording(root / "drive", n_frames=FRAMES)
    return root, write_prior(root / "prior.npy", frames)


@pytest.fixture(scope="module", autouse=True)
def report(request):
    yield
    lines = [f"  {name}: median {t:.2f} s per run, {FRAMES / t:.1f} frames/s" for name, t in _MEDIANS.items()]
    if {"workers_1", "workers_2"} <= set(_MEDIANS):
        lines.append(f"  scaling 1 -> 2 workers: {_MEDIANS['workers_1'] / _MEDIANS['workers_2']:.2f}x")
    if _SHARE:
        lines.append(f"  the monitor's stages per frame: median {_SHARE[0]:.1f} ms = "
                     f"{100 * _SHARE[0] / (1e3 / HZ):.0f}% of a {HZ:g} Hz frame budget ({1e3 / HZ:.1f} ms)")
    write_report(request, f"fuzzrisk monitor on {FRAMES} depth maps (1600x900):", lines)


def _run(recording, out: Path, workers: int) -> None:
    root, prior = recording
    shutil.rmtree(out, ignore_errors=True)
    assert main(["monitor", "-o", str(out), "--recording", str(root / "drive"), "--prior", str(prior),
                 "--workers", str(workers)]) == 0


def test_the_pool_reports_equal_the_serial_reports(recording, tmp_path):
    _run(recording, tmp_path / "one", 1)
    _run(recording, tmp_path / "two", 2)
    assert read_rows(tmp_path / "one") == read_rows(tmp_path / "two")
    rows = [json.loads(line) for line in (tmp_path / "one" / "scenes" / "drive.jsonl").read_text().splitlines()]
    _SHARE.append(float(np.median([sum(r["timings_ms"].values()) for r in rows])))


@pytest.mark.parametrize("workers", [1, 2])
def test_monitor_command(benchmark, recording, tmp_path, workers):
    benchmark.group = f"fuzzrisk monitor, {FRAMES} frames 1600x900"
    benchmark.pedantic(_run, args=(recording, tmp_path / "out", workers), rounds=3, iterations=1,
                       warmup_rounds=1)
    _MEDIANS[f"workers_{workers}"] = benchmark.stats.stats.median
