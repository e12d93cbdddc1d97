"""fuzzrisk monitor on recording folders and synthetic scenes: outputs, resume, pool, errors."""
import json

import numpy as np
import pytest

import fuzzcore
import monitor.cli.monitor as monitor_command
from monitor.cli import main
from monitor.config import load_config
from monitor.depth.prior import load_prior
from monitor.risk_monitor import RiskMonitor
from monitor.shield import Shield
from monitor.shipped import shipped_rules
from recording_fixture import read_rows, write_prior, write_recording

N_FRAMES = 10  # two chunks of 8 and 2 frames (monitor.offline.run.CHUNK_FRAMES)


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    root = tmp_path_factory.mktemp("rec")
    frames = write_recording(root / "drive-a", n_frames=N_FRAMES)
    write_recording(root / "drive-b", condition="rain", seed=4, n_frames=3, ground_truth=False)
    return root, frames, write_prior(root / "prior.npy", frames)


def _argv(recording, out, *extra):
    root, _, prior = recording
    return ["monitor", "-o", str(out), "--recording", str(root / "drive-a"), str(root / "drive-b"),
            "--prior", str(prior), *extra]


@pytest.fixture(scope="module")
def serial_run(recording, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial") / "out"
    assert main(_argv(recording, out)) == 0
    return out


def test_reports_are_the_monitor_and_shield_run_frame_by_frame(recording, serial_run):
    root, frames, prior = recording
    rows = read_rows(serial_run)["drive-a.jsonl"]
    assert [r["frame"] for r in rows] == list(range(N_FRAMES))
    config = load_config()
    mon = RiskMonitor(fuzzcore.load(shipped_rules()), load_prior(prior), frames[0].camera, config)
    shield = Shield(config.shield)
    for frame, row in zip(frames, rows):
        report = mon.step(frame.depth_est, frame.det_boxes3d, frame.det_scores)
        decision = shield.update(report.risk)
        assert (row["risk"], row["status"], row["time"], row["key"]) == (
            report.risk, report.status, frame.timestamp, f"{frame.index:06d}")
        assert row["S"] == report.S.tolist() and row["P"] == report.P.tolist()
        assert row["shield"] == {"engaged": decision.engaged, "deceleration": decision.deceleration}
        assert [f["rule"] for f in row["fired"]] == [r + 1 for r, _, _ in report.fired]
        if report.alignment is not None:
            assert row["alignment"]["partner"] == report.alignment.partner.tolist()
        assert row["target"] is None or 0.0 <= row["target"] <= 1.0
    assert any(r["status"] == "ok" for r in rows)
    # drive-b has no ground_truth.jsonl: no target, never a made-up one
    assert all(r["target"] is None for r in read_rows(serial_run)["drive-b.jsonl"])


def test_timelines_summary_and_run_file(serial_run):
    for name in ("drive-a.png", "drive-b.png"):
        assert (serial_run / "scenes" / name).stat().st_size > 1000
    summary = (serial_run / "summary.md").read_text()
    assert "| drive-a | recorded | 10 |" in summary and "scenes/drive-b.png" in summary
    run = json.loads((serial_run / "run.json").read_text())
    assert run["scenes"] == [["drive-a", N_FRAMES], ["drive-b", 3]]


def test_two_workers_give_the_serial_reports(recording, serial_run, tmp_path):
    assert main(_argv(recording, tmp_path / "pool", "--workers", "2")) == 0
    assert read_rows(tmp_path / "pool") == read_rows(serial_run)


def test_an_interrupted_run_resumes_to_the_same_lines(recording, serial_run, tmp_path, monkeypatch):
    out = tmp_path / "out"
    real = monitor_command.process_chunks

    def interrupted(*args, **kwargs):  # the first chunk, then Ctrl-C
        chunks = real(*args, **kwargs)
        yield next(chunks)
        raise KeyboardInterrupt

    monkeypatch.setattr(monitor_command, "process_chunks", interrupted)
    with pytest.raises(KeyboardInterrupt):
        main(_argv(recording, out))
    assert len(read_rows(out)["drive-a.jsonl"]) == 8 and not (out / "scenes" / "drive-a.png").exists()
    # a torn last line, as a kill in the middle of a write leaves
    with open(out / "scenes" / "drive-a.jsonl", "a") as f:
        f.write('{"scene": "drive-a", "frame": 8, "ke')
    monkeypatch.setattr(monitor_command, "process_chunks", real)
    assert main(_argv(recording, out)) == 0
    assert read_rows(out) == read_rows(serial_run)
    assert (out / "scenes" / "drive-a.png").is_file()


def test_a_complete_run_started_again_does_nothing_new(recording, serial_run, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(_argv(recording, out)) == 0
    before = (out / "scenes" / "drive-a.jsonl").read_bytes()
    assert main(_argv(recording, out)) == 0
    assert "13 frames done, 0 to go" in capsys.readouterr().out
    assert (out / "scenes" / "drive-a.jsonl").read_bytes() == before


def test_another_run_is_not_overwritten_without_the_flag(recording, tmp_path, capsys):
    out = tmp_path / "out"
    root, _, prior = recording
    assert main(["monitor", "-o", str(out), "--recording", str(root / "drive-b"), "--prior", str(prior)]) == 0
    capsys.readouterr()
    assert main(_argv(recording, out)) == 2
    assert "holds a run with other scenes, sources; pass --overwrite" in capsys.readouterr().err
    assert main(_argv(recording, out, "--overwrite")) == 0
    assert len(read_rows(out)["drive-a.jsonl"]) == N_FRAMES


def test_a_folder_that_is_not_a_run_is_refused(recording, tmp_path, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert main(_argv(recording, out)) == 2
    assert "is not empty (no run.json: not a fuzzrisk monitor run)" in capsys.readouterr().err


def test_a_damaged_line_is_an_error_naming_it(recording, serial_run, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(_argv(recording, out)) == 0
    path = out / "scenes" / "drive-a.jsonl"
    lines = path.read_text().splitlines(keepends=True)
    lines[2] = lines[3]
    path.write_text("".join(lines))
    assert main(_argv(recording, out)) == 2
    assert "drive-a.jsonl: line 3: is frame ('drive-a', 3, '000003'), expected (scene, frame, key) = " \
           "('drive-a', 2, '000002')" in capsys.readouterr().err


def test_unprocessable_frames_are_reported_and_strict_stops(recording, tmp_path, capsys):
    root, frames, prior = recording
    import shutil
    rec = tmp_path / "drive-a"
    shutil.copytree(root / "drive-a", rec)
    np.save(rec / "depth" / "000004.npy", np.ones((90, 160), np.float32))  # wrong size
    (rec / "depth" / "000006.npy").write_bytes(b"not an array")
    argv = ["monitor", "-o", str(tmp_path / "out"), "--recording", str(rec), "--prior", str(prior)]
    assert main(argv) == 0
    rows = read_rows(tmp_path / "out")["drive-a.jsonl"]
    bad = {r["frame"]: r for r in rows if r["status"] == "unprocessed"}
    assert sorted(bad) == [4, 6] and all(bad[k]["risk"] is None and bad[k]["shield"] is None for k in bad)
    assert "000004.npy: depth_est is ((90, 160), dtype('float32')), expected a float32 array of shape " \
           "(900, 1600)" in bad[4]["error"]
    assert "000006.npy: not a .npy file" in bad[6]["error"]
    out = capsys.readouterr().out
    assert "2 frames could not be processed" in out
    assert "Frames that could not be processed (2)" in (tmp_path / "out" / "summary.md").read_text()
    assert main(argv[:2] + [str(tmp_path / "strict")] + argv[3:] + ["--strict"]) == 2
    err = capsys.readouterr().err
    assert "scene 'drive-a' frame 4 (000004)" in err and "--strict: stopped" in err


def test_synthetic_scenes_by_default(tmp_path):
    out = tmp_path / "out"
    assert main(["monitor", "-o", str(out), "--frames", "2", "--conditions", "night", "--prior-scenes", "1",
                 "--workers", "1"]) == 0
    rows = read_rows(out)["night-5000.jsonl"]
    assert [r["frame"] for r in rows] == [0, 1]
    assert all(r["target"] is None or 0 <= r["target"] <= 1 for r in rows)
    assert "synthetic" in (out / "summary.md").read_text()


def test_a_path_gated_shield_is_refused(recording, tmp_path, capsys):
    # this command's shield runs on the risk alone: a gate is refused up front, naming the
    # setting, and nothing is written
    config = tmp_path / "gate.yaml"
    config.write_text("shield: {path_half_width: 1.25}\n")
    out = tmp_path / "out"
    assert main(_argv(recording, out, "--config", str(config))) == 2
    assert "shield.path_half_width = 1.25: fuzzrisk monitor runs the shield on the risk alone" in \
        capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())
