"""fuzzrisk monitor on recording folders and synthetic scenes: outputs, resume, pool, errors."""
import json
import shutil

import numpy as np
import pytest

import fuzzcore
import monitor.cli.monitor as monitor_command
from monitor.cli import main
from monitor.config import ShieldConfig, load_config
from monitor.datasets.recordings import RecordingReader
from monitor.depth.prior import load_prior
from monitor.offline.run import RunSpec, ScenePlan, observe_plans
from monitor.risk_monitor import RiskMonitor
from monitor.shield import Shield
from monitor.shipped import shipped_rules
from monitor.synthetic import render_depth
from recording_fixture import read_rows, write_prior, write_recording
from shield_reference import GATE_YAML, gated_engaged

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


def _configured_run(recording, folder, shield: str):
    """A run into ``folder / "out"`` with ``shield`` (YAML) as its config's shield section."""
    config = folder / "config.yaml"
    config.write_text(f"shield:\n  {shield}\n")
    assert main(_argv(recording, folder / "out", "--config", str(config))) == 0
    return folder / "out", config


@pytest.fixture(scope="module")
def emerging_run(recording, tmp_path_factory):
    return _configured_run(recording, tmp_path_factory.mktemp("emerging"), "confirm_emerged: 0.5")


def _walkers(frame, config):
    """The frame's detected pedestrians scoring the config's ``detections.min_score``, by hand."""
    return [box[:2] for box, c, s in zip(frame.det_boxes3d.tolist(), frame.det_classes, frame.det_scores)
            if c == "pedestrian" and s >= config.detections.min_score]


def _replayed(frames, prior, config):
    """The monitor and shield of ``config`` run on ``frames`` in order: per frame the
    report, the emerged shares and the decision."""
    mon = RiskMonitor(fuzzcore.load(shipped_rules()), load_prior(prior), frames[0].camera, config)
    shield, earlier, last, out = Shield(config.shield), [], None, []  # the frames before: (report, travel since)
    for frame in frames:
        report = mon.step(frame.depth_est, frame.det_boxes3d, frame.det_scores)
        earlier = [(r, s + frame.ego_speed * (frame.timestamp - last)) for r, s in earlier]
        emerged = mon.emerged(report, earlier)
        decision = shield.update(report.risk, speed=frame.ego_speed, unseen=report.unseen,
                                 time=frame.timestamp, emerged=emerged,
                                 walkers=np.array(_walkers(frame, config)).reshape(-1, 2),
                                 contact=report.unseen_contact)
        earlier, last = [(report, 0.0), *earlier][:2], frame.timestamp
        out.append((report, emerged, decision))
    return out


def test_reports_are_the_monitor_and_shield_run_frame_by_frame(recording, serial_run):
    root, frames, prior = recording
    rows = read_rows(serial_run)["drive-a.jsonl"]
    assert [r["frame"] for r in rows] == list(range(N_FRAMES))
    for frame, row, (report, emerged, decision) in zip(frames, rows, _replayed(frames, prior, load_config()),
                                                       strict=True):
        # the shipped shield confirms what came out of the road: a share per unseen object
        assert row["emerged"] == (None if emerged is None else [None if np.isnan(e) else e for e in emerged.tolist()])
        assert (row["risk"], row["status"], row["time"], row["ego_speed"], row["key"]) == (
            report.risk, report.status, frame.timestamp, frame.ego_speed, f"{frame.index:06d}")
        assert row["S"] == report.S.tolist() and row["P"] == report.P.tolist()
        assert row["unseen"] == report.unseen.tolist()
        assert row["shield"] == {"engaged": decision.engaged, "deceleration": decision.deceleration}
        assert [f["rule"] for f in row["fired"]] == [r + 1 for r, _, _ in report.fired]
        if report.alignment is not None:
            stored = row["alignment"]
            assert stored["partner"] == report.alignment.partner.tolist() and stored["objects"] == "known"
            # the features are the means of the stored terms: the S no detection covers and
            # the counted detections
            unseen, counted = ~np.array(stored["counted"], bool), np.array(stored["det_counted"], bool)
            if row["status"] == "ok":
                n = unseen.sum() + counted.sum()
                assert row["iou"] == pytest.approx(np.array(stored["det_iou"])[counted].sum() / n)
                assert row["rdd"] == pytest.approx((unseen.sum() + np.array(stored["det_rdd"])[counted].sum()) / n)
        assert row["target"] is None or 0.0 <= row["target"] <= 1.0
    assert any(r["status"] == "ok" for r in rows)
    # drive-b has no ground_truth.jsonl: no target, never a made-up one
    assert all(r["target"] is None for r in read_rows(serial_run)["drive-b.jsonl"])


def test_a_shield_that_confirms_what_came_out_of_the_road_gets_it_per_frame(recording, serial_run, emerging_run):
    _, frames, prior = recording
    out, config = emerging_run
    rows = read_rows(out)["drive-a.jsonl"]
    for row, plain, (_, emerged, decision) in zip(rows, read_rows(serial_run)["drive-a.jsonl"],
                                                  _replayed(frames, prior, load_config(config)), strict=True):
        assert row["emerged"] == [None if np.isnan(e) else e for e in emerged.tolist()]
        assert row["shield"] == {"engaged": decision.engaged, "deceleration": decision.deceleration}
        # the setting changes what is stored and decided, never the risk
        assert {k: v for k, v in row.items() if k not in ("emerged", "shield")} == \
            {k: v for k, v in plain.items() if k not in ("emerged", "shield")}
    # from the second frame on, what each unseen object has of the road of the frames before
    assert rows[0]["emerged"] == [None] * len(rows[0]["unseen"])
    assert any(e is not None for r in rows[1:] for e in r["emerged"])


def test_the_paper_s_view_gives_a_shield_that_confirms_what_came_out_of_the_road_nothing_measured(
        recording, tmp_path):
    # the paper's view does not see the road: every unseen object's share is not measured
    # (null, NaN to the shield), so not asked, and the run replays the monitor and shield
    _, frames, prior = recording
    config = tmp_path / "config.yaml"
    config.write_text("retrieval:\n  method: paper\nshield:\n  confirm_emerged: 0.5\n")
    assert main(_argv(recording, tmp_path / "out", "--config", str(config))) == 0
    rows = read_rows(tmp_path / "out")["drive-a.jsonl"]
    for row, (report, emerged, decision) in zip(rows, _replayed(frames, prior, load_config(config)), strict=True):
        assert row["unseen"] == report.unseen.tolist() and np.isnan(emerged).all()
        assert row["emerged"] == [None] * len(report.unseen)
        assert row["shield"] == {"engaged": decision.engaged, "deceleration": decision.deceleration}
    assert any(row["unseen"] for row in rows)


def test_evaluations_run_no_shield_so_their_views_keep_no_blocks(recording):
    # observe_plans (fuzzrisk eval, features): the shipped config confirms what came out of
    # the road, but no shield runs there; the reports are the monitor's but for the blocks
    root, frames, prior = recording
    config = load_config()
    assert config.shield.confirm_emerged is not None
    spec = RunSpec(shipped_rules(), load_prior(prior), frames[0].camera, config)
    plan = ScenePlan.of_records("drive-a", "nominal", RecordingReader(root / "drive-a").records())
    observed = observe_plans(spec, [plan])
    for (report, _, _), observation in zip(_replayed(frames, prior, config), observed, strict=True):
        assert report.road_depth is not None and observation.report.road_depth is None
        assert observation.report.unseen_points == () and len(report.unseen_points) == len(report.unseen)
        assert observation.report.risk == report.risk
        assert observation.report.unseen.tolist() == report.unseen.tolist()


def test_the_shipped_shield_gets_the_detector_s_walkers_per_frame(recording, serial_run):
    # it watches walkers (walker_horizon), so each line stores the frame's, and the reference
    # loop (_replayed) that gives the decisions of the test above is given them
    _, frames, _ = recording
    rows, config = read_rows(serial_run)["drive-a.jsonl"], load_config()
    assert config.shield.walker_horizon is not None
    for frame, row in zip(frames, rows, strict=True):
        assert row["walkers"] == _walkers(frame, config)
    assert sum(len(r["walkers"]) for r in rows) >= len(rows)  # the recording's streets have walkers


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


@pytest.mark.parametrize("run", ["serial_run", "emerging_run"])
def test_an_interrupted_run_resumes_to_the_same_lines(recording, run, request, tmp_path, monkeypatch):
    # the shipped shield (which replays the stored walkers), and one that replays the stored
    # emerged shares as well
    done, extra = request.getfixturevalue(run), ()
    if run != "serial_run":
        done, extra = done[0], ("--config", str(done[1]))
    out = tmp_path / "out"
    real = monitor_command.process_chunks

    def interrupted(*args, **kwargs):  # the first chunk, then Ctrl-C
        chunks = real(*args, **kwargs)
        yield next(chunks)
        raise KeyboardInterrupt

    monkeypatch.setattr(monitor_command, "process_chunks", interrupted)
    with pytest.raises(KeyboardInterrupt):
        main(_argv(recording, out, *extra))
    assert len(read_rows(out)["drive-a.jsonl"]) == 8 and not (out / "scenes" / "drive-a.png").exists()
    # a torn last line, as a kill in the middle of a write leaves
    with open(out / "scenes" / "drive-a.jsonl", "a") as f:
        f.write('{"scene": "drive-a", "frame": 8, "ke')
    monkeypatch.setattr(monitor_command, "process_chunks", real)
    assert main(_argv(recording, out, *extra)) == 0
    assert read_rows(out) == read_rows(done)
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


def test_an_empty_road_is_written_as_strict_json(recording, tmp_path):
    # the geometric view finds nothing on an empty road: its free distance is inf, which strict
    # JSON cannot hold as a number (it once stopped the run)
    root, frames, prior = recording
    rec = tmp_path / "drive-a"
    shutil.copytree(root / "drive-a", rec)
    road = render_depth(frames[0].camera, np.zeros((0, 7))).depth
    np.save(rec / "depth" / "000003.npy", np.where(np.isfinite(road), road, 80.0).astype(np.float32))
    assert main(["monitor", "-o", str(tmp_path / "out"), "--recording", str(rec), "--prior", str(prior)]) == 0
    rows = read_rows(tmp_path / "out")["drive-a.jsonl"]
    assert rows[3]["S"] == [] and rows[3]["free_distance"] == "inf"
    assert all(isinstance(r["free_distance"], float) for r in rows if r["S"])


def test_synthetic_scenes_by_default(tmp_path):
    out = tmp_path / "out"
    assert main(["monitor", "-o", str(out), "--frames", "2", "--conditions", "night", "--prior-scenes", "1",
                 "--workers", "1"]) == 0
    rows = read_rows(out)["night-5000.jsonl"]
    assert [r["frame"] for r in rows] == [0, 1]
    assert all(r["target"] is None or 0 <= r["target"] <= 1 for r in rows)
    assert "synthetic" in (out / "summary.md").read_text()


# --- a path-gated shield: given each frame's ego speed and unseen objects, replayed on a resume

def _unseen(row: dict):
    return None if row["unseen"] is None else np.array(row["unseen"], dtype=np.float64).reshape(-1, 3)


def _shares(row: dict, name: str):
    """A row's ``emerged`` or ``unseen_contact``: None, or the shares with NaN for null."""
    return None if row[name] is None else np.array([np.nan if e is None else e for e in row[name]])


def _gated_argv(recording, out, config, *extra):
    # drive-b (3 frames, one chunk) first: its frames are where the gate decides (see below)
    root, _, prior = recording
    return ["monitor", "-o", str(out), "--recording", str(root / "drive-b"), str(root / "drive-a"),
            "--prior", str(prior), "--config", str(config), *extra]


@pytest.fixture(scope="module")
def gated_run(recording, tmp_path_factory):
    folder = tmp_path_factory.mktemp("gated")
    config = folder / "gate.yaml"
    config.write_text(GATE_YAML)
    assert main(_gated_argv(recording, folder / "out", config)) == 0
    return folder / "out", config


def test_a_gated_shield_gets_each_frames_speed_and_unseen_objects(recording, serial_run, gated_run):
    root, _, _ = recording
    out, config_path = gated_run
    c = load_config(config_path).shield
    assert c.path_half_width == 1.25 and c.hold_frames == 0
    gated, plain = read_rows(out), read_rows(serial_run)
    assert sorted(gated) == sorted(plain) == ["drive-a.jsonl", "drive-b.jsonl"]
    for name in gated:
        recorded = [json.loads(line)["ego_speed"] for line in
                    (root / name.removesuffix(".jsonl") / "frames.jsonl").read_text().splitlines()]
        assert [r["ego_speed"] for r in gated[name]] == recorded
        shield = Shield(c)
        for row, other in zip(gated[name], plain[name], strict=True):
            # the gate changes the decisions only, never the reports
            assert {k: v for k, v in row.items() if k != "shield"} == \
                {k: v for k, v in other.items() if k != "shield"}
            decision = shield.update(row["risk"], speed=row["ego_speed"], unseen=_unseen(row),
                                     emerged=_shares(row, "emerged"), contact=_shares(row, "unseen_contact"))
            assert row["shield"] == {"engaged": decision.engaged, "deceleration": decision.deceleration}
            assert row["shield"]["engaged"] is gated_engaged(row, c)
    # drive-b (rain) moves at 4.4 m/s with high risk from objects beside its path or beyond its
    # reach (7.4 m): the paper's shield (the risk alone, no hold) brakes there, the gated one does not
    paper = Shield(ShieldConfig(threshold=0.5, release=0.5, path_half_width=None, hold_frames=0, walker_horizon=None))
    decisions = [(row["shield"]["engaged"], paper.update(row["risk"]).engaged) for row in gated["drive-b.jsonl"]]
    differ = [d for d in decisions if d[0] != d[1]]
    assert differ and all(not engaged and paper_engaged for engaged, paper_engaged in differ)


def test_an_interrupted_gated_run_resumes_to_the_same_lines(recording, gated_run, tmp_path, monkeypatch):
    out, config = tmp_path / "out", gated_run[1]
    real = monitor_command.process_chunks

    def interrupted(*args, **kwargs):  # drive-b's chunk, then Ctrl-C
        chunks = real(*args, **kwargs)
        yield next(chunks)
        raise KeyboardInterrupt

    monkeypatch.setattr(monitor_command, "process_chunks", interrupted)
    with pytest.raises(KeyboardInterrupt):
        main(_gated_argv(recording, out, config))
    rows = read_rows(out)
    assert len(rows["drive-b.jsonl"]) == 3 and rows["drive-a.jsonl"] == []
    # the resume replays drive-b's decisions, which the risk alone does not give (test above)
    monkeypatch.setattr(monitor_command, "process_chunks", real)
    assert main(_gated_argv(recording, out, config)) == 0
    assert read_rows(out) == read_rows(gated_run[0])


def test_a_tampered_ego_speed_does_not_replay(recording, gated_run, tmp_path, capsys):
    out = tmp_path / "out"
    shutil.copytree(gated_run[0], out)
    assert main(_gated_argv(recording, out, gated_run[1])) == 0  # as it was, every line replays
    c = load_config(gated_run[1]).shield
    path = out / "scenes" / "drive-b.jsonl"
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    # a frame the gated shield let go whose unseen object in the path would be within the reach
    # at 20 m/s (400 / 6 + 10 + 2 = 78.7 m): with that speed stored it engages
    n = next(k for k, r in enumerate(rows)
             if not r["shield"]["engaged"] and gated_engaged({**r, "ego_speed": 20.0}, c))
    rows[n]["ego_speed"] = 20.0
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    assert main(_gated_argv(recording, out, gated_run[1])) == 2
    assert f"drive-b.jsonl: line {n + 1}: shield {{'engaged': False, 'deceleration': 0.0}} does not replay" \
        in capsys.readouterr().err


def test_tampered_walkers_do_not_replay(recording, serial_run, tmp_path, capsys):
    # the recording's walkers never walk into the path; stored ones that do make the replayed
    # shield brake. The ego stands still (reach: the 2 m margin) and the frames are 0.5 s
    # apart: a walker 1.2 m ahead of the bumper crossing at 1.5 m/s from 3.5 m to the left is,
    # at the third frame, 2.0 - 0.3 - 1.25 = 0.45 m from the path, within a second's walk
    out = tmp_path / "out"
    shutil.copytree(serial_run, out)
    path = out / "scenes" / "drive-a.jsonl"
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    assert [r["time"] for r in rows[:3]] == [0.0, 0.5, 1.0] and {r["ego_speed"] for r in rows[:3]} == {0.0}
    assert not any(r["shield"]["engaged"] for r in rows[:3])
    for r, y in zip(rows, (3.5, 2.75, 2.0)):
        r["walkers"] = [[5.0, y]]
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    assert main(_argv(recording, out)) == 2
    err = capsys.readouterr().err
    assert "drive-a.jsonl: line 3: shield {'engaged': False, 'deceleration': 0.0} does not replay" in err
    assert "deceleration=6.0" in err and "cause='walker'" in err


@pytest.mark.parametrize("name", ["ego_speed", "walkers"])
def test_lines_without_a_replayed_field_are_refused_naming_it(recording, serial_run, tmp_path, capsys, name):
    # lines written before the rows carried the ego's speed, or the walkers: a resume cannot
    # replay them
    out = tmp_path / "out"
    shutil.copytree(serial_run, out)
    path = out / "scenes" / "drive-a.jsonl"
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    del rows[0][name]
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    assert main(_argv(recording, out)) == 2
    assert f"drive-a.jsonl: line 1: has no {name!r} field, which a resume needs (a line of an older " \
           "fuzzrisk monitor?); pass --overwrite" in capsys.readouterr().err
