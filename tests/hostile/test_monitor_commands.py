"""Hostile command lines for the monitor's commands: outputs checked before any work,
never an input, never replaced without --overwrite (issue 13, items 9 and 12)."""
import numpy as np
import pytest

from monitor.cli import main
from monitor.depth.prior import load_prior


@pytest.fixture
def depth_dir(tmp_path):
    folder = tmp_path / "depth"
    folder.mkdir()
    # two frames: a road 4..40 m ahead (rows), and the same 25 % nearer
    road = np.linspace(40.0, 4.0, 6, dtype=np.float32)[:, None].repeat(8, axis=1)
    np.save(folder / "000.npy", road)
    np.save(folder / "001.npy", road * np.float32(0.75))
    return folder


def test_prior_build_twice_never_reads_its_own_output(depth_dir, tmp_path, capsys):
    # written inside DEPTH_DIR, the next run would read the prior as a depth map: refused
    assert main(["prior", "build", str(depth_dir), "-o", str(depth_dir / "prior.npy")]) == 2
    assert "lies in" in capsys.readouterr().err and not (depth_dir / "prior.npy").exists()
    out = tmp_path / "prior.npy"
    assert main(["prior", "build", str(depth_dir), "-o", str(out)]) == 0
    first = load_prior(out)
    # by hand: mean of 1/D and 1/(0.75 D) = (1 + 4/3) / 2 / D = (7/6) / D; at 40 m 0.029166..
    np.testing.assert_allclose(first[0], np.full(8, 7 / 6 / 40.0), rtol=1e-6)
    assert first.max() == pytest.approx(7 / 6 / 4.0, rel=1e-6)
    capsys.readouterr()
    # the second run: the existing prior is not replaced without --overwrite ...
    assert main(["prior", "build", str(depth_dir), "-o", str(out)]) == 2
    assert "already exists" in capsys.readouterr().err
    # ... and with it the result is the same (nothing of the first prior entered it)
    assert main(["prior", "build", str(depth_dir), "-o", str(out), "--overwrite"]) == 0
    np.testing.assert_array_equal(load_prior(out), first)


def test_a_prior_in_the_depth_folder_is_refused_by_name(depth_dir, tmp_path, capsys):
    assert main(["prior", "build", str(depth_dir), "-o", str(tmp_path / "p.npy")]) == 0
    (tmp_path / "p.npy").rename(depth_dir / "002.npy")  # an earlier prior among the maps
    assert main(["prior", "build", str(depth_dir), "-o", str(tmp_path / "q.npy")]) == 2
    err = capsys.readouterr().err
    assert "002.npy: median valid value" in err and "inverse depth in 1/m" in err
    assert not (tmp_path / "q.npy").exists()


@pytest.mark.parametrize("argv, message", [
    (["prior", "build", "{depth}", "-o", "{tmp}/p.txt"], "suffix '.txt', expected .npy"),
    (["prior", "build", "{depth}", "-o", "{tmp}/missing/p.npy"], "does not exist; create it first"),
    (["prior", "build", "{depth}", "-o", "{tmp}"], "expected .npy"),
    (["features", "-o", "{tmp}/f.json"], "suffix '.json', expected .csv"),
    (["features", "-o", "{tmp}/missing/f.csv"], "does not exist"),
    (["features", "-o", "{tmp}/existing.csv"], "already exists"),
    (["eval", "-o", "{tmp}/existing.csv"], "is a file, expected a folder"),
    (["eval", "-o", "{tmp}/missing/deeper"], "does not exist"),
    (["eval", "-o", "{tmp}/old"], "already holds report.md"),
    (["demo", "-o", "{tmp}/old"], "already holds report.md"),
    (["simulate", "-o", "{tmp}/old"], "already holds runs.jsonl, traces.png"),
])
def test_outputs_are_checked_before_the_work(argv, message, depth_dir, tmp_path, capsys):
    (tmp_path / "existing.csv").write_text("mine")
    old = tmp_path / "old"
    old.mkdir()
    for name in ("report.md", "runs.jsonl", "traces.png"):
        (old / name).write_text("mine")
    argv = [a.format(depth=depth_dir, tmp=tmp_path) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err, err
    # nothing was replaced
    assert (tmp_path / "existing.csv").read_text() == "mine"
    assert all((old / n).read_text() == "mine" for n in ("report.md", "runs.jsonl", "traces.png"))


def test_features_overwrite_replaces_whole(tmp_path, capsys):
    out = tmp_path / "f.csv"
    out.write_text("mine")
    argv = ["features", "-o", str(out), "--scenes", "1", "--test-scenes", "0", "--frames", "1",
            "--prior-scenes", "1", "--conditions", "nominal", "--split", "train"]
    assert main(argv) == 2 and out.read_text() == "mine"
    assert main(argv + ["--overwrite"]) == 0
    assert out.read_text().startswith("scene,frame,condition,iou,rdd,target")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.csv"]  # no temporary file left
